#pragma once
/* The kinematic baseline: every strand keeps its rest shape in the head's frame and follows
 * the head's animated transform rigidly (translation, rotation and scale). */
#include <vector>

#include "core/math.hh"
#include "core/span.hh"

namespace hairdyn {

/* r_dst[i] = m * src[i] (points, w = 1). src and r_dst may be the same array. */
void transform_points(const mat4 &m, Span<vec3> src, MutableSpan<vec3> r_dst);

class FollowSolver {
 public:
  /* `head_to_world_rest` is the head's object-to-world matrix at the rest frame, when the
   * groom had `rest_positions_wo`. */
  FollowSolver(Span<int32_t> curve_offsets, Span<vec3> rest_positions_wo,
               const mat4 &head_to_world_rest);

  /* Places the groom for the head's current transform. */
  void step(const mat4 &head_to_world);
  /* Back to the rest shape. */
  void reset();

  Span<vec3> positions() const { return positions_wo_; }
  Span<vec3> rest_positions() const { return rest_positions_wo_; }
  Span<int32_t> curve_offsets() const { return curve_offsets_; }

 private:
  std::vector<int32_t> curve_offsets_;
  std::vector<vec3> rest_positions_wo_;
  glm::dmat4 world_to_head_rest_;
  std::vector<vec3> positions_wo_;
};

}  // namespace hairdyn
