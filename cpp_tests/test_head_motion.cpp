/* The one head-motion model (core/head_motion.hh) against analytic rigid-body kinematics: a
 * head spinning at a constant rate about an axis that does not pass through its origin. */
#include <gtest/gtest.h>

#include <glm/gtc/quaternion.hpp>

#include "core/head_motion.hh"

using namespace hairdyn;

namespace {

/* The head spins at `rate` rad/s about the axis through `pivot` along `axis`; at t = 0 its
 * origin is at `origin0`, unrotated, scaled by `scale`. */
struct SpinningHead {
  glm::dvec3 pivot{0.3, -0.2, 0.1};
  glm::dvec3 axis = glm::normalize(glm::dvec3(0.2, 0.3, 1.0));
  double rate = 2.0;
  glm::dvec3 origin0{0.05, 0.1, 1.6};
  glm::dvec3 scale{1.5, 1.5, 1.5};

  glm::dmat3 rotation(const double t) const
  {
    return glm::mat3_cast(glm::angleAxis(rate * t, axis));
  }
  glm::dvec3 origin(const double t) const { return pivot + rotation(t) * (origin0 - pivot); }
  /* World position at time t of the point whose head coordinates are p0 + u t. */
  glm::dvec3 point(const double t, const glm::dvec3 &p0, const glm::dvec3 &u) const
  {
    return origin(t) + rotation(t) * (scale * (p0 + u * t));
  }
  mat4 matrix(const double t) const
  {
    glm::dmat4 m(rotation(t) * glm::dmat3(glm::scale(glm::dmat4(1.0), scale)));
    m[3] = glm::dvec4(origin(t), 1.0);
    return mat4(m);
  }
};

}  // namespace

TEST(HeadMotion, FictitiousAccelerationMatchesTheKinematicsOfASpinningHead)
{
  /* A point moving at constant velocity u in the head's (scaled) frame has zero acceleration
   * relative to the head, so its world acceleration is the fictitious a_rel(r, v_rel):
   * transport (here purely centripetal about the off-centre axis) plus Coriolis 2 ω × v_rel.
   * Reference: the world trajectory differentiated twice by central differences in double
   * precision (step 1e-4 s: truncation ~ (ω h)² / 12 · |a| ≈ 1e-8 m/s²). */
  const SpinningHead spin;
  const double t = 0.7;
  const double dt = 1e-4;
  for (const glm::dvec3 &u : {glm::dvec3(0.0), glm::dvec3(0.4, -0.3, 0.2)}) {
    const glm::dvec3 p0(0.08, -0.05, 0.12);
    const glm::dvec3 x = spin.point(t, p0, u);
    const glm::dvec3 world_acceleration = (spin.point(t + dt, p0, u) - 2.0 * x +
                                           spin.point(t - dt, p0, u)) /
                                          (dt * dt);
    const glm::dvec3 omega = spin.rate * spin.axis;
    HeadAcceleration head;
    head.center = vec3(spin.origin(t));
    head.angular_velocity = vec3(omega);
    head.angular_acceleration = vec3(0.0f);
    /* The origin itself turns about the pivot: centripetal ω × (ω × (c − pivot)). */
    head.linear = vec3(glm::cross(omega, glm::cross(omega, spin.origin(t) - spin.pivot)));
    const vec3 v_rel = vec3(spin.rotation(t) * (spin.scale * u));
    const vec3 a_rel = head.fictitious(vec3(x), v_rel);
    for (int axis = 0; axis < 3; axis++) {
      EXPECT_NEAR(a_rel[axis], world_acceleration[axis], 1e-5) << "u " << u.x << " axis " << axis;
    }
    /* Transport alone is the centripetal acceleration about the pivot axis. */
    const glm::dvec3 centripetal = glm::cross(omega, glm::cross(omega, x - spin.pivot));
    const vec3 transport = head.transport(vec3(x));
    for (int axis = 0; axis < 3; axis++) {
      EXPECT_NEAR(transport[axis], centripetal[axis], 1e-5);
    }
    /* The affine form the strand solver uses gives the same transport acceleration. */
    const vec3 affine = head.linear + head.transport_gradient() * (vec3(x) - head.center);
    EXPECT_NEAR(glm::length(affine - transport), 0.0f, 1e-5f);
  }
}

TEST(HeadMotion, VelocitiesAndAccelerationFromFramesOfASpinningHead)
{
  /* The path every method takes: poses of consecutive frames (scale included) → chord
   * velocities → their difference. Compared with the analytic ω and centripetal acceleration
   * to what single precision and the O((ω Δt)²) of a chord allow (Δt = 1/240 s). */
  const SpinningHead spin;
  const float dt = 1.0f / 240.0f;
  const HeadPose p0 = HeadPose::from_matrix(spin.matrix(0.0));
  const HeadPose p1 = HeadPose::from_matrix(spin.matrix(dt));
  const HeadPose p2 = HeadPose::from_matrix(spin.matrix(2.0 * dt));
  EXPECT_NEAR(p1.scale.x, 1.5f, 1e-5f);
  const HeadVelocity v01 = HeadVelocity::between(p0, p1, dt);
  const HeadVelocity v12 = HeadVelocity::between(p1, p2, dt);
  const vec3 omega = vec3(spin.rate * spin.axis);
  EXPECT_LT(glm::length(v12.angular - omega), 1e-3f * spin.rate);
  HeadAcceleration head = HeadAcceleration::between(v01, v12, dt);
  head.center = p1.translation;
  EXPECT_LT(glm::length(head.angular_acceleration), 0.2f) << "constant rate: ω̇ = 0";
  const glm::dvec3 r = spin.point(dt, glm::dvec3(0.08, -0.05, 0.12), glm::dvec3(0.0));
  const glm::dvec3 expected = glm::cross(glm::dvec3(omega),
                                         glm::cross(glm::dvec3(omega), r - spin.pivot));
  EXPECT_LT(glm::length(glm::dvec3(head.transport(vec3(r))) - expected),
            1e-2 * glm::length(expected));
  /* A point fixed in the head, carried by the pose, is where the kinematics put it. */
  const vec3 p_head(0.08f, -0.05f, 0.12f);
  EXPECT_LT(glm::length(glm::dvec3(p1.transform_point(p_head)) - r), 1e-5);
  EXPECT_LT(glm::length(p1.inverse_transform_point(p1.transform_point(p_head)) - p_head), 1e-5f);
}
