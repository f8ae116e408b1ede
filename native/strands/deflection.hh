#pragma once
/* The deflection D(θ, φ) = R_x(−φ) R_y(θ) that turns a segment out of its rest frame (see
 * strand_solver.hh): its columns are e_θ = ∂d/∂θ, e_φ = ∂d/∂φ / cos θ and
 * d = (sin θ, cos θ sin φ, cos θ cos φ). */
#include <cmath>

#include "core/math.hh"

namespace hairdyn {

/* chart · D without forming D: each column of D is a combination of chart's columns
 * (chart[0..2], r_frame[0..2]). For any scalar S and vector V with these operations: one
 * strand's (Deflection::rotate) or several strands' in lanes. */
template<class S, class V>
inline void rotate_chart(const S &sin_theta, const S &cos_theta, const S &sin_phi,
                         const S &cos_phi, const V *chart, V *r_frame)
{
  r_frame[0] = cos_theta * chart[0] - sin_theta * (sin_phi * chart[1] + cos_phi * chart[2]);
  r_frame[1] = cos_phi * chart[1] - sin_phi * chart[2];
  r_frame[2] = sin_theta * chart[0] + cos_theta * (sin_phi * chart[1] + cos_phi * chart[2]);
}

struct Deflection {
  float sin_theta, cos_theta, sin_phi, cos_phi;

  explicit Deflection(const glm::vec2 &angles)
  {
    sin_cos<float, int32_t>(angles.x, sin_theta, cos_theta);
    sin_cos<float, int32_t>(angles.y, sin_phi, cos_phi);
  }
  /* From sines and cosines computed before: (sin θ, cos θ, sin φ, cos φ). */
  explicit Deflection(const vec4 &trig)
      : sin_theta(trig.x), cos_theta(trig.y), sin_phi(trig.z), cos_phi(trig.w)
  {
  }
  vec4 trig() const { return vec4(sin_theta, cos_theta, sin_phi, cos_phi); }

  /* chart · D (rotate_chart). */
  mat3 rotate(const mat3 &chart) const
  {
    const vec3 columns[3] = {chart[0], chart[1], chart[2]};
    vec3 frame[3];
    rotate_chart(sin_theta, cos_theta, sin_phi, cos_phi, columns, frame);
    return mat3(frame[0], frame[1], frame[2]);
  }
};

/* `angle` plus the multiple of 2π that brings it nearest `near`. */
inline float unwrap_near(const float angle, const float near)
{
  constexpr float two_pi = 6.28318531f;
  return angle + two_pi * std::nearbyint((near - angle) * (1.0f / two_pi));
}

/* The deflection that points a segment along `direction` (any length but zero) in `chart`,
 * and its angles in r_angles, chosen continuous with the angles r_angles holds on entry.
 *
 * The sines and cosines are the direction's own components in the chart,
 * d = (sin θ, cos θ sin φ, cos θ cos φ), so no sine or cosine is evaluated; θ and φ take one
 * atan2_fast each. Every direction has two readings, (θ, φ) and (π − θ, φ + π), each up to
 * whole turns; the hinge's angles are not bounded (a limp hinge turns past the chart's pole),
 * so the reading nearest the current angles is kept. Another reading would turn the meaning
 * of the hinge's rates (θ̇ reverses on the other one) and its spring's angle (a whole turn of
 * k q) under the segment without moving it: energy from nowhere each time a pass moves it. */
inline Deflection chart_deflection(const mat3 &chart, const vec3 &direction, glm::vec2 &r_angles)
{
  const vec3 local = glm::transpose(chart) * direction;
  const float across = std::sqrt(local.y * local.y + local.z * local.z); /* |cos θ| · |d| */
  const float inv_length = 1.0f / std::sqrt(local.x * local.x + across * across);
  const glm::vec2 near = r_angles;
  const glm::vec2 principal(atan2_fast(local.x, across), atan2_fast(local.y, local.z));
  /* At the chart's pole φ is undefined: atan2 of the zeros chose it. */
  float sin_phi = 0.0f, cos_phi = 1.0f;
  if (!(across > 0.0f)) {
    sin_cos<float, int32_t>(principal.y, sin_phi, cos_phi);
  }
  const Deflection deflection =
      across > 0.0f ? Deflection(vec4(local.x * inv_length, across * inv_length,
                                      local.y / across, local.z / across)) :
                      Deflection(vec4(local.x * inv_length, 0.0f, sin_phi, cos_phi));
  const glm::vec2 first(unwrap_near(principal.x, near.x), unwrap_near(principal.y, near.y));
  const glm::vec2 second(unwrap_near(3.14159265f - principal.x, near.x),
                         unwrap_near(principal.y + 3.14159265f, near.y));
  const glm::vec2 a = first - near, b = second - near;
  if (glm::dot(b, b) < glm::dot(a, a)) {
    r_angles = second;
    return Deflection(vec4(deflection.sin_theta, -deflection.cos_theta, -deflection.sin_phi,
                           -deflection.cos_phi));
  }
  r_angles = first;
  return deflection;
}

}  // namespace hairdyn
