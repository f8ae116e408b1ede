#pragma once
/* The deflection D(θ, φ) = R_x(−φ) R_y(θ) that turns a segment out of its rest frame (see
 * strand_solver.hh): its columns are e_θ = ∂d/∂θ, e_φ = ∂d/∂φ / cos θ and
 * d = (sin θ, cos θ sin φ, cos θ cos φ). */
#include <cmath>

#include "core/math.hh"

namespace hairdyn {

struct Deflection {
  float sin_theta, cos_theta, sin_phi, cos_phi;

  explicit Deflection(const glm::vec2 &angles)
      : sin_theta(std::sin(angles.x)),
        cos_theta(std::cos(angles.x)),
        sin_phi(std::sin(angles.y)),
        cos_phi(std::cos(angles.y))
  {
  }
  /* From sines and cosines computed before: (sin θ, cos θ, sin φ, cos φ). */
  explicit Deflection(const vec4 &trig)
      : sin_theta(trig.x), cos_theta(trig.y), sin_phi(trig.z), cos_phi(trig.w)
  {
  }
  vec4 trig() const { return vec4(sin_theta, cos_theta, sin_phi, cos_phi); }

  /* chart · D without forming D: each column of D is a combination of chart's columns. */
  mat3 rotate(const mat3 &chart) const
  {
    const vec3 e_theta = cos_theta * chart[0] -
                         sin_theta * (sin_phi * chart[1] + cos_phi * chart[2]);
    const vec3 e_phi = cos_phi * chart[1] - sin_phi * chart[2];
    const vec3 d = sin_theta * chart[0] + cos_theta * (sin_phi * chart[1] + cos_phi * chart[2]);
    return mat3(e_theta, e_phi, d);
  }
};

/* The angles (θ, φ) that point a segment along the unit `direction` in `chart`. */
inline glm::vec2 chart_angles(const mat3 &chart, const vec3 &direction)
{
  const vec3 local = glm::transpose(chart) * direction;
  return glm::vec2(std::asin(glm::clamp(local.x, -1.0f, 1.0f)), std::atan2(local.y, local.z));
}

/* The deflection that points a segment along `direction` (any length but zero) in `chart`,
 * and its angles in r_angles. The sines and cosines are the direction's own components in
 * the chart, d = (sin θ, cos θ sin φ, cos θ cos φ), so no sine or cosine is evaluated; θ and
 * φ take one atan2_fast each (θ ∈ [−π/2, π/2], as asin gives it). */
inline Deflection chart_deflection(const mat3 &chart, const vec3 &direction, glm::vec2 &r_angles)
{
  const vec3 local = glm::transpose(chart) * direction;
  const float across = std::sqrt(local.y * local.y + local.z * local.z); /* |cos θ| · |d| */
  const float inv_length = 1.0f / std::sqrt(local.x * local.x + across * across);
  r_angles = glm::vec2(atan2_fast(local.x, across), atan2_fast(local.y, local.z));
  if (!(across > 0.0f)) {
    /* At the chart's pole φ is undefined: atan2 of the zeros chose it. */
    return Deflection(vec4(local.x * inv_length, 0.0f, std::sin(r_angles.y),
                           std::cos(r_angles.y)));
  }
  const float inv_across = 1.0f / across;
  return Deflection(vec4(local.x * inv_length, across * inv_length, local.y * inv_across,
                         local.z * inv_across));
}

}  // namespace hairdyn
