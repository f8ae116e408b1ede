#include "groom/groom.hh"

#include <algorithm>
#include <limits>
#include <sstream>

namespace hairdyn {

float min_segment_length(const Span<vec3> positions)
{
  vec3 low(std::numeric_limits<float>::max()), high(-std::numeric_limits<float>::max());
  for (const vec3 &p : positions) {
    if (is_finite(p)) {
      low = glm::min(low, p);
      high = glm::max(high, p);
    }
  }
  const glm::dvec3 extent = glm::dvec3(high) - glm::dvec3(low);
  const double diagonal = glm::all(glm::greaterThanEqual(extent, glm::dvec3(0.0))) ?
                              glm::length(extent) :
                              0.0;
  return std::max(float(double(min_segment_length_relative) * diagonal),
                  std::numeric_limits<float>::min());
}

/* Index within the strand of the first segment shorter than min_length, or -1. */
static int64_t first_short_segment(const Span<int32_t> curve_offsets, const Span<vec3> positions,
                                   const int64_t curve, const float min_length)
{
  const IndexRange points = curve_points(curve_offsets, curve);
  for (int64_t i = points.start; i + 1 < points.one_after_last(); i++) {
    if (!(glm::length(positions[i + 1] - positions[i]) >= min_length)) {
      return i - points.start;
    }
  }
  return -1;
}

std::string find_strands_error(const Span<int32_t> curve_offsets, const int64_t points_num)
{
  if (curve_offsets.size() < 2) {
    return "the hair has no strands";
  }
  std::ostringstream msg;
  if (curve_offsets[0] != 0) {
    msg << "curve offsets must start at 0, not " << curve_offsets[0];
    return msg.str();
  }
  if (curve_offsets.last() != points_num) {
    msg << "curve offsets end at " << curve_offsets.last() << " but there are " << points_num
        << " points";
    return msg.str();
  }
  for (int64_t curve = 0; curve + 1 < curve_offsets.size(); curve++) {
    const int64_t strand_points_num = curve_offsets[curve + 1] - curve_offsets[curve];
    if (strand_points_num < 0) {
      msg << "curve offsets decrease at strand " << curve;
      return msg.str();
    }
    if (strand_points_num < 2) {
      msg << "strand " << curve << " has " << strand_points_num
          << " point(s); every strand needs at least 2";
      return msg.str();
    }
  }
  return {};
}

std::string find_groom_error(const Span<int32_t> curve_offsets, const Span<vec3> positions,
                             const bool check_segments)
{
  const std::string strands_error = find_strands_error(curve_offsets, positions.size());
  if (!strands_error.empty()) {
    return strands_error;
  }
  std::ostringstream msg;
  for (int64_t i = 0; i < positions.size(); i++) {
    if (!is_finite(positions[i])) {
      msg << "point " << i << " has a position that is not a finite number (NaN or infinity)";
      return msg.str();
    }
  }
  if (!check_segments) {
    return {};
  }
  const float min_length = min_segment_length(positions);
  for (int64_t curve = 0; curve + 1 < curve_offsets.size(); curve++) {
    const int64_t segment = first_short_segment(curve_offsets, positions, curve, min_length);
    if (segment >= 0) {
      msg << "strand " << curve << " has a zero-length segment at point " << segment
          << " (shorter than " << min_length << ", a millionth of the groom's size)";
      return msg.str();
    }
  }
  return {};
}

int64_t find_degenerate_curves(const Span<int32_t> curve_offsets, const Span<vec3> positions,
                               const MutableSpan<uint8_t> r_degenerate)
{
  const float min_length = min_segment_length(positions);
  int64_t count = 0;
  for (int64_t curve = 0; curve + 1 < curve_offsets.size(); curve++) {
    const bool degenerate = first_short_segment(curve_offsets, positions, curve, min_length) >= 0;
    r_degenerate[curve] = degenerate ? 1 : 0;
    count += degenerate ? 1 : 0;
  }
  return count;
}

}  // namespace hairdyn
