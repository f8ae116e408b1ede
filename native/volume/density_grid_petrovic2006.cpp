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

namespace {

template<typename Keep>
HeadBox head_box_keeping(const Span<vec3> positions_wo, const mat4 &world_to_head, const Keep &keep)
{
  return parallel_reduce(
      positions_wo.size(), point_grain, HeadBox(),
      [&](const IndexRange range) {
        HeadBox box;
        for (int64_t i = range.start; i < range.one_after_last(); i++) {
          const vec3 p = transform_point(world_to_head, positions_wo[i]);
          keep(i, p);
          if (is_finite(positions_wo[i])) {
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

template<typename HeadOf>
void bin_by(const GridFrame &grid, const int64_t points_num, const HeadOf &head_of,
            PointBins &r_bins)
{
  r_bins.vertex_of.resize(size_t(points_num));
  r_bins.fraction.resize(size_t(points_num));
  parallel_for(points_num, point_grain, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      ivec3 cell;
      vec3 fraction(0.0f);
      const bool inside = locate(grid, head_of(i) / grid.cell_size - vec3(grid.origin), cell,
                                 fraction);
      r_bins.vertex_of[size_t(i)] = inside ? int32_t(grid.vertex_index(cell.x, cell.y, cell.z)) :
                                             -1;
      r_bins.fraction[size_t(i)] = fraction;
    }
  });
}

}  // namespace

HeadBox head_box(const Span<vec3> positions_wo, const mat4 &world_to_head)
{
  return head_box_keeping(positions_wo, world_to_head, [](int64_t, const vec3 &) {});
}

HeadBox head_box(const Span<vec3> positions_wo, const mat4 &world_to_head,
                 const MutableSpan<vec3> r_positions_head)
{
  return head_box_keeping(positions_wo, world_to_head,
                          [&](const int64_t i, const vec3 &p) { r_positions_head[i] = p; });
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
  bin_by(grid, positions_wo.size(), [&](const int64_t i) {
    return transform_point(grid.world_to_head, positions_wo[i]);
  }, r_bins);
}

void bin_head_points(const GridFrame &grid, const Span<vec3> positions_head, PointBins &r_bins)
{
  bin_by(grid, positions_head.size(), [&](const int64_t i) { return positions_head[i]; }, r_bins);
}

void splat_density(const GridFrame &grid, const PointBins &bins, const MutableSpan<float> r_density,
                   std::vector<float> &scratch)
{
  splat_to_grid<float>(grid, bins, [](int64_t) { return 1.0f; }, r_density, scratch);
}

namespace {

/* One axis of blur_binomial over `planes` planes of `length` × `width` values, plane p starting
 * at p · plane_offset, value (t, i) of a plane at t · step + i from its start; t runs along the
 * axis. A plane is copied to the same place in `scratch` and filtered back from there, so the
 * planes are independent and each is read while it is in cache. */
template<typename T>
void blur_axis(const Span<float> weights, const int64_t planes, const int64_t plane_offset,
               const int length, const int64_t step, const int64_t width,
               const MutableSpan<T> values, const MutableSpan<T> scratch)
{
  const int radius = int(weights.size() / 2);
  const int64_t grain = std::max<int64_t>(1, blur_grain / (int64_t(length) * width));
  parallel_for(planes, grain, [&](const IndexRange range) {
    for (int64_t p = range.start; p < range.one_after_last(); p++) {
      const int64_t start = p * plane_offset;
      for (int t = 0; t < length; t++) {
        const int64_t row = start + t * step;
        std::copy(&values[row], &values[row] + width, &scratch[row]);
      }
      for (int t = 0; t < length; t++) {
        const int k_lo = std::max(-radius, -t), k_hi = std::min(radius, length - 1 - t);
        T *out = &values[start + t * step];
        std::fill(out, out + width, T(0.0f));
        for (int k = k_lo; k <= k_hi; k++) {
          const float w = weights[k + radius];
          const T *in = &scratch[start + (t + k) * step];
          for (int64_t i = 0; i < width; i++) {
            out[i] += w * in[i];
          }
        }
      }
    }
  });
}

}  // namespace

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
  const MutableSpan<T> copy(scratch);
  const int64_t sx = size.x, sxy = int64_t(size.x) * size.y;
  blur_axis<T>(weights, int64_t(size.y) * size.z, sx, size.x, 1, 1, values, copy);
  blur_axis<T>(weights, size.z, sxy, size.y, sx, sx, values, copy);
  blur_axis<T>(weights, size.y, sx, size.z, sxy, sx, values, copy);
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
