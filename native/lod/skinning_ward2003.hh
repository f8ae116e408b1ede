#pragma once
/* How skeletons carry what hangs off them (Ward & Lin 2003, §4.2: "the individual hair strands
 * ... follow the dynamics of the skeleton"; §6.2: children positioned by their stored offsets;
 * §6.3: children averaged back into the parent).
 *
 * A skeleton's current frames are transported without twist from its root frame, which the
 * head carries rigidly. Anything stored as an offset in a skeleton's rest frames (a strand
 * point, a child skeleton) is placed by the same offset in the current frames. */
#include "core/math.hh"
#include "core/span.hh"
#include "lod/hierarchy_ward2003.hh"

namespace hairdyn {

/* r_frames: the current frames of a skeleton whose rest frames are `rest_frames` (see
 * LodHierarchy::rest_frames), its root frame turned by `head_rotation` (the head's rotation
 * since rest). */
void current_skeleton_frames(Span<vec3> skeleton_wo, Span<mat3> rest_frames,
                             const mat3 &head_rotation, MutableSpan<mat3> r_frames);

/* The points of strand `strand` placed on a node's current skeleton and frames: each point
 * keeps its rest offset from the skeleton, in the frame of the skeleton segment it lies on
 * (the root point in the root frame). At rest this gives the rest strand. r_positions_wo
 * holds the strand's points only. */
void skin_strand(const LodHierarchy &hierarchy, int64_t node, int64_t strand,
                 Span<vec3> skeleton_wo, Span<mat3> frames, MutableSpan<vec3> r_positions_wo);
/* The offsets skin_strand places strand `strand`'s points by on node `node` (each in its
 * skeleton frame), to place it again and again without computing them (the same result). */
void strand_offsets(const LodHierarchy &hierarchy, int64_t node, int64_t strand,
                    MutableSpan<vec3> r_offsets);
/* skin_strand by the strand's strand_offsets on the node they were computed for. */
void skin_strand(const LodHierarchy &hierarchy, int64_t strand, Span<vec3> offsets,
                 Span<vec3> skeleton_wo, Span<mat3> frames, MutableSpan<vec3> r_positions_wo);

/* Follow the leader (Müller, Kim & Chentanez 2012, "Fast simulation of inextensible hair and
 * fur", §4, without the velocity correction, since a placed strand has no state of its own),
 * one point: `r_point` moved along the line from `previous` to `rest_length` from it (a point
 * on `previous` keeps its place). Applied root to tip, it gives each segment of a placed
 * strand its rest length, keeping its direction: a strand placed by rigid offsets from a
 * skeleton (skin_strand) stretches on the outside of a bend of the skeleton and shrinks on
 * the inside, by the offset times the turn between two segments' frames; on wide strips that
 * is several times a segment. */
inline void follow(const vec3 &previous, const float rest_length, vec3 &r_point)
{
  const vec3 along = r_point - previous;
  const float length = glm::length(along);
  if (length > 1e-6f * rest_length) {
    r_point = previous + (rest_length / length) * along;
  }
}

/* §6.2: a child's control points on its parent's current skeleton and frames, by the child's
 * stored offsets. */
void place_child(Span<vec3> parent_skeleton_wo, Span<mat3> parent_frames, Span<vec3> offsets,
                 MutableSpan<vec3> r_child_wo);

/* §6.3: where a child puts its parent's control points, r_parent = child − its offset, the
 * offset turned by the child's own frames since rest (the parent's current frames are what
 * is being sought). */
void parent_from_child(Span<vec3> child_wo, Span<mat3> child_frames, Span<mat3> child_rest_frames,
                       Span<mat3> parent_rest_frames, Span<vec3> offsets,
                       MutableSpan<vec3> r_parent_wo);

}  // namespace hairdyn
