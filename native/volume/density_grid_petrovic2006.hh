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
 * Splatting is a gather: points are sorted by cell (stable, by index), and each vertex sums the
 * points of its 8 adjacent cells in that order, so the result has the same bits on any thread
 * count. */
#include <cstdint>
#include <limits>
#include <vector>

#include "core/math.hh"
#include "core/parallel.hh"
#include "core/span.hh"

namespace hairdyn {

/* Most vertices a grid may have (2^22, 16 MB of floats); a box that would need more takes the
 * smallest power-of-two multiple of the cell size that fits. */
constexpr int64_t max_grid_vertices = int64_t(1) << 22;

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

/* The grid of spacing `cell_size` (coarsened to fit max_grid_vertices) covering `box` with
 * `margin` spare vertices on every side; `head_to_world` is the rigid head transform. */
GridFrame grid_around(const HeadBox &box, float cell_size, int margin, const mat4 &head_to_world);

/* Mean length of the segments of the strands (m), 0 for no segments. */
float mean_segment_length(Span<int32_t> curve_offsets, Span<vec3> positions);

/* Points sorted by grid cell. Points outside the grid (or not finite) are in no cell. */
struct PointBins {
  std::vector<vec3> coords;         /* per point: grid coordinates */
  std::vector<int32_t> cell_of;     /* per point: cell index, or -1 outside */
  std::vector<int32_t> cell_start;  /* per cell c: its points are points[cell_start[c] ..
                                       cell_start[c + 1]) */
  std::vector<int32_t> points;      /* point indices, by cell, ascending within a cell */
};

void bin_points(const GridFrame &grid, Span<vec3> positions_wo, PointBins &r_bins);

/* eq. 1's tent weight of a point at grid coordinates `p` for the vertex at `v`. */
inline float tent_weight(const vec3 &p, const vec3 &v)
{
  const vec3 d = glm::abs(p - v);
  return (1.0f - d.x) * (1.0f - d.y) * (1.0f - d.z);
}

/* r_grid[v] = Σ_i tent(P_i, v) · value_of(i) over the binned points (eq. 1 with a value per
 * point; value_of(i) ≡ 1 is the density). */
template<typename T, typename ValueFn>
void splat_to_grid(const GridFrame &grid, const PointBins &bins, const ValueFn &value_of,
                   MutableSpan<T> r_grid)
{
  const ivec3 n = grid.size;
  parallel_for(n.z, 1, [&](const IndexRange slices) {
    for (int k = int(slices.start); k < int(slices.one_after_last()); k++) {
      for (int j = 0; j < n.y; j++) {
        for (int i = 0; i < n.x; i++) {
          const vec3 vertex = vec3(float(i), float(j), float(k));
          T sum(0.0f);
          for (int ck = k - 1; ck <= k; ck++) {
            for (int cj = j - 1; cj <= j; cj++) {
              for (int ci = i - 1; ci <= i; ci++) {
                if (ci < 0 || cj < 0 || ck < 0 || ci >= n.x - 1 || cj >= n.y - 1 ||
                    ck >= n.z - 1) {
                  continue;
                }
                const int64_t cell = grid.cell_index(ci, cj, ck);
                for (int32_t slot = bins.cell_start[size_t(cell)];
                     slot < bins.cell_start[size_t(cell) + 1]; slot++)
                {
                  const int32_t point = bins.points[size_t(slot)];
                  sum += tent_weight(bins.coords[size_t(point)], vertex) * value_of(point);
                }
              }
            }
          }
          r_grid[grid.vertex_index(i, j, k)] = sum;
        }
      }
    }
  });
}

/* eq. 1: the density of the binned points. */
void splat_density(const GridFrame &grid, const PointBins &bins, MutableSpan<float> r_density);

/* The cell holding grid coordinates `p` and the fractions within it; false outside. */
bool locate(const GridFrame &grid, const vec3 &p, ivec3 &r_cell, vec3 &r_fraction);

/* Trilinear interpolation of vertex values at grid coordinates `p` (the tent weights of eq. 1
 * read back); T(0) outside the grid. */
template<typename T> T sample_grid(const GridFrame &grid, Span<T> values, const vec3 &p)
{
  ivec3 cell;
  vec3 f;
  if (!locate(grid, p, cell, f)) {
    return T(0.0f);
  }
  T sum(0.0f);
  for (int c = 0; c < 8; c++) {
    const ivec3 corner = ivec3(c & 1, (c >> 1) & 1, (c >> 2) & 1);
    const float w = (corner.x ? f.x : 1.0f - f.x) * (corner.y ? f.y : 1.0f - f.y) *
                    (corner.z ? f.z : 1.0f - f.z);
    sum += w * values[grid.vertex_index(cell.x + corner.x, cell.y + corner.y, cell.z + corner.z)];
  }
  return sum;
}

/* Separable binomial filter of radius r (weights C(2r, r + k) / 4^r along each axis, zero
 * outside the grid): symmetric, and it keeps the sum of values away from the border. */
template<typename T>
void blur_binomial(const ivec3 &size, int radius, MutableSpan<T> values, std::vector<T> &scratch);

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
    parallel_for(points_num, 4096, [&](const IndexRange range) {
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
