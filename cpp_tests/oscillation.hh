#pragma once
/* Periods of sampled oscillations, for the strand tests' analytic frequency references. */
#include <gtest/gtest.h>

#include <vector>

namespace hairdyn::test {

/* Times at which x(t) crosses zero (linear interpolation between samples dt apart). */
inline std::vector<double> zero_crossings(const std::vector<double> &x, const double dt)
{
  std::vector<double> times;
  for (size_t i = 1; i < x.size(); i++) {
    if ((x[i - 1] < 0.0) != (x[i] < 0.0)) {
      times.push_back(dt * (double(i - 1) + x[i - 1] / (x[i - 1] - x[i])));
    }
  }
  return times;
}

/* The mean period over the crossings (two per period); 0 and a test failure for fewer than 3. */
inline double period_from_crossings(const std::vector<double> &crossings)
{
  EXPECT_GE(crossings.size(), 3u);
  if (crossings.size() < 3) {
    return 0.0;
  }
  return 2.0 * (crossings.back() - crossings.front()) / double(crossings.size() - 1);
}

}  // namespace hairdyn::test
