#include "lod/skinning_ward2003.hh"

#include <algorithm>
#include <cassert>

#include "groom/frames.hh"
#include "groom/groom.hh"

namespace hairdyn {

void current_skeleton_frames(const Span<vec3> skeleton_wo, const Span<mat3> rest_frames,
                             const mat3 &head_rotation, const MutableSpan<mat3> r_frames)
{
  skeleton_frames(skeleton_wo, head_rotation * rest_frames[0], r_frames);
}

void skin_strand(const LodHierarchy &hierarchy, const int64_t node, const int64_t strand,
                 const Span<vec3> skeleton_wo, const Span<mat3> frames,
                 const MutableSpan<vec3> r_positions_wo)
{
  const Span<vec3> rest_skeleton = hierarchy.rest_skeleton(node);
  const Span<mat3> rest_frames = hierarchy.rest_frames(node);
  const Span<vec3> rest = hierarchy.rest_positions();
  const Span<int32_t> segments = hierarchy.point_segments();
  const Span<float> weights = hierarchy.point_weights();
  const IndexRange points = curve_points(hierarchy.curve_offsets(), strand);
  for (int64_t i = points.start; i < points.one_after_last(); i++) {
    const int32_t a = segments[i];
    const float w = weights[i];
    /* The frame of the segment a → a + 1 (it ends at a + 1); the root in the root frame. */
    const int32_t f = i == points.start ? 0 : a + 1;
    const vec3 offset_rest = rest[i] - glm::mix(rest_skeleton[a], rest_skeleton[a + 1], w);
    const vec3 offset_local = glm::transpose(rest_frames[f]) * offset_rest;
    r_positions_wo[i - points.start] =
        glm::mix(skeleton_wo[a], skeleton_wo[a + 1], w) + frames[f] * offset_local;
  }
}

void keep_segment_lengths(const Span<float> rest_lengths, const MutableSpan<vec3> r_positions_wo)
{
  keep_segment_lengths(&rest_lengths, &r_positions_wo, 1);
}

void keep_segment_lengths(const Span<float> *rest_lengths, const MutableSpan<vec3> *r_positions_wo,
                          const int strands_num)
{
  assert(strands_num <= 4);
  int64_t points_num = 0;
  for (int s = 0; s < strands_num; s++) {
    points_num = std::max(points_num, r_positions_wo[s].size());
  }
  /* Each strand's chain of square roots and divisions is serial; the strands' chains are
   * interleaved point by point so that the processor overlaps them (the same operations per
   * strand as one at a time). */
  for (int64_t i = 1; i < points_num; i++) {
    for (int s = 0; s < strands_num; s++) {
      const MutableSpan<vec3> x = r_positions_wo[s];
      if (i >= x.size()) {
        continue;
      }
      const float rest_length = rest_lengths[s][i];
      const vec3 along = x[i] - x[i - 1];
      const float length = glm::length(along);
      if (length > 1e-6f * rest_length) { /* a point on its parent keeps its place */
        x[i] = x[i - 1] + (rest_length / length) * along;
      }
    }
  }
}

void place_child(const Span<vec3> parent_skeleton_wo, const Span<mat3> parent_frames,
                 const Span<vec3> offsets, const MutableSpan<vec3> r_child_wo)
{
  for (int64_t k = 0; k < offsets.size(); k++) {
    r_child_wo[k] = parent_skeleton_wo[k] + parent_frames[k] * offsets[k];
  }
}

void parent_from_child(const Span<vec3> child_wo, const Span<mat3> child_frames,
                       const Span<mat3> child_rest_frames, const Span<mat3> parent_rest_frames,
                       const Span<vec3> offsets, const MutableSpan<vec3> r_parent_wo)
{
  for (int64_t k = 0; k < offsets.size(); k++) {
    const mat3 turn = child_frames[k] * glm::transpose(child_rest_frames[k]);
    r_parent_wo[k] = child_wo[k] - turn * (parent_rest_frames[k] * offsets[k]);
  }
}

}  // namespace hairdyn
