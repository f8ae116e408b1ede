#pragma once
/* Run-time selection of Ward & Lin 2003, §6.1: every frame each hair group is tested for
 * visibility (outside the camera's field of view, or occluded by the body: the coarsest
 * strip), then its viewing distance and its velocity are compared with thresholds that are
 * interpolated linearly between those of the coarsest and of the finest level; whichever
 * test asks for more detail wins. */
#include <vector>

#include "collision/bvh.hh"
#include "collision/collider.hh"
#include "core/math.hh"
#include "lod/lod_params_ward2003.hh"

namespace hairdyn {

/* A camera given by its view-projection matrix (OpenGL clip space, as Blender's
 * `projection_matrix @ view_matrix`: a point is in view when −w ≤ x, y, z ≤ w). */
class LodCamera {
 public:
  explicit LodCamera(const mat4 &view_projection);
  /* False when the sphere lies wholly outside one of the six frustum planes. */
  bool sees_sphere(const vec3 &centre_wo, float radius) const;
  /* m, the viewing distance of a point: from the eye (perspective) or from the near plane
   * (orthographic). */
  float distance_to(const vec3 &p_wo) const;
  /* The eye (perspective cameras). */
  const vec3 &position_wo() const { return position_wo_; }
  bool is_orthographic() const { return orthographic_; }

 private:
  vec4 planes_[6]; /* Inside where dot(xyz, p) + w >= 0, xyz of unit length. */
  vec3 position_wo_{0.0f};
  bool orthographic_ = false;
};

/* The level that distance and velocity ask for (§6.1), in [coarsest, finest]: level ℓ's
 * distance threshold is distance_near + (distance_far − distance_near)(finest − ℓ) /
 * (finest − coarsest), its velocity threshold velocity_slow + (velocity_fast −
 * velocity_slow)(ℓ − coarsest) / (finest − coarsest); the deepest level whose distance test
 * passes or whose velocity test passes wins. */
int32_t wanted_level(float distance, float speed, const LodParams &params, int32_t coarsest,
                     int32_t finest);

/* True when the segment from the eye to `point_wo`, stopped `margin_wo` short of it, crosses a
 * collider's triangles (§6.1: "occluded by the body").
 *
 * `r_occluder` (optional) remembers the triangle that hid the point (collider << 32 | its
 * place in the collider's tree; -1: none): tested first next time, a point hidden at the
 * last frame is usually hidden by the same triangle, one ray-triangle test instead of a walk
 * down the tree. The answer is the same either way: the remembered triangle counts only
 * where the ray meets it now. */
bool hidden_by_colliders(const ColliderSet &colliders, const vec3 &eye_wo, const vec3 &point_wo,
                         float margin_wo, int64_t *r_occluder = nullptr);

}  // namespace hairdyn
