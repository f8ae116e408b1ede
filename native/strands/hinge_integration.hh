#pragma once
/* One time step of a hinge angle q (θ or φ, measured from rest) with angular velocity ω under
 *
 *   I q̈ + γ q̇ = M − k q                  (Kurihara 1993, eq. 1 and 4)
 *
 * Both integrators take the form
 *
 *   ω ← ω + h g (M − k q − c ω),   q ← q + h ω
 *
 * with the external torque M always explicit:
 *
 * Explicit, Kurihara 1993, eq. 7: q^{n+1} − 2q^n + q^{n−1} + (γ h / I)(q^n − q^{n−1}) = h² M / I.
 *   With ω^{n+1/2} = (q^{n+1} − q^n) / h this is g = 1 / I, c = γ (symplectic Euler; stable
 *   while h √(k / I) < 2).
 *
 * Implicit, Ward & Lin 2003, appendix A: backward Euler with the spring linearised at the new
 *   state, Δω = (−h k (q − q₀) − h² k ω₀) / (1 + h² k) for I = 1, γ = 0, M = 0. With I and γ:
 *   I Δω = h (M − k (q + h (ω + Δω)) − γ (ω + Δω)), so
 *   Δω = h (M − k q − (γ + h k) ω) / (I + h γ + h² k): g = 1 / (I + h γ + h² k), c = γ + h k.
 *   Unconditionally stable for the spring and the damping.
 *
 * T is float, or vec2 for a (θ, φ) pair with their own stiffnesses. */
#include "strands/strand_params.hh"

namespace hairdyn {

template<typename T> struct HingeStep {
  T gain;    /* g */
  T damping; /* c */
};

template<typename T>
HingeStep<T> hinge_step(const Integrator integrator, const float inertia, const T stiffness,
                        const float damping, const float h)
{
  if (integrator == Integrator::Explicit) {
    return {T(1.0f / inertia), T(damping)};
  }
  return {1.0f / (inertia + h * damping + h * h * stiffness), damping + h * stiffness};
}

template<typename T>
void advance_hinge(const HingeStep<T> &step, const float h, const T stiffness, const T torque,
                   T &q, T &omega)
{
  omega += h * step.gain * (torque - stiffness * q - step.damping * omega);
  q += h * omega;
}

}  // namespace hairdyn
