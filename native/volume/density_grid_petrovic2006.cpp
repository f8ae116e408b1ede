#include "volume/density_grid_petrovic2006.hh"

#include <algorithm>
#include <cmath>

#include "groom/groom.hh"
#include "core/head_motion.hh"

namespace hairdyn {

mat4 rigid_head_to_world(const mat4 &head_to_world)
{
  const HeadPose pose = HeadPose::from_matrix(head_to_world);
  mat4 rigid(glm::mat3_cast(pose.rotation));
  rigid[3] = vec4(pose.translation, 1.0f);
  return rigid;
}

mat4 GridFrame::grid_to_world() const
{
  const mat4 lattice = glm::scale(glm::translate(mat4(1.0f), vec3(origin) * cell_size),
                                  vec3(cell_size));
  return head_to_world * lattice;
}

HeadBox head_box(const Span<vec3> positions_wo, const mat4 &world_to_head)
{
  return parallel_reduce(
      positions_wo.size(), point_grain, HeadBox(),
      [&](const IndexRange range) {
        HeadBox box;
        for (int64_t i = range.start; i < range.one_after_last(); i++) {
          if (is_finite(positions_wo[i])) {
            const vec3 p = transform_point(world_to_head, positions_wo[i]);
            box.lo = glm::min(box.lo, p);
            box.hi = glm::max(box.hi, p);
          }
        }
        return box;
      },
      [](HeadBox a, const HeadBox &b) {
        a.include(b);
        return a;
      });
}

GridFrame grid_around(const HeadBox &box, float cell_size, const int margin,
                      const mat4 &head_to_world)
{
  GridFrame grid;
  grid.head_to_world = head_to_world;
  grid.world_to_head = glm::inverse(head_to_world);
  if (box.is_empty()) {
    grid.cell_size = cell_size;
    return grid;
  }
  while (true) {
    const vec3 lo = glm::floor(box.lo / cell_size) - float(margin);
    const vec3 hi = glm::ceil(box.hi / cell_size) + float(margin);
    const vec3 extent = hi - lo + 1.0f;
    if (double(extent.x) * double(extent.y) * double(extent.z) <= double(max_grid_vertices)) {
      grid.cell_size = cell_size;
      grid.origin = ivec3(lo);
      grid.size = ivec3(extent);
      return grid;
    }
    cell_size *= 2.0f;
  }
}

float mean_segment_length(const Span<int32_t> curve_offsets, const Span<vec3> positions)
{
  const int64_t curves_num = curve_offsets.size() - 1;
  const double total = parallel_sum(curves_num, 1024, [&](const IndexRange range) {
    double sum = 0.0;
    for (int64_t curve = range.start; curve < range.one_after_last(); curve++) {
      const IndexRange points = curve_points(curve_offsets, curve);
      for (int64_t p = points.start + 1; p < points.one_after_last(); p++) {
        sum += double(glm::length(positions[p] - positions[p - 1]));
      }
    }
    return sum;
  });
  const int64_t segments_num = positions.size() - curves_num;
  return segments_num > 0 ? float(total / double(segments_num)) : 0.0f;
}

void bin_points(const GridFrame &grid, const Span<vec3> positions_wo, PointBins &r_bins)
{
  const int64_t points_num = positions_wo.size();
  r_bins.coords.resize(size_t(points_num));
  r_bins.cell_of.resize(size_t(points_num));
  parallel_for(points_num, point_grain, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      const vec3 p = grid.to_grid(positions_wo[i]);
      ivec3 cell;
      vec3 fraction;
      r_bins.coords[size_t(i)] = p;
      r_bins.cell_of[size_t(i)] = locate(grid, p, cell, fraction) ?
                                      int32_t(grid.cell_index(cell.x, cell.y, cell.z)) :
                                      -1;
    }
  });
}

void splat_density(const GridFrame &grid, const PointBins &bins, const MutableSpan<float> r_density,
                   std::vector<float> &scratch)
{
  splat_to_grid<float>(grid, bins, [](int64_t) { return 1.0f; }, r_density, scratch);
}

template<typename T>
void blur_binomial(const ivec3 &size, const int radius, const MutableSpan<T> values,
                   std::vector<T> &scratch)
{
  if (radius <= 0) {
    return;
  }
  std::vector<float> weights(static_cast<size_t>(2 * radius + 1));
  double binomial = 1.0; /* C(2r, k) */
  for (int k = 0; k <= 2 * radius; k++) {
    weights[size_t(k)] = float(binomial / std::pow(4.0, radius));
    binomial = binomial * double(2 * radius - k) / double(k + 1);
  }
  scratch.resize(size_t(values.size()));
  const int64_t strides[3] = {1, int64_t(size.x), int64_t(size.x) * size.y};
  for (int axis = 0; axis < 3; axis++) {
    const int64_t stride = strides[axis];
    const int length = size[axis];
    std::copy(values.begin(), values.end(), scratch.begin());
    parallel_for(values.size(), grid_grain, [&](const IndexRange range) {
      for (int64_t v = range.start; v < range.one_after_last(); v++) {
        const int at = int((v / stride) % length);
        T sum(0.0f);
        for (int k = -radius; k <= radius; k++) {
          if (at + k >= 0 && at + k < length) {
            sum += weights[size_t(k + radius)] * scratch[size_t(v + k * stride)];
          }
        }
        values[v] = sum;
      }
    });
  }
}

template void blur_binomial<float>(const ivec3 &, int, MutableSpan<float>, std::vector<float> &);
template void blur_binomial<vec3>(const ivec3 &, int, MutableSpan<vec3>, std::vector<vec3> &);
template void blur_binomial<vec4>(const ivec3 &, int, MutableSpan<vec4>, std::vector<vec4> &);

void copy_between_grids(const GridFrame &from, const Span<float> values, const GridFrame &to,
                        const MutableSpan<float> r_values)
{
  const ivec3 offset = to.origin - from.origin;
  parallel_for(to.size.z, slab_grain(to.size), [&](const IndexRange slices) {
    for (int k = int(slices.start); k < int(slices.one_after_last()); k++) {
      for (int j = 0; j < to.size.y; j++) {
        for (int i = 0; i < to.size.x; i++) {
          const ivec3 v = ivec3(i, j, k) + offset;
          const bool inside = glm::all(glm::greaterThanEqual(v, ivec3(0))) &&
                              glm::all(glm::lessThan(v, from.size));
          r_values[to.vertex_index(i, j, k)] = inside ? values[from.vertex_index(v.x, v.y, v.z)] :
                                                        0.0f;
        }
      }
    }
  });
}

float max_value(const Span<float> values)
{
  return parallel_reduce(
      values.size(), grid_grain, 0.0f,
      [&](const IndexRange range) {
        float m = 0.0f;
        for (int64_t i = range.start; i < range.one_after_last(); i++) {
          m = std::max(m, values[i]);
        }
        return m;
      },
      [](const float a, const float b) { return std::max(a, b); });
}

}  // namespace hairdyn
