/* strands/deflection.hh: the angles a pass's move gives a hinge are read continuously with the
 * hinge's own, whichever of a direction's readings and whole turns those are on. */
#include <gtest/gtest.h>

#include <random>

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
