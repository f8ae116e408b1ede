#pragma once
/* Directing hair toward a target shape by its density (Petrovic, Henne and Anderson 2006,
 * §5.2). With D_s the density of the simulated hair and D_t that of the target (eq. 1 on the
 * same grid), the grid's energy is
 *
 *   E = ½ Σ_xyz (D_s − D_t)²                                               (eq. 3)
 *
 * and each node feels the force F = −∂E/∂P^i: with D_d = D_s − D_t and the tent factors
 * ax = 1 − |P_x − x| (ay, az alike) of the cell holding the node,
 *
 *   F_x = ay az (D_d(x,y,z) − D_d(x+1,y,z)) + (1−ay) az (D_d(x,y+1,z) − D_d(x+1,y+1,z))
 *       + ay (1−az) (D_d(x,y,z+1) − D_d(x+1,y,z+1))
 *       + (1−ay)(1−az) (D_d(x,y+1,z+1) − D_d(x+1,y+1,z+1)),
 *
 * F_y and F_z alike, in grid units; on a vertex plane (P_x = x) the derivative is taken as 0.
 * The paper writes F = ∂E/∂P, but its F_x is the descent direction −∂E/∂P_x, which is what
 * lowers E; that is the one used. */
#include <vector>

#include "core/math.hh"
#include "core/span.hh"
#include "volume/density_grid_petrovic2006.hh"

namespace hairdyn {

/* r_difference = D_s − D_t; returns E of eq. 3. */
double density_difference(Span<float> density, Span<float> target,
                          MutableSpan<float> r_difference);

/* The force after eq. 3 on every point (grid units); 0 for points outside the grid. */
void density_forces(const GridFrame &grid, const PointBins &bins, Span<float> difference,
                    MutableSpan<vec3> r_forces);

/* A target shape, stored in the head's frame, with its density on every lattice it was asked
 * for (the coarse-to-fine levels). */
class DensityTarget {
 public:
  DensityTarget() = default;
  DensityTarget(Span<vec3> positions_wo, const mat4 &head_to_world);

  bool is_empty() const { return positions_head_.empty(); }
  const HeadBox &box() const { return box_; }
  /* D_t on `grid`'s vertices (the target's density on the lattice of grid.cell_size, which is
   * computed once per cell size and kept); returns D̄_t, its mean over the vertices it
   * reaches (1 when it reaches none). */
  float density_on(const GridFrame &grid, MutableSpan<float> r_density);

 private:
  struct Level {
    GridFrame grid;
    std::vector<float> density;
    float mean = 1.0f;
  };
  std::vector<vec3> positions_head_;
  HeadBox box_;
  std::vector<Level> levels_;
};

/* What one evaluation of eq. 3 on a grid leaves behind. */
struct TargetGrids {
  std::vector<float> density;
  std::vector<float> target;
  std::vector<float> difference;
  std::vector<float> scratch;
  float target_mean = 1.0f; /* D̄_t (DensityTarget::density_on) */
};

/* E of eq. 3 between `positions_wo` (binned on `grid` in `bins`) and `target`; leaves D_s,
 * D_t and D_d in `grids`. */
double target_error(const GridFrame &grid, const PointBins &bins, DensityTarget &target,
                    TargetGrids &grids);

}  // namespace hairdyn
