#include "core/spatial_grid.hh"

#include <algorithm>
#include <cmath>

#include "core/parallel.hh"

namespace hairdyn {

static int32_t cell_coordinate(const float x, const float cell_size)
{
  /* Clamped so that exploded (but finite) states still hash instead of overflowing. */
  const float c = std::floor(x / cell_size);
  return int32_t(std::clamp(c, -1.0e9f, 1.0e9f));
}

ivec3 SpatialGrid::cell_of(const vec3 &p) const
{
  return ivec3(cell_coordinate(p.x, cell_size_), cell_coordinate(p.y, cell_size_),
               cell_coordinate(p.z, cell_size_));
}

void SpatialGrid::build(const Span<vec3> points, const float cell_size)
{
  assert(cell_size > 0.0f);
  points_ = points;
  cell_size_ = cell_size;
  uint32_t buckets_num = 64;
  while (buckets_num < uint32_t(2 * points.size()) && buckets_num < (1u << 30)) {
    buckets_num <<= 1;
  }
  bucket_mask_ = buckets_num - 1;

  point_buckets_.resize(size_t(points.size()));
  point_cells_.resize(size_t(points.size()));
  parallel_for(points.size(), 4096, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      point_cells_[size_t(i)] = cell_of(points[i]);
      point_buckets_[size_t(i)] = bucket_of_cell(point_cells_[size_t(i)]);
    }
  });
  /* Counting sort by bucket: stable, so indices inside a bucket stay in increasing order. */
  bucket_offsets_.assign(size_t(buckets_num) + 1, 0);
  for (const uint32_t b : point_buckets_) {
    bucket_offsets_[b + 1]++;
  }
  for (size_t b = 0; b < buckets_num; b++) {
    bucket_offsets_[b + 1] += bucket_offsets_[b];
  }
  sorted_indices_.resize(size_t(points.size()));
  std::vector<int32_t> &fill = sorted_indices_;
  std::vector<int32_t> cursor(bucket_offsets_.begin(), bucket_offsets_.end() - 1);
  for (int64_t i = 0; i < points.size(); i++) {
    fill[size_t(cursor[point_buckets_[size_t(i)]]++)] = int32_t(i);
  }
  sorted_cells_.resize(size_t(points.size()));
  sorted_points_.resize(size_t(points.size()));
  parallel_for(points.size(), 4096, [&](const IndexRange range) {
    for (int64_t k = range.start; k < range.one_after_last(); k++) {
      sorted_cells_[size_t(k)] = point_cells_[size_t(sorted_indices_[size_t(k)])];
      sorted_points_[size_t(k)] = points[sorted_indices_[size_t(k)]];
    }
  });
}

void SpatialGrid::own_neighbors(const float radius, NeighborList &r_list) const
{
  assert(radius <= cell_size_ * 1.0001f);
  const int64_t size = points_.size();
  const int64_t buckets_num = int64_t(bucket_mask_) + 1;
  const int64_t grain = 1024;
  const int64_t chunks_num = (buckets_num + grain - 1) / grain;
  r_list.offsets.assign(size_t(size) + 1, 0);
  for (auto *scratch : { &r_list.chunk_indices, &r_list.chunk_rows }) {
    if (int64_t(scratch->size()) < chunks_num) {
      scratch->resize(size_t(chunks_num));
    }
  }
  const float radius_sq = radius * radius;
  parallel_for(buckets_num, grain, [&](const IndexRange range) {
    std::vector<int32_t> &indices = r_list.chunk_indices[size_t(range.start / grain)];
    std::vector<int32_t> &rows = r_list.chunk_rows[size_t(range.start / grain)];
    indices.clear();
    rows.clear();
    std::vector<vec3> candidates;
    std::vector<int32_t> candidate_ids;
    for (int64_t b = range.start; b < range.one_after_last(); b++) {
      const int32_t begin = bucket_offsets_[size_t(b)], end = bucket_offsets_[size_t(b) + 1];
      for (int32_t k = begin; k < end; k++) {
        /* Each cell of the bucket once (a bucket may hold several cells: hash collisions). */
        const ivec3 cell = sorted_cells_[size_t(k)];
        if (std::find(sorted_cells_.begin() + begin, sorted_cells_.begin() + k, cell) !=
            sorted_cells_.begin() + k)
        {
          continue;
        }
        candidates.clear();
        candidate_ids.clear();
        for_each_around_cell(cell, [&](const int64_t m) {
          candidates.push_back(sorted_points_[size_t(m)]);
          candidate_ids.push_back(sorted_indices_[size_t(m)]);
        });
        for (int32_t q = k; q < end; q++) {
          if (sorted_cells_[size_t(q)] != cell) {
            continue;
          }
          const int32_t i = sorted_indices_[size_t(q)];
          const vec3 p = sorted_points_[size_t(q)];
          /* Without a branch per candidate (a quarter of them are neighbours, at random):
           * every candidate is written, the count moves past the neighbours only. */
          const size_t before = indices.size();
          indices.resize(before + candidates.size());
          int32_t *out = indices.data() + before;
          size_t count = 0;
          for (size_t m = 0; m < candidates.size(); m++) {
            const vec3 d = candidates[m] - p;
            out[count] = candidate_ids[m];
            count += size_t((glm::dot(d, d) < radius_sq) & (candidate_ids[m] != i));
          }
          indices.resize(before + count);
          r_list.offsets[size_t(i) + 1] = int32_t(count);
          rows.push_back(i);
        }
      }
    }
  });
  for (int64_t i = 0; i < size; i++) {
    r_list.offsets[size_t(i) + 1] += r_list.offsets[size_t(i)];
  }
  r_list.indices.resize(size_t(r_list.offsets[size_t(size)]));
  parallel_for(chunks_num, 1, [&](const IndexRange range) {
    for (int64_t c = range.start; c < range.one_after_last(); c++) {
      const std::vector<int32_t> &indices = r_list.chunk_indices[size_t(c)];
      size_t cursor = 0;
      for (const int32_t i : r_list.chunk_rows[size_t(c)]) {
        const int32_t count = r_list.offsets[size_t(i) + 1] - r_list.offsets[size_t(i)];
        std::copy(indices.begin() + int64_t(cursor), indices.begin() + int64_t(cursor) + count,
                  r_list.indices.begin() + r_list.offsets[size_t(i)]);
        cursor += size_t(count);
      }
    }
  });
}

void find_neighbors(const SpatialGrid &grid, const Span<vec3> query_points, const float radius,
                    const bool exclude_self, NeighborList &r_list)
{
  assert(radius <= grid.cell_size() * 1.0001f);
  if (exclude_self && query_points.data() == grid.points().data() &&
      query_points.size() == grid.points().size())
  {
    grid.own_neighbors(radius, r_list);
    return;
  }
  const int64_t size = query_points.size();
  const int64_t grain = 512;
  const int64_t chunks_num = std::max<int64_t>(1, (size + grain - 1) / grain);
  r_list.offsets.assign(size_t(size) + 1, 0);
  if (int64_t(r_list.chunk_indices.size()) < chunks_num) {
    r_list.chunk_indices.resize(size_t(chunks_num));
  }
  parallel_for(size, grain, [&](const IndexRange range) {
    std::vector<int32_t> &chunk = r_list.chunk_indices[size_t(range.start / grain)];
    chunk.clear();
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      const size_t before = chunk.size();
      grid.for_each_in_radius(query_points[i], radius, [&](const int32_t j) {
        if (!(exclude_self && j == i)) {
          chunk.push_back(j);
        }
      });
      r_list.offsets[size_t(i) + 1] = int32_t(chunk.size() - before);
    }
  });
  for (int64_t i = 0; i < size; i++) {
    r_list.offsets[size_t(i) + 1] += r_list.offsets[size_t(i)];
  }
  r_list.indices.resize(size_t(r_list.offsets[size_t(size)]));
  parallel_for(chunks_num, 1, [&](const IndexRange range) {
    for (int64_t c = range.start; c < range.one_after_last(); c++) {
      if (c * grain >= size) {
        continue;
      }
      const std::vector<int32_t> &chunk = r_list.chunk_indices[size_t(c)];
      std::copy(chunk.begin(), chunk.end(),
                r_list.indices.begin() + r_list.offsets[size_t(c * grain)]);
    }
  });
}

bool VerletNeighbors::update(const Span<vec3> points, const float radius, const float skin)
{
  bool valid = int64_t(built_at_.size()) == points.size() && radius == radius_ && skin == skin_;
  if (valid) {
    const float limit_sq = 0.25f * skin * skin;
    /* Written so that a NaN position fails the test and forces a rebuild. */
    valid = parallel_reduce(
        points.size(), 4096, true,
        [&](const IndexRange range) {
          for (int64_t i = range.start; i < range.one_after_last(); i++) {
            const vec3 d = points[i] - built_at_[size_t(i)];
            if (!(glm::dot(d, d) <= limit_sq)) {
              return false;
            }
          }
          return true;
        },
        [](const bool a, const bool b) {
          return a && b;
        });
  }
  if (valid) {
    return false;
  }
  grid_.build(points, radius + skin);
  find_neighbors(grid_, points, radius + skin, true, list_);
  built_at_.assign(points.begin(), points.end());
  radius_ = radius;
  skin_ = skin;
  builds_++;
  return true;
}

}  // namespace hairdyn
