#include "collision/hair_hair_ward2003.hh"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "core/parallel.hh"

namespace hairdyn {

namespace {

/* The most cells the grid may have: more than this (a groom spread far apart) and the cells
 * grow instead, so that the per-cell arrays stay small. */
constexpr int64_t max_cells_per_segment = 4;
/* Fixed chunks of segments for the counting sort (independent of the thread count). */
constexpr int64_t sort_chunks_num = 8;
/* Re-tests of the pairs found, each applying the response again to those still in contact:
 * one substep's Jacobi sweep under-resolves a node pushed by several pairs. */
constexpr int response_iterations = 3;

/* Where a segment's nodes were at the substep's start. */
struct StartPositions {
  Span<vec3> x0;  /* given, or empty */
  Span<vec3> x, v; /* else x − h v when v is given, else x */
  float h = 0.0f;
  vec3 operator[](const int64_t p) const
  {
    if (!x0.is_empty()) {
      return x0[p];
    }
    return v.is_empty() ? x[p] : x[p] - h * v[p];
  }
  bool sweeps() const { return !x0.is_empty() || !v.is_empty(); }
};

/* Segments, their swept boxes and cells, and the grid entries in cell order (§5.3: "insert
 * each SSV of the hair into the grids"; the cell edge is the mean segment length). Returns
 * false when there is no segment. */
bool build_grid(const Span<int32_t> curve_offsets, const Span<vec3> positions,
                const StartPositions &start, const Span<float> radii, const float default_radius,
                SegmentGridScratch &g)
{
  const int64_t curves_num = curve_offsets.size() - 1;
  const int64_t points_num = positions.size();
  const int64_t segments_num = points_num - curves_num;
  if (curves_num <= 0 || segments_num <= 0) {
    return false;
  }
  g.point_curve.resize(size_t(points_num));
  g.segment_curve.resize(size_t(segments_num));
  g.segment_sweep.resize(size_t(segments_num));
  g.box_min.resize(size_t(segments_num));
  g.box_max.resize(size_t(segments_num));
  g.cell_min.resize(size_t(segments_num));
  g.cell_max.resize(size_t(segments_num));
  g.entry_offsets.resize(size_t(segments_num) + 1);

  /* Boxes of the swept segments and the mean segment length. */
  struct Bounds {
    vec3 lo{std::numeric_limits<float>::max()}, hi{-std::numeric_limits<float>::max()};
    double length = 0.0;
  };
  const Bounds bounds = parallel_reduce(
      curves_num, 256, Bounds(),
      [&](const IndexRange range) {
        Bounds b;
        for (int64_t c = range.start; c < range.one_after_last(); c++) {
          const int32_t first = curve_offsets[c], last = curve_offsets[c + 1] - 1;
          for (int32_t p = first; p <= last; p++) {
            g.point_curve[size_t(p)] = int32_t(c);
          }
          for (int32_t p = first; p < last; p++) {
            const size_t k = size_t(p - c);
            g.segment_curve[k] = int32_t(c);
            const float r = radii.is_empty() ? default_radius : 0.5f * (radii[p] + radii[p + 1]);
            const vec3 a = positions[p], e = positions[p + 1];
            vec3 lo = glm::min(a, e), hi = glm::max(a, e);
            float sweep = 0.0f;
            if (start.sweeps()) {
              const vec3 a0 = start[p], e0 = start[p + 1];
              lo = glm::min(lo, glm::min(a0, e0));
              hi = glm::max(hi, glm::max(a0, e0));
              sweep = std::max(glm::length(a - a0), glm::length(e - e0));
            }
            g.segment_sweep[k] = sweep;
            g.box_min[k] = lo - vec3(r);
            g.box_max[k] = hi + vec3(r);
            b.lo = glm::min(b.lo, g.box_min[k]);
            b.hi = glm::max(b.hi, g.box_max[k]);
            b.length += double(glm::length(e - a));
          }
        }
        return b;
      },
      [](const Bounds &a, const Bounds &b) {
        Bounds r;
        r.lo = glm::min(a.lo, b.lo);
        r.hi = glm::max(a.hi, b.hi);
        r.length = a.length + b.length;
        return r;
      });
  const vec3 extent = bounds.hi - bounds.lo;
  const float largest = std::max(extent.x, std::max(extent.y, extent.z));
  /* §5.3: the cell edge is the mean segment length; never so small that the cells outnumber
   * a few per segment (a groom spread far apart) or the indices overflow. */
  float cell = float(bounds.length / double(segments_num));
  cell = std::max({cell, largest * 1e-6f, 1e-9f});
  ivec3 dims;
  for (;;) {
    dims = ivec3(glm::floor(extent / cell)) + ivec3(1);
    if (double(dims.x) * dims.y * dims.z <= double(max_cells_per_segment * segments_num + 4096)) {
      break;
    }
    cell *= 1.25f;
  }
  g.cell_size = cell;
  const float inv_cell = 1.0f / cell;
  const int64_t cells_num = int64_t(dims.x) * dims.y * dims.z;

  parallel_for(segments_num, 4096, [&](const IndexRange range) {
    for (int64_t k = range.start; k < range.one_after_last(); k++) {
      const ivec3 c0 = glm::clamp(ivec3(glm::floor((g.box_min[size_t(k)] - bounds.lo) * inv_cell)),
                                  ivec3(0), dims - 1);
      const ivec3 c1 = glm::clamp(ivec3(glm::floor((g.box_max[size_t(k)] - bounds.lo) * inv_cell)),
                                  ivec3(0), dims - 1);
      g.cell_min[size_t(k)] = c0;
      g.cell_max[size_t(k)] = c1;
      const ivec3 n = c1 - c0 + ivec3(1);
      g.entry_offsets[size_t(k) + 1] = n.x * n.y * n.z;
    }
  });
  g.entry_offsets[0] = 0;
  for (int64_t k = 0; k < segments_num; k++) {
    g.entry_offsets[size_t(k) + 1] += g.entry_offsets[size_t(k)];
  }
  const int64_t entries_num = g.entry_offsets.back();
  g.entry_keys.resize(size_t(entries_num));
  parallel_for(segments_num, 4096, [&](const IndexRange range) {
    for (int64_t k = range.start; k < range.one_after_last(); k++) {
      const ivec3 c0 = g.cell_min[size_t(k)], c1 = g.cell_max[size_t(k)];
      int64_t e = g.entry_offsets[size_t(k)];
      for (int32_t z = c0.z; z <= c1.z; z++) {
        for (int32_t y = c0.y; y <= c1.y; y++) {
          for (int32_t x = c0.x; x <= c1.x; x++) {
            g.entry_keys[size_t(e++)] = uint32_t(x + dims.x * (y + dims.y * z));
          }
        }
      }
    }
  });

  /* Counting sort of the entries by cell, stable (a cell lists its segments in increasing
   * order before the sort by x below), over fixed chunks of segments. */
  const int64_t chunk = (segments_num + sort_chunks_num - 1) / sort_chunks_num;
  g.chunk_counts.assign(size_t(sort_chunks_num * cells_num), 0);
  run_chunks(sort_chunks_num, [&](const int64_t ch) {
    uint32_t *counts = &g.chunk_counts[size_t(ch * cells_num)];
    const int64_t k_end = std::min(segments_num, (ch + 1) * chunk);
    if (ch * chunk >= k_end) {
      return;
    }
    for (int64_t e = g.entry_offsets[size_t(ch * chunk)]; e < g.entry_offsets[size_t(k_end)]; e++) {
      counts[g.entry_keys[size_t(e)]]++;
    }
  });
  g.cell_offsets.resize(size_t(cells_num) + 1);
  uint32_t total = 0;
  for (int64_t cell_index = 0; cell_index < cells_num; cell_index++) {
    g.cell_offsets[size_t(cell_index)] = total;
    for (int64_t ch = 0; ch < sort_chunks_num; ch++) {
      uint32_t &count = g.chunk_counts[size_t(ch * cells_num + cell_index)];
      const uint32_t n = count;
      count = total; /* now: where chunk ch's first entry of this cell goes */
      total += n;
    }
  }
  g.cell_offsets[size_t(cells_num)] = total;
  g.entries.resize(size_t(entries_num));
  run_chunks(sort_chunks_num, [&](const int64_t ch) {
    uint32_t *fill = &g.chunk_counts[size_t(ch * cells_num)];
    const int64_t k_end = std::min(segments_num, (ch + 1) * chunk);
    for (int64_t k = ch * chunk; k < k_end; k++) {
      const int32_t curve = g.segment_curve[size_t(k)];
      const vec3 lo = g.box_min[size_t(k)], hi = g.box_max[size_t(k)];
      const ivec3 c0 = g.cell_min[size_t(k)];
      int64_t e = g.entry_offsets[size_t(k)];
      for (int32_t z = c0.z; z <= g.cell_max[size_t(k)].z; z++) {
        for (int32_t y = c0.y; y <= g.cell_max[size_t(k)].y; y++) {
          for (int32_t x = c0.x; x <= g.cell_max[size_t(k)].x; x++) {
            const uint32_t key = g.entry_keys[size_t(e++)];
            SegmentGridScratch::Entry &entry = g.entries[fill[key]++];
            entry.min_x = lo.x;
            entry.max_x = hi.x;
            entry.min_y = lo.y;
            entry.max_y = hi.y;
            entry.min_z = lo.z;
            entry.max_z = hi.z;
            entry.point = int32_t(k) + curve;
            entry.curve_flags = uint32_t(curve) << 3 | uint32_t(x == c0.x) |
                                uint32_t(y == c0.y) << 1 | uint32_t(z == c0.z) << 2;
          }
        }
      }
    }
  });
  /* Within a cell, by the lower x of the boxes (sweep and prune along x; ties by point). */
  parallel_for(cells_num, 1024, [&](const IndexRange range) {
    for (int64_t cell_index = range.start; cell_index < range.one_after_last(); cell_index++) {
      const uint32_t begin = g.cell_offsets[size_t(cell_index)];
      const uint32_t end = g.cell_offsets[size_t(cell_index) + 1];
      if (end - begin > 1) {
        std::sort(g.entries.begin() + begin, g.entries.begin() + end,
                  [](const SegmentGridScratch::Entry &a, const SegmentGridScratch::Entry &b) {
                    return a.min_x < b.min_x || (a.min_x == b.min_x && a.point < b.point);
                  });
      }
    }
  });
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

/* (b0 − a0) · (da × db): the signed volume of the two segments' lines, zero when they are
 * coplanar; its sign says on which side of segment a's line segment b passes. */
inline float side_volume(const vec3 &a0, const vec3 &a1, const vec3 &b0, const vec3 &b1)
{
  return glm::dot(b0 - a0, glm::cross(a1 - a0, b1 - b0));
}

struct PairContext {
  Span<vec3> x;
  StartPositions start;
  Span<float> radii;
  float default_radius = 0.0f;
  Span<vec3> v;
  const SweptSphereParams *params = nullptr;
  float sin_parallel = 0.0f;
};

/* The narrow phase of one pair of segments (first points pi < pj): true, with the contact
 * and its §5.3 response, when their swept spheres overlap at the end of the substep or passed
 * through each other during it. */
bool test_pair(const PairContext &ctx, const int32_t pi, const int32_t pj, const float sweeps,
               SegmentContact &r_c)
{
  const Span<vec3> x = ctx.x;
  const vec3 a0 = x[pi], a1 = x[pi + 1], b0 = x[pj], b1 = x[pj + 1];
  const float ri = ctx.radii.is_empty() ? ctx.default_radius :
                                          0.5f * (ctx.radii[pi] + ctx.radii[pi + 1]);
  const float rj = ctx.radii.is_empty() ? ctx.default_radius :
                                          0.5f * (ctx.radii[pj] + ctx.radii[pj + 1]);
  const float radii_sum = ri + rj;
  const vec3 da = a1 - a0, db = b1 - b0;
  const vec3 n1 = glm::cross(da, db);
  const float f1 = glm::dot(b0 - a0, n1);
  const float nn1 = glm::dot(n1, n1);
  const float lengths2 = glm::dot(da, da) * glm::dot(db, db);
  const bool parallel = nn1 <= ctx.sin_parallel * ctx.sin_parallel * lengths2;
  /* The distance between the lines bounds the segments' from below: most pairs end here. */
  const bool may_overlap = f1 * f1 <= radii_sum * radii_sum * nn1;
  /* Continuous detection: the pair passed through each other when the side of their lines
   * flipped and, at the moment the lines were coplanar, the segments touched. */
  bool crossed = false;
  float side0 = 0.0f;
  /* Every point of a segment moved at most its nodes' largest move (`sweeps`, both segments
   * together), so pairs whose lines end farther apart than that plus the radii never touched. */
  const float reach = radii_sum + sweeps;
  if (ctx.start.sweeps() && !parallel && f1 * f1 <= reach * reach * nn1) {
    const vec3 A0 = ctx.start[pi], A1 = ctx.start[pi + 1], B0 = ctx.start[pj],
               B1 = ctx.start[pj + 1];
    side0 = side_volume(A0, A1, B0, B1);
    if (side0 != 0.0f && (side0 > 0.0f) != (f1 > 0.0f)) {
      /* The root of the (cubic) side volume along the linear sweep: bisection, then a
       * secant step. */
      float lo = 0.0f, hi = 1.0f, f_lo = side0, f_hi = f1;
      const auto at = [&](const float tau, vec3 &p0, vec3 &p1, vec3 &q0, vec3 &q1) {
        p0 = glm::mix(A0, a0, tau);
        p1 = glm::mix(A1, a1, tau);
        q0 = glm::mix(B0, b0, tau);
        q1 = glm::mix(B1, b1, tau);
      };
      vec3 p0, p1, q0, q1;
      for (int k = 0; k < 5; k++) {
        const float mid = 0.5f * (lo + hi);
        at(mid, p0, p1, q0, q1);
        const float f = side_volume(p0, p1, q0, q1);
        if ((f > 0.0f) == (f_lo > 0.0f)) {
          lo = mid;
          f_lo = f;
        }
        else {
          hi = mid;
          f_hi = f;
        }
      }
      const float tau = lo + (hi - lo) * (f_lo / (f_lo - f_hi));
      at(tau, p0, p1, q0, q1);
      crossed = segment_segment_distance(p0, p1, q0, q1).distance < radii_sum;
    }
  }
  if (!crossed) {
    if (!parallel && !may_overlap) {
      return false;
    }
    if (parallel) {
      /* Near parallel pairs (side by side in combed hair: most pairs of a groom): b's
       * projection onto the plane normal to a, seen from a's projected point, bounds the
       * segments' distance from below. */
      const float aa = glm::dot(da, da);
      if (aa > 0.0f) {
        const vec3 w0 = b0 - a0, w1 = b1 - a0;
        const vec3 q0 = w0 - (glm::dot(w0, da) / aa) * da, q1 = w1 - (glm::dot(w1, da) / aa) * da;
        const vec3 dq = q1 - q0;
        const float qq = glm::dot(dq, dq);
        const float u = qq > 0.0f ? glm::clamp(-glm::dot(q0, dq) / qq, 0.0f, 1.0f) : 0.0f;
        const vec3 closest = q0 + u * dq;
        if (glm::dot(closest, closest) >= radii_sum * radii_sum) {
          return false;
        }
      }
    }
  }
  const CoreDistance core = segment_segment_distance(a0, a1, b0, b1);
  if (!crossed && core.distance >= radii_sum) {
    return false;
  }
  r_c.first = pi;
  r_c.second = pj;
  r_c.core = core;
  r_c.crossed = crossed;
  r_c.parallel = parallel;
  r_c.move = r_c.dv_first = r_c.dv_second = vec3(0.0f);
  r_c.overlap = core.distance - radii_sum;
  if (ctx.params == nullptr) {
    return true;
  }
  const Span<vec3> v = ctx.v;
  const float s = core.s, t = core.t;
  const vec3 va = glm::mix(v[pi], v[pi + 1], s), vb = glm::mix(v[pj], v[pj + 1], t);
  if (parallel) {
    /* §5.3: near parallel, both take the average of their velocities. */
    const vec3 average = 0.5f * (va + vb);
    r_c.dv_first = average - va;
    r_c.dv_second = average - vb;
    return true;
  }
  /* §5.3: each moves half the overlap, in opposite directions along the vector between the
   * closest points (s1 → s2). A pair that passed through each other goes back to the sides
   * it came from: along the lines' common normal, oriented as b lay at the start, by the
   * whole way through plus the radii. */
  vec3 n;
  float depth;
  const float nn_len = std::sqrt(nn1);
  if (crossed) {
    n = (side0 > 0.0f ? 1.0f : -1.0f) * n1 / nn_len;
    depth = radii_sum - glm::dot(core.point_b - core.point_a, n);
    r_c.overlap = -depth;
  }
  else {
    if (core.distance > 1e-4f * radii_sum) {
      n = (core.point_b - core.point_a) / core.distance;
    }
    else {
      const float side = ctx.start.sweeps() ? side0 : f1;
      n = (side >= 0.0f ? 1.0f : -1.0f) * n1 / nn_len;
    }
    depth = radii_sum - core.distance;
  }
  r_c.move = (0.5f * ctx.params->push_strength * depth) * n;
  /* The approaching normal velocity is removed (inelastic, like the push), so that the next
   * substep does not undo the push. */
  const float approach = glm::dot(vb - va, n);
  if (approach < 0.0f) {
    r_c.dv_first = (0.5f * ctx.params->push_strength * approach) * n;
    r_c.dv_second = -r_c.dv_first;
  }
  return true;
}

/* The chunks' contacts in the order of their pairs (first, then second point): a fixed order
 * that depends neither on the thread count nor on the grid's layout. A counting sort by the
 * first point, then each point's few contacts by the second. */
void gather_in_pair_order(const int64_t points_num, SegmentGridScratch &g,
                          std::vector<SegmentContact> &r_contacts)
{
  g.contact_offsets.assign(size_t(points_num) + 1, 0);
  for (const std::vector<SegmentContact> &chunk : g.chunk_contacts) {
    for (const SegmentContact &c : chunk) {
      g.contact_offsets[size_t(c.first) + 1]++;
    }
  }
  for (int64_t p = 0; p < points_num; p++) {
    g.contact_offsets[size_t(p) + 1] += g.contact_offsets[size_t(p)];
  }
  r_contacts.resize(size_t(g.contact_offsets.back()));
  for (const std::vector<SegmentContact> &chunk : g.chunk_contacts) {
    for (const SegmentContact &c : chunk) {
      r_contacts[g.contact_offsets[size_t(c.first)]++] = c;
    }
  }
  uint32_t begin = 0;
  for (int64_t p = 0; p < points_num; p++) {
    const uint32_t end = g.contact_offsets[size_t(p)];
    for (uint32_t i = begin + 1; i < end; i++) {
      const SegmentContact c = r_contacts[i];
      uint32_t j = i;
      for (; j > begin && r_contacts[j - 1].second > c.second; j--) {
        r_contacts[j] = r_contacts[j - 1];
      }
      r_contacts[j] = c;
    }
    begin = end;
  }
}

}  // namespace

void find_segment_contacts(const Span<int32_t> curve_offsets, const Span<vec3> positions,
                           const Span<float> radii, const float default_radius,
                           const bool different_strands_only, SegmentGridScratch &g,
                           std::vector<SegmentContact> &r_contacts,
                           const Span<vec3> start_positions, const Span<vec3> velocities,
                           const SweptSphereParams *params, const float h)
{
  r_contacts.clear();
  g.candidate_pairs_num = 0;
  PairContext ctx;
  ctx.x = positions;
  ctx.radii = radii;
  ctx.default_radius = default_radius;
  ctx.v = velocities;
  ctx.params = params;
  ctx.start.x0 = start_positions;
  ctx.start.x = positions;
  ctx.start.h = h;
  ctx.start.v = params != nullptr && start_positions.is_empty() ? velocities : Span<vec3>();
  ctx.sin_parallel = params != nullptr ? std::sin(params->near_parallel_angle) : 0.0f;
  if (!build_grid(curve_offsets, positions, ctx.start, radii, default_radius, g)) {
    return;
  }
  const int64_t cells_num = int64_t(g.cell_offsets.size()) - 1;
  /* Fixed chunks of cells (independent of the thread count), each with its own list. */
  const int64_t grain = std::max<int64_t>(cells_num / 256, 16);
  const int64_t chunks_num = (cells_num + grain - 1) / grain;
  g.chunk_contacts.resize(size_t(chunks_num));
  const int64_t candidates = parallel_reduce(
      chunks_num, 1, int64_t(0),
      [&](const IndexRange chunks) {
        int64_t tested = 0;
        for (int64_t chunk = chunks.start; chunk < chunks.one_after_last(); chunk++) {
          std::vector<SegmentContact> &out = g.chunk_contacts[size_t(chunk)];
          out.clear();
          const int64_t c_end = std::min(cells_num, (chunk + 1) * grain);
          for (int64_t c = chunk * grain; c < c_end; c++) {
            const uint32_t begin = g.cell_offsets[size_t(c)], end = g.cell_offsets[size_t(c) + 1];
            for (uint32_t e = begin; e + 1 < end; e++) {
              const SegmentGridScratch::Entry a = g.entries[e];
              for (uint32_t f = e + 1; f < end; f++) {
                const SegmentGridScratch::Entry &b = g.entries[f];
                if (b.min_x > a.max_x) {
                  break;
                }
                if (a.max_y < b.min_y || b.max_y < a.min_y || a.max_z < b.min_z ||
                    b.max_z < a.min_z)
                {
                  continue;
                }
                /* Each pair once: in the first cell both touch (along every axis, this cell
                 * is the first of one of them). */
                if (((a.curve_flags | b.curve_flags) & 7u) != 7u) {
                  continue;
                }
                const bool same_curve = (a.curve_flags >> 3) == (b.curve_flags >> 3);
                const int32_t pi = std::min(a.point, b.point), pj = std::max(a.point, b.point);
                if (same_curve && (different_strands_only || pj - pi <= 1)) {
                  continue;
                }
                tested++;
                SegmentContact contact;
                const float sweeps = g.segment_sweep[size_t(a.point - int32_t(a.curve_flags >> 3))] +
                                     g.segment_sweep[size_t(b.point - int32_t(b.curve_flags >> 3))];
                if (test_pair(ctx, pi, pj, sweeps, contact)) {
                  out.push_back(contact);
                }
              }
            }
          }
        }
        return tested;
      },
      [](const int64_t a, const int64_t b) { return a + b; });
  g.candidate_pairs_num = candidates;
  gather_in_pair_order(positions.size(), g, r_contacts);
}

int64_t count_crossings(const Span<int32_t> curve_offsets, const Span<vec3> positions,
                        const Span<float> radii, const float default_radius)
{
  SegmentGridScratch scratch;
  std::vector<SegmentContact> contacts;
  find_segment_contacts(curve_offsets, positions, radii, default_radius, true, scratch, contacts);
  return int64_t(contacts.size());
}

namespace {

/* Each node's corrections averaged over its contacts' weights (roots stay), summed in the
 * contacts' fixed order: the same bits on any thread count. */
void apply_contacts(const Span<SegmentContact> contacts, const SubstepState &state,
                    SegmentGridScratch &g)
{
  const MutableSpan<vec3> x = state.positions_wo;
  const MutableSpan<vec3> v = state.velocities_wo;
  const size_t points_num = size_t(x.size());
  g.dx.assign(points_num, vec4(0.0f));
  g.dv.assign(points_num, vec4(0.0f));
  const auto is_root = [&](const int32_t p) {
    return p == state.curve_offsets[g.point_curve[size_t(p)]];
  };
  /* Spreads a change δ of the segment's point at s over its two nodes. */
  const auto add = [&](std::vector<vec4> &delta, const int32_t p, const float s,
                       const vec3 &change) {
    const auto [w0, w1] = barycentric_weights(s);
    if (!is_root(p)) {
      delta[size_t(p)] += vec4(w0 * change, 1.0f - s);
    }
    delta[size_t(p) + 1] += vec4(w1 * change, s);
  };
  for (const SegmentContact &c : contacts) {
    if (c.parallel) {
      add(g.dv, c.first, c.core.s, c.dv_first);
      add(g.dv, c.second, c.core.t, c.dv_second);
      continue;
    }
    add(g.dx, c.first, c.core.s, -c.move);
    add(g.dx, c.second, c.core.t, c.move);
    if (c.dv_first != vec3(0.0f)) {
      add(g.dv, c.first, c.core.s, c.dv_first);
      add(g.dv, c.second, c.core.t, c.dv_second);
    }
  }
  parallel_for(int64_t(points_num), 8192, [&](const IndexRange range) {
    for (int64_t p = range.start; p < range.one_after_last(); p++) {
      const vec4 dx = g.dx[size_t(p)], dv = g.dv[size_t(p)];
      if (dx.w > 0.0f) {
        x[p] += vec3(dx) / std::max(1.0f, dx.w);
      }
      if (dv.w > 0.0f) {
        v[p] += vec3(dv) / std::max(1.0f, dv.w);
      }
    }
  });
}

}  // namespace

HairHairStats resolve_hair_hair(const SweptSphereParams &params, const SubstepState &state,
                                SegmentGridScratch &g, std::vector<SegmentContact> &contacts)
{
  HairHairStats stats;
  const MutableSpan<vec3> x = state.positions_wo;
  const MutableSpan<vec3> v = state.velocities_wo;
  find_segment_contacts(state.curve_offsets, x, state.radii, params.thickness, false, g, contacts,
                        state.start_positions_wo, v, &params, state.h);
  stats.pairs_num = int64_t(contacts.size());
  stats.candidates_num = g.candidate_pairs_num;
  for (const SegmentContact &c : contacts) {
    stats.averaged_num += c.parallel ? 1 : 0;
    stats.pushed_num += c.parallel ? 0 : 1;
    stats.crossed_num += c.crossed ? 1 : 0;
  }
  if (contacts.empty()) {
    return stats;
  }
  apply_contacts(contacts, state, g);
  /* Bounded re-tests of the pairs found: a node several pairs push gets their average, which
   * can leave a pair still overlapping. Crossed pairs keep their side. */
  PairContext ctx;
  ctx.x = x;
  ctx.radii = state.radii;
  ctx.default_radius = params.thickness;
  ctx.v = v;
  ctx.params = &params;
  ctx.sin_parallel = std::sin(params.near_parallel_angle);
  for (int iteration = 1; iteration < response_iterations; iteration++) {
    size_t kept = 0;
    for (size_t i = 0; i < contacts.size(); i++) {
      SegmentContact c = contacts[i];
      if (c.parallel) {
        continue;
      }
      const bool was_crossed = c.crossed;
      const vec3 side = c.move;
      if (!test_pair(ctx, c.first, c.second, 0.0f, c)) {
        continue;
      }
      if (was_crossed && glm::dot(c.core.point_b - c.core.point_a, side) < 0.0f) {
        /* Still on the wrong side: push on along the side it came from. */
        const float len = glm::length(side);
        if (!(len > 0.0f)) {
          continue;
        }
        const vec3 n = side / len;
        const float radii_sum = c.core.distance - c.overlap;
        const float depth = radii_sum - glm::dot(c.core.point_b - c.core.point_a, n);
        c.move = (0.5f * params.push_strength * depth) * n;
        c.crossed = true;
      }
      if (c.parallel) {
        continue;
      }
      contacts[kept++] = c;
    }
    if (kept == 0) {
      break;
    }
    apply_contacts(Span<SegmentContact>(contacts.data(), int64_t(kept)), state, g);
  }
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
  stats_.crossed_num += stats.crossed_num;
  stats_.ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                   .count();
}

}  // namespace hairdyn
