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
                                  Span<vec3> directions, Span<float> masses,
                                  Span<float> density, const NeighborList &neighbors,
                                  const HairInteractionSettings &settings,
                                  MutableSpan<vec3> r_forces, MutableSpan<vec3> r_damped_forces,
                                  MutableSpan<float> r_damping);

/* Interpenetrating pairs: pairs of particles (i < j, at least one of them free) closer than
 * `distance`. Two samples of the hair volume in the same place means one lock of hair has
 * passed into another; the solver uses distance = h₂ / 2, below the closest spacing the
 * Poisson-disc initialisation produces for h₂ ≈ spacing. */
int64_t count_close_pairs(Span<vec3> positions, Span<uint8_t> is_fixed,
                          const NeighborList &neighbors, float distance);

}  // namespace hairdyn
