/* strands/deflection.hh: the angles a pass's move gives a hinge are read continuously with the
 * hinge's own, whichever of a direction's readings and whole turns those are on; the hinges'
 * sines and cosines are accurate and the same in lanes as alone. */
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "strands/chain_lanes.hh"
#include "strands/deflection.hh"

using namespace hairdyn;

TEST(StrandsDeflection, AMovedSegmentKeepsItsHingesReadingOfTheAngles)
{
  /* Hinge angles anywhere (a limp hinge turns past the chart's pole, θ beyond ±π/2, and
   * through whole turns of φ) in a turned chart; the segment moves by a small angle. The
   * angles read back lie beside the old ones, and their sines and cosines point the segment
   * where it went. The principal reading (θ from asin, φ from atan2) is off by π − 2θ or by
   * whole turns for most of these. */
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> theta(-6.0f, 6.0f), phi(-20.0f, 20.0f);
  std::uniform_real_distribution<float> nudge(-0.01f, 0.01f);
  const mat3 chart = glm::mat3_cast(glm::angleAxis(0.7f, glm::normalize(vec3(1.0f, 2.0f, 3.0f))));
  int tested = 0;
  for (int k = 0; k < 100000; k++) {
    const glm::vec2 angles(theta(rng), phi(rng));
    if (std::abs(std::cos(angles.x)) < 0.05f) {
      continue; /* at the chart's pole φ is not defined by the direction */
    }
    const glm::vec2 moved = angles + glm::vec2(nudge(rng), nudge(rng));
    const vec3 direction = Deflection(moved).rotate(chart)[2];
    glm::vec2 read = angles;
    const Deflection deflection = chart_deflection(chart, 0.3f * direction, read);
    ASSERT_NEAR(read.x, moved.x, 1e-3f) << angles.x << " " << angles.y;
    ASSERT_NEAR(read.y, moved.y, 1e-3f) << angles.x << " " << angles.y;
    const vec4 expected = Deflection(moved).trig();
    for (int c = 0; c < 4; c++) {
      ASSERT_NEAR(deflection.trig()[c], expected[c], 1e-4f) << angles.x << " " << angles.y;
    }
    tested++;
  }
  EXPECT_GT(tested, 90000);
}

TEST(StrandsDeflection, SinCosIsAccurateAndTheSameInLanes)
{
  /* Against the double-precision sine and cosine, over angles a hinge reaches (±60 rad: a limp
   * hinge winds through turns) and beside every multiple of π/4 up to ±10π: within 1e-7
   * absolutely (an ulp of 1 is 1.19e-7) and 2 ulp of the value where it is not near zero;
   * exactly 0 and 1 at 0 (a hinge at rest deflects nothing). */
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> angle(-60.0f, 60.0f);
  std::vector<float> xs;
  for (int i = 0; i < 1000000; i++) {
    xs.push_back(angle(rng));
  }
  for (int k = -40; k <= 40; k++) {
    for (const float offset : {0.0f, 1e-7f, -1e-7f, 1e-3f, -1e-3f}) {
      xs.push_back(float(k) * 0.785398163f + offset);
    }
  }
  double worst_absolute = 0.0, worst_ulps = 0.0;
  for (const float x : xs) {
    float s, c;
    sin_cos<float, int32_t>(x, s, c);
    for (const auto &[value, exact] :
         {std::pair<float, double>{s, std::sin(double(x))}, {c, std::cos(double(x))}})
    {
      const double error = std::abs(double(value) - exact);
      worst_absolute = std::max(worst_absolute, error);
      if (std::abs(exact) > 1e-3) {
        worst_ulps = std::max(worst_ulps, error / std::ldexp(1.0, std::ilogb(exact) - 23));
      }
    }
  }
  EXPECT_LE(worst_absolute, 1e-7);
  EXPECT_LE(worst_ulps, 2.0);
  float s0, c0;
  sin_cos<float, int32_t>(0.0f, s0, c0);
  EXPECT_EQ(s0, 0.0f);
  EXPECT_EQ(c0, 1.0f);

  /* Eight lanes at once give each lane's bits alone (the articulated commit's vectors). */
  for (size_t start = 0; start + 8 <= xs.size(); start += 997) {
    chain::Floats<8> x, s, c;
    for (int lane = 0; lane < 8; lane++) {
      x[lane] = xs[start + size_t(lane)];
    }
    sin_cos<chain::Floats<8>, chain::Ints<8>>(x, s, c);
    for (int lane = 0; lane < 8; lane++) {
      float s1, c1;
      sin_cos<float, int32_t>(x[lane], s1, c1);
      ASSERT_EQ(std::memcmp(&s1, &s[lane], sizeof(float)), 0) << "sin of " << x[lane];
      ASSERT_EQ(std::memcmp(&c1, &c[lane], sizeof(float)), 0) << "cos of " << x[lane];
    }
  }
}
