#include <gtest/gtest.h>

#include <random>

#include "groom/follow.hh"

using namespace hairdyn;

namespace {

std::vector<vec3> random_points(const int n, const unsigned seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<vec3> points(static_cast<size_t>(n));
  for (vec3 &p : points) {
    p = vec3(u(rng), u(rng), u(rng));
  }
  return points;
}

mat4 head_transform(const vec3 &translation, const float angle, const vec3 &axis,
                    const vec3 &scale)
{
  return glm::scale(glm::rotate(glm::translate(mat4(1.0f), translation), angle, axis), scale);
}

}  // namespace

TEST(Follow, SpanIsZeroCopy)
{
  std::vector<vec3> points = random_points(10, 1);
  const Span<vec3> view(points);
  const MutableSpan<vec3> mutable_view(points);
  EXPECT_EQ(view.data(), points.data());
  EXPECT_EQ(Span<vec3>(mutable_view).data(), points.data());
  EXPECT_EQ(view.slice(3, 4).data(), points.data() + 3);
}

TEST(Follow, UnmovedHeadKeepsRestShapeExactly)
{
  const std::vector<vec3> rest = random_points(1000, 2);
  const std::vector<int32_t> offsets{0, 500, 1000};
  const mat4 head = head_transform(vec3(0.3f, -2.0f, 1.5f), 0.7f, glm::normalize(vec3(1, 2, 3)),
                                   vec3(1.3f));
  FollowSolver solver(offsets, rest, head);
  solver.step(head);
  for (size_t i = 0; i < rest.size(); i++) {
    EXPECT_NEAR(glm::length(solver.positions()[int64_t(i)] - rest[i]), 0.0f, 2e-6f) << i;
  }
}

TEST(Follow, StrandsFollowTheHeadRigidly)
{
  /* The groom at rest with the head at identity; the head then moves, turns and scales: every
   * point must land on M * p to float precision, so distances scale by exactly s. */
  const std::vector<vec3> rest = random_points(2000, 3);
  const std::vector<int32_t> offsets{0, 1000, 2000};
  FollowSolver solver(offsets, rest, mat4(1.0f));
  const mat4 head = head_transform(vec3(5.0f, 1.0f, -3.0f), 2.1f, glm::normalize(vec3(0, 1, 1)),
                                   vec3(2.0f));
  solver.step(head);
  for (size_t i = 0; i < rest.size(); i++) {
    const vec3 expected = transform_point(head, rest[i]);
    EXPECT_LE(glm::length(solver.positions()[int64_t(i)] - expected),
              1e-6f * (1.0f + glm::length(expected)))
        << i;
  }
  const float d_rest = glm::length(rest[1] - rest[0]);
  const float d_now = glm::length(solver.positions()[1] - solver.positions()[0]);
  EXPECT_NEAR(d_now / d_rest, 2.0f, 1e-5f);

  solver.reset();
  EXPECT_EQ(solver.positions()[7], rest[7]);
}

TEST(Follow, RestFrameNeedNotBeIdentity)
{
  /* Groom captured with the head already moved: going back to identity undoes that move. */
  const std::vector<vec3> rest_at_identity = random_points(100, 4);
  const mat4 head_rest = head_transform(vec3(1, 2, 3), 0.4f, vec3(0, 0, 1), vec3(0.5f));
  std::vector<vec3> rest_wo(rest_at_identity.size());
  transform_points(head_rest, rest_at_identity, rest_wo);
  FollowSolver solver(std::vector<int32_t>{0, 100}, rest_wo, head_rest);
  solver.step(mat4(1.0f));
  for (size_t i = 0; i < rest_wo.size(); i++) {
    EXPECT_LE(glm::length(solver.positions()[int64_t(i)] - rest_at_identity[i]), 2e-6f) << i;
  }
}
