#include "groom/metrics.hh"

#include <algorithm>
#include <cfloat>
#include <cmath>

#include "groom/groom.hh"

namespace hairdyn {

float max_relative_stretch(const Span<int32_t> curve_offsets, const Span<vec3> rest_positions,
                           const Span<vec3> positions)
{
  /* The extremes of (l / l_rest)², one division per segment and no square root in the loop
   * (it vectorises): |l / l_rest − 1| is largest at one of them. */
  float lowest = 1.0f, highest = 1.0f;
  bool broken = false;
  for (int64_t curve = 0; curve + 1 < curve_offsets.size(); curve++) {
    const IndexRange points = curve_points(curve_offsets, curve);
    for (int64_t i = points.start; i + 1 < points.one_after_last(); i++) {
      const vec3 rest = rest_positions[i + 1] - rest_positions[i];
      const vec3 now = positions[i + 1] - positions[i];
      const float ratio = glm::dot(now, now) / glm::dot(rest, rest);
      broken |= !(ratio <= FLT_MAX); /* NaN or infinite */
      lowest = std::min(lowest, ratio);
      highest = std::max(highest, ratio);
    }
  }
  if (broken) {
    return INFINITY; /* A NaN segment counts as broken, never as unstretched. */
  }
  return std::max(std::sqrt(highest) - 1.0f, 1.0f - std::sqrt(lowest));
}

void point_tangents(const Span<int32_t> curve_offsets, const Span<vec3> positions,
                    const MutableSpan<vec3> r_tangents)
{
  for (int64_t curve = 0; curve + 1 < curve_offsets.size(); curve++) {
    const IndexRange points = curve_points(curve_offsets, curve);
    const int64_t tip = points.one_after_last() - 1;
    for (int64_t i = points.start; i < tip; i++) {
      const vec3 forward = positions[i + 1] - positions[i];
      r_tangents[i] = forward / std::max(std::sqrt(glm::dot(forward, forward)), 1e-30f);
    }
    r_tangents[tip] = r_tangents[tip - 1]; /* a tip takes its segment's direction */
  }
}

int64_t count_nonfinite(const Span<vec3> positions)
{
  int64_t count = 0;
  for (const vec3 &p : positions) {
    count += is_finite(p) ? 0 : 1;
  }
  return count;
}

}  // namespace hairdyn
