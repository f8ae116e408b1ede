#pragma once
/* The volumetric methods of Petrovic, Henne and Anderson 2006 as a substep pass of the strand
 * solver: each substep, velocity smoothing (§5.1) on the density grid (eq. 1), then, when a
 * target shape is set, the density force toward it (§5.2, eq. 3), on a grid that starts coarse
 * and refines as the error drops. The grid is a lattice fixed to the head (SubstepState's
 * head_to_world), boxed around the hair (and the target) every substep. */
#include <vector>

#include "strands/substep_pass.hh"
#include "volume/density_grid_petrovic2006.hh"
#include "volume/density_target_petrovic2006.hh"
#include "volume/velocity_smoothing_petrovic2006.hh"
#include "volume/volume_params.hh"

namespace hairdyn {

class VolumePass : public SubstepPass {
 public:
  explicit VolumePass(const VolumeParams &params = VolumeParams());

  const char *name() const override { return "volume"; }
  void apply(const SubstepState &state) override;

  const VolumeParams &params() const { return params_; }
  void set_params(const VolumeParams &params);

  /* The target shape (§5.2): world positions with the head at `head_to_world`; the target
   * moves with the head. Targeting restarts on the coarsest level. */
  void set_target(Span<vec3> positions_wo, const mat4 &head_to_world);
  void clear_target();
  bool has_target() const { return !target_.is_empty(); }

  /* Targeting back to its coarsest level, the figures below cleared. */
  void reset();

  /* Report of the substeps since the last reset. */
  double volume_ms() const { return volume_ms_; }          /* time spent in apply */
  int64_t substeps_num() const { return substeps_num_; }
  /* Of the last substep: eq. 1's largest density, and eq. 3's error on the finest grid (the
   * cell size h) before the targeting force acted; 0 without a target. */
  float density_max() const { return density_max_; }
  double target_error() const { return target_error_; }
  /* The targeting grid's current level: cells of 2^level · h. */
  int target_level() const { return level_; }
  /* m, the cell size h in use (params.cell_size, or the mean segment length when that is 0). */
  float cell_size() const { return cell_size_; }

 private:
  VolumeParams params_;
  DensityTarget target_;
  int level_ = 0;
  double level_start_error_ = -1.0; /* eq. 3 when the current level began; < 0: not yet */
  double level_best_error_ = 0.0;
  int substeps_since_best_ = 0;

  float cell_size_ = 0.0f;
  float density_max_ = 0.0f;
  double target_error_ = 0.0;
  double volume_ms_ = 0.0;
  int64_t substeps_num_ = 0;

  /* Scratch kept between substeps. */
  PointBins bins_;
  VelocityGrids velocity_grids_;
  TargetGrids target_grids_;
  std::vector<vec3> positions_head_;
  std::vector<vec3> point_values_; /* the targeting force per point */
};

}  // namespace hairdyn
