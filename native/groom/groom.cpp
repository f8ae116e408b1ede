#include "groom/groom.hh"

#include <sstream>

namespace hairdyn {

std::string find_groom_error(const Span<int32_t> curve_offsets, const Span<vec3> positions)
{
  std::ostringstream msg;
  if (curve_offsets.size() < 2) {
    return "the hair has no strands";
  }
  if (curve_offsets[0] != 0) {
    msg << "curve offsets must start at 0, not " << curve_offsets[0];
    return msg.str();
  }
  if (curve_offsets.last() != positions.size()) {
    msg << "curve offsets end at " << curve_offsets.last() << " but there are "
        << positions.size() << " points";
    return msg.str();
  }
  for (int64_t curve = 0; curve + 1 < curve_offsets.size(); curve++) {
    const int64_t points_num = curve_offsets[curve + 1] - curve_offsets[curve];
    if (points_num < 0) {
      msg << "curve offsets decrease at strand " << curve;
      return msg.str();
    }
    if (points_num < 2) {
      msg << "strand " << curve << " has " << points_num
          << " point(s); every strand needs at least 2";
      return msg.str();
    }
  }
  for (int64_t i = 0; i < positions.size(); i++) {
    if (!is_finite(positions[i])) {
      msg << "point " << i << " has a position that is not a finite number (NaN or infinity)";
      return msg.str();
    }
  }
  for (int64_t curve = 0; curve + 1 < curve_offsets.size(); curve++) {
    const IndexRange points = curve_points(curve_offsets, curve);
    for (int64_t i = points.start; i + 1 < points.one_after_last(); i++) {
      if (glm::length(positions[i + 1] - positions[i]) < min_segment_length) {
        msg << "strand " << curve << " has a zero-length segment at point " << i - points.start;
        return msg.str();
      }
    }
  }
  return {};
}

}  // namespace hairdyn
