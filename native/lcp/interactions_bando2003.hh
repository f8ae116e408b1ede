#pragma once
/* Hair-hair interactions of Bando 2003, §3.4, between current neighbours within 2h₂: SPH
 * density (eq. 1), attraction/repulsion (eq. 16), inelastic collision (eq. 17) and friction
 * (eq. 18). Stateless kernels over spans and a neighbour list (core/spatial_grid.hh). */
#include "core/math.hh"
#include "core/span.hh"
#include "core/spatial_grid.hh"

namespace hairdyn {

/* Bando 2003, eq. 1: ρ_i = Σ_j m_j W(‖x_j − x_i‖, h), the particle itself included. */
void compute_density(Span<vec3> positions, Span<float> masses, const NeighborList &neighbors,
                     float h, MutableSpan<float> r_density);

struct HairInteractionSettings {
  float h2;
  bool attraction_repulsion;
  float pressure_stiffness; /* k_a */
  float rest_density;       /* ρ₀ */
  bool collision;
  float collision_damping; /* d_c, per unit SPH volume (1/s) */
  bool friction;
  float friction_damping; /* d_f, per unit SPH volume (1/s) */
};

/* Eq. 16 forces go to r_forces (explicit); eq. 17-18 forces, linear in the relative velocity,
 * go to r_damped_forces with their diagonal coefficients in r_damping. */
void accumulate_hair_interactions(Span<vec3> positions, Span<vec3> velocities,
                                  Span<vec3> directions, Span<float> masses, Span<float> density,
                                  const NeighborList &neighbors,
                                  const HairInteractionSettings &settings,
                                  MutableSpan<vec3> r_forces, MutableSpan<vec3> r_damped_forces,
                                  MutableSpan<float> r_damping);

/* Eq. 16 as a stiffness, for the implicit step of lcp/implicit_springs.hh. With
 * P = k_a (ρ − ρ₀), eq. 16 is the force of the energy U = Σ_i ½ κ_i (ρ_i − ρ₀)² with
 * κ_i = m_i k_a / ρ_i² held over the step: by eq. 1, ∂ρ_i/∂x_i = Σ_j m_j ∇_i W_ij and
 * ∂ρ_j/∂x_i = m_i ∇_i W_ij, so
 *     −∂U/∂x_i = −Σ_j (κ_i C_i m_j + κ_j C_j m_i) ∇_i W_ij
 *              = −Σ_j m_i m_j (P_i/ρ_i² + P_j/ρ_j²) ∇_i W_ij     (C = ρ − ρ₀),
 * eq. 16 term by term. Its stiffness is K_p = Jᵀ κ J + Σ_i κ_i C_i ∂²ρ_i/∂x². The first
 * (Gauss–Newton) part is positive semi-definite, with J = ∂ρ/∂x:
 *     (J d)_i = Σ_j g_ij · (d_i − d_j),   (Jᵀ t)_i = Σ_j g_ij (t_i + (m_i/m_j) t_j),
 * g_ij = m_j ∇_i W_ij over the neighbours within 2h₂. The second is a sum over pairs, each a
 * spring between i and j: c_ij [W'' x̂x̂ᵀ + (W'/r)(I − x̂x̂ᵀ)] with c_ij = κ_i C_i m_j +
 * κ_j C_j m_i (the pair's W appears in ρ_i and in ρ_j); its positive parts are kept, as the
 * springs keep theirs (lcp/implicit_springs.hh). Without them a compressed cluster (ρ ≫ ρ₀)
 * whose pairs sit in the kernel's convex tail (W'' > 0) overshoots at large steps. */
struct DensityJacobian {
  struct Entry {
    int32_t partner; /* j */
    /* The pair spring's positive parts: along x̂x̂ᵀ (over |g_ij|², so that along · g (g · d)
     * is that term) and across I. */
    float along, across;
    vec3 gradient; /* g_ij */
  };
  /* Compressed rows: the neighbours j of particle i within 2h₂ are
   * entries[offsets[i] .. offsets[i + 1]). */
  std::vector<int32_t> offsets;
  std::vector<Entry> entries;
  std::vector<float> kappa; /* κ_i = m_i k_a / ρ_i² */
};
void compute_density_jacobian(Span<vec3> positions, Span<float> masses, Span<float> density,
                              const NeighborList &neighbors, float h, float pressure_stiffness,
                              float rest_density, DensityJacobian &r_jacobian);

/* Interpenetrating pairs: pairs of particles (i < j, at least one of them free) closer than
 * `distance`. Two samples of the hair volume in the same place means one lock of hair has
 * passed into another; the solver uses distance = h₂ / 2, below the closest spacing the
 * Poisson-disc initialisation produces for h₂ ≈ spacing. */
int64_t count_close_pairs(Span<vec3> positions, Span<uint8_t> is_fixed,
                          const NeighborList &neighbors, float distance);

}  // namespace hairdyn
