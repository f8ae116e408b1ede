#pragma once
/* A groom as Blender stores curves: `curve_offsets[C + 1]` into one `positions[N]` array.
 * Curve i owns the points [curve_offsets[i], curve_offsets[i + 1]). */
#include <string>

#include "core/math.hh"
#include "core/span.hh"

namespace hairdyn {

inline IndexRange curve_points(Span<int32_t> curve_offsets, int64_t curve)
{
  return IndexRange{curve_offsets[curve], curve_offsets[curve + 1] - curve_offsets[curve]};
}

/* Shortest segment a groom may have, relative to the groom's size: a segment shorter than a
 * millionth of the groom's bounding-box diagonal has a direction lost in single-precision
 * round-off (its end points differ by a few ulps of the coordinates). Relative, so that a
 * groom is accepted or refused alike in metres, centimetres or a file's own units. */
constexpr float min_segment_length_relative = 1e-6f;

/* min_segment_length_relative × the bounding-box diagonal of the finite positions (and at
 * least the smallest normal float, so that a groom of coincident points is refused). */
float min_segment_length(Span<vec3> positions);

/* Returns an empty string when the offsets split `points_num` points into strands:
 * they start at 0, never decrease, end at points_num, and give every strand at least two
 * points; otherwise one sentence that says what is wrong and where. */
std::string find_strands_error(Span<int32_t> curve_offsets, int64_t points_num);

/* Returns an empty string when the groom is valid, otherwise one sentence that says what is
 * wrong and where: offsets start at 0, never decrease, end at the point count; every strand
 * has at least two points; every position is finite; no segment is shorter than
 * min_segment_length(positions) (unless check_segments is false). */
std::string find_groom_error(Span<int32_t> curve_offsets, Span<vec3> positions,
                             bool check_segments = true);

/* r_degenerate[c] = 1 for each strand c with a segment shorter than
 * min_segment_length(positions) (the strands a reader drops, with a warning, rather than
 * refusing the groom); returns their number. The offsets must be valid (find_groom_error's
 * first checks). */
int64_t find_degenerate_curves(Span<int32_t> curve_offsets, Span<vec3> positions,
                               MutableSpan<uint8_t> r_degenerate);

}  // namespace hairdyn
