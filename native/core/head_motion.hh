#pragma once
/* The head's animated rigid motion, one model for every method (strands, LCP, follow).
 *
 * The head's transform is given once per frame; substeps interpolate it (lerp translation and
 * scale, slerp rotation), and its velocity and acceleration come from finite differences
 * across frames. A method whose state is carried by the head (strand angles in head-carried
 * frames, LCP particles in the head's frame) sees the head's motion as a fictitious force per
 * unit mass −a_rel(r, v_rel) with
 *
 *   a_rel(r, v_rel) = a + ω̇ × (r − c) + ω × (ω × (r − c)) + 2 ω × v_rel
 *
 * (transport acceleration of the head-fixed point at r, plus Coriolis; c the head's origin, a
 * its acceleration, ω its angular velocity, v_rel the point's velocity relative to the head).
 * Kurihara 1993, eq. 6 names this term a; Bando 2003 §4.4 applies it in the head's frame. */
#include <glm/gtc/quaternion.hpp>

#include "core/math.hh"

namespace hairdyn {

/* A head transform split into parts that interpolate well. Shear is not supported. */
struct HeadPose {
  vec3 translation = vec3(0.0f);
  glm::quat rotation = glm::quat(1.0f, 0.0f, 0.0f, 0.0f);
  vec3 scale = vec3(1.0f);

  static HeadPose from_matrix(const mat4 &head_to_world);
  /* Translation and scale lerped, rotation slerped (shortest arc); t in [0, 1]. */
  static HeadPose interpolate(const HeadPose &a, const HeadPose &b, float t);
  /* Head space (scaled) to world, and back. */
  vec3 transform_point(const vec3 &p_head) const;
  vec3 inverse_transform_point(const vec3 &p_wo) const;
  mat3 rotation_matrix() const { return glm::mat3_cast(rotation); }
  /* The same pose seen from a frame whose origin sits at `origin` (world): translation only. */
  HeadPose translated(const vec3 &offset) const
  {
    HeadPose pose = *this;
    pose.translation += offset;
    return pose;
  }
};

/* Linear velocity of the head's origin and its angular velocity, both in world space. */
struct HeadVelocity {
  vec3 linear = vec3(0.0f);  /* m/s */
  vec3 angular = vec3(0.0f); /* rad/s */

  /* Finite difference of two poses dt seconds apart (rotation: the shortest arc). */
  static HeadVelocity between(const HeadPose &from, const HeadPose &to, float dt);
  /* m/s, velocity of the head-fixed point at `arm` = r − c from the head's origin (a vec3,
   * or several points in lanes: strands/chain_lanes.hh). */
  template<class V> V of_point(const V &arm) const { return linear + cross(angular, arm); }
};

/* The head's rigid-body acceleration field at one instant. */
struct HeadAcceleration {
  vec3 center = vec3(0.0f);               /* m, c, the head's origin */
  vec3 linear = vec3(0.0f);               /* m/s², a of the origin */
  vec3 angular_velocity = vec3(0.0f);     /* rad/s, ω */
  vec3 angular_acceleration = vec3(0.0f); /* rad/s², ω̇ */

  /* From the velocities of two consecutive frames dt apart: a = Δv / dt, ω̇ = Δω / dt, ω the
   * later one. `center` is left at the origin: set it to the head's position. */
  static HeadAcceleration between(const HeadVelocity &before, const HeadVelocity &after,
                                  float dt);

  /* Transport acceleration of the head-fixed point at r: a + ω̇ × (r − c) + ω × (ω × (r − c)). */
  vec3 transport(const vec3 &r) const
  {
    const vec3 arm = r - center;
    return linear + glm::cross(angular_acceleration, arm) +
           glm::cross(angular_velocity, glm::cross(angular_velocity, arm));
  }
  /* Coriolis acceleration 2 ω × v_rel of a point moving at v_rel relative to the head. */
  vec3 coriolis(const vec3 &v_rel) const { return 2.0f * glm::cross(angular_velocity, v_rel); }
  /* a_rel(r, v_rel): the world acceleration of a point at r moving at v_rel relative to the
   * head, minus its acceleration relative to the head. The fictitious force per unit mass in
   * the head's frame is its negative. */
  vec3 fictitious(const vec3 &r, const vec3 &v_rel) const { return transport(r) + coriolis(v_rel); }

  /* The transport acceleration is affine in r: transport(r) = linear + A (r − c) with
   * A = [ω̇]× + [ω]×². */
  mat3 transport_gradient() const;
};

/* [v]×, the matrix of v × (·). */
inline mat3 cross_matrix(const vec3 &v)
{
  return mat3(vec3(0.0f, v.z, -v.y), vec3(-v.z, 0.0f, v.x), vec3(v.y, -v.x, 0.0f));
}

}  // namespace hairdyn
