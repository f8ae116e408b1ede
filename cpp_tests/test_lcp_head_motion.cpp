/* LCP feels the head's motion through core/head_motion.hh, the one model of every method
 * (issue 10): a head spinning at a constant rate about an axis that misses its origin. */
#include <gtest/gtest.h>

#include "core/head_motion.hh"
#include "lcp_scenes.hh"

using namespace hairdyn;
using namespace hairdyn::lcp_scenes;

TEST(LcpHeadMotion, SpinningHeadGivesTheSharedModulesFictitiousAccelerations)
{
  constexpr float frame_dt = 1.0f / 24.0f;
  LcpParams params = params_for_spacing(0.012f);
  params.max_length = 0.1f;
  params.substeps = 1;
  params.attraction_repulsion = false; /* one substep a frame: no CFL bound */
  const vec3 axis = glm::normalize(vec3(0.3f, 0.2f, 1.0f));
  const vec3 pivot(0.2f, -0.1f, 0.05f); /* off the head's origin */
  const float rate = 3.0f;              /* rad/s */
  const mat4 rest = glm::translate(mat4(1.0f), vec3(0.0f, 0.0f, 1.5f));
  const auto head_at = [&](const int frame) {
    return glm::translate(mat4(1.0f), pivot) *
           glm::rotate(mat4(1.0f), rate * frame_dt * float(frame), axis) *
           glm::translate(mat4(1.0f), -pivot) * rest;
  };
  LcpSolver solver(params, curtain(params), rest);
  for (int frame = 1; frame <= 3; frame++) {
    ASSERT_TRUE(solver.step(frame_dt, head_at(frame))) << solver.failure();
  }
  /* The shared module's view of the last substep (the middle of frame 3); its own tests hold
   * it against the analytic fictitious forces of a spinning head. */
  const HeadPose pose1 = HeadPose::from_matrix(head_at(1)), pose2 = HeadPose::from_matrix(head_at(2)),
                 pose3 = HeadPose::from_matrix(head_at(3));
  const HeadVelocity velocity = HeadVelocity::between(pose2, pose3, frame_dt);
  HeadAcceleration head = HeadAcceleration::between(HeadVelocity::between(pose1, pose2, frame_dt),
                                                    velocity, frame_dt);
  const HeadPose mid = HeadPose::interpolate(pose2, pose3, 0.5f);
  head.center = mid.translation;
  const mat3 rotation_mid = mid.rotation_matrix(), rotation_end = pose3.rotation_matrix();
  float largest = 0.0f, coriolis_largest = 0.0f;
  for (int64_t i = 0; i < solver.particles_num(); i++) {
    /* Particle i's state from the world outputs, at the end of the frame. */
    const vec3 p = solver.positions()[i];
    const vec3 x_head = glm::transpose(rotation_end) * (p - pose3.translation);
    const vec3 v_rel_wo = solver.velocities()[i] - velocity.of_point(p - pose3.translation);
    const vec3 expected = -glm::transpose(rotation_mid) *
                          head.fictitious(rotation_mid * x_head + mid.translation,
                                          rotation_mid * glm::transpose(rotation_end) * v_rel_wo);
    const vec3 got = solver.fictitious_acceleration(i);
    ASSERT_NEAR(got.x, expected.x, 1e-5f) << i;
    ASSERT_NEAR(got.y, expected.y, 1e-5f) << i;
    ASSERT_NEAR(got.z, expected.z, 1e-5f) << i;
    largest = std::max(largest, glm::length(expected));
    coriolis_largest = std::max(coriolis_largest, glm::length(2.0f * rate * glm::cross(axis, v_rel_wo)));
  }
  EXPECT_GT(largest, 1.0f) << "the scene does not spin the hair";
  EXPECT_GT(coriolis_largest, 0.01f) << "the hair does not move in the head's frame";
}
