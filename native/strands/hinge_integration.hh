#pragma once
/* One time step of a hinge angle q (θ or φ) with angular velocity ω under
 *
 *   I q̈ + γ q̇ = M_ext − k q                  (Kurihara 1993, eq. 1 and 4; q measured from rest)
 *
 * External torques are always explicit; the integrator decides how the spring and the damping
 * are treated. Both return the new ω and advance q by h ω_new. */
#include "strands/strand_params.hh"

namespace hairdyn {

struct HingeCoefficients {
  float inertia;   /* kg·m², I */
  float stiffness; /* N·m/rad, k */
  float damping;   /* N·m·s/rad, γ */
};

/* Kurihara 1993, eq. 7: q^{n+1} − 2q^n + q^{n−1} + (γ h / I)(q^n − q^{n−1}) = h² M / I, written
 * with ω^{n+1/2} = (q^{n+1} − q^n) / h: ω += h (M − k q − γ ω) / I; q += h ω. Symplectic
 * Euler; stable while h √(k / I) < 2. */
inline void integrate_hinge_explicit(const HingeCoefficients &c, const float h,
                                     const float torque, float &q, float &omega)
{
  omega += h * (torque - c.stiffness * q - c.damping * omega) / c.inertia;
  q += h * omega;
}

/* Ward & Lin 2003, appendix A: backward Euler, the spring linearised at the new state,
 *   Δω = h (M − k q − k h ω) / (1 + h² k)          (for I = 1, γ = 0, M = 0: the paper's form)
 * extended to I and γ: I Δω = h (M − k (q + h (ω + Δω)) − γ (ω + Δω)), hence
 *   Δω = h (M − k q − (γ + h k) ω) / (I + h γ + h² k),   Δq = h (ω + Δω).
 * Unconditionally stable for the spring and damping. */
inline void integrate_hinge_implicit(const HingeCoefficients &c, const float h,
                                     const float torque, float &q, float &omega)
{
  omega += h * (torque - c.stiffness * q - (c.damping + h * c.stiffness) * omega) /
           (c.inertia + h * c.damping + h * h * c.stiffness);
  q += h * omega;
}

inline void integrate_hinge(const Integrator integrator, const HingeCoefficients &c,
                            const float h, const float torque, float &q, float &omega)
{
  if (integrator == Integrator::Explicit) {
    integrate_hinge_explicit(c, h, torque, q, omega);
  }
  else {
    integrate_hinge_implicit(c, h, torque, q, omega);
  }
}

}  // namespace hairdyn
