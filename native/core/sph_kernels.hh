#pragma once
/* Smoothing kernels for smoothed particle hydrodynamics (Monaghan 1992), as Bando 2003 uses
 * them for hair density, hair-hair interactions and wind. Stateless, header-only. */
#include <cmath>

#include "core/math.hh"

namespace hairdyn {

constexpr float pi_f = 3.14159265358979323846f;

/* The cubic spline kernel, Bando 2003, eq. 2: support radius 2h, integrates to 1 over space.
 *   W(r, h) = 1 / (4 π h³) · { 4 − 6 q² + 3 q³   0 ≤ q ≤ 1
 *                             { (2 − q)³          1 ≤ q ≤ 2      with q = r / h
 *                             { 0                 2 ≤ q                              */
inline float sph_kernel(const float r, const float h)
{
  const float q = r / h;
  const float norm = 1.0f / (4.0f * pi_f * h * h * h);
  if (q < 1.0f) {
    return norm * (4.0f - 6.0f * q * q + 3.0f * q * q * q);
  }
  if (q < 2.0f) {
    const float a = 2.0f - q;
    return norm * a * a * a;
  }
  return 0.0f;
}

/* dW/dr of eq. 2 (≤ 0 everywhere). */
inline float sph_kernel_derivative(const float r, const float h)
{
  const float q = r / h;
  const float norm = 1.0f / (4.0f * pi_f * h * h * h * h);
  if (q < 1.0f) {
    return norm * (-12.0f * q + 9.0f * q * q);
  }
  if (q < 2.0f) {
    const float a = 2.0f - q;
    return norm * (-3.0f * a * a);
  }
  return 0.0f;
}

/* d²W/dr² of eq. 2: negative near the centre (q < 2/3), positive in the tail. */
inline float sph_kernel_second_derivative(const float r, const float h)
{
  const float q = r / h;
  const float norm = 1.0f / (4.0f * pi_f * h * h * h * h * h);
  if (q < 1.0f) {
    return norm * (-12.0f + 18.0f * q);
  }
  if (q < 2.0f) {
    return norm * 6.0f * (2.0f - q);
  }
  return 0.0f;
}

/* ∂/∂x_i W(‖x_j − x_i‖, h) for x_ij = x_j − x_i (the gradient used in eq. 16). */
inline vec3 sph_kernel_gradient_i(const vec3 &x_ij, const float h)
{
  const float r = glm::length(x_ij);
  if (r <= 0.0f) {
    return vec3(0.0f);
  }
  return x_ij * (-sph_kernel_derivative(r, h) / r);
}

}  // namespace hairdyn
