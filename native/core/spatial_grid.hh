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

class SpatialGrid {
 public:
  /* Sorts `points` into cells of edge `cell_size` (> 0). Queries of radius ≤ cell_size visit
   * the 27 cells around a point. The grid keeps a view of `points`: they must outlive it and
   * stay unchanged until the next build. */
  void build(Span<vec3> points, float cell_size);

  /* Calls fn(j) for every point j with ‖points[j] − p‖ < radius (radius ≤ cell_size), in a
   * fixed order (by cell bucket, then by index). */
  template<typename Fn> void for_each_in_radius(const vec3 &p, const float radius, Fn &&fn) const
  {
    int32_t buckets[27];
    const int buckets_num = neighbor_buckets(p, buckets);
    const float radius_sq = radius * radius;
    for (int b = 0; b < buckets_num; b++) {
      for (int32_t k = bucket_offsets_[buckets[b]]; k < bucket_offsets_[buckets[b] + 1]; k++) {
        const int32_t j = sorted_indices_[k];
        const vec3 d = points_[j] - p;
        if (glm::dot(d, d) < radius_sq) {
          fn(j);
        }
      }
    }
  }

  float cell_size() const { return cell_size_; }
  Span<vec3> points() const { return points_; }

 private:
  /* The distinct hash buckets of the 27 cells around p, sorted; returns their count. */
  int neighbor_buckets(const vec3 &p, int32_t r_buckets[27]) const;
  uint32_t bucket_of_cell(int32_t x, int32_t y, int32_t z) const;

  Span<vec3> points_;
  float cell_size_ = 1.0f;
  uint32_t bucket_mask_ = 0;
  std::vector<int32_t> bucket_offsets_;
  std::vector<int32_t> sorted_indices_;
  std::vector<uint32_t> point_buckets_;
};

/* Neighbours of each query point as compressed rows: the neighbours of point i are
 * indices[offsets[i] .. offsets[i + 1]). Buffers are reused from step to step. */
struct NeighborList {
  std::vector<int32_t> offsets;
  std::vector<int32_t> indices;
  /* Per-chunk scratch for the parallel fill. */
  std::vector<std::vector<int32_t>> chunk_indices;

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

}  // namespace hairdyn
