#pragma once
/* Wind of Bando 2003, §3.5: the air is a set of SPH particles, coupled to the hair particles
 * by drag forces both ways, so the hair also slows the air (Hadap and Magnenat-Thalmann
 * 2001). Air lives in world space in a box around the hair that is periodic across the
 * wind: air leaving downstream comes back upstream as fresh free-stream air, whose velocity
 * is the shared wind field's (core/wind.hh: mean direction, speed, turbulence) where and when
 * it enters. */
#include <random>
#include <vector>

#include "core/math.hh"
#include "core/span.hh"
#include "core/spatial_grid.hh"
#include "core/wind.hh"

namespace hairdyn {

/* The box of air, aligned with the wind: axis 0 along the wind, 1 and 2 across it (2 as near
 * world Z as the wind allows). */
struct WindBox {
  mat3 axes_wo{ 1.0f };        /* Columns: along, across, up. */
  vec3 lo{ 0.0f }, hi{ 0.0f }; /* In box coordinates. */
};

/* A box around `hair_positions_wo` padded by `margin`, for wind blowing along `direction`
 * (non-zero, world). */
WindBox wind_box_around(Span<vec3> hair_positions_wo, const vec3 &direction, float margin);

/* How many air particles fill_wind_box puts in `box` at `spacing`. */
int64_t wind_box_count(const WindBox &box, float spacing);

/* Air particles on a jittered lattice of `spacing` filling the box, moving with the wind
 * field at `time`. */
void fill_wind_box(const WindBox &box, float spacing, const WindField &wind, float time,
                   uint64_t seed, std::vector<vec3> &r_positions, std::vector<vec3> &r_velocities);

/* Periodic box: air that leaves across the wind re-enters on the other side; air that leaves
 * downstream (or upstream) re-enters at the opposite face with the free-stream velocity, the
 * wind field's there at `time`. */
void wrap_air_particles(const WindBox &box, const WindField &wind, float time,
                        MutableSpan<vec3> r_positions, MutableSpan<vec3> r_velocities);

/* SPH pressure between air particles (Monaghan 1992), P = c² (ρ − ρ_air) ≥ 0, with the
 * density of eq. 1 (r_density is written). */
void accumulate_air_pressure(Span<vec3> positions, float mass, float rest_density,
                             float sound_speed, float h, const NeighborList &neighbors,
                             MutableSpan<float> r_density, MutableSpan<vec3> r_forces);

/* Drag between two particle sets: on target i from source j,
 *   f = k_d · a_i · b_j · W(‖x_ij‖, h) · (v_j − v_i),
 * where the hair side's factor is its mass and the air side's its volume, so that the force
 * on the hair from air j is minus the force on air j from the hair (both ways, §3.5).
 * Forces are added to r_forces, their coefficients to r_damping. */
void accumulate_drag(Span<vec3> target_positions, Span<vec3> target_velocities,
                     Span<float> target_factors, Span<vec3> source_positions,
                     Span<vec3> source_velocities, Span<float> source_factors,
                     const NeighborList &target_to_sources, float h, float k_d,
                     MutableSpan<vec3> r_forces, MutableSpan<float> r_damping);

}  // namespace hairdyn
