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
#ifdef HAIRDYN_LANES4_SSE
        /* transform_point and glm::min/max lane by lane, in glm's order of operations:
         * (m0 x + m1 y) + (m2 z + m3 · 1), min(a, b) = b < a ? b : a. */
        const __m128 m0 = _mm_loadu_ps(&world_to_head[0].x),
                     m1 = _mm_loadu_ps(&world_to_head[1].x);
        const __m128 m2 = _mm_loadu_ps(&world_to_head[2].x),
                     m3 = _mm_loadu_ps(&world_to_head[3].x);
        __m128 lo = _mm_set1_ps(box.lo.x), hi = _mm_set1_ps(box.hi.x);
        for (int64_t i = range.start; i < range.one_after_last(); i++) {
          const vec3 &q = positions_wo[i];
          const __m128 sum = _mm_add_ps(
              _mm_add_ps(_mm_mul_ps(m0, _mm_set1_ps(q.x)), _mm_mul_ps(m1, _mm_set1_ps(q.y))),
              _mm_add_ps(_mm_mul_ps(m2, _mm_set1_ps(q.z)), m3));
          float out[4];
          _mm_storeu_ps(out, sum);
          keep(i, vec3(out[0], out[1], out[2]));
          if (is_finite(q)) {
            lo = _mm_min_ps(sum, lo);
            hi = _mm_max_ps(sum, hi);
          }
        }
        float out_lo[4], out_hi[4];
        _mm_storeu_ps(out_lo, lo);
        _mm_storeu_ps(out_hi, hi);
        box.lo = vec3(out_lo[0], out_lo[1], out_lo[2]);
        box.hi = vec3(out_hi[0], out_hi[1], out_hi[2]);
#else
        for (int64_t i = range.start; i < range.one_after_last(); i++) {
          const vec3 p = transform_point(world_to_head, positions_wo[i]);
          keep(i, p);
          if (is_finite(positions_wo[i])) {
            box.lo = glm::min(box.lo, p);
            box.hi = glm::max(box.hi, p);
          }
        }
#endif
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
  if (grid.cells_num() == 0) {
    std::fill(r_bins.vertex_of.begin(), r_bins.vertex_of.end(), -1);
    std::fill(r_bins.fraction.begin(), r_bins.fraction.end(), vec3(0.0f));
    return;
  }
  /* locate() with the grid's constants hoisted out of the loop (the same bits). */
  const vec3 origin(grid.origin), last(grid.size - 1);
  const ivec3 last_cell = grid.size - 2;
  const int32_t dy = grid.size.x, dz = grid.size.x * grid.size.y; /* < max_grid_vertices */
  const float cell_size = grid.cell_size;
#ifdef HAIRDYN_LANES4_SSE
  const __m128 origin4 = _mm_setr_ps(origin.x, origin.y, origin.z, 0.0f);
  const __m128 last4 = _mm_setr_ps(last.x, last.y, last.z, 0.0f);
  const __m128i last_cell4 = _mm_setr_epi32(last_cell.x, last_cell.y, last_cell.z, 0);
#endif
  parallel_for(points_num, point_grain, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      const vec3 head = head_of(i);
#ifdef HAIRDYN_LANES4_SSE
      /* The same operations, lane by lane. */
      const __m128 p = _mm_sub_ps(
          _mm_div_ps(_mm_setr_ps(head.x, head.y, head.z, 0.0f), _mm_set1_ps(cell_size)), origin4);
      const int inside =
          _mm_movemask_ps(_mm_and_ps(_mm_cmpge_ps(p, _mm_setzero_ps()), _mm_cmple_ps(p, last4)));
      if ((inside & 7) != 7) {
        r_bins.vertex_of[size_t(i)] = -1;
        r_bins.fraction[size_t(i)] = vec3(0.0f);
        continue;
      }
      /* p ≥ 0: truncation is the floor; min(cell, last_cell) as glm::min on integers. */
      const __m128i truncated = _mm_cvttps_epi32(p);
      const __m128i cell =
          _mm_xor_si128(last_cell4, _mm_and_si128(_mm_xor_si128(truncated, last_cell4),
                                                  _mm_cmplt_epi32(truncated, last_cell4)));
      alignas(16) int32_t c[4];
      alignas(16) float f[4];
      _mm_store_si128(reinterpret_cast<__m128i *>(c), cell);
      _mm_store_ps(f, _mm_sub_ps(p, _mm_cvtepi32_ps(cell)));
      r_bins.vertex_of[size_t(i)] = c[2] * dz + c[1] * dy + c[0];
      r_bins.fraction[size_t(i)] = vec3(f[0], f[1], f[2]);
#else
      const vec3 p = head / cell_size - origin;
      if (!(p.x >= 0.0f && p.y >= 0.0f && p.z >= 0.0f && p.x <= last.x && p.y <= last.y &&
            p.z <= last.z))
      {
        r_bins.vertex_of[size_t(i)] = -1;
        r_bins.fraction[size_t(i)] = vec3(0.0f);
        continue;
      }
      const ivec3 cell = glm::min(ivec3(p), last_cell); /* p ≥ 0: truncation is the floor */
      r_bins.vertex_of[size_t(i)] = cell.z * dz + cell.y * dy + cell.x;
      r_bins.fraction[size_t(i)] = p - vec3(cell);
#endif
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

/* One axis of blur_binomial from `in` into `out` over `planes` planes of `length` × `width`
 * values, plane p starting at p · plane_offset, value (t, i) of a plane at t · step + i from its
 * start; t runs along the axis. Each value sums its taps from 0 in the order of k, k outer and
 * the row inner (along x, where a row is one value, the whole plane is the row). */
template<typename T> void blur_axis(const Span<float> weights, const int64_t planes,
                                    const int64_t plane_offset, const int length,
                                    const int64_t step, const int64_t width, const Span<T> in,
                                    const MutableSpan<T> out)
{
  const int radius = int(weights.size() / 2);
  const int64_t grain = std::max<int64_t>(1, blur_grain / (int64_t(length) * width));
  /* out[i] = Σ_k w_k in_k[i] for i < n, the terms added to out. */
  const auto add_tap = [](T *r_out, const T *in_k, const float w, const int64_t n) {
    if constexpr (std::is_same_v<T, vec4>) {
      const Lanes4 w4 = Lanes4::splat(w);
      for (int64_t i = 0; i < n; i++) {
        (Lanes4::load(r_out[i]) + w4 * Lanes4::load(in_k[i])).store(r_out[i]);
      }
    }
    else {
      for (int64_t i = 0; i < n; i++) {
        r_out[i] += w * in_k[i];
      }
    }
  };
  parallel_for(planes, grain, [&](const IndexRange range) {
    for (int64_t p = range.start; p < range.one_after_last(); p++) {
      const int64_t start = p * plane_offset;
      if (width == 1 && step == 1) {
        T *row_out = &out[start];
        const T *row_in = &in[start];
        std::fill(row_out, row_out + length, T(0.0f));
        for (int k = -radius; k <= radius; k++) {
          const int t_lo = std::max(0, -k), t_hi = std::min(length, length - k);
          if (t_lo < t_hi) {
            add_tap(row_out + t_lo, row_in + t_lo + k, weights[k + radius], t_hi - t_lo);
          }
        }
        continue;
      }
      for (int t = 0; t < length; t++) {
        const int k_lo = std::max(-radius, -t), k_hi = std::min(radius, length - 1 - t);
        T *row_out = &out[start + t * step];
        std::fill(row_out, row_out + width, T(0.0f));
        for (int k = k_lo; k <= k_hi; k++) {
          add_tap(row_out, &in[start + (t + k) * step], weights[k + radius], width);
        }
      }
    }
  });
}

}  // namespace

template<typename T>
void blur_binomial(const ivec3 &size, const int radius, std::vector<T> &values,
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
  scratch.resize(values.size());
  const MutableSpan<T> in(values), copy(scratch);
  const int64_t sx = size.x, sxy = int64_t(size.x) * size.y;
  /* x into the scratch, y back, z into the scratch, which then becomes the values. */
  blur_axis<T>(weights, int64_t(size.y) * size.z, sx, size.x, 1, 1, in, copy);
  blur_axis<T>(weights, size.z, sxy, size.y, sx, sx, copy, in);
  blur_axis<T>(weights, size.y, sx, size.z, sxy, sx, in, copy);
  std::swap(values, scratch);
}

template void blur_binomial<float>(const ivec3 &, int, std::vector<float> &, std::vector<float> &);
template void blur_binomial<vec3>(const ivec3 &, int, std::vector<vec3> &, std::vector<vec3> &);
template void blur_binomial<vec4>(const ivec3 &, int, std::vector<vec4> &, std::vector<vec4> &);

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
