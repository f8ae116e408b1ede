#include "groom/metrics.hh"

#include <algorithm>
#include <cmath>

#include "groom/groom.hh"

namespace hairdyn {

float max_relative_stretch(const Span<int32_t> curve_offsets, const Span<vec3> rest_positions,
                           const Span<vec3> positions)
{
  float stretch_max = 0.0f;
  for (int64_t curve = 0; curve + 1 < curve_offsets.size(); curve++) {
    const IndexRange points = curve_points(curve_offsets, curve);
    for (int64_t i = points.start; i + 1 < points.one_after_last(); i++) {
      const float rest = glm::length(rest_positions[i + 1] - rest_positions[i]);
      const float now = glm::length(positions[i + 1] - positions[i]);
      const float stretch = std::abs(now / rest - 1.0f);
      if (std::isnan(stretch)) {
        return INFINITY; /* A NaN segment counts as broken, never as unstretched. */
      }
      stretch_max = std::max(stretch_max, stretch);
    }
  }
  return stretch_max;
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
