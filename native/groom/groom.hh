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

/* Shortest segment a groom may have (scene units); shorter ones have no direction. */
constexpr float min_segment_length = 1e-6f;

/* Returns an empty string when the groom is valid, otherwise one sentence that says what is
 * wrong and where: offsets start at 0, never decrease, end at the point count; every strand
 * has at least two points; every position is finite; no segment is shorter than
 * `min_segment_length`. */
std::string find_groom_error(Span<int32_t> curve_offsets, Span<vec3> positions);

}  // namespace hairdyn
