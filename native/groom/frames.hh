#pragma once
/* Orthonormal frames along strands. A frame is a mat3 whose columns are (tangent, bitangent,
 * normal) = (x, y, z); a segment's frame has z along the segment. */
#include "core/math.hh"
#include "core/span.hh"

namespace hairdyn {

/* The root's coordinate system (Kurihara 1993, §2, Figure 2): z = the unit `normal`, x = a
 * tangent chosen deterministically (the world axis least aligned with the normal, made
 * perpendicular to it), y = z × x. */
mat3 root_frame_from_normal(const vec3 &normal);

/* `frame` turned by the smallest rotation that takes its z axis onto the unit `direction`
 * (rotation-minimising transport, no twist). A reversal turns it half a turn about x. */
mat3 parallel_transport(const mat3 &frame, const vec3 &direction);

/* One root frame per strand. `root_normals` has one unit normal per strand, or is empty: then
 * each strand's first segment direction is its normal. */
void compute_root_frames(Span<int32_t> curve_offsets, Span<vec3> positions,
                         Span<vec3> root_normals, MutableSpan<mat3> r_root_frames);

}  // namespace hairdyn
