#pragma once
/* GLM types used across the core. Points are packed 12-byte vec3 so that an (N, 3) float32
 * numpy array or Blender's position attribute is a vec3 array without conversion. */
#include <algorithm>
#include <cmath>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

namespace hairdyn {

using glm::ivec3;
using glm::mat3;
using glm::mat4;
using glm::vec3;
using glm::vec4;

static_assert(sizeof(vec3) == 12, "vec3 must be packed: it maps onto (N, 3) float32 arrays");
static_assert(sizeof(mat4) == 64, "mat4 must be 16 packed floats");

/* Affine transform of a point (w = 1). */
inline vec3 transform_point(const mat4 &m, const vec3 &p)
{
  return vec3(m * vec4(p, 1.0f));
}

/* atan2(y, x) in float without a library call, within 3e-7 rad of the exact angle (tested; a
 * float ulp at π is 2.4e-7): the octant reduction to [0, 1], then atan(a) = π/4 +
 * atan((a − 1)/(a + 1)) above tan(π/8), and the degree-9 odd polynomial of Cephes' atanf on
 * |t| ≤ tan(π/8) (Moshier 1989, "Methods and Programs for Mathematical Functions", atanf.c).
 * Signs and zeros as std::atan2 gives them; NaN in, NaN out. Branch-free, so the compiler keeps
 * it in registers in a strand's loop. */
inline float atan2_fast(const float y, const float x)
{
  const float ax = std::fabs(x), ay = std::fabs(y);
  const float hi = std::max(ax, ay), lo = std::min(ax, ay);
  const bool upper = lo > 0.41421356f * hi; /* a = lo / hi > tan(π/8) */
  const float t = hi > 0.0f ? (upper ? (lo - hi) / (lo + hi) : lo / hi) : 0.0f;
  const float z = t * t;
  float r = (((8.05374449538e-2f * z - 1.38776856032e-1f) * z + 1.99777106478e-1f) * z -
             3.33329491539e-1f) *
                z * t +
            t;
  r += upper ? 0.78539816f : 0.0f;
  r = ay > ax ? 1.57079633f - r : r;
  r = std::signbit(x) ? 3.14159265f - r : r;
  r = std::isnan(x) || std::isnan(y) ? x + y : r;
  return std::copysign(r, y);
}

/* v turned by `angle` (rad, right hand) about the unit vector `axis` (Rodrigues' formula). */
inline vec3 rotate_about_axis(const vec3 &v, const vec3 &axis, const float angle)
{
  const float c = std::cos(angle), s = std::sin(angle);
  return c * v + s * glm::cross(axis, v) + (1.0f - c) * glm::dot(axis, v) * axis;
}

inline bool is_finite(const vec3 &v)
{
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

}  // namespace hairdyn
