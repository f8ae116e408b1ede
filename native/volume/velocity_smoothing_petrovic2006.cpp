#include "volume/velocity_smoothing_petrovic2006.hh"

#include <algorithm>

#include "core/parallel.hh"

namespace hairdyn {

void smooth_grid_velocity(const GridFrame &grid, const PointBins &bins,
                          const Span<vec3> velocities, const int filter_radius,
                          VelocityGrids &grids)
{
  const int64_t vertices_num = grid.vertices_num();
  grids.momentum_density.resize(size_t(vertices_num));
  grids.velocity.resize(size_t(vertices_num));
  /* §5.1: Σ w v and eq. 1's Σ w at each vertex, in one gather. */
  splat_to_grid<vec4>(
      grid, bins,
      [&](const int64_t i) {
        return vec4(velocities[i], 1.0f);
      },
      MutableSpan<vec4>(grids.momentum_density), grids.splat_scratch);
  const Span<vec4> splat(grids.momentum_density);
  /* The largest of eq. 1's Σ w (a maximum: the same on any thread count). */
  grids.density_max = parallel_reduce(
      vertices_num, grid_grain, 0.0f,
      [&](const IndexRange range) {
        float m = 0.0f;
        for (int64_t v = range.start; v < range.one_after_last(); v++) {
          m = std::max(m, splat[v].w);
        }
        return m;
      },
      [](const float a, const float b) {
        return std::max(a, b);
      });
  /* B M and B D. */
  blur_binomial(grid.size, filter_radius, grids.momentum_density, grids.scratch4);
  const Span<vec4> md(grids.momentum_density);
  const MutableSpan<vec4> v_grid(grids.velocity);
  parallel_for(vertices_num, grid_grain, [&](const IndexRange range) {
    for (int64_t v = range.start; v < range.one_after_last(); v++) {
      const float w = md[v].w;
      if (w > 0.0f) {
        (Lanes4::load(md[v]) / Lanes4::splat(w)).store(v_grid[v]); /* vec3(m) / m.w */
        v_grid[v].w = 0.0f;
      }
      else {
        v_grid[v] = vec4(0.0f);
      }
    }
  });
  /* B V. */
  blur_binomial(grid.size, filter_radius, grids.velocity, grids.scratch4);
}

void drag_toward(const GridFrame &grid, const PointBins &bins, const VelocityGrids &grids,
                 const float strength, const float h, const Span<int32_t> curve_offsets,
                 const MutableSpan<vec3> positions, const MutableSpan<vec3> velocities)
{
  for_each_free_point(curve_offsets, velocities.size(), [&](const int64_t i) {
    const vec3 v = velocities[i];
    const vec3 dv = strength * (grid_velocity_at(grid, grids, bins, i, v) - v);
    velocities[i] = v + dv;
    positions[i] += h * dv;
  });
}

}  // namespace hairdyn
