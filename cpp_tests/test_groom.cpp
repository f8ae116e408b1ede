#include <gtest/gtest.h>

#include <cmath>

#include "core/parallel.hh"
#include "core/random.hh"
#include "groom/groom.hh"
#include "groom/metrics.hh"

using namespace hairdyn;

namespace {

/* Two straight strands of 3 and 4 points along +z. */
struct TwoStrands {
  std::vector<int32_t> offsets{0, 3, 7};
  std::vector<vec3> positions;
  TwoStrands()
  {
    for (int i = 0; i < 3; i++) {
      positions.emplace_back(0.0f, 0.0f, 0.1f * float(i));
    }
    for (int i = 0; i < 4; i++) {
      positions.emplace_back(1.0f, 0.0f, 0.1f * float(i));
    }
  }
};

}  // namespace

TEST(Groom, ValidGroomHasNoError)
{
  const TwoStrands g;
  EXPECT_EQ(find_groom_error(g.offsets, g.positions), "");
  EXPECT_EQ(curve_points(g.offsets, 1).start, 3);
  EXPECT_EQ(curve_points(g.offsets, 1).size, 4);
}

TEST(Groom, OffsetsMustStartAtZeroAndMatchCount)
{
  TwoStrands g;
  g.offsets = {1, 3, 7};
  EXPECT_NE(find_groom_error(g.offsets, g.positions).find("start at 0"), std::string::npos);
  g.offsets = {0, 3, 6};
  EXPECT_NE(find_groom_error(g.offsets, g.positions).find("7 points"), std::string::npos);
  g.offsets = {0};
  EXPECT_EQ(find_groom_error(g.offsets, g.positions), "the hair has no strands");
}

TEST(Groom, OffsetsMustBeMonotone)
{
  TwoStrands g;
  g.offsets = {0, 5, 4, 7};
  EXPECT_NE(find_groom_error(g.offsets, g.positions).find("decrease at strand 1"),
            std::string::npos);
}

TEST(Groom, SinglePointStrandIsAnError)
{
  TwoStrands g;
  g.offsets = {0, 1, 7};
  EXPECT_NE(find_groom_error(g.offsets, g.positions).find("strand 0 has 1 point"),
            std::string::npos);
}

TEST(Groom, NonFiniteAndZeroLengthAreErrors)
{
  TwoStrands g;
  g.positions[4].y = NAN;
  EXPECT_NE(find_groom_error(g.offsets, g.positions).find("point 4"), std::string::npos);
  g = TwoStrands();
  g.positions[5] = g.positions[4];
  EXPECT_NE(find_groom_error(g.offsets, g.positions).find("strand 1 has a zero-length segment"),
            std::string::npos);
}

TEST(Metrics, StretchAndNonFinite)
{
  const TwoStrands rest;
  TwoStrands now;
  EXPECT_EQ(max_relative_stretch(rest.offsets, rest.positions, now.positions), 0.0f);
  now.positions[6].z += 0.05f; /* last segment 0.1 -> 0.15 */
  EXPECT_NEAR(max_relative_stretch(rest.offsets, rest.positions, now.positions), 0.5f, 1e-5f);
  EXPECT_EQ(count_nonfinite(now.positions), 0);
  now.positions[2].x = INFINITY;
  now.positions[3].z = NAN;
  EXPECT_EQ(count_nonfinite(now.positions), 2);
  EXPECT_TRUE(std::isinf(max_relative_stretch(rest.offsets, rest.positions, now.positions)));
}

/* strand_frame's one pass gives what the separate measures give, on 9,000 strands of 2 to 20
 * points (several chunks of the thread pool), the same bits on 1 and 2 threads. */
TEST(Metrics, StrandFrameIsTheSeparateMeasuresInOnePass)
{
  RandomNumberGenerator rng(7);
  std::vector<int32_t> offsets{0};
  std::vector<vec3> rest, now, previous;
  for (int c = 0; c < 9000; c++) {
    const int points = 2 + int(rng.next_uint64() % 19);
    vec3 p(rng.next_float(), rng.next_float(), rng.next_float());
    for (int i = 0; i < points; i++) {
      const vec3 step(rng.next_float(-0.01f, 0.01f), rng.next_float(-0.01f, 0.01f), 0.01f);
      rest.push_back(p);
      now.push_back(p + 0.1f * step + vec3(0.0f, 0.0f, 0.002f * float(i)));
      previous.push_back(p + vec3(0.003f, 0.0f, 0.0f));
      p += step;
    }
    offsets.push_back(int32_t(rest.size()));
  }
  const float dt = 1.0f / 24.0f;
  std::vector<vec3> tangents(now.size());
  point_tangents(offsets, now, tangents);
  StrandFrame frames[2];
  std::vector<vec3> velocities[2], frame_tangents[2], previous_after[2];
  for (int threads = 1; threads <= 2; threads++) {
    set_thread_num(threads);
    std::vector<vec3> &v = velocities[threads - 1], &t = frame_tangents[threads - 1];
    previous_after[threads - 1] = previous;
    v.assign(now.size(), vec3(0.0f));
    t.assign(now.size(), vec3(0.0f));
    frames[threads - 1] = strand_frame(offsets, rest, now, dt, previous_after[threads - 1], v, t);
  }
  set_thread_num(0);
  EXPECT_EQ(frames[0].nonfinite, 0);
  EXPECT_EQ(frames[0].stretch, max_relative_stretch(offsets, rest, now));
  EXPECT_GT(frames[0].stretch, 0.1f);
  for (size_t i = 0; i < now.size(); i++) {
    ASSERT_EQ(previous_after[0][i], now[i]) << i;
    ASSERT_EQ(frame_tangents[0][i], tangents[i]) << i;
    ASSERT_EQ(velocities[0][i], (now[i] - previous[i]) / dt) << i;
    ASSERT_EQ(velocities[1][i], velocities[0][i]) << i;
    ASSERT_EQ(frame_tangents[1][i], frame_tangents[0][i]) << i;
  }
  EXPECT_EQ(frames[1].stretch, frames[0].stretch);
  /* Points that are not finite numbers: counted, and the stretch is infinite. */
  now[5].x = NAN;
  now[now.size() - 1].z = -INFINITY;
  std::vector<vec3> v(now.size()), t(now.size());
  const StrandFrame broken = strand_frame(offsets, rest, now, dt, previous_after[0], v, t);
  EXPECT_EQ(broken.nonfinite, 2);
  EXPECT_TRUE(std::isinf(broken.stretch));
}

TEST(Metrics, StretchCountsShrinkingAsMuchAsStretching)
{
  const TwoStrands rest;
  TwoStrands now;
  now.positions[2].z = 0.15f; /* second segment 0.1 -> 0.05 */
  EXPECT_NEAR(max_relative_stretch(rest.offsets, rest.positions, now.positions), 0.5f, 1e-5f);
  now.positions[6].z = 0.2f; /* the last segment 0.1 -> 0: a shrink to nothing, the larger */
  EXPECT_NEAR(max_relative_stretch(rest.offsets, rest.positions, now.positions), 1.0f, 1e-6f);
  TwoStrands collapsed_rest; /* a rest segment of no length: any length is infinitely far */
  collapsed_rest.positions[1] = collapsed_rest.positions[0];
  EXPECT_TRUE(std::isinf(max_relative_stretch(rest.offsets, collapsed_rest.positions,
                                              rest.positions)));
}

TEST(Metrics, PointBoundsAreTheMinimumAndMaximumOfEachCoordinate)
{
  vec3 low, high;
  point_bounds({}, low, high); /* no points: an empty box */
  EXPECT_TRUE(glm::all(glm::equal(low, vec3(INFINITY))));
  EXPECT_TRUE(glm::all(glm::equal(high, vec3(-INFINITY))));
  /* Counts around the 16-point blocks, the extremes placed in every lane and in the tail. */
  RandomNumberGenerator rng(7);
  for (const int count : {1, 15, 16, 17, 47, 700}) {
    std::vector<vec3> points(static_cast<size_t>(count));
    for (vec3 &p : points) {
      p = vec3(rng.next_float(-1.0f, 1.0f), rng.next_float(-2.0f, 2.0f), rng.next_float(3.0f, 4.0f));
    }
    for (const int at : {0, count / 2, count - 1}) {
      std::vector<vec3> with = points;
      with[size_t(at)] = vec3(-5.0f, 9.0f, NAN); /* NaN is passed over */
      vec3 expected_low(INFINITY), expected_high(-INFINITY);
      for (const vec3 &p : with) {
        for (int a = 0; a < 3; a++) {
          if (!std::isnan(p[a])) {
            expected_low[a] = std::min(expected_low[a], p[a]);
            expected_high[a] = std::max(expected_high[a], p[a]);
          }
        }
      }
      point_bounds(with, low, high);
      EXPECT_EQ(low, expected_low) << count << " points, extreme at " << at;
      EXPECT_EQ(high, expected_high) << count << " points, extreme at " << at;
      EXPECT_EQ(low.x, -5.0f);
      EXPECT_EQ(high.y, 9.0f);
    }
  }
}

TEST(Groom, StrandsErrorChecksTheOffsetsAlone)
{
  TwoStrands g;
  g.positions[4].y = NAN; /* values are not its concern */
  EXPECT_EQ(find_strands_error(g.offsets, int64_t(g.positions.size())), "");
  EXPECT_NE(find_strands_error(g.offsets, 6).find("6 points"), std::string::npos);
  g.offsets = {0, 1, 7};
  EXPECT_NE(find_strands_error(g.offsets, 7).find("strand 0 has 1 point"), std::string::npos);
}

TEST(Metrics, PointTangentsFollowEachStrand)
{
  TwoStrands g;
  g.positions[5] = g.positions[4]; /* a zero-length segment: a zero direction */
  g.positions[6] = g.positions[4] + vec3(0.3f, 0.0f, 0.0f);
  std::vector<vec3> tangents(g.positions.size(), vec3(7.0f));
  point_tangents(g.offsets, g.positions, tangents);
  const std::vector<vec3> expected = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, /* a tip: its segment's */
                                      {0, 0, 1}, {0, 0, 0}, {1, 0, 0}, {1, 0, 0}};
  for (size_t i = 0; i < expected.size(); i++) {
    EXPECT_NEAR(glm::distance(tangents[i], expected[i]), 0.0f, 1e-6f) << "point " << i;
  }
}
