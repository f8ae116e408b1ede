#include "lod/selection_ward2003.hh"

#include <algorithm>
#include <cmath>

namespace hairdyn {

LodCamera::LodCamera(const mat4 &view_projection)
{
  /* Gribb & Hartmann: the frustum planes are row 3 ± rows 0, 1, 2 of the matrix. */
  const auto row = [&](const int r) {
    return vec4(view_projection[0][r], view_projection[1][r], view_projection[2][r],
                view_projection[3][r]);
  };
  const vec4 w = row(3);
  for (int axis = 0; axis < 3; axis++) {
    planes_[2 * axis] = w + row(axis);
    planes_[2 * axis + 1] = w - row(axis);
  }
  for (vec4 &plane : planes_) {
    const float length = glm::length(vec3(plane));
    plane = length > 0.0f ? plane / length : vec4(0.0f, 0.0f, 0.0f, 1.0f);
  }
  /* The eye maps to clip (0, 0, ±z, 0): it is the inverse image of (0, 0, 1, 0). An
   * orthographic camera maps it to a direction (w = 0): its eye is at infinity. */
  const vec4 eye = glm::inverse(view_projection) * vec4(0.0f, 0.0f, 1.0f, 0.0f);
  orthographic_ = !(std::abs(eye.w) > 1e-9f * glm::length(vec3(eye)));
  position_wo_ = orthographic_ ? vec3(0.0f) : vec3(eye) / eye.w;
}

bool LodCamera::sees_sphere(const vec3 &centre_wo, const float radius) const
{
  for (const vec4 &plane : planes_) {
    if (glm::dot(vec3(plane), centre_wo) + plane.w < -radius) {
      return false;
    }
  }
  return true;
}

float LodCamera::distance_to(const vec3 &p_wo) const
{
  if (orthographic_) {
    const vec4 &near_plane = planes_[4];
    return std::max(glm::dot(vec3(near_plane), p_wo) + near_plane.w, 0.0f);
  }
  return glm::length(p_wo - position_wo_);
}

int32_t wanted_level(const float distance, const float speed, const LodParams &params,
                     const int32_t coarsest, const int32_t finest)
{
  const float levels = float(finest - coarsest);
  /* The fraction of the way from the coarsest to the finest level each test asks for. */
  const float by_distance = 1.0f - glm::clamp((distance - params.distance_near) /
                                                  (params.distance_far - params.distance_near),
                                              0.0f, 1.0f);
  const float by_speed = glm::clamp((speed - params.velocity_slow) /
                                        (params.velocity_fast - params.velocity_slow),
                                    0.0f, 1.0f);
  const float wanted = float(coarsest) + levels * std::max(by_distance, by_speed);
  return std::clamp(int32_t(std::floor(wanted + 1e-4f)), coarsest, finest);
}

bool hidden_by_colliders(const ColliderSet &colliders, const vec3 &eye_wo, const vec3 &point_wo,
                         const float margin_wo, int64_t *const r_occluder)
{
  const float distance = glm::length(point_wo - eye_wo);
  if (distance <= margin_wo) {
    return false;
  }
  const float t_max = 1.0f - margin_wo / distance;
  /* The ray in collider i's own space. */
  const auto ray = [&](const Collider &collider, vec3 &r_origin, vec3 &r_direction) {
    r_origin = transform_point(collider.world_to_object(), eye_wo);
    r_direction = transform_point(collider.world_to_object(), point_wo) - r_origin;
  };
  vec3 origin, direction;
  if (r_occluder != nullptr && *r_occluder >= 0) {
    const int64_t i = *r_occluder >> 32;
    if (i < colliders.colliders_num()) {
      const Collider &collider = colliders.collider(i);
      ray(collider, origin, direction);
      if (collider.exact().bvh().ray_hits_leaf(origin, direction, t_max,
                                               int32_t(*r_occluder & 0xffffffff)))
      {
        return true;
      }
    }
  }
  for (int64_t i = 0; i < colliders.colliders_num(); i++) {
    const Collider &collider = colliders.collider(i);
    const TriangleBVH &bvh = collider.exact().bvh();
    if (bvh.is_empty()) {
      continue;
    }
    ray(collider, origin, direction);
    int32_t leaf = -1;
    if (bvh.ray_hits_any(origin, direction, t_max, &leaf)) {
      if (r_occluder != nullptr) {
        *r_occluder = (i << 32) | int64_t(leaf);
      }
      return true;
    }
  }
  if (r_occluder != nullptr) {
    *r_occluder = -1;
  }
  return false;
}

}  // namespace hairdyn
