#pragma once
/* The head's animated rigid motion as the strands feel it. The head's transform is given once
 * per frame; substeps interpolate it (lerp translation and scale, slerp rotation), and its
 * velocity and acceleration come from finite differences across frames. The strands' angles
 * live in frames carried by the head, so the head's acceleration enters the equations of
 * motion as an inertial (fictitious) force: Kurihara 1993, eq. 6, the term a. */
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
  vec3 transform_point(const vec3 &p_head) const;
  mat3 rotation_matrix() const { return glm::mat3_cast(rotation); }
};

/* Linear velocity of the head's origin and its angular velocity, both in world space. */
struct HeadVelocity {
  vec3 linear = vec3(0.0f);  /* m/s */
  vec3 angular = vec3(0.0f); /* rad/s */

  /* Finite difference of two poses dt seconds apart. */
  static HeadVelocity between(const HeadPose &from, const HeadPose &to, float dt);
};

/* The head's rigid-body acceleration field during one substep. */
struct HeadAcceleration {
  vec3 center = vec3(0.0f);               /* m, the head's origin */
  vec3 linear = vec3(0.0f);               /* m/s², a of the origin */
  vec3 angular_velocity = vec3(0.0f);     /* rad/s, ω */
  vec3 angular_acceleration = vec3(0.0f); /* rad/s², ω̇ */

  /* Acceleration of the head-fixed point at r: a + ω̇ × (r − c) + ω × (ω × (r − c)). A strand
   * element at r feels the inertial force −c·a(r) per length (Kurihara 1993, eq. 6). The
   * Coriolis term −2ω × v_rel is left out: the strands' own velocity relative to the head is
   * small next to the head's for the turns a head makes. */
  vec3 at(const vec3 &r) const
  {
    const vec3 arm = r - center;
    return linear + glm::cross(angular_acceleration, arm) +
           glm::cross(angular_velocity, glm::cross(angular_velocity, arm));
  }
};

}  // namespace hairdyn
