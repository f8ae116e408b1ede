#pragma once
/* Hair–hair interaction by velocity smoothing (Petrovic, Henne and Anderson 2006, §5.1).
 *
 * The node velocities are averaged on the density grid,
 *
 *   V_xyz = Σ_i (1 − |P_x^i − x|)(1 − |P_y^i − y|)(1 − |P_z^i − z|) v^i / D_xyz,
 *
 * smoothed by a filter kernel on the grid, and every node is dragged toward the grid velocity
 * at its position: v^i ← v^i + s (V(P^i) − v^i).
 *
 * The filter is the binomial kernel B (symmetric, weights summing to 1), applied on both sides
 * of the average: to the momentum and density before dividing (V = B M / B D) and to the
 * averaged velocity before it is read back at the nodes with the same tent weights W. The map
 * from node velocities to the grid velocity at the nodes is then T = W B diag(1 / B D) B Wᵀ:
 * symmetric, positive semidefinite, and its eigenvalues are at most 1 (D⁻¹(WB)ᵀWB has
 * non-negative entries and row sums ≤ 1). Hence, with equal node masses,
 *   - the drag v ← (1 − s) v + s T v never adds kinetic energy for s ∈ [0, 1] (the paper's
 *     "will always lead to the dissipation of energy"), the filter keeping the grid's total
 *     mass and momentum;
 *   - a uniform velocity field passes unchanged (B M = v₀ B D wherever B D > 0). */
#include <vector>

#include "core/math.hh"
#include "core/span.hh"
#include "volume/density_grid_petrovic2006.hh"

namespace hairdyn {

/* Scratch grids of the smoothing, kept between substeps to avoid reallocation. */
struct VelocityGrids {
  std::vector<vec4> momentum_density; /* (Σ w v, Σ w) per vertex, then filtered */
  std::vector<vec4> velocity; /* V per vertex (w unused: four lanes, lanes4.hh), then filtered */
  std::vector<vec4> splat_scratch; /* the splat's chunk grids */
  std::vector<vec4> scratch4;      /* the filter's */
  float density_max = 0.0f; /* eq. 1's largest value on the grid, before filtering */
};

/* B V on the grid's vertices, into grids.velocity. `bins` must hold the points of `velocities`
 * binned on `grid`. */
void smooth_grid_velocity(const GridFrame &grid, const PointBins &bins, Span<vec3> velocities,
                          int filter_radius, VelocityGrids &grids);

/* The smoothed grid velocity (T v)_i at point i's position, read back with the tent weights; a
 * point outside the grid keeps its own velocity `v`. */
inline vec3 grid_velocity_at(const GridFrame &grid, const VelocityGrids &grids,
                             const PointBins &bins, const int64_t i, const vec3 &v)
{
  const int32_t vertex = bins.vertex_of[size_t(i)];
  return vertex < 0 ? v
                    : vec3(sample_cell(grid, Span<vec4>(grids.velocity), vertex,
                                       bins.fraction[size_t(i)]));
}

/* §5.1's drag toward the grid velocity of smooth_grid_velocity: v ← v + s (V − v) for every point
 * except the roots of `curve_offsets` (empty: every point); the positions move by h times the
 * change of velocity, as if the drag had acted through the substep of length h (symplectic
 * Euler's x += h v with the dragged v). A change of velocity alone, carried into the next
 * substep, was mostly taken back by the implicit hinge dampers before the nodes moved: the
 * Fig. 4 sheets crossed 22 times instead of 3 on the articulated model. */
void drag_toward(const GridFrame &grid, const PointBins &bins, const VelocityGrids &grids,
                 float strength, float h, Span<int32_t> curve_offsets,
                 MutableSpan<vec3> positions, MutableSpan<vec3> velocities);

}  // namespace hairdyn
