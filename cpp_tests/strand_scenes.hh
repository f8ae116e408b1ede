#pragma once
/* Scenes shared by the strand tests: a wavy groom hanging from the top of a 0.1 m head, and a
 * head that sways about the vertical while it slides sideways. */
#include <cmath>
#include <vector>

#include "core/math.hh"

namespace hairdyn::strand_scenes {

struct Groom {
  std::vector<int32_t> offsets{ 0 };
  std::vector<vec3> positions;
};

/* `strands_num` wavy strands of `segments_num` segments of `segment_length` m, rooted on a
 * 3 cm circle on the top of a 0.1 m head. */
inline Groom wavy_groom(const int strands_num, const int segments_num, const float segment_length)
{
  Groom groom;
  for (int s = 0; s < strands_num; s++) {
    const float angle = 6.2831853f * float(s) / float(strands_num);
    const vec3 out(std::cos(angle), std::sin(angle), 0.0f);
    vec3 p = vec3(0.0f, 0.0f, 0.101f) + 0.03f * out;
    for (int i = 0; i <= segments_num; i++) {
      groom.positions.push_back(p);
      p += segment_length * glm::normalize(out + vec3(0.0f, 0.3f * std::sin(float(i)), -0.5f));
    }
    groom.offsets.push_back(int32_t(groom.positions.size()));
  }
  return groom;
}

/* The head at `frame` (24 fps): ±0.6 rad about the vertical at `yaw_rate` rad/s and ±5 cm
 * along x at `slide_rate` rad/s. */
inline mat4 swaying_head(const int frame, const float yaw_rate, const float slide_rate)
{
  const float t = float(frame) / 24.0f;
  return glm::rotate(
      glm::translate(mat4(1.0f), vec3(0.05f * std::sin(slide_rate * t), 0.0f, 0.0f)),
      0.6f * std::sin(yaw_rate * t), vec3(0.0f, 0.0f, 1.0f));
}

}  // namespace hairdyn::strand_scenes
