#include "volume/volume_pass.hh"

#include <chrono>
#include <algorithm>
#include <cmath>

#include "groom/groom.hh"

namespace hairdyn {

namespace {

/* Substeps without a 1% improvement of eq. 3 after which a level counts as done. */
constexpr int refine_patience = 20;

}  // namespace

VolumePass::VolumePass(const VolumeParams &params) : params_(params)
{
  reset();
}

void VolumePass::set_params(const VolumeParams &params)
{
  const bool levels_changed = params.target_levels != params_.target_levels;
  const bool cell_changed = params.cell_size != params_.cell_size;
  params_ = params;
  if (cell_changed) {
    cell_size_ = 0.0f; /* measured again at the next substep */
  }
  if (levels_changed || cell_changed) {
    level_ = params_.target_levels - 1;
    level_start_error_ = -1.0;
  }
}

void VolumePass::set_target(const Span<vec3> positions_wo, const mat4 &head_to_world)
{
  target_ = DensityTarget(positions_wo, head_to_world);
  level_ = params_.target_levels - 1;
  level_start_error_ = -1.0;
  target_error_ = 0.0;
}

void VolumePass::clear_target()
{
  target_ = DensityTarget();
  target_error_ = 0.0;
}

void VolumePass::reset()
{
  level_ = params_.target_levels - 1;
  level_start_error_ = -1.0;
  cell_size_ = 0.0f;
  density_max_ = 0.0f;
  target_error_ = 0.0;
  volume_ms_ = 0.0;
  substeps_num_ = 0;
}

void VolumePass::apply(const SubstepState &state)
{
  const auto start = std::chrono::steady_clock::now();
  const int64_t points_num = state.positions_wo.size();
  if (cell_size_ <= 0.0f) {
    cell_size_ = params_.cell_size > 0.0f ?
                     params_.cell_size :
                     std::max(mean_segment_length(state.curve_offsets, state.positions_wo),
                              min_segment_length(state.positions_wo));
  }
  const mat4 head_to_world = rigid_head_to_world(state.head_to_world);
  const mat4 world_to_head = glm::inverse(head_to_world);
  positions_head_.resize(size_t(points_num));
  const HeadBox hair_box = head_box(state.positions_wo, world_to_head, positions_head_);

  /* §5.1: velocity smoothing on the grid of spacing h. */
  const GridFrame grid = grid_around(hair_box, cell_size_, params_.filter_radius + 1,
                                     head_to_world);
  bin_head_points(grid, positions_head_, bins_);
  if (params_.smoothing > 0.0f) {
    smooth_grid_velocity(grid, bins_, state.velocities_wo, params_.filter_radius,
                         velocity_grids_);
    drag_toward(grid, bins_, velocity_grids_, params_.smoothing, state.h, state.curve_offsets,
                state.positions_wo, state.velocities_wo);
    density_max_ = velocity_grids_.density_max;
  }
  else {
    std::vector<float> &density = target_grids_.density;
    density.resize(size_t(grid.vertices_num()));
    splat_density(grid, bins_, density, target_grids_.scratch);
    density_max_ = max_value(density);
  }

  /* §5.2: the density force toward the target, coarse to fine; it moves the nodes by h Δv as
   * the drag does. */
  if (has_target() && params_.target_strength > 0.0f) {
    if (params_.smoothing > 0.0f) {
      head_box(state.positions_wo, world_to_head, positions_head_); /* the drag moved them */
    }
    HeadBox box = hair_box;
    box.include(target_.box());
    /* The error on the finest grid, of the state before the targeting force. */
    if (level_ > 0) {
      const GridFrame fine_grid = grid_around(box, cell_size_, 1, head_to_world);
      bin_head_points(fine_grid, positions_head_, bins_);
      target_error_ = hairdyn::target_error(fine_grid, bins_, target_, target_grids_);
    }
    const GridFrame level_grid = grid_around(box, std::ldexp(cell_size_, level_), 1,
                                             head_to_world);
    bin_head_points(level_grid, positions_head_, bins_);
    const double error = hairdyn::target_error(level_grid, bins_, target_, target_grids_);
    if (level_ == 0) {
      target_error_ = error;
    }
    point_values_.resize(size_t(points_num));
    density_forces(level_grid, bins_, target_grids_.difference, point_values_);
    /* The force of eq. 3 grows with the nodes per cell: with the target's mean density over
     * the vertices it reaches, D̄_t, F / D̄_t is a relative density gradient, the same for a
     * sparse or a dense groom and on every level (D and F both grow as the cell's volume).
     * Taken raw, the shipped example's groom (a coarse level's cell of 11 cm, 24 nodes per
     * reached vertex) was kicked by 37 m/s a substep at κ = 20 and diverged. D̄_t is found
     * once per level, with the target's density there. */
    const float kick = state.h * params_.target_strength / target_grids_.target_mean;
    for_each_free_point(state.curve_offsets, points_num, [&](const int64_t i) {
      const vec3 dv = kick * point_values_[size_t(i)];
      state.velocities_wo[i] += dv;
      state.positions_wo[i] += state.h * dv;
    });

    if (level_ > 0) {
      if (level_start_error_ < 0.0) {
        level_start_error_ = level_best_error_ = error;
        substeps_since_best_ = 0;
      }
      else if (error < 0.99 * level_best_error_) {
        level_best_error_ = error;
        substeps_since_best_ = 0;
      }
      else {
        substeps_since_best_++;
      }
      if (error <= double(params_.target_refine) * level_start_error_ ||
          substeps_since_best_ >= refine_patience)
      {
        level_--;
        level_start_error_ = -1.0;
      }
    }
  }
  volume_ms_ += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                    .count();
  substeps_num_++;
}

}  // namespace hairdyn
