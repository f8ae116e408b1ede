#pragma once
/* Quality figures every solver reports through the headless entry point. */
#include "core/math.hh"
#include "core/span.hh"

namespace hairdyn {

/* Largest |l / l_rest - 1| over all segments: 0 means no strand stretched or shrank. */
float max_relative_stretch(Span<int32_t> curve_offsets, Span<vec3> rest_positions,
                           Span<vec3> positions);

/* The unit direction of each point along its strand: the segment it starts (a zero vector
 * for a zero-length one), the last segment's at a tip. Every strand has 2 points or more. */
void point_tangents(Span<int32_t> curve_offsets, Span<vec3> positions,
                    MutableSpan<vec3> r_tangents);

/* Number of points with a NaN or infinite coordinate. */
int64_t count_nonfinite(Span<vec3> positions);

/* The points' axis-aligned bounding box, corner by corner (+inf and -inf for no points); NaN
 * coordinates are ignored. */
void point_bounds(Span<vec3> positions, vec3 &r_low, vec3 &r_high);

/* What a frame's strand positions give the reports and the outputs, in one pass over them on
 * the thread pool (issue 18: one native pass per frame instead of one per figure). */
struct StrandFrame {
  int64_t nonfinite = 0; /* count_nonfinite(positions) */
  float stretch = 0.0f;  /* max_relative_stretch(curve_offsets, rest_positions, positions) */
};

/* The figures above, and per point r_tangents (point_tangents), r_velocities
 * (positions − r_previous) / dt, then r_previous = positions: the next frame's previous. The
 * same values on any thread count. */
StrandFrame strand_frame(Span<int32_t> curve_offsets, Span<vec3> rest_positions,
                         Span<vec3> positions, float dt, MutableSpan<vec3> r_previous,
                         MutableSpan<vec3> r_velocities, MutableSpan<vec3> r_tangents);

}  // namespace hairdyn
