/* core/math.hh: the library-free atan2 the strand take-back uses. */
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "core/math.hh"

using namespace hairdyn;

TEST(CoreMath, Atan2FastIsWithinAboutAFloatUlpOfTheExactAngle)
{
  /* Directions all round the circle at every scale, and points near the axes and diagonals
   * where the octant reduction switches. */
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> angle(-3.14159265f, 3.14159265f);
  std::uniform_real_distribution<float> exponent(-20.0f, 20.0f);
  float worst = 0.0f;
  for (int k = 0; k < 1000000; k++) {
    const float a = angle(rng), r = std::exp2(exponent(rng));
    const float y = r * std::sin(a), x = r * std::cos(a);
    worst = std::max(worst, float(std::abs(double(atan2_fast(y, x)) -
                                           std::atan2(double(y), double(x)))));
  }
  EXPECT_LT(worst, 3e-7f); /* a float ulp at π is 2.4e-7 */
  for (const float e : { 0.0f, 1e-30f, 1e-7f, 0.41421356f, 0.41421357f, 1.0f, 2.4142135f }) {
    for (const float sx : { -1.0f, 1.0f }) {
      for (const float sy : { -1.0f, 1.0f }) {
        EXPECT_NEAR(atan2_fast(sy * e, sx), std::atan2(sy * e, sx), 3e-7f) << e;
        EXPECT_NEAR(atan2_fast(sy, sx * e), std::atan2(sy, sx * e), 3e-7f) << e;
      }
    }
  }
}

TEST(CoreMath, Atan2FastKeepsTheLibrarysZerosSignsAndNaN)
{
  for (const float y : { 0.0f, -0.0f }) {
    for (const float x : { 0.0f, -0.0f, 1.0f, -1.0f }) {
      EXPECT_EQ(atan2_fast(y, x), std::atan2(y, x)) << y << " " << x;
      EXPECT_EQ(std::signbit(atan2_fast(y, x)), std::signbit(std::atan2(y, x))) << y << " " << x;
    }
  }
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_TRUE(std::isnan(atan2_fast(nan, 1.0f)));
  EXPECT_TRUE(std::isnan(atan2_fast(1.0f, nan)));
}
