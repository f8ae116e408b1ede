#include "groom/frames.hh"

#include <cmath>

#include "core/parallel.hh"
#include "groom/groom.hh"

namespace hairdyn {

mat3 root_frame_from_normal(const vec3 &normal)
{
  const vec3 n = glm::normalize(normal);
  const vec3 a = glm::abs(n);
  const vec3 axis = (a.x <= a.y && a.x <= a.z) ? vec3(1, 0, 0) :
                    (a.y <= a.z)               ? vec3(0, 1, 0) :
                                                 vec3(0, 0, 1);
  const vec3 tangent = glm::normalize(axis - glm::dot(axis, n) * n);
  return mat3(tangent, glm::cross(n, tangent), n);
}

mat3 parallel_transport(const mat3 &frame, const vec3 &direction)
{
  const vec3 z = frame[2];
  const float c = glm::dot(z, direction);
  vec3 x;
  if (c < -0.9999f) {
    x = frame[0]; /* Half a turn about x keeps x. */
  }
  else {
    /* Rodrigues' rotation taking z onto direction: R v = c v + a × v + a (a·v) / (1 + c),
     * with a = z × direction. */
    const vec3 a = glm::cross(z, direction);
    x = c * frame[0] + glm::cross(a, frame[0]) + a * (glm::dot(a, frame[0]) / (1.0f + c));
  }
  /* Re-orthonormalise so that rounding never accumulates along a strand. */
  x = glm::normalize(x - glm::dot(x, direction) * direction);
  return mat3(x, glm::cross(direction, x), direction);
}

void compute_root_frames(const Span<int32_t> curve_offsets, const Span<vec3> positions,
                         const Span<vec3> root_normals, const MutableSpan<mat3> r_root_frames)
{
  parallel_for(r_root_frames.size(), 1024, [&](const IndexRange range) {
    for (int64_t curve = range.start; curve < range.one_after_last(); curve++) {
      const IndexRange points = curve_points(curve_offsets, curve);
      const vec3 normal = root_normals.is_empty() ?
                              positions[points.start + 1] - positions[points.start] :
                              root_normals[curve];
      r_root_frames[curve] = root_frame_from_normal(normal);
    }
  });
}

}  // namespace hairdyn
