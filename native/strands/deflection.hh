#pragma once
/* The deflection D(θ, φ) = R_x(−φ) R_y(θ) that turns a segment out of its rest frame (see
 * strand_solver.hh): its columns are e_θ = ∂d/∂θ, e_φ = ∂d/∂φ / cos θ and
 * d = (sin θ, cos θ sin φ, cos θ cos φ). */
#include <cmath>
#include <cstdint>
#include <type_traits>

#include "core/math.hh"

namespace hairdyn {

/* sin x and cos x in single precision, for the hinges' angles: x less the nearest multiple k
 * of π/2 (Cody and Waite's reduction, π/2 in three parts: exact for |x| up to 5·10⁴ rad), then
 * the minimax polynomials of Cephes's sinf and cosf on [−π/4, π/4] (S. L. Moshier, Cephes Math
 * Library), the quadrant k mod 4 choosing and signing them: sin 0 = 0 and cos 0 = 1 exactly.
 * Written once for a float (I = int32_t) and for GCC vectors of floats (I the vector of
 * int32_t with as many lanes), every operation elementwise and none fused: a segment's sines
 * and cosines have the same bits in a vector of segments as alone (test
 * StrandsDeflection.SinCosIsAccurateAndTheSameInLanes). */
template<class F, class I> inline void sin_cos(const F &x, F &r_sin, F &r_cos)
{
  /* x · 2/π rounded to the nearest integer (ties to even) by adding and taking away 1.5 · 2²³. */
  const F k = (x * 0.636619772f + 12582912.0f) - 12582912.0f;
  const F r = ((x - k * 1.5703125f) - k * 4.837512969970703125e-4f) -
              k * 7.54978995489188216e-8f;
  const F z = r * r;
  const F s = ((-1.9515295891e-4f * z + 8.3321608736e-3f) * z - 1.6666654611e-1f) * z * r + r;
  const F c = ((2.443315711809948e-5f * z - 1.388731625493765e-3f) * z +
               4.166664568298827e-2f) *
                  z * z -
              0.5f * z + 1.0f;
  I q;
  if constexpr (std::is_same_v<F, float>) {
    q = I(k);
  }
  else {
    q = __builtin_convertvector(k, I);
  }
  /* sin x: s, c, −s, −c and cos x: c, −s, −c, s in quadrants 0 to 3. */
  const auto swap = (q & 1) != 0;
  const F sin_x = swap ? c : s, cos_x = swap ? s : c;
  r_sin = (q & 2) != 0 ? -sin_x : sin_x;
  r_cos = ((q + 1) & 2) != 0 ? -cos_x : cos_x;
}

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

/* `direction` turned about from × to by the part beyond `kept` radians of the turn that takes
 * the unit vector `from` to the unit vector `to`; unchanged when that turn is within `kept`. */
inline vec3 turn_beyond(const vec3 &direction, const vec3 &from, const vec3 &to, const float kept)
{
  const vec3 axis = glm::cross(from, to);
  const float sin_turn = glm::length(axis);
  const float beyond = std::atan2(sin_turn, glm::dot(from, to)) - kept;
  if (!(beyond > 0.0f && sin_turn > 0.0f)) {
    return direction;
  }
  return rotate_about_axis(direction, axis / sin_turn, beyond);
}

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
