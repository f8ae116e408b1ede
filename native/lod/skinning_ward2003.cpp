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

namespace {

/* Strand point i's skeleton segment a (between control points a and a + 1, at weight w) and
 * the frame f it is offset in: the segment's (it ends at a + 1), the root in the root frame. */
struct PointOnSkeleton {
  int32_t a, f;
  float w;
};
PointOnSkeleton point_on_skeleton(const LodHierarchy &hierarchy, const int64_t first,
                                  const int64_t i)
{
  const int32_t a = hierarchy.point_segments()[i];
  return {a, i == first ? 0 : a + 1, hierarchy.point_weights()[i]};
}

/* Point i's rest offset from the node's skeleton, in the skeleton's rest frame f. */
vec3 rest_offset(const LodHierarchy &hierarchy, const int64_t node, const int64_t i,
                 const PointOnSkeleton &p)
{
  const Span<vec3> rest_skeleton = hierarchy.rest_skeleton(node);
  const vec3 offset_rest = hierarchy.rest_positions()[i] -
                           glm::mix(rest_skeleton[p.a], rest_skeleton[p.a + 1], p.w);
  return glm::transpose(hierarchy.rest_frames(node)[p.f]) * offset_rest;
}

/* Strand `strand`'s points on the skeleton and frames, each by offset_of(i, p), its offset in
 * frame p.f. */
template<typename OffsetOf>
void place_points(const LodHierarchy &hierarchy, const int64_t strand, const Span<vec3> skeleton_wo,
                  const Span<mat3> frames, const MutableSpan<vec3> r_positions_wo,
                  const OffsetOf &offset_of)
{
  const IndexRange points = curve_points(hierarchy.curve_offsets(), strand);
  for (int64_t i = points.start; i < points.one_after_last(); i++) {
    const PointOnSkeleton p = point_on_skeleton(hierarchy, points.start, i);
    r_positions_wo[i - points.start] = glm::mix(skeleton_wo[p.a], skeleton_wo[p.a + 1], p.w) +
                                       frames[p.f] * offset_of(i, p);
  }
}

}  // namespace

void skin_strand(const LodHierarchy &hierarchy, const int64_t node, const int64_t strand,
                 const Span<vec3> skeleton_wo, const Span<mat3> frames,
                 const MutableSpan<vec3> r_positions_wo)
{
  place_points(hierarchy, strand, skeleton_wo, frames, r_positions_wo,
               [&](const int64_t i, const PointOnSkeleton &p) {
                 return rest_offset(hierarchy, node, i, p);
               });
}

void strand_offsets(const LodHierarchy &hierarchy, const int64_t node, const int64_t strand,
                    const MutableSpan<vec3> r_offsets)
{
  const IndexRange points = curve_points(hierarchy.curve_offsets(), strand);
  for (int64_t i = points.start; i < points.one_after_last(); i++) {
    r_offsets[i - points.start] =
        rest_offset(hierarchy, node, i, point_on_skeleton(hierarchy, points.start, i));
  }
}

void skin_strand(const LodHierarchy &hierarchy, const int64_t strand, const Span<vec3> offsets,
                 const Span<vec3> skeleton_wo, const Span<mat3> frames,
                 const MutableSpan<vec3> r_positions_wo)
{
  const int64_t first = curve_points(hierarchy.curve_offsets(), strand).start;
  place_points(hierarchy, strand, skeleton_wo, frames, r_positions_wo,
               [&](const int64_t i, const PointOnSkeleton & /*p*/) { return offsets[i - first]; });
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
