#pragma once
/* Neighbour search on a uniform grid of cells, rebuilt from scratch whenever the points move
 * (linear time: one counting sort). Cells are hashed into a table about twice the point
 * count, so the memory does not depend on how far apart the points are. No cap on the
 * number of neighbours: lists are compressed rows (offsets + indices) of any length. */
#include <cstdint>
#include <vector>

#include "core/math.hh"
#include "core/span.hh"

namespace hairdyn {

struct NeighborList;

class SpatialGrid {
 public:
  /* Sorts `points` into cells of edge `cell_size` (> 0). Queries of radius ≤ cell_size visit
   * the 27 cells around a point. The grid keeps a view of `points`: they must outlive it and
   * stay unchanged until the next build. */
  void build(Span<vec3> points, float cell_size);

  /* Calls fn(j) for every point j with ‖points[j] − p‖ < radius (radius ≤ cell_size), in a
   * fixed order (the 27 cells around p in turn, then by index). */
  template<typename Fn> void for_each_in_radius(const vec3 &p, const float radius, Fn &&fn) const
  {
    const float radius_sq = radius * radius;
    for_each_around_cell(cell_of(p), [&](const int64_t k) {
      const vec3 d = sorted_points_[size_t(k)] - p;
      if (glm::dot(d, d) < radius_sq) {
        fn(sorted_indices_[size_t(k)]);
      }
    });
  }

  float cell_size() const { return cell_size_; }
  Span<vec3> points() const { return points_; }

  /* find_neighbors of the grid's own points (i not its own neighbour), cell by cell: the
   * points of the 27 cells around a cell are gathered once, into contiguous arrays, for all the
   * points of that cell. */
  void own_neighbors(float radius, NeighborList &r_list) const;

 private:
  ivec3 cell_of(const vec3 &p) const;
  /* Calls fn(k) for the sorted position k of every point in the 27 cells around `center`, the
   * cells in turn, then by index. */
  template<typename Fn> void for_each_around_cell(const ivec3 &center, Fn &&fn) const
  {
    for (int32_t dz = -1; dz <= 1; dz++) {
      for (int32_t dy = -1; dy <= 1; dy++) {
        for (int32_t dx = -1; dx <= 1; dx++) {
          const ivec3 cell = center + ivec3(dx, dy, dz);
          const uint32_t bucket = bucket_of_cell(cell);
          for (int32_t k = bucket_offsets_[bucket]; k < bucket_offsets_[bucket + 1]; k++) {
            /* A bucket may hold other cells' points too (hash collisions): skip them, so
             * that a bucket shared by two of the 27 cells yields each point once. */
            if (sorted_cells_[size_t(k)] == cell) {
              fn(int64_t(k));
            }
          }
        }
      }
    }
  }
  uint32_t bucket_of_cell(const ivec3 &cell) const
  {
    /* Teschner et al. 2003 spatial hash. */
    const uint32_t h = (uint32_t(cell.x) * 73856093u) ^ (uint32_t(cell.y) * 19349663u) ^
                       (uint32_t(cell.z) * 83492791u);
    return h & bucket_mask_;
  }

  Span<vec3> points_;
  float cell_size_ = 1.0f;
  uint32_t bucket_mask_ = 0;
  std::vector<int32_t> bucket_offsets_;
  /* Points sorted by bucket: their indices, cells and positions (copied, for locality). */
  std::vector<int32_t> sorted_indices_;
  std::vector<ivec3> sorted_cells_;
  std::vector<vec3> sorted_points_;
  std::vector<uint32_t> point_buckets_;
  std::vector<ivec3> point_cells_;
};

/* Neighbours of each query point as compressed rows: the neighbours of point i are
 * indices[offsets[i] .. offsets[i + 1]). Buffers are reused from step to step. */
struct NeighborList {
  std::vector<int32_t> offsets;
  std::vector<int32_t> indices;
  /* Per-chunk scratch for the parallel fill: the rows' neighbours, and (when rows are filled
   * out of order) the point of each row. */
  std::vector<std::vector<int32_t>> chunk_indices, chunk_rows;

  Span<int32_t> neighbors_of(const int64_t i) const
  {
    return Span<int32_t>(indices.data() + offsets[i], offsets[i + 1] - offsets[i]);
  }
  int64_t size() const { return int64_t(offsets.size()) - 1; }
};

/* For every query point, the grid's points closer than `radius` (≤ grid.cell_size()).
 * `exclude_self`: the query points are the grid's own points and i is not its own neighbour.
 * Deterministic for any thread count. */
void find_neighbors(const SpatialGrid &grid, Span<vec3> query_points, float radius,
                    bool exclude_self, NeighborList &r_list);

/* The neighbours of a moving point set within `radius` of each other, kept as a Verlet list
 * (Verlet 1967): found within radius + skin and reused until some point has moved more than
 * skin / 2 since, so that no pair closer than `radius` can be missing (two points close by at
 * most twice the largest displacement). Rows may hold points up to radius + skin away: users
 * test the distance. */
class VerletNeighbors {
 public:
  /* The list for `points` (the grid's own points, i not its own neighbour), rebuilt when a
   * point has moved too far, the point count or the radii changed, or after invalidate().
   * True when it was rebuilt. */
  bool update(Span<vec3> points, float radius, float skin);
  void invalidate() { built_at_.clear(); }
  const NeighborList &list() const { return list_; }
  /* Rebuilds since the list was made (for the benchmarks' counters). */
  int64_t builds() const { return builds_; }

 private:
  SpatialGrid grid_;
  NeighborList list_;
  std::vector<vec3> built_at_;
  float radius_ = 0.0f, skin_ = 0.0f;
  int64_t builds_ = 0;
};

}  // namespace hairdyn
