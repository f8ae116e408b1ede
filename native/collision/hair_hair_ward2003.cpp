#include "collision/hair_hair_ward2003.hh"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#if defined(__SSE2__)
#  include <emmintrin.h>
#endif

#include "collision/collider.hh"
#include "core/head_motion.hh"
#include "core/parallel.hh"
#if defined(HAIRDYN_COLLISION_AVX2)
#include <immintrin.h>
#endif

namespace hairdyn {

namespace {

/* The most cells the grid may have, per segment: more than this (a groom spread far apart)
 * and the cells grow instead, so that the per-cell array stays small. */
constexpr int64_t max_cells_per_segment = 1;
/* The most segments whose box outgrows a cell (tested against the cells their box covers
 * and against each other one by one): more, and the cells grow. */
constexpr int64_t max_big_segments = 1024;
/* Re-tests of the pairs found, each applying the response again to those still in contact:
 * one substep's Jacobi sweep under-resolves a node pushed by several pairs. */
constexpr int response_iterations = 3;
/* A segment's box is at most this share of a cell along every axis (else it is a big one):
 * below 1, so that rounding in the cell coordinates never loses a pair. */
constexpr float cell_fill = 0.999f;

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

/* The box of entry e across the column axes as the other entries' boxes are compared with
 * it: its (hi y, hi z, −lo y, −lo z) against their (lo y, lo z, −hi y, −hi z). */
inline vec4 cross_of(const SegmentGridScratch &g, const size_t e)
{
  return vec4(-g.neg_hi_y[e], -g.neg_hi_z[e], -g.lo_y[e], -g.lo_z[e]);
}

/* Whether entry f's box overlaps, across the column axes, the box whose cross_of is `cross`. */
inline bool boxes_meet(const SegmentGridScratch &g, const size_t f, const vec4 &cross)
{
  return g.lo_y[f] <= cross.x && g.lo_z[f] <= cross.y && g.neg_hi_y[f] <= cross.z &&
         g.neg_hi_z[f] <= cross.w;
}

/* test_pair's rejections, from the grid's copies of the two segments (they lie near each
 * other in memory, where the nodes of two strands do not), with a little slack for rounding:
 * true when test_pair would find neither an overlap at the end of the substep nor a crossing
 * during it. Pairs near the edge of a criterion are left to test_pair. */
inline bool cannot_touch(const SegmentGridScratch::Segment &a,
                         const SegmentGridScratch::Segment &b, const float sin_parallel2,
                         const bool sweeps)
{
  const vec3 da = vec3(a.tip) - vec3(a.origin), db = vec3(b.tip) - vec3(b.origin);
  const vec3 n1 = glm::cross(da, db);
  const float nn1 = glm::dot(n1, n1);
  const float parallel_limit = sin_parallel2 * (a.tip.w * b.tip.w);
  const float radii_sum = 1.001f * (a.origin.w + b.origin.w);
  const vec3 w = vec3(b.origin) - vec3(a.origin);
  if (nn1 > 1.001f * parallel_limit) {
    /* Not near parallel: the lines' distance bounds the segments' from below; they crossed
     * only if b's side of a's line flipped. */
    const float f1 = glm::dot(w, n1);
    if (f1 * f1 <= radii_sum * radii_sum * nn1) {
      return false;
    }
    if (!sweeps) {
      return true;
    }
    const vec3 n0 = glm::cross(vec3(a.start_tip) - vec3(a.start_origin),
                               vec3(b.start_tip) - vec3(b.start_origin));
    const vec3 w0 = vec3(b.start_origin) - vec3(a.start_origin);
    const float side0 = glm::dot(w0, n0);
    return (side0 > 0.0f) == (f1 > 0.0f) &&
           side0 * side0 > 1e-8f * glm::dot(w0, w0) * glm::dot(n0, n0);
  }
  if (nn1 < 0.999f * parallel_limit && a.tip.w > 0.0f) {
    /* Near parallel: b's projection onto the plane normal to a, seen from a's first node,
     * bounds the segments' distance from below. */
    const float aa = a.tip.w;
    const vec3 w1 = w + db;
    const vec3 q0 = w - (glm::dot(w, da) / aa) * da, q1 = w1 - (glm::dot(w1, da) / aa) * da;
    const vec3 dq = q1 - q0;
    const float qq = glm::dot(dq, dq);
    const float u = qq > 0.0f ? glm::clamp(-glm::dot(q0, dq) / qq, 0.0f, 1.0f) : 0.0f;
    const vec3 closest = q0 + u * dq;
    return glm::dot(closest, closest) >= radii_sum * radii_sum;
  }
  return false;
}

#if defined(__SSE2__)
/* The vector operations the lane code below is written in, four lanes (SSE2) or, where the
 * collision code's AVX2 forms run, eight (AVX2). Each lane does what the scalar code does, in
 * the same order (no FMA), so four and eight lanes give the same bits. */
#define HAIRDYN_LANES_FN [[gnu::always_inline]] static inline
struct Lanes4 {
  using V = __m128;
  static constexpr int width = 4;
  HAIRDYN_LANES_FN V set(const float v) { return _mm_set1_ps(v); }
  HAIRDYN_LANES_FN V zero() { return _mm_setzero_ps(); }
  HAIRDYN_LANES_FN V load(const float *p) { return _mm_loadu_ps(p); }
  HAIRDYN_LANES_FN V add(const V p, const V q) { return _mm_add_ps(p, q); }
  HAIRDYN_LANES_FN V sub(const V p, const V q) { return _mm_sub_ps(p, q); }
  HAIRDYN_LANES_FN V mul(const V p, const V q) { return _mm_mul_ps(p, q); }
  HAIRDYN_LANES_FN V div(const V p, const V q) { return _mm_div_ps(p, q); }
  HAIRDYN_LANES_FN V min(const V p, const V q) { return _mm_min_ps(p, q); }
  HAIRDYN_LANES_FN V max(const V p, const V q) { return _mm_max_ps(p, q); }
  HAIRDYN_LANES_FN V gt(const V p, const V q) { return _mm_cmpgt_ps(p, q); }
  HAIRDYN_LANES_FN V lt(const V p, const V q) { return _mm_cmplt_ps(p, q); }
  HAIRDYN_LANES_FN V ge(const V p, const V q) { return _mm_cmpge_ps(p, q); }
  HAIRDYN_LANES_FN V le(const V p, const V q) { return _mm_cmple_ps(p, q); }
  HAIRDYN_LANES_FN V and_(const V p, const V q) { return _mm_and_ps(p, q); }
  HAIRDYN_LANES_FN V or_(const V p, const V q) { return _mm_or_ps(p, q); }
  HAIRDYN_LANES_FN V xor_(const V p, const V q) { return _mm_xor_ps(p, q); }
  HAIRDYN_LANES_FN V andnot(const V p, const V q) { return _mm_andnot_ps(p, q); }
  HAIRDYN_LANES_FN int mask(const V p) { return _mm_movemask_ps(p); }
  HAIRDYN_LANES_FN V dot(const V px, const V py, const V pz, const V qx, const V qy, const V qz)
  {
    return add(add(mul(px, qx), mul(py, qy)), mul(pz, qz));
  }
  /* The segments' `field`, one lane each: x, y, z and w in four registers. */
  HAIRDYN_LANES_FN void rows(const SegmentGridScratch::Segment *const b[],
                             vec4 SegmentGridScratch::Segment::*const field, V &x, V &y, V &z,
                             V &w)
  {
    x = _mm_loadu_ps(&(b[0]->*field).x);
    y = _mm_loadu_ps(&(b[1]->*field).x);
    z = _mm_loadu_ps(&(b[2]->*field).x);
    w = _mm_loadu_ps(&(b[3]->*field).x);
    _MM_TRANSPOSE4_PS(x, y, z, w);
  }
};
#if defined(HAIRDYN_COLLISION_AVX2)
#define HAIRDYN_LANES8_FN __attribute__((target("avx2"))) static inline
struct Lanes8 {
  using V = __m256;
  static constexpr int width = 8;
  HAIRDYN_LANES8_FN V set(const float v) { return _mm256_set1_ps(v); }
  HAIRDYN_LANES8_FN V zero() { return _mm256_setzero_ps(); }
  HAIRDYN_LANES8_FN V load(const float *p) { return _mm256_loadu_ps(p); }
  HAIRDYN_LANES8_FN V add(const V p, const V q) { return _mm256_add_ps(p, q); }
  HAIRDYN_LANES8_FN V sub(const V p, const V q) { return _mm256_sub_ps(p, q); }
  HAIRDYN_LANES8_FN V mul(const V p, const V q) { return _mm256_mul_ps(p, q); }
  HAIRDYN_LANES8_FN V div(const V p, const V q) { return _mm256_div_ps(p, q); }
  HAIRDYN_LANES8_FN V min(const V p, const V q) { return _mm256_min_ps(p, q); }
  HAIRDYN_LANES8_FN V max(const V p, const V q) { return _mm256_max_ps(p, q); }
  HAIRDYN_LANES8_FN V gt(const V p, const V q) { return _mm256_cmp_ps(p, q, _CMP_GT_OS); }
  HAIRDYN_LANES8_FN V lt(const V p, const V q) { return _mm256_cmp_ps(p, q, _CMP_LT_OS); }
  HAIRDYN_LANES8_FN V ge(const V p, const V q) { return _mm256_cmp_ps(p, q, _CMP_GE_OS); }
  HAIRDYN_LANES8_FN V le(const V p, const V q) { return _mm256_cmp_ps(p, q, _CMP_LE_OS); }
  HAIRDYN_LANES8_FN V and_(const V p, const V q) { return _mm256_and_ps(p, q); }
  HAIRDYN_LANES8_FN V or_(const V p, const V q) { return _mm256_or_ps(p, q); }
  HAIRDYN_LANES8_FN V xor_(const V p, const V q) { return _mm256_xor_ps(p, q); }
  HAIRDYN_LANES8_FN V andnot(const V p, const V q) { return _mm256_andnot_ps(p, q); }
  HAIRDYN_LANES8_FN int mask(const V p) { return _mm256_movemask_ps(p); }
  HAIRDYN_LANES8_FN V dot(const V px, const V py, const V pz, const V qx, const V qy, const V qz)
  {
    return add(add(mul(px, qx), mul(py, qy)), mul(pz, qz));
  }
  /* Segments k and k + 4 share a 128-bit half's transpose. */
  HAIRDYN_LANES8_FN void rows(const SegmentGridScratch::Segment *const b[],
                              vec4 SegmentGridScratch::Segment::*const field, V &x, V &y, V &z,
                              V &w)
  {
    V r[4];
    for (int k = 0; k < 4; k++) {
      r[k] = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(&(b[k]->*field).x)),
                                  _mm_loadu_ps(&(b[k + 4]->*field).x), 1);
    }
    const V t0 = _mm256_unpacklo_ps(r[0], r[1]), t1 = _mm256_unpackhi_ps(r[0], r[1]);
    const V t2 = _mm256_unpacklo_ps(r[2], r[3]), t3 = _mm256_unpackhi_ps(r[2], r[3]);
    x = _mm256_shuffle_ps(t0, t2, 0x44);
    y = _mm256_shuffle_ps(t0, t2, 0xEE);
    z = _mm256_shuffle_ps(t1, t3, 0x44);
    w = _mm256_shuffle_ps(t1, t3, 0xEE);
  }
};
#endif

/* The lane templates below are compiled only inside their vector code's wrapper (flatten, at
 * the end), never as functions of their own: the eight-lane values never cross a call. */
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"
/* cannot_touch of segment a against L::width segments at once (the same arithmetic, a lane
 * each): bit i of the result set when the pair with b[i] is rejected. */
template<class L> [[gnu::always_inline]] inline int cannot_touch_lanes(
    const SegmentGridScratch::Segment &a, const SegmentGridScratch::Segment *const b[],
    const float sin_parallel2, const bool sweeps)
{
  using V = typename L::V;
  V ox, oy, oz, radius, dx, dy, dz, dd;
  L::rows(b, &SegmentGridScratch::Segment::origin, ox, oy, oz, radius);
  L::rows(b, &SegmentGridScratch::Segment::tip, dx, dy, dz, dd);
  dx = L::sub(dx, ox);
  dy = L::sub(dy, oy);
  dz = L::sub(dz, oz);
  const vec3 da = vec3(a.tip) - vec3(a.origin);
  const V ax = L::set(da.x), ay = L::set(da.y), az = L::set(da.z);
  const V nx = L::sub(L::mul(ay, dz), L::mul(az, dy)), ny = L::sub(L::mul(az, dx), L::mul(ax, dz)),
          nz = L::sub(L::mul(ax, dy), L::mul(ay, dx));
  const V nn1 = L::dot(nx, ny, nz, nx, ny, nz);
  const V parallel_limit = L::mul(L::set(sin_parallel2), L::mul(L::set(a.tip.w), dd));
  const V radii_sum = L::mul(L::set(1.001f), L::add(L::set(a.origin.w), radius));
  const V radii2 = L::mul(radii_sum, radii_sum);
  const V wx = L::sub(ox, L::set(a.origin.x)), wy = L::sub(oy, L::set(a.origin.y)),
          wz = L::sub(oz, L::set(a.origin.z));
  const V zero = L::zero();
  /* Not near parallel. */
  const V not_parallel = L::gt(nn1, L::mul(L::set(1.001f), parallel_limit));
  const V f1 = L::dot(wx, wy, wz, nx, ny, nz);
  const V lines_apart = L::gt(L::mul(f1, f1), L::mul(radii2, nn1));
  V reject = L::and_(not_parallel, lines_apart);
  if (sweeps) {
    V sx, sy, sz, unused, tx, ty, tz;
    L::rows(b, &SegmentGridScratch::Segment::start_origin, sx, sy, sz, unused);
    L::rows(b, &SegmentGridScratch::Segment::start_tip, tx, ty, tz, unused);
    tx = L::sub(tx, sx);
    ty = L::sub(ty, sy);
    tz = L::sub(tz, sz);
    const vec3 start_da = vec3(a.start_tip) - vec3(a.start_origin);
    const V bx = L::set(start_da.x), by = L::set(start_da.y), bz = L::set(start_da.z);
    const V mx = L::sub(L::mul(by, tz), L::mul(bz, ty)),
            my = L::sub(L::mul(bz, tx), L::mul(bx, tz)),
            mz = L::sub(L::mul(bx, ty), L::mul(by, tx));
    const V vx = L::sub(sx, L::set(a.start_origin.x)), vy = L::sub(sy, L::set(a.start_origin.y)),
            vz = L::sub(sz, L::set(a.start_origin.z));
    const V side0 = L::dot(vx, vy, vz, mx, my, mz);
    const V same_sign = L::xor_(L::gt(side0, zero), L::gt(f1, zero));
    const V clear =
        L::gt(L::mul(side0, side0), L::mul(L::set(1e-8f), L::mul(L::dot(vx, vy, vz, vx, vy, vz),
                                                                 L::dot(mx, my, mz, mx, my, mz))));
    reject = L::and_(reject, L::andnot(same_sign, clear));
  }
  /* Near parallel. */
  if (a.tip.w > 0.0f) {
    const V parallel = L::lt(nn1, L::mul(L::set(0.999f), parallel_limit));
    const V aa = L::set(a.tip.w);
    const V s0 = L::div(L::dot(wx, wy, wz, ax, ay, az), aa);
    const V w1x = L::add(wx, dx), w1y = L::add(wy, dy), w1z = L::add(wz, dz);
    const V s1 = L::div(L::dot(w1x, w1y, w1z, ax, ay, az), aa);
    const V q0x = L::sub(wx, L::mul(s0, ax)), q0y = L::sub(wy, L::mul(s0, ay)),
            q0z = L::sub(wz, L::mul(s0, az));
    const V q1x = L::sub(w1x, L::mul(s1, ax)), q1y = L::sub(w1y, L::mul(s1, ay)),
            q1z = L::sub(w1z, L::mul(s1, az));
    const V qx = L::sub(q1x, q0x), qy = L::sub(q1y, q0y), qz = L::sub(q1z, q0z);
    const V qq = L::dot(qx, qy, qz, qx, qy, qz);
    const V u =
        L::and_(L::gt(qq, zero),
                L::min(L::max(L::div(L::sub(zero, L::dot(q0x, q0y, q0z, qx, qy, qz)), qq), zero),
                       L::set(1.0f)));
    const V cx = L::add(q0x, L::mul(u, qx)), cy = L::add(q0y, L::mul(u, qy)),
            cz = L::add(q0z, L::mul(u, qz));
    const V apart = L::ge(L::dot(cx, cy, cz, cx, cy, cz), radii2);
    reject = L::or_(reject, L::and_(parallel, apart));
  }
  return L::mask(reject);
}

/* Per 4-bit mask of lanes: its set lanes in order (the rest 0), and how many there are. */
struct LaneOrder {
  alignas(16) int32_t lanes[16][4];
  uint8_t count[16];
};
constexpr LaneOrder make_lane_order()
{
  LaneOrder order{};
  for (int mask = 0; mask < 16; mask++) {
    int k = 0;
    for (int lane = 0; lane < 4; lane++) {
      if (mask >> lane & 1) {
        order.lanes[mask][k++] = lane;
      }
    }
    order.count[mask] = uint8_t(k);
  }
  return order;
}
constexpr LaneOrder lane_order = make_lane_order();

/* The grid's arrays along and across its columns, as the sweep reads them. */
struct ColumnArrays {
  const float *lo_x, *lo_y, *lo_z, *neg_hi_y, *neg_hi_z;
  const int32_t *entry_point;
};

/* L::width entries from `first` against e's box (hi along, then hi y, hi z, −lo y, −lo z
 * across, each in all lanes): those that start before e's end, within the column (`lanes`),
 * and whose boxes meet e's across, appended to the hits (L::width written, the hits counted).
 * Returns whether all of them start before e's end. */
template<class L> [[gnu::always_inline]] inline bool sweep_block(const ColumnArrays &a,
                                                                 const typename L::V e_box[5],
                                                                 const uint32_t first,
                                                                 const int lanes, uint32_t *hits,
                                                                 size_t &hits_num)
{
  using V = typename L::V;
  const V along = L::le(L::load(a.lo_x + first), e_box[0]);
  const V meet = L::and_(
      L::and_(L::le(L::load(a.lo_y + first), e_box[1]), L::le(L::load(a.lo_z + first), e_box[2])),
      L::and_(L::le(L::load(a.neg_hi_y + first), e_box[3]),
              L::le(L::load(a.neg_hi_z + first), e_box[4])));
  const int hit_bits = L::mask(L::and_(along, meet)) & lanes;
  for (int half = 0; half < L::width; half += 4) {
    const int bits = (hit_bits >> half) & 15;
    _mm_storeu_si128(
        reinterpret_cast<__m128i *>(hits + hits_num),
        _mm_add_epi32(_mm_set1_epi32(int32_t(first) + half),
                      _mm_load_si128(reinterpret_cast<const __m128i *>(lane_order.lanes[bits]))));
    hits_num += lane_order.count[bits];
  }
  return L::mask(along) == (1 << L::width) - 1;
}

/* The sweep of one entry (e's lower end `lo` along the columns and its first point, for the
 * order of ties; its box: hi along, then hi y, hi z, −lo y, −lo z across) over the columns
 * n = 3 dz + dy (dz < n_z, dy < n_y), each from next[n] (moved past the entries that start
 * before e) to stop[n], L::width entries at a time without a branch per entry: the entries
 * that start before e's end (a column is sorted: the first ones) and whose boxes meet e's
 * across. Their indices go to `hits` in order (a block writes L::width whatever it keeps:
 * `hits` grows to leave room); returns how many. */
template<class L> [[gnu::always_inline]] inline size_t sweep_entry_lanes(
    const ColumnArrays &a, const float lo, const int32_t point, const float box[5],
    uint32_t next[9], const uint32_t stop[9], const int n_y, const int n_z,
    std::vector<uint32_t> &hits)
{
  using V = typename L::V;
  constexpr int w = L::width, all = (1 << w) - 1;
  const V e_box[5] = { L::set(box[0]), L::set(box[1]), L::set(box[2]), L::set(box[3]),
                       L::set(box[4]) };
  size_t hits_num = 0;
  for (int dz = 0; dz < n_z; dz++) {
    for (int dy = 0; dy < n_y; dy++) {
      const int n = dz * 3 + dy;
      uint32_t f = next[n];
      const uint32_t f_stop = stop[n];
      while (f < f_stop && (a.lo_x[f] < lo || (a.lo_x[f] == lo && a.entry_point[f] <= point))) {
        f++;
      }
      next[n] = f;
      if (hits.size() < hits_num + (f_stop - f) + w) {
        hits.resize(2 * (hits_num + (f_stop - f) + w));
      }
      for (; f + w <= f_stop; f += w) {
        if (!sweep_block<L>(a, e_box, f, all, hits.data(), hits_num)) {
          break;
        }
      }
      if (f < f_stop && f + w > f_stop) {
        sweep_block<L>(a, e_box, f, (1 << (f_stop - f)) - 1, hits.data(), hits_num);
      }
    }
  }
  return hits_num;
}

#pragma GCC diagnostic pop

/* The baseline code's four lanes and the AVX2 code's eight, compiled each for its own. */
inline int cannot_touch4(const SegmentGridScratch::Segment &a,
                         const SegmentGridScratch::Segment *const b[], const float sin_parallel2,
                         const bool sweeps)
{
  return cannot_touch_lanes<Lanes4>(a, b, sin_parallel2, sweeps);
}
inline size_t sweep_entry4(const ColumnArrays &a, const float lo, const int32_t point,
                           const float box[5], uint32_t next[9], const uint32_t stop[9],
                           const int n_y, const int n_z, std::vector<uint32_t> &hits)
{
  return sweep_entry_lanes<Lanes4>(a, lo, point, box, next, stop, n_y, n_z, hits);
}
#if defined(HAIRDYN_COLLISION_AVX2)
__attribute__((target("avx2"), flatten)) int cannot_touch8(
    const SegmentGridScratch::Segment &a, const SegmentGridScratch::Segment *const b[],
    const float sin_parallel2, const bool sweeps)
{
  return cannot_touch_lanes<Lanes8>(a, b, sin_parallel2, sweeps);
}
__attribute__((target("avx2"), flatten)) size_t sweep_entry8(const ColumnArrays &a, const float lo,
                                                             const int32_t point,
                                                             const float box[5], uint32_t next[9],
                                                             const uint32_t stop[9], const int n_y,
                                                             const int n_z,
                                                             std::vector<uint32_t> &hits)
{
  return sweep_entry_lanes<Lanes8>(a, lo, point, box, next, stop, n_y, n_z, hits);
}
#endif
#endif

/* The grid cell holding p (clamped to the grid). */
ivec3 cell_of(const vec3 &p, const vec3 &lo, const glm::dvec3 &inv_cell, const ivec3 &dims)
{
  ivec3 c;
  for (int a = 0; a < 3; a++) {
    c[a] = std::clamp(int(std::floor((double(p[a]) - double(lo[a])) * inv_cell[a])), 0,
                      dims[a] - 1);
  }
  return c;
}

/* Whether a box whose upper end along grid axis `axis` (1 or 2) is `hi` reaches the column
 * after `column` along it: cell_of's cell of `hi` beyond `column`, without its floor. */
inline bool reaches_next(const float hi, const int axis, const int32_t column,
                         const SegmentGridScratch &g)
{
  return column + 1 < g.dims[axis] &&
         (double(hi) - double(g.grid_lo[axis])) * g.inv_cell[axis] >= double(column + 1);
}

/* Segments, their swept boxes, and the grid (§5.3: "insert each SSV of the hair into the
 * grids"). Here the cells are columns along the axis of the thinnest boxes (on average), each
 * segment inserted once, in the column of its box's lower corner, and sorted along it. Across
 * the columns, a cell is at least as wide as every box along each axis (up to twice the mean
 * segment length), so two segments whose boxes overlap lie in the same or in neighbouring
 * columns; the few boxes wider than that are listed apart. Returns false when there is no
 * segment. */
bool build_grid(const Span<int32_t> curve_offsets, const Span<vec3> positions,
                const StartPositions &start, const Span<float> radii, const float default_radius,
                const Span<vec3> half_widths, SegmentGridScratch &g)
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
  g.segment_cell.resize(size_t(segments_num));

  /* The boxes are swept in the frame that moves with the nodes' mean displacement over the
   * substep, d: two segments at any instant of the substep are as far apart in it as in the
   * world (both shift by the same τ d), so a pair that meets during the substep has boxes that
   * meet there too, and each segment's move there, its `sweep`, bounds how far it moved
   * against any other. Hair that moves together (a swing, a turn) then sweeps smaller boxes:
   * fewer candidate pairs, the same contacts between line swept spheres (a strip's crossing is
   * sampled in steps of that move, so it takes fewer samples). */
  vec3 common_move(0.0f);
  if (start.sweeps()) {
    const glm::dvec3 sum = parallel_reduce(
        points_num, 4096, glm::dvec3(0.0),
        [&](const IndexRange range) {
          glm::dvec3 s(0.0);
          for (int64_t p = range.start; p < range.one_after_last(); p++) {
            s += glm::dvec3(positions[p] - start[p]);
          }
          return s;
        },
        [](const glm::dvec3 &a, const glm::dvec3 &b) {
          return a + b;
        });
    common_move = vec3(sum / double(points_num));
  }
  /* Boxes of the swept segments, the mean segment length and the largest box. */
  struct Bounds {
    vec3 lo{std::numeric_limits<float>::max()}, hi{-std::numeric_limits<float>::max()};
    double length = 0.0;
    vec3 largest_box{0.0f}, box_sum{0.0f};
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
            /* A strip segment's rectangle reaches its half width from the segment. */
            const float r = segment_reach(radii, default_radius, half_widths, p);
            const vec3 a = positions[p], e = positions[p + 1];
            vec3 lo = glm::min(a, e), hi = glm::max(a, e);
            float sweep = 0.0f;
            if (start.sweeps()) {
              const vec3 a0 = start[p], e0 = start[p + 1];
              const vec3 a1 = a - common_move, e1 = e - common_move;
              lo = glm::min(glm::min(a1, e1), glm::min(a0, e0));
              hi = glm::max(glm::max(a1, e1), glm::max(a0, e0));
              sweep = std::max(glm::length(a1 - a0), glm::length(e1 - e0));
            }
            g.segment_sweep[k] = sweep;
            g.box_min[k] = lo - vec3(r);
            g.box_max[k] = hi + vec3(r);
            b.lo = glm::min(b.lo, g.box_min[k]);
            b.hi = glm::max(b.hi, g.box_max[k]);
            b.length += double(glm::length(e - a));
            const vec3 size = g.box_max[k] - g.box_min[k];
            b.largest_box = glm::max(b.largest_box, size);
            b.box_sum += size;
          }
        }
        return b;
      },
      [](const Bounds &a, const Bounds &b) {
        Bounds r;
        r.lo = glm::min(a.lo, b.lo);
        r.hi = glm::max(a.hi, b.hi);
        r.length = a.length + b.length;
        r.largest_box = glm::max(a.largest_box, b.largest_box);
        r.box_sum = a.box_sum + b.box_sum;
        return r;
      });
  /* Sweep and prune along the axis of the thinnest boxes (on average): the grid's cells are
   * columns along it. The boxes are stored with that axis first. */
  const int sweep_axis = bounds.box_sum.x <= bounds.box_sum.y ?
                             (bounds.box_sum.x <= bounds.box_sum.z ? 0 : 2) :
                             (bounds.box_sum.y <= bounds.box_sum.z ? 1 : 2);
  const ivec3 axes = sweep_axis == 0 ? ivec3(0, 1, 2) :
                     sweep_axis == 1 ? ivec3(1, 2, 0) :
                                       ivec3(2, 0, 1);
  const auto swizzle = [&](const vec3 &p) { return vec3(p[axes.x], p[axes.y], p[axes.z]); };
  g.axes = axes;
  parallel_for(segments_num, 4096, [&](const IndexRange range) {
    for (int64_t k = range.start; k < range.one_after_last(); k++) {
      g.box_min[size_t(k)] = swizzle(g.box_min[size_t(k)]);
      g.box_max[size_t(k)] = swizzle(g.box_max[size_t(k)]);

    }
  });
  const vec3 grid_lo = swizzle(bounds.lo);
  const vec3 extent = swizzle(bounds.hi) - grid_lo;
  const float largest = std::max(extent.x, std::max(extent.y, extent.z));
  const float mean_length = float(bounds.length / double(segments_num));
  /* Across the columns, a cell is as large as the largest box along each axis (up to twice
   * the mean segment length; the boxes larger than that are listed apart, as big ones). */
  const vec3 largest_box = swizzle(bounds.largest_box);
  vec3 cell(0.0f); /* along the columns: unused */
  for (int a = 1; a < 3; a++) {
    cell[a] = std::max({std::min(largest_box[a], 2.0f * mean_length) / cell_fill,
                        largest * 1e-6f, 1e-9f});
  }
  const auto is_big = [&](const int64_t k) {
    const vec3 size = g.box_max[size_t(k)] - g.box_min[size_t(k)];
    return size.y > cell_fill * cell.y || size.z > cell_fill * cell.z;
  };
  if (largest_box.y > cell_fill * cell.y || largest_box.z > cell_fill * cell.z) {
    /* Too many big boxes (a fast motion): the cells grow to all but the largest few. */
    int64_t big = 0;
    for (int64_t k = 0; k < segments_num; k++) {
      big += is_big(k) ? 1 : 0;
    }
    if (big > max_big_segments) {
      std::vector<float> &sizes = g.sort_scratch;
      sizes.resize(size_t(segments_num));
      for (int a = 1; a < 3; a++) {
        for (int64_t k = 0; k < segments_num; k++) {
          sizes[size_t(k)] = g.box_max[size_t(k)][a] - g.box_min[size_t(k)][a];
        }
        const auto rank = sizes.end() - max_big_segments / 2 - 1;
        std::nth_element(sizes.begin(), rank, sizes.end());
        cell[a] = std::max(cell[a], *rank / cell_fill);
      }
    }
  }
  ivec3 dims;
  for (;;) {
    dims = ivec3(1, int(std::floor(extent.y / cell.y)) + 1, int(std::floor(extent.z / cell.z)) + 1);
    if (double(dims.y) * dims.z <= double(max_cells_per_segment * segments_num + 4096)) {
      break;
    }
    cell *= 1.25f;
  }
  cell.x = 0.0f;
  g.cell_size = cell;
  g.dims = dims;
  const int64_t cells_num = int64_t(dims.x) * dims.y * dims.z;
  const glm::dvec3 inv_cell(0.0, 1.0 / double(cell.y), 1.0 / double(cell.z));

  /* The cell of each box's lower corner (in double: no rounding across a cell's edge), or
   * `big_cell` for the big ones. */
  const uint32_t big_cell = std::numeric_limits<uint32_t>::max();
  parallel_for(segments_num, 4096, [&](const IndexRange range) {
    for (int64_t k = range.start; k < range.one_after_last(); k++) {
      if (is_big(k)) {
        g.segment_cell[size_t(k)] = big_cell;
        continue;
      }
      const ivec3 c = cell_of(g.box_min[size_t(k)], grid_lo, inv_cell, dims);
      g.segment_cell[size_t(k)] = uint32_t(c.x + dims.x * (c.y + dims.y * c.z));
    }
  });
  g.grid_lo = grid_lo;
  g.inv_cell = inv_cell;

  /* Counting sort of the segments by cell, stable: a cell lists its segments in order. */
  g.cell_offsets.assign(size_t(cells_num) + 1, 0);
  g.big_segments.clear();
  for (int64_t k = 0; k < segments_num; k++) {
    const uint32_t c = g.segment_cell[size_t(k)];
    if (c == big_cell) {
      g.big_segments.push_back(int32_t(k));
    }
    else {
      g.cell_offsets[size_t(c) + 1]++;
    }
  }
  for (int64_t c = 0; c < cells_num; c++) {
    g.cell_offsets[size_t(c) + 1] += g.cell_offsets[size_t(c)];
  }
  const size_t entries_num = g.cell_offsets.back();
  g.entry_segment.resize(entries_num);
  g.fill.assign(g.cell_offsets.begin(), g.cell_offsets.end() - 1);
  for (int64_t k = 0; k < segments_num; k++) {
    const uint32_t c = g.segment_cell[size_t(k)];
    if (c != big_cell) {
      g.entry_segment[g.fill[c]++] = int32_t(k);
    }
  }
  /* Within a column, by the lower end along the sweep axis (ties by segment): sorted as keys
   * of the end's bits in an order that is the floats' (−0 taken as 0) and then the segment. */
  g.column_keys.resize(entries_num);
  parallel_for(cells_num, 64, [&](const IndexRange range) {
    for (int64_t c = range.start; c < range.one_after_last(); c++) {
      const uint32_t begin = g.cell_offsets[size_t(c)], end = g.cell_offsets[size_t(c) + 1];
      for (uint32_t e = begin; e < end; e++) {
        const int32_t k = g.entry_segment[e];
        uint32_t bits;
        const float lo = g.box_min[size_t(k)].x + 0.0f;
        std::memcpy(&bits, &lo, sizeof(bits));
        bits = (bits & 0x80000000u) ? ~bits : bits | 0x80000000u;
        g.column_keys[e] = uint64_t(bits) << 32 | uint32_t(k);
      }
      std::sort(g.column_keys.begin() + begin, g.column_keys.begin() + end);
      for (uint32_t e = begin; e < end; e++) {
        g.entry_segment[e] = int32_t(uint32_t(g.column_keys[e]));
      }
    }
  });
  g.hi_x.resize(entries_num);
  for (std::vector<float> *values : {&g.lo_x, &g.lo_y, &g.lo_z, &g.neg_hi_y, &g.neg_hi_z}) {
    values->resize(entries_num + 7);
    std::fill(values->end() - 7, values->end(), 0.0f); /* the padding: loaded, never a hit */
  }
  g.entry_segments.resize(entries_num);
  g.entry_point.resize(entries_num);
  g.entry_curve.resize(entries_num);
  g.entry_sweep.resize(entries_num);
  g.entry_strip.resize(half_widths.is_empty() ? 0 : entries_num);
  parallel_for(int64_t(entries_num), 4096, [&](const IndexRange range) {
    for (int64_t e = range.start; e < range.one_after_last(); e++) {
      const size_t k = size_t(g.entry_segment[size_t(e)]);
      const vec3 lo = g.box_min[k], hi = g.box_max[k];
      g.lo_x[size_t(e)] = lo.x;
      g.hi_x[size_t(e)] = hi.x;
      g.lo_y[size_t(e)] = lo.y;
      g.lo_z[size_t(e)] = lo.z;
      g.neg_hi_y[size_t(e)] = -hi.y;
      g.neg_hi_z[size_t(e)] = -hi.z;
      const int32_t p = int32_t(k) + g.segment_curve[k];
      SegmentGridScratch::Segment &segment = g.entry_segments[size_t(e)];
      const vec3 da = positions[p + 1] - positions[p];
      segment.origin = vec4(positions[p], radii.is_empty() ? default_radius :
                                                             0.5f * (radii[p] + radii[p + 1]));
      segment.tip = vec4(positions[p + 1], glm::dot(da, da));
      const vec3 start0 = start[p], start1 = start[p + 1];
      segment.start_origin = vec4(start0, 0.0f);
      segment.start_tip = vec4(start1, 0.0f);
      g.entry_curve[size_t(e)] = g.segment_curve[k];
      g.entry_point[size_t(e)] = int32_t(k) + g.segment_curve[k];
      g.entry_sweep[size_t(e)] = g.segment_sweep[k];
      if (!half_widths.is_empty()) {
        g.entry_strip[size_t(e)] = half_widths[p] != vec3(0.0f) || half_widths[p + 1] != vec3(0.0f);
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

/* Whether the segments a (nodes 0, 1) and b (nodes 2, 3), moving linearly from `start` to
 * `end`, stay farther apart than `reach` all the way: along an axis normal to one of them in
 * the plane of both lines (n: their common normal at the end), their projections are
 * separated by more than `reach` at the start and at the end, on the same side. The gap along
 * a fixed axis is concave in time (the least of linear functions minus the largest), so it is
 * as large in between. A quick test before the root search of a side flip: most flips are of
 * lines that passed each other far beyond the segments. */
bool apart_throughout(const std::array<vec3, 4> &start, const std::array<vec3, 4> &end,
                      const vec3 &n, const float reach)
{
  for (const int owner : {0, 2}) {
    const vec3 u = glm::cross(n, end[size_t(owner) + 1] - end[size_t(owner)]);
    const float uu = glm::dot(u, u);
    if (!(uu > 0.0f)) {
      continue;
    }
    const float least = reach * std::sqrt(uu);
    float up = std::numeric_limits<float>::max(), down = up;
    for (const std::array<vec3, 4> *nodes : {&start, &end}) {
      const float pa0 = glm::dot((*nodes)[0], u), pa1 = glm::dot((*nodes)[1], u);
      const float pb0 = glm::dot((*nodes)[2], u), pb1 = glm::dot((*nodes)[3], u);
      up = std::min(up, std::min(pb0, pb1) - std::max(pa0, pa1));
      down = std::min(down, std::min(pa0, pa1) - std::max(pb0, pb1));
    }
    if (up > least || down > least) {
      return true;
    }
  }
  return false;
}

struct PairContext {
  Span<vec3> x;
  StartPositions start;
  Span<float> radii;
  float default_radius = 0.0f;
  Span<vec3> half_widths;    /* per point, world; empty: no strips */
  Span<vec3> rest_positions; /* per point, in the half widths' frame; empty: none */
  Span<vec3> v;
  const SweptSphereParams *params = nullptr;
  float sin_parallel = 0.0f;
};

/* The contact of segments pi < pj whose cores are `core` apart (its s and t: the closest
 * points' parameters along them) and must keep `kept` apart (kept_distance), and §5.3's
 * response when ctx has parameters: near-parallel pairs take the average of their
 * velocities, the others move apart along the unit vector n (first to second) by `depth` in
 * all, half each. */
void respond(const PairContext &ctx, const int32_t pi, const int32_t pj, const CoreDistance &core,
             const float kept, const bool parallel, const bool crossed, const vec3 &n,
             const float depth, SegmentContact &r_c)
{
  r_c.first = pi;
  r_c.second = pj;
  r_c.core = core;
  r_c.crossed = crossed;
  r_c.parallel = parallel;
  r_c.move = r_c.dv_first = r_c.dv_second = vec3(0.0f);
  r_c.overlap = core.distance - kept;
  if (ctx.params == nullptr) {
    return;
  }
  const Span<vec3> v = ctx.v;
  const float s = core.s, t = core.t;
  const vec3 va = glm::mix(v[pi], v[pi + 1], s), vb = glm::mix(v[pj], v[pj + 1], t);
  if (parallel) {
    /* §5.3: near parallel, both take the average of their velocities. */
    const vec3 average = 0.5f * (va + vb);
    r_c.dv_first = average - va;
    r_c.dv_second = average - vb;
    return;
  }
  if (crossed) {
    r_c.overlap = -depth;
  }
  r_c.move = (0.5f * ctx.params->push_strength * depth) * n;
  /* The approaching normal velocity is removed (inelastic, like the push), so that the next
   * substep does not undo the push. */
  const float approach = glm::dot(vb - va, n);
  if (approach < 0.0f) {
    r_c.dv_first = (0.5f * ctx.params->push_strength * approach) * n;
    r_c.dv_second = -r_c.dv_first;
  }
}

/* Segment p's swept-sphere radius and strip half width (strands/substep_pass.hh). */
inline float segment_radius(const PairContext &ctx, const int32_t p)
{
  return segment_radius(ctx.radii, ctx.default_radius, p);
}
inline vec3 segment_half_width(const PairContext &ctx, const int32_t p)
{
  return segment_half_width(ctx.half_widths, p);
}

/* The closest points of two segments' cores: each a rectangle when it has a half width (a
 * strip's: the segment widened by it both ways), else the segment. point_a on the first. */
CoreDistance group_cores(const vec3 &a0, const vec3 &a1, const vec3 &half_a, const vec3 &b0,
                         const vec3 &b1, const vec3 &half_b)
{
  const auto rect = [](const vec3 &p0, const vec3 &p1, const vec3 &half) {
    return RectSS::from_segment(p0, p1, half, 2.0f * glm::length(half), 0.0f);
  };
  const bool strip_a = half_a != vec3(0.0f), strip_b = half_b != vec3(0.0f);
  if (strip_a && strip_b) {
    return rectangle_rectangle_distance(rect(a0, a1, half_a), rect(b0, b1, half_b));
  }
  if (strip_a) {
    CoreDistance core = segment_rectangle_distance(b0, b1, rect(a0, a1, half_a));
    std::swap(core.point_a, core.point_b);
    return core;
  }
  if (strip_b) {
    return segment_rectangle_distance(a0, a1, rect(b0, b1, half_b));
  }
  return segment_segment_distance(a0, a1, b0, b1);
}

/* The distance segments pi and pj must keep apart: the sum of their radii, or their cores'
 * distance at rest when that is less (GroupVolumes). */
float kept_distance(const PairContext &ctx, const int32_t pi, const int32_t pj,
                    const float radii_sum)
{
  if (ctx.rest_positions.is_empty()) {
    return radii_sum;
  }
  const Span<vec3> rest = ctx.rest_positions;
  const float at_rest = group_cores(rest[pi], rest[pi + 1], segment_half_width(ctx, pi),
                                    rest[pj], rest[pj + 1], segment_half_width(ctx, pj))
                            .distance;
  return std::min(radii_sum, at_rest);
}

/* Whether segments pi < pj of one strand can meet only by the strand folding back: the
 * strand between them (pj − pi − 1 segments, about as long as the two) is longer than their
 * radii and half widths together. A thick group's skeleton (level of detail) is not pushed
 * apart by its own straight run; a thin strand's segments are always far enough apart. */
bool folded_back(const PairContext &ctx, const int32_t pi, const int32_t pj)
{
  const auto reach = [&](const int32_t p) {
    return segment_reach(ctx.radii, ctx.default_radius, ctx.half_widths, p);
  };
  const float between = float(pj - pi - 1) * 0.5f *
                        (glm::length(ctx.x[pi + 1] - ctx.x[pi]) +
                         glm::length(ctx.x[pj + 1] - ctx.x[pj]));
  return between > reach(pi) + reach(pj);
}

/* test_pair for a pair of which at least one is a strip segment, a rectangle swept sphere
 * (§5.2): the exact distance between the cores (segment–rectangle or rectangle–rectangle) and
 * the same response, at the closest points' places along the two segments. Continuous like the
 * line swept spheres' test, by sampling instead of a root search: the sweep from the substep's
 * start is cut into steps in which the two move less than the sum of their radii relative to
 * each other (at most 64), so a thin strip cannot pass through another between samples; a
 * pair that came within reach during the substep is pushed back to the side it came from. */
bool test_strip_pair(const PairContext &ctx, const int32_t pi, const int32_t pj,
                     const vec3 &half_i, const vec3 &half_j, const float sweeps,
                     SegmentContact &r_c)
{
  const float radii_sum = segment_radius(ctx, pi) + segment_radius(ctx, pj);
  /* The cores' closest points with the nodes at (p0, p1), (q0, q1). */
  const auto cores = [&](const vec3 &p0, const vec3 &p1, const vec3 &q0, const vec3 &q1) {
    return group_cores(p0, p1, half_i, q0, q1, half_j);
  };
  const Span<vec3> x = ctx.x;
  const vec3 a0 = x[pi], a1 = x[pi + 1], b0 = x[pj], b1 = x[pj + 1];
  CoreDistance core = cores(a0, a1, b0, b1);
  const float kept = kept_distance(ctx, pi, pj, radii_sum);
  /* The side the pair came from, when it came within reach during the substep. */
  bool crossed = false;
  vec3 n(0.0f);
  float depth = kept - core.distance;
  /* Only groups apart at rest: see test_pair. */
  if (ctx.start.sweeps() && sweeps > 0.0f && kept > 0.0f && kept >= radii_sum) {
    const vec3 A0 = ctx.start[pi], A1 = ctx.start[pi + 1];
    const vec3 B0 = ctx.start[pj], B1 = ctx.start[pj + 1];
    const int samples = int(std::min(64.0f, std::ceil(sweeps / kept)));
    CoreDistance last = cores(A0, A1, B0, B1);
    for (int k = 1; k <= samples && last.distance >= kept; k++) {
      const float tau = float(k) / float(samples);
      const CoreDistance now = k == samples ?
                                   core :
                                   cores(glm::mix(A0, a0, tau), glm::mix(A1, a1, tau),
                                         glm::mix(B0, b0, tau), glm::mix(B1, b1, tau));
      if (now.distance < kept) {
        n = (last.point_b - last.point_a) / last.distance;
        /* Still within reach of that side at the end: pushed back to it. */
        depth = kept - glm::dot(core.point_b - core.point_a, n);
        crossed = depth > 0.0f;
      }
      last = now;
    }
  }
  if (!crossed && core.distance >= kept) {
    return false;
  }
  if (!crossed) {
    depth = kept - core.distance;
  }
  core.s = closest_segment_parameter(core.point_a, a0, a1);
  core.t = closest_segment_parameter(core.point_b, b0, b1);
  const vec3 da = a1 - a0, db = b1 - b0;
  const vec3 n1 = glm::cross(da, db);
  const bool parallel = !crossed &&
                        glm::dot(n1, n1) <= ctx.sin_parallel * ctx.sin_parallel *
                                                glm::dot(da, da) * glm::dot(db, db);
  if (!crossed && core.distance > 1e-4f * radii_sum) {
    n = (core.point_b - core.point_a) / core.distance;
  }
  else if (!crossed) {
    /* Cores that meet (and met at the start): apart along the lines' common normal, toward
     * the side where b's middle lies (or from a's middle to b's). */
    const vec3 apart = 0.5f * (b0 + b1 - a0 - a1);
    const float nn = glm::dot(n1, n1);
    n = nn > 0.0f ? (glm::dot(apart, n1) >= 0.0f ? 1.0f : -1.0f) * n1 / std::sqrt(nn) : apart;
    const float length = glm::length(n);
    n = length > 0.0f ? n / length : vec3(0.0f);
  }
  respond(ctx, pi, pj, core, kept, parallel, crossed, n, depth, r_c);
  return true;
}

/* The narrow phase of one pair of segments (first points pi < pj): true, with the contact
 * and its §5.3 response, when their swept spheres overlap at the end of the substep or passed
 * through each other during it. */
bool test_pair(const PairContext &ctx, const int32_t pi, const int32_t pj, const float sweeps,
               SegmentContact &r_c, const SegmentGridScratch::Segment *copy_i = nullptr,
               const SegmentGridScratch::Segment *copy_j = nullptr)
{
  if (!ctx.half_widths.is_empty()) {
    const vec3 half_i = segment_half_width(ctx, pi), half_j = segment_half_width(ctx, pj);
    if (half_i != vec3(0.0f) || half_j != vec3(0.0f)) {
      return test_strip_pair(ctx, pi, pj, half_i, half_j, sweeps, r_c);
    }
  }
  const Span<vec3> x = ctx.x;
  /* The nodes from the grid's copies when given (the same values, nearer in memory). */
  const vec3 a0 = copy_i ? vec3(copy_i->origin) : x[pi], a1 = copy_i ? vec3(copy_i->tip) : x[pi + 1];
  const vec3 b0 = copy_j ? vec3(copy_j->origin) : x[pj], b1 = copy_j ? vec3(copy_j->tip) : x[pj + 1];
  const float ri = copy_i ? copy_i->origin.w : segment_radius(ctx, pi);
  const float rj = copy_j ? copy_j->origin.w : segment_radius(ctx, pj);
  const float radii_sum = ri + rj;
  /* The distance to keep (kept_distance), found when first needed. */
  float kept_value = -1.0f;
  const auto kept = [&]() {
    if (kept_value < 0.0f) {
      kept_value = kept_distance(ctx, pi, pj, radii_sum);
    }
    return kept_value;
  };
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
    const vec3 A0 = copy_i ? vec3(copy_i->start_origin) : ctx.start[pi];
    const vec3 A1 = copy_i ? vec3(copy_i->start_tip) : ctx.start[pi + 1];
    const vec3 B0 = copy_j ? vec3(copy_j->start_origin) : ctx.start[pj];
    const vec3 B1 = copy_j ? vec3(copy_j->start_tip) : ctx.start[pj + 1];
    side0 = side_volume(A0, A1, B0, B1);
    /* Groups whose volumes overlap at rest (kept below the radii: their strands interleave)
     * are not two bodies: their cores may pass each other, and the overlap test below keeps
     * them as far apart as at rest. */
    if (side0 != 0.0f && (side0 > 0.0f) != (f1 > 0.0f) &&
        !apart_throughout({ A0, A1, B0, B1 }, { a0, a1, b0, b1 }, n1, 1.001f * radii_sum) &&
        kept() >= radii_sum)
    {
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
      const float touching = segment_segment_distance(p0, p1, q0, q1).distance;
      crossed = touching < radii_sum;
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
  if (!crossed && core.distance >= kept()) {
    return false;
  }
  vec3 n(0.0f);
  float depth = kept() - core.distance;
  if (ctx.params != nullptr && !parallel) {
    /* §5.3: each moves half the overlap, in opposite directions along the vector between the
     * closest points (s1 → s2). A pair that passed through each other goes back to the sides
     * it came from: along the lines' common normal, oriented as b lay at the start, by the
     * whole way through plus the radii. */
    const float nn_len = std::sqrt(nn1);
    if (crossed) {
      n = (side0 > 0.0f ? 1.0f : -1.0f) * n1 / nn_len;
      depth = kept() - glm::dot(core.point_b - core.point_a, n);
    }
    else if (core.distance > 1e-4f * radii_sum) {
      n = (core.point_b - core.point_a) / core.distance;
    }
    else {
      const float side = ctx.start.sweeps() ? side0 : f1;
      n = (side >= 0.0f ? 1.0f : -1.0f) * n1 / nn_len;
    }
  }
  respond(ctx, pi, pj, core, kept(), parallel, crossed, n, depth, r_c);
  return true;
}

/* The chunks' contacts in the order of their pairs (first, then second point): a fixed order
 * that depends neither on the thread count nor on the grid's layout. In parallel: each
 * contact's key (and where it is) goes to a bucket of first points (chunk by chunk), each
 * bucket is sorted by key (the keys differ), then the contacts are copied in that order. */
void gather_in_pair_order(const int64_t points_num, SegmentGridScratch &g,
                          std::vector<SegmentContact> &r_contacts)
{
  constexpr int64_t buckets_num = 64;
  const int64_t chunks_num = int64_t(g.chunk_contacts.size());
  const auto bucket = [&](const int32_t point) {
    return int64_t(point) * buckets_num / std::max<int64_t>(points_num, 1);
  };
  /* Per bucket and chunk (bucket-major): how many, then where they go. */
  g.contact_offsets.assign(size_t(buckets_num * chunks_num) + 1, 0);
  parallel_for(chunks_num, 8, [&](const IndexRange range) {
    for (int64_t chunk = range.start; chunk < range.one_after_last(); chunk++) {
      for (const SegmentContact &c : g.chunk_contacts[size_t(chunk)]) {
        g.contact_offsets[size_t(bucket(c.first) * chunks_num + chunk)]++;
      }
    }
  });
  uint32_t total = 0;
  for (size_t i = 0; i + 1 < g.contact_offsets.size(); i++) {
    const uint32_t n = g.contact_offsets[i];
    g.contact_offsets[i] = total;
    total += n;
  }
  g.contact_offsets.back() = total;
  g.contact_keys.resize(total);
  parallel_for(chunks_num, 8, [&](const IndexRange range) {
    for (int64_t chunk = range.start; chunk < range.one_after_last(); chunk++) {
      const std::vector<SegmentContact> &contacts = g.chunk_contacts[size_t(chunk)];
      for (size_t i = 0; i < contacts.size(); i++) {
        const SegmentContact &c = contacts[i];
        uint32_t &next = g.contact_offsets[size_t(bucket(c.first) * chunks_num + chunk)];
        g.contact_keys[next++] = {uint64_t(uint32_t(c.first)) << 32 | uint32_t(c.second),
                                  uint32_t(chunk), uint32_t(i)};
      }
    }
  });
  r_contacts.resize(total);
  parallel_for(buckets_num, 1, [&](const IndexRange range) {
    for (int64_t b = range.start; b < range.one_after_last(); b++) {
      /* The bucket's range: its chunks' counting offsets have moved to their ends. */
      const uint32_t begin = b == 0 ? 0 : g.contact_offsets[size_t(b * chunks_num - 1)];
      const uint32_t end = g.contact_offsets[size_t((b + 1) * chunks_num - 1)];
      std::sort(g.contact_keys.begin() + begin, g.contact_keys.begin() + end,
                [](const SegmentGridScratch::ContactKey &p,
                   const SegmentGridScratch::ContactKey &q) { return p.pair < q.pair; });
      for (uint32_t i = begin; i < end; i++) {
        const SegmentGridScratch::ContactKey &key = g.contact_keys[i];
        r_contacts[i] = g.chunk_contacts[key.chunk][key.index];
      }
    }
  });
}

}  // namespace

void find_segment_contacts(const Span<int32_t> curve_offsets, const Span<vec3> positions,
                           const Span<float> radii, const float default_radius,
                           const bool different_strands_only, SegmentGridScratch &g,
                           std::vector<SegmentContact> &r_contacts,
                           const Span<vec3> start_positions, const Span<vec3> velocities,
                           const SweptSphereParams *params, const float h,
                           const GroupVolumes &groups)
{
  const Span<vec3> half_widths = groups.half_widths;
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
  ctx.half_widths = half_widths;
  ctx.rest_positions = groups.rest_positions;
  if (!build_grid(curve_offsets, positions, ctx.start, radii, default_radius, half_widths, g)) {
    return;
  }
  const ivec3 dims = g.dims;
  const int64_t cells_num = int64_t(dims.x) * dims.y * dims.z;
  const auto cell_index = [&](const int32_t x, const int32_t y, const int32_t z) {
    return size_t(x) + size_t(dims.x) * (size_t(y) + size_t(dims.y) * size_t(z));
  };
  /* A pair whose boxes overlap: tested unless they are neighbours on one strand (or of one
   * strand at all, with different_strands_only). */
  const auto test = [&](const int32_t point_a, const int32_t curve_a, const float sweep_a,
                        const int32_t point_b, const int32_t curve_b, const float sweep_b,
                        std::vector<SegmentContact> &out,
                        const SegmentGridScratch::Segment *copy_a = nullptr,
                        const SegmentGridScratch::Segment *copy_b = nullptr) {
    const int32_t pi = std::min(point_a, point_b), pj = std::max(point_a, point_b);
    if (curve_a == curve_b && (different_strands_only || pj - pi <= 1 ||
                               !folded_back(ctx, pi, pj))) {
      return int64_t(0);
    }
    if (point_a > point_b) {
      std::swap(copy_a, copy_b);
    }
    SegmentContact contact;
    if (test_pair(ctx, pi, pj, sweep_a + sweep_b, contact, copy_a, copy_b)) {
      out.push_back(contact);
    }
    return int64_t(1);
  };
  /* Tests segment a's box against the grid entries [begin, end). */
  const auto test_entries = [&](const vec3 &lo, const vec3 &hi, const int32_t point, const int32_t curve, const float sweep,
                                const uint32_t begin, const uint32_t end,
                                std::vector<SegmentContact> &out) {
    const vec4 cross(hi.y, hi.z, -lo.y, -lo.z);
    int64_t tested = 0;
    for (uint32_t f = begin; f < end; f++) {
      if (g.lo_x[f] > hi.x || g.hi_x[f] < lo.x || !boxes_meet(g, f, cross)) {
        continue;
      }
      tested += test(point, curve, sweep, g.entry_point[f], g.entry_curve[f], g.entry_sweep[f],
                     out);
    }
    return tested;
  };
  /* Fixed chunks of columns (independent of the thread count), each with its own list, then
   * one chunk per big segment. */
  const int64_t grain = std::max<int64_t>(cells_num / 256, 1);
  const int64_t cell_chunks_num = (cells_num + grain - 1) / grain;
  const int64_t big_num = int64_t(g.big_segments.size());
  const float sin_parallel2 = ctx.sin_parallel * ctx.sin_parallel;
  const bool sweeps = ctx.start.sweeps();
  /* The sweep and cannot_touch take eight entries at a time where the AVX2 code runs, else
   * four. */
  const size_t block_lanes = collision_avx2_used() ? 8 : 4;
  const float *lo_x = g.lo_x.data(), *hi_x = g.hi_x.data();
  const SegmentGridScratch::Segment *segments = g.entry_segments.data();
#if defined(__SSE2__)
  const ColumnArrays columns{ g.lo_x.data(),     g.lo_y.data(),     g.lo_z.data(),
                              g.neg_hi_y.data(), g.neg_hi_z.data(), g.entry_point.data() };
#endif
  const int32_t *entry_point = g.entry_point.data(), *entry_curve = g.entry_curve.data();
  const float *entry_sweep = g.entry_sweep.data();
  const uint8_t *entry_strip = g.entry_strip.empty() ? nullptr : g.entry_strip.data();
#if !defined(__SSE2__)
  /* The pair of entries e and f, whose boxes overlap (rejected: by cannot_touch). */
  const auto test_hit = [&](const uint32_t e, const uint32_t f, const bool rejected,
                            std::vector<SegmentContact> &out) {
    if (!rejected) {
      return test(entry_point[e], entry_curve[e], entry_sweep[e], entry_point[f],
                  entry_curve[f], entry_sweep[f], out, &segments[e], &segments[f]);
    }
    return entry_curve[e] != entry_curve[f] ||
                   (!different_strands_only && std::abs(entry_point[e] - entry_point[f]) > 1) ?
               int64_t(1) :
               int64_t(0);
  };
#else
  /* What test counts for the pair of entries e and f, without a branch. */
  const auto is_candidate = [&](const uint32_t e, const uint32_t f) {
    return int64_t((entry_curve[e] != entry_curve[f]) |
                   (!different_strands_only & (std::abs(entry_point[e] - entry_point[f]) > 1)));
  };
#endif
  g.chunk_contacts.resize(size_t(cell_chunks_num + big_num));
  const int64_t candidates = parallel_reduce(
      cell_chunks_num + big_num, 1, int64_t(0),
      [&](const IndexRange chunks) {
        int64_t tested = 0;
#if defined(__SSE2__)
        /* An entry's box hits (entries), gathered first and then tested four (or eight) at a
         * time. */
        std::vector<uint32_t> hits(1024);
#endif
        for (int64_t chunk = chunks.start; chunk < chunks.one_after_last(); chunk++) {
          std::vector<SegmentContact> &out = g.chunk_contacts[size_t(chunk)];
          out.clear();
          if (chunk >= cell_chunks_num) {
            /* A big segment: against every entry of the cells its box covers, widened by one
             * cell downwards (the entries there reach a cell up), and the big ones after it. */
            const size_t k = size_t(g.big_segments[size_t(chunk - cell_chunks_num)]);
            const vec3 lo = g.box_min[k], hi = g.box_max[k];
            const int32_t curve = g.segment_curve[k], point = int32_t(k) + curve;
            const float sweep = g.segment_sweep[k];
            const ivec3 c0 = glm::max(cell_of(lo, g.grid_lo, g.inv_cell, dims) - 1, ivec3(0));
            const ivec3 c1 = cell_of(hi, g.grid_lo, g.inv_cell, dims);
            for (int32_t z = c0.z; z <= c1.z; z++) {
              for (int32_t y = c0.y; y <= c1.y; y++) {
                const size_t column = cell_index(0, y, z);
                const uint32_t begin = g.cell_offsets[column];
                const uint32_t end = uint32_t(
                    std::upper_bound(g.lo_x.begin() + begin,
                                     g.lo_x.begin() + g.cell_offsets[column + 1], hi.x) -
                    g.lo_x.begin());
                tested += test_entries(lo, hi, point, curve, sweep, begin, end, out);
              }
            }
            for (int64_t i = chunk - cell_chunks_num + 1; i < big_num; i++) {
              const size_t m = size_t(g.big_segments[size_t(i)]);
              if (glm::any(glm::greaterThan(g.box_min[m], hi)) ||
                  glm::any(glm::lessThan(g.box_max[m], lo)))
              {
                continue;
              }
              tested += test(point, curve, sweep, int32_t(m) + g.segment_curve[m],
                             g.segment_curve[m], g.segment_sweep[m], out);
            }
            continue;
          }
          const int64_t c_end = std::min(cells_num, (chunk + 1) * grain);
          for (int64_t c = chunk * grain; c < c_end; c++) {
            const uint32_t begin = g.cell_offsets[size_t(c)], end = g.cell_offsets[size_t(c) + 1];
            if (begin == end) {
              continue;
            }
            /* Sweep and prune along the column, against this one and those around that the
             * segment's box reaches (a box lower than this one's by up to a cell may meet it):
             * a segment meets those that start after it (ties by point) before its end. */
            const int32_t y = int32_t(c % dims.y), z = int32_t(c / dims.y);
            uint32_t next[9], stop[9];
            for (int n = 0; n < 9; n++) {
              const int32_t yy = y + n % 3 - 1, zz = z + n / 3 - 1;
              if (yy < 0 || yy >= dims.y || zz < 0 || zz >= dims.z) {
                next[n] = stop[n] = 0;
                continue;
              }
              next[n] = g.cell_offsets[cell_index(0, yy, zz)];
              stop[n] = g.cell_offsets[cell_index(0, yy, zz) + 1];
            }
            for (uint32_t e = begin; e < end; e++) {
              const float lo = lo_x[e], hi = hi_x[e];
              const int32_t point = entry_point[e];
              const vec4 cross = cross_of(g, e); /* (hi y, hi z, −lo y, −lo z) */
              const int n_y = reaches_next(cross.x, 1, y, g) ? 3 : 2;
              const int n_z = reaches_next(cross.y, 2, z, g) ? 3 : 2;
#if defined(__SSE2__)
              const float box[5] = { hi, cross.x, cross.y, cross.z, cross.w };
#if defined(HAIRDYN_COLLISION_AVX2)
              const size_t hits_num =
                  block_lanes == 8
                      ? sweep_entry8(columns, lo, point, box, next, stop, n_y, n_z, hits)
                      : sweep_entry4(columns, lo, point, box, next, stop, n_y, n_z, hits);
#else
              const size_t hits_num =
                  sweep_entry4(columns, lo, point, box, next, stop, n_y, n_z, hits);
#endif
#else
              const SegmentGridScratch::Segment &segment = segments[e];
              for (int dz = 0; dz < n_z; dz++) {
                for (int dy = 0; dy < n_y; dy++) {
                  const int n = dz * 3 + dy;
                  uint32_t f = next[n];
                  const uint32_t f_stop = stop[n];
                  while (f < f_stop &&
                         (lo_x[f] < lo || (lo_x[f] == lo && entry_point[f] <= point))) {
                    f++;
                  }
                  next[n] = f;
                  for (; f < f_stop && lo_x[f] <= hi; f++) {
                    if (boxes_meet(g, f, cross)) {
                      const bool strip =
                          entry_strip != nullptr && (entry_strip[e] | entry_strip[f]);
                      tested += test_hit(
                          e, f,
                          !strip && cannot_touch(segment, segments[f], sin_parallel2, sweeps),
                          out);
                    }
                  }
                }
              }
#endif
#if defined(__SSE2__)
              /* e's hits: all counted, cannot_touch's rejections four (eight) at a time, the exact
               * test for the few kept. */
              for (size_t i = 0; i < hits_num; i += block_lanes) {
                const int n = int(std::min<size_t>(hits_num - i, block_lanes));
                const uint32_t *const group = hits.data() + i;
                const SegmentGridScratch::Segment *b[8];
                for (int m = 0; m < n; m++) {
                  b[m] = &segments[group[m]];
                }
                int rejected = 0;
                if (n == 4) {
                  rejected = cannot_touch4(segments[e], b, sin_parallel2, sweeps);
                }
#if defined(HAIRDYN_COLLISION_AVX2)
                else if (n == 8) {
                  rejected = cannot_touch8(segments[e], b, sin_parallel2, sweeps);
                }
#endif
                else {
                  for (int m = 0; m < n; m++) {
                    rejected |=
                        cannot_touch(segments[e], *b[m], sin_parallel2, sweeps) ? 1 << m : 0;
                  }
                }
                for (int m = 0; m < n; m++) {
                  tested += is_candidate(e, group[m]);
                  /* cannot_touch knows line swept spheres only: strips go to test_pair. */
                  if (entry_strip != nullptr && (entry_strip[e] | entry_strip[group[m]])) {
                    rejected &= ~(1 << m);
                  }
                }
                for (int kept = ~rejected & ((1 << n) - 1); kept != 0; kept &= kept - 1) {
                  const uint32_t f = group[__builtin_ctz(unsigned(kept))];
                  test(entry_point[e], entry_curve[e], entry_sweep[e], entry_point[f],
                       entry_curve[f], entry_sweep[f], out, &segments[e], &segments[f]);
                }
              }
#endif
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
  /* Strips' half widths and the rest positions turn with the head (its rotation: lengths and
   * distances stay). */
  const mat3 turn = HeadPose::from_matrix(state.head_to_world).rotation_matrix();
  const auto turned = [&](const Span<vec3> from, std::vector<vec3> &to) {
    to.resize(size_t(from.size()));
    for (size_t p = 0; p < to.size(); p++) {
      to[p] = turn * from[int64_t(p)];
    }
  };
  turned(state.strip_half_widths_hs, g.half_widths_wo);
  turned(state.rest_positions_hs, g.rest_positions_wo);
  const GroupVolumes groups{g.half_widths_wo, g.rest_positions_wo};
  find_segment_contacts(state.curve_offsets, x, state.radii, params.thickness, false, g, contacts,
                        state.start_positions_wo, v, &params, state.h, groups);
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
  ctx.half_widths = g.half_widths_wo;
  ctx.rest_positions = g.rest_positions_wo;
  size_t active = contacts.size(); /* the pairs the last pass kept, at the front */
  for (int iteration = 1; iteration < response_iterations; iteration++) {
    /* Each pair the last pass kept is re-tested (in parallel, into a copy), then those kept
     * again move to the front in order. (The whole list was re-tested before: the stale
     * entries behind the kept ones were tested and applied a second time.) */
    g.keep.resize(active);
    g.retested.resize(active);
    parallel_for(int64_t(active), 4096, [&](const IndexRange range) {
      for (int64_t i = range.start; i < range.one_after_last(); i++) {
        SegmentContact &c = g.retested[size_t(i)];
        c = contacts[size_t(i)];
        g.keep[size_t(i)] = 0;
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
        g.keep[size_t(i)] = c.parallel ? 0 : 1;
      }
    });
    size_t kept = 0;
    for (size_t i = 0; i < active; i++) {
      if (g.keep[i]) {
        contacts[kept++] = g.retested[i];
      }
    }
    active = kept;
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
