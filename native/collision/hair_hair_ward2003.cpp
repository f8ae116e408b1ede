#include "collision/hair_hair_ward2003.hh"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "core/parallel.hh"

namespace hairdyn {

namespace {

uint32_t hash_cell(const ivec3 &cell)
{
  /* Teschner et al. 2003 spatial hash, as core/spatial_grid. */
  return (uint32_t(cell.x) * 73856093u) ^ (uint32_t(cell.y) * 19349663u) ^
         (uint32_t(cell.z) * 83492791u);
}

/* Segments, their boxes and cells, and the grid entries sorted by hashed cell (§5.3: "insert
 * each SSV of the hair into the grids"). Returns false when there is no segment. */
bool build_grid(const Span<int32_t> curve_offsets, const Span<vec3> positions,
                const Span<float> radii, const float default_radius, SegmentGridScratch &g)
{
  const int64_t curves_num = curve_offsets.size() - 1;
  g.point_curve.resize(size_t(positions.size()));
  g.segments.clear();
  for (int64_t c = 0; c < curves_num; c++) {
    for (int32_t p = curve_offsets[c]; p < curve_offsets[c + 1]; p++) {
      g.point_curve[size_t(p)] = int32_t(c);
      if (p + 1 < curve_offsets[c + 1]) {
        g.segments.push_back({vec3(0.0f), vec3(0.0f), ivec3(0), p, int32_t(c), 0.0f});
      }
    }
  }
  const int64_t segments_num = int64_t(g.segments.size());
  if (segments_num == 0) {
    return false;
  }
  g.entry_offsets.resize(size_t(segments_num) + 1);

  /* The cell edge: the mean segment length (§5.3), never so small that the cell indices of
   * the groom's extent overflow. */
  const double length_sum = parallel_sum(segments_num, 4096, [&](const IndexRange range) {
    double sum = 0.0;
    for (int64_t k = range.start; k < range.one_after_last(); k++) {
      const int32_t p = g.segments[size_t(k)].point;
      sum += double(glm::length(positions[p + 1] - positions[p]));
    }
    return sum;
  });
  vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  for (const vec3 &p : positions) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  const vec3 extent = hi - lo;
  const float largest = std::max(extent.x, std::max(extent.y, extent.z));
  float cell = float(length_sum / double(segments_num));
  cell = std::max({cell, largest * 1e-6f, 1e-9f});
  g.cell_size = cell;
  const float inv_cell = 1.0f / cell;

  parallel_for(segments_num, 2048, [&](const IndexRange range) {
    for (int64_t k = range.start; k < range.one_after_last(); k++) {
      SegmentGridScratch::Segment &seg = g.segments[size_t(k)];
      const int32_t p = seg.point;
      const float r = radii.is_empty() ? default_radius : 0.5f * (radii[p] + radii[p + 1]);
      seg.radius = r;
      const vec3 a = positions[p] - lo, b = positions[p + 1] - lo;
      seg.box_min = glm::min(a, b) - vec3(r);
      seg.box_max = glm::max(a, b) + vec3(r);
      const ivec3 c0 = ivec3(glm::floor(seg.box_min * inv_cell));
      const ivec3 c1 = ivec3(glm::floor(seg.box_max * inv_cell));
      seg.cell_min = c0;
      const ivec3 n = c1 - c0 + ivec3(1);
      g.entry_offsets[size_t(k) + 1] = int64_t(n.x) * n.y * n.z;
    }
  });
  g.entry_offsets[0] = 0;
  for (int64_t k = 0; k < segments_num; k++) {
    g.entry_offsets[size_t(k) + 1] += g.entry_offsets[size_t(k)];
  }
  const int64_t entries_num = g.entry_offsets.back();
  g.entry_cells.resize(size_t(entries_num));
  parallel_for(segments_num, 2048, [&](const IndexRange range) {
    for (int64_t k = range.start; k < range.one_after_last(); k++) {
      const ivec3 c0 = g.segments[size_t(k)].cell_min;
      const ivec3 c1 = ivec3(glm::floor(g.segments[size_t(k)].box_max * inv_cell));
      int64_t e = g.entry_offsets[size_t(k)];
      for (int32_t z = c0.z; z <= c1.z; z++) {
        for (int32_t y = c0.y; y <= c1.y; y++) {
          for (int32_t x = c0.x; x <= c1.x; x++) {
            g.entry_cells[size_t(e++)] = ivec3(x, y, z);
          }
        }
      }
    }
  });

  /* Counting sort of the entries by hashed cell, stable: a bucket lists its segments in
   * increasing order. */
  uint32_t buckets_num = 1024;
  while (int64_t(buckets_num) < 2 * entries_num) {
    buckets_num *= 2;
  }
  const uint32_t mask = buckets_num - 1;
  g.bucket_offsets.assign(size_t(buckets_num) + 1, 0);
  for (int64_t e = 0; e < entries_num; e++) {
    g.bucket_offsets[(hash_cell(g.entry_cells[size_t(e)]) & mask) + 1]++;
  }
  for (uint32_t b = 0; b < buckets_num; b++) {
    g.bucket_offsets[b + 1] += g.bucket_offsets[b];
  }
  g.sorted_entries.resize(size_t(entries_num));
  g.sorted_cells.resize(size_t(entries_num));
  std::vector<uint32_t> &fill = g.fill;
  fill.assign(g.bucket_offsets.begin(), g.bucket_offsets.end() - 1);
  for (int64_t k = 0; k < segments_num; k++) {
    for (int64_t e = g.entry_offsets[size_t(k)]; e < g.entry_offsets[size_t(k) + 1]; e++) {
      const ivec3 entry_cell = g.entry_cells[size_t(e)];
      const uint32_t slot = fill[hash_cell(entry_cell) & mask]++;
      g.sorted_entries[slot] = int32_t(k);
      g.sorted_cells[slot] = entry_cell;
    }
  }
  /* Within a bucket, by the lower x of the boxes (sweep and prune along x, ties by segment). */
  parallel_for(int64_t(buckets_num), 4096, [&](const IndexRange range) {
    std::vector<std::pair<float, uint32_t>> order;
    std::vector<int32_t> entries;
    std::vector<ivec3> cells;
    for (int64_t b = range.start; b < range.one_after_last(); b++) {
      const uint32_t begin = g.bucket_offsets[size_t(b)], end = g.bucket_offsets[size_t(b) + 1];
      if (end - begin < 2) {
        continue;
      }
      order.clear();
      for (uint32_t e = begin; e < end; e++) {
        order.push_back({g.segments[size_t(g.sorted_entries[e])].box_min.x, e});
      }
      std::sort(order.begin(), order.end(), [&](const auto &p, const auto &q) {
        return p.first < q.first ||
               (p.first == q.first && g.sorted_entries[p.second] < g.sorted_entries[q.second]);
      });
      entries.resize(order.size());
      cells.resize(order.size());
      for (size_t i = 0; i < order.size(); i++) {
        entries[i] = g.sorted_entries[order[i].second];
        cells[i] = g.sorted_cells[order[i].second];
      }
      std::copy(entries.begin(), entries.end(), g.sorted_entries.begin() + begin);
      std::copy(cells.begin(), cells.end(), g.sorted_cells.begin() + begin);
    }
  });
  g.sorted_max_x.resize(size_t(entries_num));
  g.sorted_min_x.resize(size_t(entries_num));
  for (int64_t e = 0; e < entries_num; e++) {
    g.sorted_min_x[size_t(e)] = g.segments[size_t(g.sorted_entries[size_t(e)])].box_min.x;
    g.sorted_max_x[size_t(e)] = g.segments[size_t(g.sorted_entries[size_t(e)])].box_max.x;
  }
  return true;
}

/* Weights that move the point a + s (b − a) by exactly δ when a moves by w0 δ and b by w1 δ,
 * with the smallest change of the two nodes. */
std::pair<float, float> barycentric_weights(const float s)
{
  const float w0 = 1.0f - s, w1 = s;
  const float norm = w0 * w0 + w1 * w1;
  return {w0 / norm, w1 / norm};
}

}  // namespace

void find_segment_contacts(const Span<int32_t> curve_offsets, const Span<vec3> positions,
                           const Span<float> radii, const float default_radius,
                           const bool different_strands_only, SegmentGridScratch &g,
                           std::vector<SegmentContact> &r_contacts)
{
  r_contacts.clear();
  g.candidate_pairs_num = 0;
  if (!build_grid(curve_offsets, positions, radii, default_radius, g)) {
    return;
  }
  const int64_t buckets_num = int64_t(g.bucket_offsets.size()) - 1;
  /* Fixed chunks of buckets (independent of the thread count), each with its own list. */
  const int64_t grain = std::max<int64_t>(buckets_num / 256, 64);
  const int64_t chunks_num = (buckets_num + grain - 1) / grain;
  g.chunk_contacts.resize(size_t(chunks_num));
  const int64_t candidates = parallel_reduce(
      chunks_num, 1, int64_t(0),
      [&](const IndexRange chunks) {
        int64_t tested = 0;
        for (int64_t chunk = chunks.start; chunk < chunks.one_after_last(); chunk++) {
          std::vector<SegmentContact> &out = g.chunk_contacts[size_t(chunk)];
          out.clear();
          const int64_t b_end = std::min(buckets_num, (chunk + 1) * grain);
          for (int64_t b = chunk * grain; b < b_end; b++) {
            const uint32_t begin = g.bucket_offsets[size_t(b)], end = g.bucket_offsets[size_t(b) + 1];
            for (uint32_t x = begin; x < end; x++) {
              const ivec3 cell = g.sorted_cells[x];
              const int32_t i0 = g.sorted_entries[x];
              const float max_x = g.sorted_max_x[x];
              for (uint32_t y = x + 1; y < end && g.sorted_min_x[y] <= max_x; y++) {
                if (g.sorted_cells[y] != cell) {
                  continue;
                }
                const int32_t i = std::min(i0, g.sorted_entries[y]);
                const int32_t j = std::max(i0, g.sorted_entries[y]);
                const SegmentGridScratch::Segment &si = g.segments[size_t(i)];
                const SegmentGridScratch::Segment &sj = g.segments[size_t(j)];
                /* Each pair once: in the first cell both touch. */
                if (glm::max(si.cell_min, sj.cell_min) != cell) {
                  continue;
                }
                const int32_t pi = si.point, pj = sj.point;
                if (si.curve == sj.curve && (different_strands_only || pj - pi <= 1)) {
                  continue;
                }
                tested++;
                if (si.box_max.y < sj.box_min.y || sj.box_max.y < si.box_min.y ||
                    si.box_max.z < sj.box_min.z || sj.box_max.z < si.box_min.z)
                {
                  continue;
                }
                /* §5.3: overlap = d − (r1 + r2). */
                const CoreDistance core = segment_segment_distance(
                    positions[pi], positions[pi + 1], positions[pj], positions[pj + 1]);
                const float overlap = core.distance - si.radius - sj.radius;
                if (overlap < 0.0f) {
                  out.push_back({pi, pj, core, overlap});
                }
              }
            }
          }
        }
        return tested;
      },
      [](const int64_t a, const int64_t b) { return a + b; });
  g.candidate_pairs_num = candidates;
  for (const std::vector<SegmentContact> &chunk : g.chunk_contacts) {
    r_contacts.insert(r_contacts.end(), chunk.begin(), chunk.end());
  }
  std::sort(r_contacts.begin(), r_contacts.end(),
            [](const SegmentContact &a, const SegmentContact &b) {
              return a.first < b.first || (a.first == b.first && a.second < b.second);
            });
}

int64_t count_crossings(const Span<int32_t> curve_offsets, const Span<vec3> positions,
                        const Span<float> radii, const float default_radius)
{
  SegmentGridScratch scratch;
  std::vector<SegmentContact> contacts;
  find_segment_contacts(curve_offsets, positions, radii, default_radius, true, scratch, contacts);
  return int64_t(contacts.size());
}

HairHairStats resolve_hair_hair(const SweptSphereParams &params, const SubstepState &state,
                                SegmentGridScratch &g, std::vector<SegmentContact> &contacts)
{
  HairHairStats stats;
  const MutableSpan<vec3> x = state.positions_wo;
  const MutableSpan<vec3> v = state.velocities_wo;
  find_segment_contacts(state.curve_offsets, x, state.radii, params.thickness, false, g, contacts);
  stats.pairs_num = int64_t(contacts.size());
  stats.candidates_num = g.candidate_pairs_num;
  if (contacts.empty()) {
    return stats;
  }
  const size_t points_num = size_t(x.size());
  g.dx.assign(points_num, vec3(0.0f));
  g.dv.assign(points_num, vec3(0.0f));
  g.wx.assign(points_num, 0.0f);
  g.wv.assign(points_num, 0.0f);
  const auto is_root = [&](const int32_t p) {
    return p == state.curve_offsets[g.point_curve[size_t(p)]];
  };
  /* Spreads a change δ of the segment's point at s over its two nodes (roots stay). */
  const auto add = [&](std::vector<vec3> &delta, std::vector<float> &weight, const int32_t p,
                       const float s, const vec3 &change) {
    const auto [w0, w1] = barycentric_weights(s);
    if (!is_root(p)) {
      delta[size_t(p)] += w0 * change;
      weight[size_t(p)] += 1.0f - s;
    }
    delta[size_t(p) + 1] += w1 * change;
    weight[size_t(p) + 1] += s;
  };
  const float sin_parallel = std::sin(params.near_parallel_angle);
  const float strength = params.push_strength;
  for (const SegmentContact &c : contacts) {
    const int32_t i = c.first, j = c.second;
    const float s = c.core.s, t = c.core.t;
    const vec3 d1 = x[i + 1] - x[i], d2 = x[j + 1] - x[j];
    const float lengths = glm::length(d1) * glm::length(d2);
    const vec3 va = glm::mix(v[i], v[i + 1], s), vb = glm::mix(v[j], v[j + 1], t);
    if (lengths > 0.0f && glm::length(glm::cross(d1, d2)) < sin_parallel * lengths) {
      /* §5.3: near parallel, both take the average of their velocities. */
      const vec3 average = 0.5f * (va + vb);
      add(g.dv, g.wv, i, s, average - va);
      add(g.dv, g.wv, j, t, average - vb);
      stats.averaged_num++;
      continue;
    }
    /* §5.3: each moves half the overlap, in opposite directions along the vector between the
     * closest points (s1 → s2). */
    const float radii_sum = c.core.distance - c.overlap;
    const vec3 before = (c.core.point_b - state.h * vb) - (c.core.point_a - state.h * va);
    vec3 n;
    if (c.core.distance > 1e-4f * radii_sum) {
      n = (c.core.point_b - c.core.point_a) / c.core.distance;
    }
    else {
      const vec3 fallback = glm::dot(before, before) > 0.0f ? before : glm::cross(d1, d2);
      const float len = glm::length(fallback);
      if (!(len > 0.0f)) {
        continue;
      }
      n = fallback / len;
    }
    float depth = -c.overlap;
    if (glm::dot(before, n) < 0.0f) {
      /* They crossed during the substep: back to the side each came from. */
      n = -n;
      depth = radii_sum + c.core.distance;
    }
    const float half = 0.5f * strength * depth;
    add(g.dx, g.wx, i, s, -half * n);
    add(g.dx, g.wx, j, t, half * n);
    const float approach = glm::dot(vb - va, n);
    if (approach < 0.0f) {
      add(g.dv, g.wv, i, s, 0.5f * strength * approach * n);
      add(g.dv, g.wv, j, t, -0.5f * strength * approach * n);
    }
    stats.pushed_num++;
  }
  /* Each node's corrections averaged over its contacts' weights. */
  parallel_for(int64_t(points_num), 4096, [&](const IndexRange range) {
    for (int64_t p = range.start; p < range.one_after_last(); p++) {
      if (g.wx[size_t(p)] > 0.0f) {
        x[p] += g.dx[size_t(p)] / std::max(1.0f, g.wx[size_t(p)]);
      }
      if (g.wv[size_t(p)] > 0.0f) {
        v[p] += g.dv[size_t(p)] / std::max(1.0f, g.wv[size_t(p)]);
      }
    }
  });
  return stats;
}

void HairHairPass::apply(const SubstepState &state)
{
  if (!params_.hair_hair) {
    return;
  }
  const auto start = std::chrono::steady_clock::now();
  const HairHairStats stats = resolve_hair_hair(params_, state, scratch_, contacts_);
  stats_.pairs_num += stats.pairs_num;
  stats_.pushed_num += stats.pushed_num;
  stats_.averaged_num += stats.averaged_num;
  stats_.candidates_num += stats.candidates_num;
  stats_.ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                   .count();
}

}  // namespace hairdyn
