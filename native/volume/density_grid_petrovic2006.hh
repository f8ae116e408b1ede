#pragma once
/* The hair density grid of Petrovic, Henne and Anderson 2006 (§3):
 *
 *   D_xyz = Σ_i (1 − |P_x^i − x|)(1 − |P_y^i − y|)(1 − |P_z^i − z|)      (eq. 1)
 *
 * over the points in the cells adjacent to vertex (x, y, z), in grid units.
 *
 * The grid is a lattice of spacing h fixed in the head's frame (it moves with the head): vertex
 * (i, j, k) of a grid sits at (origin + (i, j, k)) · h in head coordinates, and a grid is a box
 * of that lattice around the hair. Grids of equal spacing therefore share vertices, and values
 * move between them by an integer offset.
 *
 * Splatting sums each vertex's terms in an order that does not depend on the threads (see
 * splat_to_grid), so the result has the same bits on any thread count. */
#include <algorithm>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <vector>

#include "core/math.hh"
#include "core/parallel.hh"
#include "core/span.hh"
#include "volume/lanes4.hh"

namespace hairdyn {

/* Most vertices a grid may have (2^22, 16 MB of floats); a box that would need more takes the
 * smallest power-of-two multiple of the cell size that fits. */
constexpr int64_t max_grid_vertices = int64_t(1) << 22;

/* Grain sizes of the parallel loops: below these, a loop runs on one thread (a parallel region
 * costs more than small grids and grooms need). Grids are cut in z-slabs of about
 * grid_grain vertices. */
constexpr int64_t point_grain = 8192;
constexpr int64_t grid_grain = 131072;
constexpr int64_t blur_grain = 16384;
inline int64_t slab_grain(const ivec3 &size)
{
  return std::max<int64_t>(1, grid_grain / std::max<int64_t>(1, int64_t(size.x) * size.y));
}

/* The rotation and translation of `head_to_world` (its scale dropped): grids are in meters. */
mat4 rigid_head_to_world(const mat4 &head_to_world);

struct GridFrame {
  float cell_size = 1.0f;     /* m, h */
  ivec3 origin = ivec3(0);    /* lattice index of vertex (0, 0, 0) */
  ivec3 size = ivec3(0);      /* vertices per axis */
  mat4 head_to_world = mat4(1.0f); /* rigid */
  mat4 world_to_head = mat4(1.0f);

  int64_t vertices_num() const { return int64_t(size.x) * size.y * size.z; }
  int64_t cells_num() const
  {
    return size.x < 2 || size.y < 2 || size.z < 2 ?
               0 :
               int64_t(size.x - 1) * (size.y - 1) * (size.z - 1);
  }
  int64_t vertex_index(const int i, const int j, const int k) const
  {
    return (int64_t(k) * size.y + j) * size.x + i;
  }
  int64_t cell_index(const int i, const int j, const int k) const
  {
    return (int64_t(k) * (size.y - 1) + j) * (size.x - 1) + i;
  }
  /* Continuous grid coordinates of a world point: vertex (i, j, k) is at (i, j, k). */
  vec3 to_grid(const vec3 &p_wo) const
  {
    return transform_point(world_to_head, p_wo) / cell_size - vec3(origin);
  }
  /* Maps grid coordinates (i, j, k) to world space (for viewing the grid, e.g. as a VDB). */
  mat4 grid_to_world() const;
};

/* Axis-aligned box in head coordinates (m); empty while lo > hi. */
struct HeadBox {
  vec3 lo = vec3(std::numeric_limits<float>::max());
  vec3 hi = vec3(-std::numeric_limits<float>::max());

  void include(const HeadBox &other)
  {
    lo = glm::min(lo, other.lo);
    hi = glm::max(hi, other.hi);
  }
  bool is_empty() const { return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z; }
};

/* Box of the finite points of `positions_wo` in the head's frame. */
HeadBox head_box(Span<vec3> positions_wo, const mat4 &world_to_head);
/* The same, keeping each point in the head's frame in r_positions_head (for bin_head_points). */
HeadBox head_box(Span<vec3> positions_wo, const mat4 &world_to_head,
                 MutableSpan<vec3> r_positions_head);

/* The grid of spacing `cell_size` (coarsened to fit max_grid_vertices) covering `box` with
 * `margin` spare vertices on every side; `head_to_world` is the rigid head transform. */
GridFrame grid_around(const HeadBox &box, float cell_size, int margin, const mat4 &head_to_world);

/* Mean length of the segments of the strands (m), 0 for no segments. */
float mean_segment_length(Span<int32_t> curve_offsets, Span<vec3> positions);

/* Points located in a grid: per point, the index of the lowest vertex of its cell (-1 for a point
 * outside the grid or not finite) and its place in that cell, each coordinate in [0, 1]. */
struct PointBins {
  std::vector<int32_t> vertex_of;
  std::vector<vec3> fraction;
};

/* Points per chunk of a splat, and most chunks: set by the point count alone. */
constexpr int64_t splat_chunk_points = 32768;
constexpr int64_t max_splat_chunks = 4;

void bin_points(const GridFrame &grid, Span<vec3> positions_wo, PointBins &r_bins);
/* bin_points for points already in the grid's head frame (the same bits). */
void bin_head_points(const GridFrame &grid, Span<vec3> positions_head, PointBins &r_bins);

/* r_grid[v] = Σ_i tent(P_i, v) · value_of(i) over the located points (eq. 1 with a value per
 * point; value_of(i) ≡ 1 is the density): each point adds its tent weights to its cell's 8
 * corners. The points are cut into chunks by their count alone (never by the thread count);
 * each chunk splats in point order into its own grid (the first into r_grid, the others into
 * `scratch`), and the chunks' grids are summed in chunk order: same bits on any thread count. */
template<typename T, typename ValueFn>
void splat_to_grid(const GridFrame &grid, const PointBins &bins, const ValueFn &value_of,
                   MutableSpan<T> r_grid, std::vector<T> &scratch)
{
  const int64_t points_num = int64_t(bins.vertex_of.size());
  const int64_t vertices_num = grid.vertices_num();
  const int64_t chunks_num = std::clamp<int64_t>(
      (points_num + splat_chunk_points - 1) / splat_chunk_points, 1, max_splat_chunks);
  const int64_t chunk_size = (points_num + chunks_num - 1) / chunks_num;
  scratch.resize(size_t((chunks_num - 1) * vertices_num));
  const int64_t dy = grid.size.x, dz = int64_t(grid.size.x) * grid.size.y;
  /* Per chunk, the vertices its points reach: [lo, hi). A chunk's own grid is zeroed and summed
   * only there (nearby points of a groom are mostly neighbours in point order), which leaves
   * the sums as they would be over whole grids. */
  IndexRange reach[max_splat_chunks];
  parallel_for(chunks_num, 1, [&](const IndexRange chunks) {
    for (int64_t chunk = chunks.start; chunk < chunks.one_after_last(); chunk++) {
      const int64_t begin = chunk * chunk_size, end = std::min(points_num, begin + chunk_size);
      int64_t lo = vertices_num, hi = 0;
      for (int64_t i = begin; i < end; i++) {
        const int64_t vertex = bins.vertex_of[size_t(i)];
        if (vertex >= 0) {
          lo = std::min(lo, vertex);
          hi = std::max(hi, vertex + dz + dy + 2);
        }
      }
      T *out = r_grid.data();
      if (chunk == 0) {
        std::fill(out, out + vertices_num, T(0.0f));
      }
      else {
        out = scratch.data() + (chunk - 1) * vertices_num;
        std::fill(out + std::min(lo, hi), out + hi, T(0.0f));
      }
      reach[chunk] = IndexRange{std::min(lo, hi), hi - std::min(lo, hi)};
      for (int64_t i = begin; i < end; i++) {
        const int32_t vertex = bins.vertex_of[size_t(i)];
        if (vertex < 0) {
          continue;
        }
        const vec3 f = bins.fraction[size_t(i)];
        const T value = value_of(i);
        const float wy[2] = {1.0f - f.y, f.y}, wz[2] = {1.0f - f.z, f.z};
        T *base = out + vertex;
        if constexpr (std::is_same_v<T, vec4>) {
          /* The same operations lane by lane (lanes4.hh). */
          /* Built from the values' registers: a 16-byte load of a vec4 just written in pieces
           * would stall on store forwarding. */
          const Lanes4 lanes = Lanes4::set(value.x, value.y, value.z, value.w);
          const Lanes4 wx0 = Lanes4::splat(1.0f - f.x), wx1 = Lanes4::splat(f.x);
          for (int c = 0; c < 4; c++) {
            const Lanes4 row = Lanes4::splat(wy[c & 1] * wz[c >> 1]) * lanes;
            T *at = base + (c & 1) * dy + (c >> 1) * dz;
            (Lanes4::load(at[0]) + wx0 * row).store(at[0]);
            (Lanes4::load(at[1]) + wx1 * row).store(at[1]);
          }
        }
        else {
          for (int c = 0; c < 4; c++) {
            const T row = (wy[c & 1] * wz[c >> 1]) * value;
            T *at = base + (c & 1) * dy + (c >> 1) * dz;
            at[0] += (1.0f - f.x) * row;
            at[1] += f.x * row;
          }
        }
      }
    }
  });
  if (chunks_num > 1) {
    parallel_for(vertices_num, grid_grain, [&](const IndexRange range) {
      for (int64_t chunk = 1; chunk < chunks_num; chunk++) {
        const T *values = scratch.data() + (chunk - 1) * vertices_num;
        const int64_t lo = std::max(range.start, reach[chunk].start);
        const int64_t hi = std::min(range.one_after_last(), reach[chunk].one_after_last());
        if constexpr (std::is_same_v<T, vec4>) {
          for (int64_t v = lo; v < hi; v++) {
            (Lanes4::load(r_grid[v]) + Lanes4::load(values[v])).store(r_grid[v]);
          }
        }
        else {
          for (int64_t v = lo; v < hi; v++) {
            r_grid[v] += values[v];
          }
        }
      }
    });
  }
}

/* eq. 1: the density of the located points. */
void splat_density(const GridFrame &grid, const PointBins &bins, MutableSpan<float> r_density,
                   std::vector<float> &scratch);

/* The cell holding grid coordinates `p` and the fractions within it; false outside. A point on
 * the last vertex plane belongs to the last cell, at fraction 1. */
inline bool locate(const GridFrame &grid, const vec3 &p, ivec3 &r_cell, vec3 &r_fraction)
{
  if (!(p.x >= 0.0f && p.y >= 0.0f && p.z >= 0.0f && p.x <= float(grid.size.x - 1) &&
        p.y <= float(grid.size.y - 1) && p.z <= float(grid.size.z - 1)) ||
      grid.cells_num() == 0)
  {
    return false;
  }
  r_cell = glm::min(ivec3(p), grid.size - 2); /* p ≥ 0: truncation is the floor */
  r_fraction = p - vec3(r_cell);
  return true;
}

/* sample_cell below on a grid of vec4, in lanes (lanes4.hh): the same bits. */
inline Lanes4 sample_cell_lanes(const GridFrame &grid, const Span<vec4> values,
                                const int64_t vertex, const vec3 &f)
{
  const int64_t dy = grid.size.x, dz = int64_t(grid.size.x) * grid.size.y;
  const vec4 *v = values.data() + vertex;
  /* The eight corner weights wx·wy·wz in two registers: the same products as sample_cell. */
  const float gx = 1.0f - f.x, gy = 1.0f - f.y;
  const Lanes4 wxy = Lanes4::set(gx, f.x, gx, f.x) * Lanes4::set(gy, gy, f.y, f.y);
  const Lanes4 w0 = wxy * Lanes4::splat(1.0f - f.z), w1 = wxy * Lanes4::splat(f.z);
  Lanes4 sum = Lanes4::zero();
  sum = sum + w0.broadcast<0>() * Lanes4::load(v[0]);
  sum = sum + w0.broadcast<1>() * Lanes4::load(v[1]);
  sum = sum + w0.broadcast<2>() * Lanes4::load(v[dy]);
  sum = sum + w0.broadcast<3>() * Lanes4::load(v[dy + 1]);
  sum = sum + w1.broadcast<0>() * Lanes4::load(v[dz]);
  sum = sum + w1.broadcast<1>() * Lanes4::load(v[dz + 1]);
  sum = sum + w1.broadcast<2>() * Lanes4::load(v[dz + dy]);
  sum = sum + w1.broadcast<3>() * Lanes4::load(v[dz + dy + 1]);
  return sum;
}

/* Trilinear interpolation (the tent weights of eq. 1 read back) in the cell whose lowest vertex
 * is `vertex`, at place `f` in it. */
template<typename T>
T sample_cell(const GridFrame &grid, const Span<T> values, const int64_t vertex, const vec3 &f)
{
  const int64_t dy = grid.size.x, dz = int64_t(grid.size.x) * grid.size.y;
  const T *v = values.data() + vertex;
  const float wx[2] = {1.0f - f.x, f.x}, wy[2] = {1.0f - f.y, f.y}, wz[2] = {1.0f - f.z, f.z};
  const float wxy[4] = { wx[0] * wy[0], wx[1] * wy[0], wx[0] * wy[1], wx[1] * wy[1] };
  if constexpr (std::is_same_v<T, vec4>) {
    return sample_cell_lanes(grid, values, vertex, f).to_vec4();
  }
  else {
    T sum(0.0f);
    for (int c = 0; c < 8; c++) {
      const int x = c & 1, y = (c >> 1) & 1, z = c >> 2;
      sum += (wxy[c & 3] * wz[z]) * v[x + y * dy + z * dz];
    }
    return sum;
  }
}

/* The same at grid coordinates `p`; T(0) outside the grid. */
template<typename T> T sample_grid(const GridFrame &grid, Span<T> values, const vec3 &p)
{
  ivec3 cell;
  vec3 f;
  if (!locate(grid, p, cell, f)) {
    return T(0.0f);
  }
  return sample_cell(grid, values, grid.vertex_index(cell.x, cell.y, cell.z), f);
}

/* Separable binomial filter of radius r (weights C(2r, r + k) / 4^r along each axis, zero
 * outside the grid): symmetric, and it keeps the sum of values away from the border. The
 * result is left in `values` by swapping it with `scratch` (spans over either are stale). */
template<typename T>
void blur_binomial(const ivec3 &size, int radius, std::vector<T> &values, std::vector<T> &scratch);

/* The values of grid `from` at the vertices of grid `to` (same cell size: the lattices
 * coincide), 0 where `from` has no vertex. */
void copy_between_grids(const GridFrame &from, Span<float> values, const GridFrame &to,
                        MutableSpan<float> r_values);

/* fn(i) for every point i that a pass may move: all of them when `curve_offsets` is empty,
 * otherwise all but each strand's root (SubstepState: roots are carried by the head). */
template<typename Fn>
void for_each_free_point(Span<int32_t> curve_offsets, const int64_t points_num, const Fn &fn)
{
  if (curve_offsets.is_empty()) {
    parallel_for(points_num, point_grain, [&](const IndexRange range) {
      for (int64_t i = range.start; i < range.one_after_last(); i++) {
        fn(i);
      }
    });
    return;
  }
  parallel_for(curve_offsets.size() - 1, 512, [&](const IndexRange range) {
    for (int64_t curve = range.start; curve < range.one_after_last(); curve++) {
      for (int64_t i = curve_offsets[curve] + 1; i < curve_offsets[curve + 1]; i++) {
        fn(i);
      }
    }
  });
}

/* Largest value, 0 for none. */
float max_value(Span<float> values);

}  // namespace hairdyn
