#include "core/head_motion.hh"

#include <cmath>

namespace hairdyn {

HeadPose HeadPose::from_matrix(const mat4 &head_to_world)
{
  HeadPose pose;
  pose.translation = vec3(head_to_world[3]);
  mat3 axes(head_to_world);
  pose.scale = vec3(glm::length(axes[0]), glm::length(axes[1]), glm::length(axes[2]));
  if (glm::determinant(axes) < 0.0f) {
    pose.scale.x = -pose.scale.x; /* A mirrored head: the rotation stays proper. */
  }
  for (int axis = 0; axis < 3; axis++) {
    axes[axis] /= pose.scale[axis];
  }
  pose.rotation = glm::normalize(glm::quat_cast(axes));
  return pose;
}

HeadPose HeadPose::interpolate(const HeadPose &a, const HeadPose &b, const float t)
{
  HeadPose pose;
  pose.translation = glm::mix(a.translation, b.translation, t);
  pose.rotation = glm::normalize(glm::slerp(a.rotation, b.rotation, t));
  pose.scale = glm::mix(a.scale, b.scale, t);
  return pose;
}

vec3 HeadPose::transform_point(const vec3 &p_head) const
{
  return translation + rotation * (scale * p_head);
}

vec3 HeadPose::inverse_transform_point(const vec3 &p_wo) const
{
  return (glm::inverse(rotation) * (p_wo - translation)) / scale;
}

HeadVelocity HeadVelocity::between(const HeadPose &from, const HeadPose &to, const float dt)
{
  HeadVelocity velocity;
  velocity.linear = (to.translation - from.translation) / dt;
  /* The relative rotation to·from⁻¹ as a rotation vector (world space), shortest arc. */
  glm::quat delta = to.rotation * glm::inverse(from.rotation);
  if (delta.w < 0.0f) {
    delta = -delta;
  }
  const vec3 v(delta.x, delta.y, delta.z);
  const float sin_half = glm::length(v);
  if (sin_half > 1e-12f) {
    const float angle = 2.0f * std::atan2(sin_half, delta.w);
    velocity.angular = v * (angle / (sin_half * dt));
  }
  return velocity;
}

HeadAcceleration HeadAcceleration::between(const HeadVelocity &before, const HeadVelocity &after,
                                           const float dt)
{
  HeadAcceleration head;
  head.linear = (after.linear - before.linear) / dt;
  head.angular_velocity = after.angular;
  head.angular_acceleration = (after.angular - before.angular) / dt;
  return head;
}

mat3 HeadAcceleration::transport_gradient() const
{
  const mat3 w = cross_matrix(angular_velocity);
  return cross_matrix(angular_acceleration) + w * w;
}

}  // namespace hairdyn
