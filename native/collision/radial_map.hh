#pragma once
/* What the cylindrical and the spherical collision maps share (Kurihara 1993 §3.1, §5): an
 * orthonormal map frame, an m × n table of radii and normals looked up bilinearly (eq. 8–10),
 * and the nearest-point approximation of eq. 11. The two maps differ only in how a point maps
 * to table coordinates (cylinder_map_kurihara1993.hh, sphere_map.hh). */
#include <cmath>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "collision/bvh.hh"
#include "core/math.hh"
#include "core/span.hh"

namespace hairdyn {

/* Map space: origin on the axis (cylinder) or at the centre (sphere); y along the axis / pole,
 * x along the reference direction (θ = 0), z = x × y. Rigid: distances are the same in object
 * and map space. */
struct MapFrame {
  vec3 origin{ 0.0f };
  vec3 axis{ 0.0f, 1.0f, 0.0f };
  vec3 reference{ 1.0f, 0.0f, 0.0f }; /* Made perpendicular to axis by make_frame. */

  /* p_map = object_to_map * p_object. */
  mat4 object_to_map() const;
  mat4 map_to_object() const;
};

/* A frame from an origin and two directions; `reference` is orthogonalised against `axis`
 * (a reference parallel to the axis is replaced by any perpendicular direction). */
MapFrame make_frame(const vec3 &origin, const vec3 &axis, const vec3 &reference);

/* Principal axes of a triangle set (area-weighted PCA of the triangle centroids): origin at
 * the area centroid, axis the direction of largest spread, reference the second. */
MapFrame fit_frame(Span<vec3> vertices, Span<ivec3> triangles);

/* A contact or signed-depth sample in map space. */
struct MapSample {
  float depth = 0.0f;         /* (Q - P) · N: > 0 inside (Kurihara 1993, eq. 11). */
  vec3 normal{ 0.0f };        /* N, unit, outward. */
  vec3 surface_point{ 0.0f }; /* T = P + depth N (eq. 11). */
  bool inside = false;        /* r_p < r_q (the comparison after eq. 10). */
};

/* The batched look-up's stages are inlined into one function, whatever the caller: the
 * AVX2 clone of the parallel query (collider.cpp) then compiles all of them for AVX2. */
#if defined(__GNUC__)
#define HAIRDYN_BATCH_INLINE inline __attribute__((always_inline))
#else
#define HAIRDYN_BATCH_INLINE inline
#endif

/* Points per batched look-up: the batch's arrays (about 25 floats per point, 13 KB) stay in L1
 * next to a default table (40 × 40 cells, 26 KB). */
constexpr int64_t map_batch_size = 128;

/* The collision code's AVX2 forms (the batched look-up's gather, RadialTable::blend_avx2; the
 * hair–hair pass's sweep and filter), compiled for AVX2 on their own and run only where the
 * CPU has it (collision_avx2_used). */
#if defined(__GNUC__) && defined(__x86_64__)
#define HAIRDYN_COLLISION_AVX2 1
#endif

/* A batch of map look-ups as a structure of arrays, so that each stage of the look-up is one
 * branch-free loop the compiler vectorises: (1) table coordinates, cell offsets and
 * weights, (2) the gather of the four cells (SSE by hand, four points at a time, or AVX2
 * eight at a time), (3) eq. 9–11. Long stages are split into short loops, one step each:
 * their iterations overlap in the CPU, where a long loop's chain of sqrt, division and
 * polynomial would leave it waiting. The loops
 * vectorise only with -fno-trapping-math (set for collider.cpp in CMakeLists.txt): with
 * trapping math GCC keeps the selects as branches. The per-point calls run the
 * same code with N = 1. Inputs x, y, z (map space); outputs valid, inside, depth, nx, ny, nz
 * (read only where valid). NaN or infinite inputs are never valid and never index out of the
 * table. */
template<int64_t N> struct MapBatch {
  int64_t size = 0;
  float x[N], y[N], z[N];
  int32_t valid[N];  /* The map is defined at the point (and it is inside, for contacts). */
  int32_t inside[N]; /* r_p < r_q. */
  float depth[N], nx[N], ny[N], nz[N];
  /* Between the stages. */
  int32_t defined[N];
  uint32_t c00[N]; /* Cell (i, j)'s offset into the table's floats (RadialTable::locate). */
  float r_p[N], u[N], v[N], r_q[N];
  /* The bilinear weights of the four cells (eq. 9), (1 - s)(1 - t), s(1 - t), (1 - s)t, st. */
  float w00[N], w10[N], w01[N], w11[N];
  /* Blend with AVX2 (RadialTable::blend_avx2): set by the caller when the CPU has it. */
  bool avx2 = false;
  /* While compacted (compact_defined): the batch's size before, the points kept (size is
   * that rounded up to a multiple of 8), and where each point was; with AVX2, which of each
   * group of eight points were kept, for how many points and slots (compact_defined_avx2). */
  int64_t full_size = 0, kept_size = 0;
  int32_t index[N];
  uint8_t group_masks[N / 8 + 1];
  int64_t packed_points = 0, packed_slots = 0;
};

#if defined(HAIRDYN_COLLISION_AVX2)
/* compact_defined's loop eight points at a time (left-packed by a permutation), from point
 * r_k and slot r_n on: advances both past the last whole group of eight. */
__attribute__((target("avx2"))) void compact_defined_avx2(MapBatch<map_batch_size> &b,
                                                          int64_t &r_n, int64_t &r_k);
/* expand_defined's loop for the groups compact_defined_avx2 packed. */
__attribute__((target("avx2"))) void expand_defined_avx2(MapBatch<map_batch_size> &b);
#endif

/* A batch in which few points can be inside (the others are beyond the map's largest radius
 * or outside its height range: the shell of a query around a collider, most of a groom) looks
 * up only those. compact_defined moves them to the front of the batch (x, y, z: the maps take
 * square roots only after it, for the points kept), the stages run on them alone, and
 * expand_defined moves their results back (valid, inside, depth, N, and x, y, z); the other
 * points are left not valid. A point's operations are the same either way, only which lane
 * runs them changes. Returns false (and leaves the batch as it is) when more than 3/4 of the
 * points are defined. */
template<int64_t N> HAIRDYN_BATCH_INLINE bool compact_defined(MapBatch<N> &b)
{
  int32_t defined_num = 0;
  for (int64_t k = 0; k < b.size; k++) {
    defined_num += b.defined[k];
  }
  if (4 * int64_t(defined_num) > 3 * b.size) {
    return false;
  }
  /* Forward, in place: slot n <= k has been read by the time it is written. Branch-free:
   * every point is written, and n moves on only past a defined one. */
  int64_t n = 0, k = 0;
#if defined(HAIRDYN_COLLISION_AVX2)
  if constexpr (N == map_batch_size) {
    if (b.avx2) {
      compact_defined_avx2(b, n, k);
    }
  }
#endif
  for (; k < b.size; k++) {
    b.index[n] = int32_t(k);
    b.x[n] = b.x[k];
    b.y[n] = b.y[k];
    b.z[n] = b.z[k];
    n += b.defined[k];
  }
  /* Whole groups of eight, the last filled with copies of the last point kept: the stages'
   * vector loops then run no remainder (scalar or half width, with branches that cannot be
   * predicted), and the copies' results are never read. */
  static_assert(N % 8 == 0, "a compacted batch is padded to groups of eight");
  const int64_t padded = (n + 7) & ~int64_t(7);
  for (int64_t j = n; j < padded; j++) {
    b.x[j] = b.x[n - 1];
    b.y[j] = b.y[n - 1];
    b.z[j] = b.z[n - 1];
  }
  b.full_size = b.size;
  b.kept_size = n;
  b.size = padded;
  for (int64_t j = 0; j < padded; j++) {
    b.defined[j] = 1;
  }
  return true;
}

template<int64_t N> HAIRDYN_BATCH_INLINE void expand_defined(MapBatch<N> &b)
{
  const int64_t n = b.kept_size;
  /* With AVX2, the slots and points compact_defined_avx2 packed are moved back by
   * expand_defined_avx2 (which writes valid and inside of all its points). */
  int64_t j_end = 0, k_start = 0;
#if defined(HAIRDYN_COLLISION_AVX2)
  if constexpr (N == map_batch_size) {
    j_end = b.avx2 ? b.packed_slots : 0;
    k_start = b.avx2 ? b.packed_points : 0;
  }
#endif
  /* valid and inside kept aside (in c00, read by no later stage), then cleared for the
   * points below. */
  for (int64_t j = 0; j < n; j++) {
    b.c00[j] = uint32_t(b.valid[j] | (b.inside[j] << 1));
  }
  for (int64_t k = k_start; k < b.full_size; k++) {
    b.valid[k] = 0;
    b.inside[k] = 0;
  }
  /* Backward, in place: index[j] >= j, and the slots below j are still to be read. */
  for (int64_t j = n - 1; j >= j_end; j--) {
    const int64_t k = b.index[j];
    b.valid[k] = int32_t(b.c00[j] & 1u);
    b.inside[k] = int32_t(b.c00[j] >> 1);
    b.depth[k] = b.depth[j];
    b.nx[k] = b.nx[j];
    b.ny[k] = b.ny[j];
    b.nz[k] = b.nz[j];
    b.x[k] = b.x[j];
    b.y[k] = b.y[j];
    b.z[k] = b.z[j];
  }
#if defined(HAIRDYN_COLLISION_AVX2)
  if constexpr (N == map_batch_size) {
    if (b.avx2) {
      expand_defined_avx2(b);
    }
  }
#endif
  b.size = b.full_size;
}

/* x clamped to [lo, hi], NaN to lo: both comparisons are false for NaN, so no input can give
 * a value outside the range (and a cell index cast from it stays inside the table). */
HAIRDYN_BATCH_INLINE float clamp_or_low(const float x, const float lo, const float hi)
{
  const float above = x > lo ? x : lo;
  return above < hi ? above : hi;
}

/* atan2 to within 1e-6 rad, several times faster than std::atan2 (the query path's only
 * transcendental function), branch-free so that it vectorises. Result in (-π, π]; 0 at the
 * origin. */
HAIRDYN_BATCH_INLINE float fast_atan2(const float y, const float x)
{
  const float ax = std::abs(x), ay = std::abs(y);
  const float big = ax < ay ? ay : ax;
  const float small = ay < ax ? ay : ax;
  /* 0 / 1 at the origin: no division is left to a branch, so the loop vectorises. */
  const float a = small / (big > 0.0f ? big : 1.0f);
  const float s = a * a;
  /* Minimax polynomial for atan on [0, 1], by Estrin's scheme (pairs of terms in s, s², s⁴
   * summed as a tree: a chain of 5 products and sums instead of Horner's 14). */
  const float s2 = s * s, s4 = s2 * s2;
  const float low =
      (-0.3332985605f + 0.1994653599f * s) + s2 * (-0.1390853351f + 0.0964200441f * s);
  const float high = (-0.0559098861f + 0.0218612288f * s) + s2 * -0.0040540580f;
  float r = (low + s4 * high) * s * a + a;
  r = ay > ax ? 1.57079637f - r : r;
  r = x < 0.0f ? 3.14159274f - r : r;
  return y < 0.0f ? -r : r;
}

/* One table cell: the outward unit normal and the radius of the outermost hit; radius < 0
 * marks an empty cell (the ray missed the part). */
struct MapCell {
  vec3 normal{ 0.0f };
  float radius = -1.0f;
};
static_assert(sizeof(MapCell) == 16, "one cell is 16 bytes: four cells per cache line");

/* The m × n table. u (azimuth, 0 <= u < m) wraps around; v (0 <= v <= n - 1) is clamped.
 * Stored padded to (m + 1) × (n + 1): column m repeats column 0 and row n repeats row n - 1,
 * so that a cell's neighbours along u and v are always the next cell and the next row, the
 * wrap and the clamp included (the look-up reads one offset per point, no selects). */
class RadialTable {
 public:
  RadialTable() = default;
  RadialTable(int32_t u_num, int32_t v_num) :
      u_num_(u_num), v_num_(v_num), u_last_(std::nextafter(float(u_num), 0.0f)),
      cells_(size_t(u_num + 1) * size_t(v_num + 1))
  {
  }

  int32_t u_num() const { return u_num_; }
  int32_t v_num() const { return v_num_; }
  MapCell &cell_for_write(const int32_t u, const int32_t v)
  {
    return cells_[size_t(v * (u_num_ + 1) + u)];
  }
  const MapCell &cell(const int32_t u, const int32_t v) const
  {
    return cells_[size_t(v * (u_num_ + 1) + u)];
  }
  int64_t empty_cells_num() const;
  /* Largest radius of a filled cell (0 when all are empty). */
  float max_radius() const { return max_radius_; }
  /* Once every cell is written: the padding and the largest radius. */
  void finish_build();

  /* Stage 1 of the bilinear look-up for point k (Kurihara 1993, eq. 8 and 10): the cell
   * i <= u < i + 1, j <= v < j + 1 and the weights of the fractions s = u - i, t = v - j. u
   * wraps once around [0, m), v is clamped to [0, n - 1]; anything else (NaN, infinities)
   * lands in cell (0, 0). */
  /* The table's size as values: read once before a loop over the batch (a store into the
   * batch's int32 arrays could otherwise be the table's own fields, for all the compiler
   * knows, and the loop would neither keep them in registers nor vectorise). */
  struct Shape {
    int32_t u_num, v_num;
    float u_last;
  };
  Shape shape() const { return { u_num_, v_num_, u_last_ }; }
  /* Float offsets from a cell to its neighbour along u and along v (the padded layout). */
  static constexpr uint32_t next_u = 4;
  uint32_t next_v() const { return 4u * uint32_t(u_num_ + 1); }

  template<int64_t N> static HAIRDYN_BATCH_INLINE void locate(const Shape shape, MapBatch<N> &b,
                                                              const int64_t k, float u,
                                                              const float v)
  {
    const float m = float(shape.u_num);
    u = u < 0.0f ? u + m : u;
    u = u < m ? u : u - m;
    u = clamp_or_low(u, 0.0f, shape.u_last);
    const float v_clamped = clamp_or_low(v, 0.0f, float(shape.v_num - 1));
    const int32_t i0 = int32_t(u);
    const int32_t j0 = int32_t(v_clamped);
    /* The cell's offset in floats; its neighbours are at next_u, next_v (padded layout). */
    b.c00[k] = 4u * uint32_t(j0 * (shape.u_num + 1) + i0);
    const float s = u - float(i0), t = v_clamped - float(j0);
    b.w00[k] = (1.0f - s) * (1.0f - t);
    b.w10[k] = s * (1.0f - t);
    b.w01[k] = (1.0f - s) * t;
    b.w11[k] = s * t;
  }

  /* Stage 2: the gather. Eq. 9: r_q by bilinear interpolation of the four cells' radii; §3.1
   * step 1: N by interpolating their normals (normalised in stage 3). A point next to an
   * empty cell is not defined: a query never reports a collision next to a missed ray. */
  template<int64_t N> HAIRDYN_BATCH_INLINE void blend(MapBatch<N> &b) const
  {
    /* The cells as floats (normal x, y, z, radius). */
    const float *cells = reinterpret_cast<const float *>(cells_.data());
    const float *cells_next_v = cells + next_v();
    int64_t k = 0;
#if defined(HAIRDYN_COLLISION_AVX2)
    if constexpr (N == map_batch_size) {
      if (b.avx2) {
        k = blend_avx2(b);
      }
    }
#endif
#if defined(__SSE2__)
    /* Four points at a time: each cell is one 16-byte load (normal and radius together),
     * blended as a vector with the same products and sums, in the same order, as the scalar
     * lanes below; the four points' results are transposed into the batch's arrays. (The
     * compiler makes no gathers of the scalar form's 16 indexed loads per point, and on
     * CPUs that split 256-bit gathers they would be slower than these loads.) */
    for (; N >= 4 && k + 4 <= b.size; k += 4) {
      __m128 sum[4], low[4], first[4];
      blend_cells(cells, cells_next_v, b, k, sum[0], low[0], first[0]);
      blend_cells(cells, cells_next_v, b, k + 1, sum[1], low[1], first[1]);
      blend_cells(cells, cells_next_v, b, k + 2, sum[2], low[2], first[2]);
      blend_cells(cells, cells_next_v, b, k + 3, sum[3], low[3], first[3]);
      _MM_TRANSPOSE4_PS(sum[0], sum[1], sum[2], sum[3]);         /* nx, ny, nz, r_q */
      _MM_TRANSPOSE4_PS(first[0], first[1], first[2], first[3]); /* c00's normal (and radius) */
      /* The radii's minimum is lane 3 of each point's componentwise minimum. */
      const __m128 low01 = _mm_unpackhi_ps(low[0], low[1]),
                   low23 = _mm_unpackhi_ps(low[2], low[3]);
      const __m128 min_radius = _mm_movehl_ps(low23, low01);
      const __m128i filled =
          _mm_srli_epi32(_mm_castps_si128(_mm_cmpge_ps(min_radius, _mm_setzero_ps())), 31);
      __m128i *defined = reinterpret_cast<__m128i *>(b.defined + k);
      _mm_storeu_si128(defined, _mm_and_si128(_mm_loadu_si128(defined), filled));
      _mm_storeu_ps(b.r_q + k, sum[3]);
      /* Opposite normals cancelling out: keep the first cell's (as below). */
      const __m128 length_sq =
          _mm_add_ps(_mm_add_ps(_mm_mul_ps(sum[0], sum[0]), _mm_mul_ps(sum[1], sum[1])),
                     _mm_mul_ps(sum[2], sum[2]));
      const __m128 keep = _mm_cmpgt_ps(length_sq, _mm_set1_ps(1e-12f));
      for (int c = 0; c < 3; c++) {
        const __m128 n = _mm_or_ps(_mm_and_ps(keep, sum[c]), _mm_andnot_ps(keep, first[c]));
        _mm_storeu_ps((c == 0 ? b.nx : c == 1 ? b.ny : b.nz) + k, n);
      }
    }
#endif
    for (; k < b.size; k++) {
      const uint32_t c00 = b.c00[k], c10 = c00 + next_u, c01 = c00 + next_v(),
                     c11 = c01 + next_u;
      const float w00 = b.w00[k], w10 = b.w10[k], w01 = b.w01[k], w11 = b.w11[k];
      const float r00 = cells[c00 + 3], r10 = cells[c10 + 3], r01 = cells[c01 + 3],
                  r11 = cells[c11 + 3];
      const float min_radius = std::min(std::min(r00, r10), std::min(r01, r11));
      b.defined[k] &= min_radius >= 0.0f ? 1 : 0;
      b.r_q[k] = r00 * w00 + r10 * w10 + r01 * w01 + r11 * w11;
      const float nx = cells[c00] * w00 + cells[c10] * w10 + cells[c01] * w01 + cells[c11] * w11;
      const float ny = cells[c00 + 1] * w00 + cells[c10 + 1] * w10 + cells[c01 + 1] * w01 +
                       cells[c11 + 1] * w11;
      const float nz = cells[c00 + 2] * w00 + cells[c10 + 2] * w10 + cells[c01 + 2] * w01 +
                       cells[c11 + 2] * w11;
      /* Opposite normals cancelling out (a thin sheet seen from both sides): any unit vector
       * is as good, keep the first cell's. */
      const bool cancelled = !(nx * nx + ny * ny + nz * nz > 1e-12f);
      b.nx[k] = cancelled ? cells[c00] : nx;
      b.ny[k] = cancelled ? cells[c00 + 1] : ny;
      b.nz[k] = cancelled ? cells[c00 + 2] : nz;
    }
  }

#if defined(HAIRDYN_COLLISION_AVX2)
  /* Stage 2 eight points at a time with 256-bit vectors, two points per vector, the same
   * products and sums in the same order as blend's: the same bits. Returns the points done
   * (the batch's size rounded down to a multiple of 8); blend does the rest. */
  __attribute__((target("avx2"))) int64_t blend_avx2(MapBatch<map_batch_size> &b) const;
#endif

 private:
#if defined(__SSE2__)
  /* Point k's four cells blended as (nx, ny, nz, r): c00 w00 + c10 w10 + c01 w01 + c11 w11
   * (each weight broadcast from memory: one load, no shuffle, with AVX), their componentwise
   * minimum, and c00 itself. */
  template<int64_t N> static HAIRDYN_BATCH_INLINE void blend_cells(const float *cells,
                                                                   const float *cells_next_v,
                                                                   const MapBatch<N> &b,
                                                                   const int64_t k,
                                                                   __m128 &r_sum, __m128 &r_min,
                                                                   __m128 &r_first)
  {
    const float *p00 = cells + b.c00[k], *p01 = cells_next_v + b.c00[k];
    const __m128 c00 = _mm_loadu_ps(p00), c10 = _mm_loadu_ps(p00 + next_u);
    const __m128 c01 = _mm_loadu_ps(p01), c11 = _mm_loadu_ps(p01 + next_u);
    r_sum = _mm_add_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(c00, _mm_set1_ps(b.w00[k])),
                                             _mm_mul_ps(c10, _mm_set1_ps(b.w10[k]))),
                                  _mm_mul_ps(c01, _mm_set1_ps(b.w01[k]))),
                       _mm_mul_ps(c11, _mm_set1_ps(b.w11[k])));
    r_min = _mm_min_ps(_mm_min_ps(c00, c10), _mm_min_ps(c01, c11));
    r_first = c00;
  }
#endif
  int32_t u_num_ = 0;
  int32_t v_num_ = 0;
  float u_last_ = 0.0f; /* The largest float below m. */
  std::vector<MapCell> cells_;
  float max_radius_ = 0.0f;
};

/* Stage 3's end, shared by both maps (Kurihara 1993, eq. 11), in two loops (see MapBatch):
 * normalise_normals makes N unit and sets valid where defined and, with
 * inside_only, r_p < r_q; then each map gives Q to set_depth, the depth (Q - P) · N along N. */
template<bool inside_only, int64_t N> HAIRDYN_BATCH_INLINE void normalise_normals(MapBatch<N> &b)
{
  for (int64_t k = 0; k < b.size; k++) {
    const float nx = b.nx[k], ny = b.ny[k], nz = b.nz[k];
    const float inv = 1.0f / std::sqrt(nx * nx + ny * ny + nz * nz);
    b.nx[k] = nx * inv;
    b.ny[k] = ny * inv;
    b.nz[k] = nz * inv;
    const int32_t inside = b.r_p[k] < b.r_q[k] ? 1 : 0;
    b.inside[k] = inside;
    b.valid[k] = b.defined[k] & (inside | (inside_only ? 0 : 1));
  }
}

template<int64_t N> HAIRDYN_BATCH_INLINE void set_depth(MapBatch<N> &b, const int64_t k,
                                                        const float qx, const float qy,
                                                        const float qz)
{
  /* PT = (PQ · N) N. */
  b.depth[k] = (qx - b.x[k]) * b.nx[k] + (qy - b.y[k]) * b.ny[k] + (qz - b.z[k]) * b.nz[k];
}

/* Point k of a batch as a MapSample (T = P + depth N); false where it is not valid. */
template<int64_t N> inline bool read_sample(const MapBatch<N> &b, const int64_t k,
                                            MapSample &r_sample)
{
  if (!b.valid[k]) {
    return false;
  }
  r_sample.depth = b.depth[k];
  r_sample.normal = vec3(b.nx[k], b.ny[k], b.nz[k]);
  r_sample.surface_point = vec3(b.x[k], b.y[k], b.z[k]) + b.depth[k] * r_sample.normal;
  r_sample.inside = b.inside[k] != 0;
  return true;
}

/* A batch of one point, for the per-point calls. */
inline MapBatch<1> single_point_batch(const vec3 &p)
{
  MapBatch<1> b;
  b.size = 1;
  b.x[0] = p.x;
  b.y[0] = p.y;
  b.z[0] = p.z;
  return b;
}

/* Fills one cell from the outermost hit of the ray origin + t direction (map space; the BVH is
 * in object space, hence the frame). The normal is the hit triangle's, turned to face along
 * the ray: the outermost surface faces outwards whatever the mesh's winding. */
void fill_cell_from_ray(const TriangleBVH &bvh, Span<vec3> vertices, Span<ivec3> triangles,
                        const mat4 &map_to_object, const vec3 &origin_map,
                        const vec3 &direction_map, MapCell &r_cell);

}  // namespace hairdyn
