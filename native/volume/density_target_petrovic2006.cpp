#include "volume/density_target_petrovic2006.hh"

#include "core/parallel.hh"

namespace hairdyn {

double density_difference(const Span<float> density, const Span<float> target,
                          const MutableSpan<float> r_difference)
{
  const double twice_energy = parallel_sum(density.size(), grid_grain, [&](const IndexRange range) {
    double sum = 0.0;
    for (int64_t v = range.start; v < range.one_after_last(); v++) {
      const float d = density[v] - target[v];
      r_difference[v] = d;
      sum += double(d) * double(d);
    }
    return sum;
  });
  return 0.5 * twice_energy; /* eq. 3 */
}

void density_forces(const GridFrame &grid, const PointBins &bins, const Span<float> difference,
                    const MutableSpan<vec3> r_forces)
{
  parallel_for(r_forces.size(), point_grain, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      const int32_t vertex = bins.vertex_of[size_t(i)];
      if (vertex < 0) {
        r_forces[i] = vec3(0.0f);
        continue;
      }
      const vec3 f = bins.fraction[size_t(i)];
      const int64_t dy = grid.size.x, dz = int64_t(grid.size.x) * grid.size.y;
      /* −∂E/∂P = −Σ_corners D_d ∂w/∂P (the force after eq. 3). */
      vec3 force(0.0f);
      for (int c = 0; c < 8; c++) {
        const ivec3 corner = ivec3(c & 1, (c >> 1) & 1, (c >> 2) & 1);
        const vec3 w(corner.x ? f.x : 1.0f - f.x, corner.y ? f.y : 1.0f - f.y,
                     corner.z ? f.z : 1.0f - f.z);
        const vec3 sign(corner.x ? -1.0f : 1.0f, corner.y ? -1.0f : 1.0f,
                        corner.z ? -1.0f : 1.0f);
        const float d = difference[vertex + corner.x + corner.y * dy + corner.z * dz];
        force += d * sign * vec3(w.y * w.z, w.x * w.z, w.x * w.y);
      }
      /* On a vertex plane the derivative is taken as 0 (§5.2). */
      for (int axis = 0; axis < 3; axis++) {
        if (f[axis] == 0.0f) {
          force[axis] = 0.0f;
        }
      }
      r_forces[i] = force;
    }
  });
}

DensityTarget::DensityTarget(const Span<vec3> positions_wo, const mat4 &head_to_world)
{
  const mat4 world_to_head = glm::inverse(rigid_head_to_world(head_to_world));
  positions_head_.resize(size_t(positions_wo.size()));
  for (int64_t i = 0; i < positions_wo.size(); i++) {
    positions_head_[size_t(i)] = transform_point(world_to_head, positions_wo[i]);
  }
  box_ = head_box(positions_head_, mat4(1.0f));
}

float DensityTarget::density_on(const GridFrame &grid, const MutableSpan<float> r_density)
{
  Level *level = nullptr;
  for (Level &candidate : levels_) {
    if (candidate.grid.cell_size == grid.cell_size) {
      level = &candidate;
    }
  }
  if (level == nullptr) {
    levels_.push_back(Level{grid_around(box_, grid.cell_size, 1, mat4(1.0f)), {}});
    level = &levels_.back();
    /* grid_around keeps the cell size: the target's box is never larger than a grid that
     * covers it. */
    PointBins bins;
    bin_points(level->grid, positions_head_, bins);
    level->density.resize(size_t(level->grid.vertices_num()));
    std::vector<float> scratch;
    splat_density(level->grid, bins, level->density, scratch);
    double sum = 0.0;
    int64_t reached = 0;
    for (const float d : level->density) {
      sum += double(d);
      reached += d > 0.0f ? 1 : 0;
    }
    level->mean = reached > 0 ? float(sum / double(reached)) : 1.0f;
  }
  copy_between_grids(level->grid, level->density, grid, r_density);
  return level->mean;
}

double target_error(const GridFrame &grid, const PointBins &bins, DensityTarget &target,
                    TargetGrids &grids)
{
  const size_t vertices_num = size_t(grid.vertices_num());
  grids.density.resize(vertices_num);
  grids.target.resize(vertices_num);
  grids.difference.resize(vertices_num);
  splat_density(grid, bins, grids.density, grids.scratch);
  grids.target_mean = target.density_on(grid, grids.target);
  return density_difference(grids.density, grids.target, grids.difference);
}

}  // namespace hairdyn
