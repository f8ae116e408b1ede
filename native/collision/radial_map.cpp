#include "collision/radial_map.hh"

#include <algorithm>

#if defined(HAIRDYN_COLLISION_AVX2)
#include <immintrin.h>
#endif

namespace hairdyn {

mat4 MapFrame::map_to_object() const
{
  const vec3 z = glm::cross(reference, axis);
  mat4 m(1.0f);
  m[0] = vec4(reference, 0.0f);
  m[1] = vec4(axis, 0.0f);
  m[2] = vec4(z, 0.0f);
  m[3] = vec4(origin, 1.0f);
  return m;
}

mat4 MapFrame::object_to_map() const
{
  /* Inverse of a rigid transform: transpose the rotation, rotate the translation back. */
  const mat3 rotation_t = glm::transpose(mat3(map_to_object()));
  mat4 m(rotation_t);
  m[3] = vec4(-(rotation_t * origin), 1.0f);
  return m;
}

MapFrame make_frame(const vec3 &origin, const vec3 &axis, const vec3 &reference)
{
  MapFrame frame;
  frame.origin = origin;
  const float axis_len = glm::length(axis);
  frame.axis = axis_len > 0.0f ? axis / axis_len : vec3(0.0f, 1.0f, 0.0f);
  vec3 ref = reference - glm::dot(reference, frame.axis) * frame.axis;
  if (!(glm::length(ref) > 1e-6f * std::max(glm::length(reference), 1.0f))) {
    /* Any direction perpendicular to the axis. */
    const vec3 helper = std::abs(frame.axis.x) < 0.9f ? vec3(1, 0, 0) : vec3(0, 1, 0);
    ref = helper - glm::dot(helper, frame.axis) * frame.axis;
  }
  frame.reference = glm::normalize(ref);
  return frame;
}

namespace {

/* Eigenvectors of a symmetric 3x3 matrix by cyclic Jacobi rotations; columns of r_vectors,
 * sorted by decreasing eigenvalue. */
void symmetric_eigen(glm::dmat3 a, glm::dvec3 &r_values, glm::dmat3 &r_vectors)
{
  glm::dmat3 v(1.0);
  for (int sweep = 0; sweep < 50; sweep++) {
    const double off = a[1][0] * a[1][0] + a[2][0] * a[2][0] + a[2][1] * a[2][1];
    if (off < 1e-30 * (a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2]) + 1e-300) {
      break;
    }
    for (int p = 0; p < 2; p++) {
      for (int q = p + 1; q < 3; q++) {
        if (a[q][p] == 0.0) {
          continue;
        }
        const double theta = (a[q][q] - a[p][p]) / (2.0 * a[q][p]);
        const double t = (theta >= 0.0 ? 1.0 : -1.0) /
                         (std::abs(theta) + std::sqrt(theta * theta + 1.0));
        const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
        glm::dmat3 rot(1.0);
        rot[p][p] = c;
        rot[q][q] = c;
        rot[q][p] = s;
        rot[p][q] = -s;
        a = glm::transpose(rot) * a * rot;
        v = v * rot;
      }
    }
  }
  int order[3] = {0, 1, 2};
  std::sort(order, order + 3, [&](const int i, const int j) { return a[i][i] > a[j][j]; });
  for (int k = 0; k < 3; k++) {
    r_values[k] = a[order[k]][order[k]];
    r_vectors[k] = v[order[k]];
  }
}

/* Deterministic sign: the largest component positive. */
vec3 canonical_sign(const glm::dvec3 &d)
{
  int largest = 0;
  for (int k = 1; k < 3; k++) {
    largest = std::abs(d[k]) > std::abs(d[largest]) ? k : largest;
  }
  return vec3(d[largest] < 0.0 ? -d : d);
}

}  // namespace

MapFrame fit_frame(const Span<vec3> vertices, const Span<ivec3> triangles)
{
  double area_sum = 0.0;
  glm::dvec3 centroid(0.0);
  for (const ivec3 &tri : triangles) {
    const glm::dvec3 a(vertices[tri.x]), b(vertices[tri.y]), c(vertices[tri.z]);
    const double area = 0.5 * glm::length(glm::cross(b - a, c - a));
    area_sum += area;
    centroid += area * (a + b + c) / 3.0;
  }
  if (!(area_sum > 0.0)) {
    return make_frame(vertices.is_empty() ? vec3(0.0f) : vertices[triangles[0].x],
                      vec3(0, 1, 0), vec3(1, 0, 0));
  }
  centroid /= area_sum;
  glm::dmat3 covariance(0.0);
  for (const ivec3 &tri : triangles) {
    const glm::dvec3 a(vertices[tri.x]), b(vertices[tri.y]), c(vertices[tri.z]);
    const double area = 0.5 * glm::length(glm::cross(b - a, c - a));
    const glm::dvec3 d = (a + b + c) / 3.0 - centroid;
    covariance += area * glm::outerProduct(d, d);
  }
  glm::dvec3 values;
  glm::dmat3 vectors;
  symmetric_eigen(covariance, values, vectors);
  return make_frame(vec3(centroid), canonical_sign(vectors[0]), canonical_sign(vectors[1]));
}

int64_t RadialTable::empty_cells_num() const
{
  int64_t num = 0;
  for (int32_t j = 0; j < v_num_; j++) {
    for (int32_t i = 0; i < u_num_; i++) {
      num += cell(i, j).radius < 0.0f ? 1 : 0;
    }
  }
  return num;
}

void RadialTable::finish_build()
{
  for (int32_t j = 0; j <= v_num_; j++) {
    const int32_t row = std::min(j, v_num_ - 1);
    for (int32_t i = 0; i <= u_num_; i++) {
      if (i < u_num_ && j < v_num_) {
        continue;
      }
      cell_for_write(i, j) = cell(i % u_num_, row);
    }
  }
  max_radius_ = 0.0f;
  for (const MapCell &cell : cells_) {
    max_radius_ = std::max(max_radius_, cell.radius);
  }
}

void fill_cell_from_ray(const TriangleBVH &bvh, const Span<vec3> vertices,
                        const Span<ivec3> triangles, const mat4 &map_to_object,
                        const vec3 &origin_map, const vec3 &direction_map, MapCell &r_cell)
{
  const vec3 origin = transform_point(map_to_object, origin_map);
  const vec3 direction = mat3(map_to_object) * direction_map;
  RayHit hit;
  if (!bvh.ray_farthest_hit(origin, direction, hit)) {
    r_cell = MapCell{};
    return;
  }
  const ivec3 tri = triangles[hit.triangle];
  const vec3 face_normal = glm::cross(vertices[tri.y] - vertices[tri.x],
                                      vertices[tri.z] - vertices[tri.x]);
  const float len = glm::length(face_normal);
  /* Normal in map space (the frame is a rotation: its transpose is its inverse). */
  vec3 normal = len > 0.0f ? glm::transpose(mat3(map_to_object)) * (face_normal / len) :
                             direction_map;
  if (glm::dot(normal, direction_map) < 0.0f) {
    normal = -normal;
  }
  const float radius = hit.t * glm::length(direction_map);
  /* A mesh at the edge of single precision (coordinates near 1e19) can give a hit at an
   * infinite or NaN distance: such a ray describes nothing, its cell stays empty. */
  if (!(std::isfinite(radius) && radius >= 0.0f && is_finite(normal))) {
    r_cell = MapCell{};
    return;
  }
  r_cell.normal = normal;
  r_cell.radius = radius;
}

#if defined(HAIRDYN_COLLISION_AVX2)
namespace {

/* The cells at float offsets lo and hi of `cells` as the low and high halves of one vector. */
__attribute__((target("avx2"))) inline __m256 load_two_cells(const float *cells,
                                                             const uint32_t lo, const uint32_t hi)
{
  return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(cells + lo)),
                              _mm_loadu_ps(cells + hi), 1);
}

/* For each mask of 8 lanes, the lanes set, first (the permutation that packs them to the
 * front), and how many there are. */
struct LeftPack {
  alignas(32) int32_t lanes[256][8];
  /* The inverse: for each lane set, its rank among them (0 for the others). */
  alignas(32) int32_t ranks[256][8];
  int32_t count[256];
  LeftPack()
  {
    for (int mask = 0; mask < 256; mask++) {
      int n = 0;
      for (int lane = 0; lane < 8; lane++) {
        ranks[mask][lane] = 0;
        if (mask & (1 << lane)) {
          ranks[mask][lane] = n;
          lanes[mask][n++] = lane;
        }
      }
      count[mask] = n;
      while (n < 8) {
        lanes[mask][n++] = 0;
      }
    }
  }
};
const LeftPack left_pack;

__attribute__((target("avx2"))) inline void pack_floats(float *values, const int64_t n,
                                                        const int64_t k, const __m256i lanes)
{
  _mm256_storeu_ps(values + n, _mm256_permutevar8x32_ps(_mm256_loadu_ps(values + k), lanes));
}

}  // namespace

__attribute__((target("avx2"))) void compact_defined_avx2(MapBatch<map_batch_size> &b,
                                                          int64_t &r_n, int64_t &r_k)
{
  int64_t n = r_n, k = r_k;
  const __m256i zero = _mm256_setzero_si256();
  for (; k + 8 <= b.size; k += 8) {
    /* Loads before stores: slots n .. n + 7 (n <= k) may overlap points k .. k + 7. */
    const __m256i defined =
        _mm256_loadu_si256(reinterpret_cast<const __m256i *>(b.defined + k));
    const int mask = _mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(defined, zero)));
    const __m256i lanes =
        _mm256_load_si256(reinterpret_cast<const __m256i *>(left_pack.lanes[mask]));
    const __m256i index = _mm256_add_epi32(_mm256_set1_epi32(int32_t(k)),
                                           _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
    _mm256_storeu_si256(reinterpret_cast<__m256i *>(b.index + n),
                        _mm256_permutevar8x32_epi32(index, lanes));
    pack_floats(b.x, n, k, lanes);
    pack_floats(b.y, n, k, lanes);
    pack_floats(b.z, n, k, lanes);
    b.group_masks[k / 8] = uint8_t(mask);
    n += left_pack.count[mask];
  }
  b.packed_points = k;
  b.packed_slots = n;
  r_n = n;
  r_k = k;
}

__attribute__((target("avx2"))) void expand_defined_avx2(MapBatch<map_batch_size> &b)
{
  /* Backward, group by group: group g's slots start at n, after the slots of the groups
   * below it, and n <= k: its stores (points k .. k + 7) reach no slot still to be read. */
  int64_t n = b.packed_slots;
  const __m256i lane_bits = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
  const __m256i one = _mm256_set1_epi32(1);
  for (int64_t k = b.packed_points - 8; k >= 0; k -= 8) {
    const int mask = b.group_masks[k / 8];
    n -= left_pack.count[mask];
    const __m256i ranks =
        _mm256_load_si256(reinterpret_cast<const __m256i *>(left_pack.ranks[mask]));
    const __m256i kept = _mm256_cmpeq_epi32(
        _mm256_and_si256(_mm256_set1_epi32(mask), lane_bits), lane_bits);
    /* valid | inside << 1, as expand_defined keeps them in c00. */
    const __m256i codes = _mm256_permutevar8x32_epi32(
        _mm256_loadu_si256(reinterpret_cast<const __m256i *>(b.c00 + n)), ranks);
    _mm256_storeu_si256(reinterpret_cast<__m256i *>(b.valid + k),
                        _mm256_and_si256(_mm256_and_si256(codes, one), kept));
    _mm256_storeu_si256(reinterpret_cast<__m256i *>(b.inside + k),
                        _mm256_and_si256(_mm256_srli_epi32(codes, 1), kept));
    /* The other points' values are not valid: whatever lands there is never read. */
    for (float *values : { b.depth, b.nx, b.ny, b.nz, b.x, b.y, b.z }) {
      _mm256_storeu_ps(values + k,
                       _mm256_permutevar8x32_ps(_mm256_loadu_ps(values + n), ranks));
    }
  }
}

__attribute__((target("avx2"))) int64_t RadialTable::blend_avx2(
    MapBatch<map_batch_size> &b) const
{
  const float *cells = reinterpret_cast<const float *>(cells_.data());
  const float *cells_next_v = cells + next_v();
  int64_t k = 0;
  for (; k + 8 <= b.size; k += 8) {
    /* The weights of points k .. k + 7, as blend computes them. */
    const __m256 w00 = _mm256_loadu_ps(b.w00 + k), w10 = _mm256_loadu_ps(b.w10 + k);
    const __m256 w01 = _mm256_loadu_ps(b.w01 + k), w11 = _mm256_loadu_ps(b.w11 + k);
    /* Vector q holds point k + q in its low half and point k + 4 + q in its high half, so
     * that the 4 × 4 transposes within each half give the points in order. */
    __m256 sum[4], low[4];
    for (int q = 0; q < 4; q++) {
      const int64_t i = k + q, j = k + 4 + q;
      const __m256i lane = _mm256_setr_epi32(q, q, q, q, q + 4, q + 4, q + 4, q + 4);
      const uint32_t ci = b.c00[i], cj = b.c00[j];
      const __m256 c00 = load_two_cells(cells, ci, cj);
      const __m256 c10 = load_two_cells(cells + next_u, ci, cj);
      const __m256 c01 = load_two_cells(cells_next_v, ci, cj);
      const __m256 c11 = load_two_cells(cells_next_v + next_u, ci, cj);
      sum[q] = _mm256_add_ps(
          _mm256_add_ps(
              _mm256_add_ps(_mm256_mul_ps(c00, _mm256_permutevar8x32_ps(w00, lane)),
                            _mm256_mul_ps(c10, _mm256_permutevar8x32_ps(w10, lane))),
              _mm256_mul_ps(c01, _mm256_permutevar8x32_ps(w01, lane))),
          _mm256_mul_ps(c11, _mm256_permutevar8x32_ps(w11, lane)));
      low[q] = _mm256_min_ps(_mm256_min_ps(c00, c10), _mm256_min_ps(c01, c11));
    }
    /* (nx, ny, nz, r_q) of the points as rows: transposed into the batch's arrays. */
    const __m256 xy01 = _mm256_unpacklo_ps(sum[0], sum[1]);
    const __m256 xy23 = _mm256_unpacklo_ps(sum[2], sum[3]);
    const __m256 zr01 = _mm256_unpackhi_ps(sum[0], sum[1]);
    const __m256 zr23 = _mm256_unpackhi_ps(sum[2], sum[3]);
    const __m256 nx = _mm256_shuffle_ps(xy01, xy23, _MM_SHUFFLE(1, 0, 1, 0));
    const __m256 ny = _mm256_shuffle_ps(xy01, xy23, _MM_SHUFFLE(3, 2, 3, 2));
    const __m256 nz = _mm256_shuffle_ps(zr01, zr23, _MM_SHUFFLE(1, 0, 1, 0));
    const __m256 r_q = _mm256_shuffle_ps(zr01, zr23, _MM_SHUFFLE(3, 2, 3, 2));
    /* The radii's minimum is the last lane of each point's componentwise minimum. */
    const __m256 min_radius = _mm256_shuffle_ps(_mm256_unpackhi_ps(low[0], low[1]),
                                                _mm256_unpackhi_ps(low[2], low[3]),
                                                _MM_SHUFFLE(3, 2, 3, 2));
    const __m256i filled = _mm256_srli_epi32(
        _mm256_castps_si256(_mm256_cmp_ps(min_radius, _mm256_setzero_ps(), _CMP_GE_OQ)), 31);
    __m256i *defined = reinterpret_cast<__m256i *>(b.defined + k);
    _mm256_storeu_si256(defined, _mm256_and_si256(_mm256_loadu_si256(defined), filled));
    _mm256_storeu_ps(b.r_q + k, r_q);
    _mm256_storeu_ps(b.nx + k, nx);
    _mm256_storeu_ps(b.ny + k, ny);
    _mm256_storeu_ps(b.nz + k, nz);
    /* Opposite normals cancelling out (rare): the first cell's normal, as in blend. */
    const __m256 length_sq = _mm256_add_ps(
        _mm256_add_ps(_mm256_mul_ps(nx, nx), _mm256_mul_ps(ny, ny)), _mm256_mul_ps(nz, nz));
    const int keep = _mm256_movemask_ps(
        _mm256_cmp_ps(length_sq, _mm256_set1_ps(1e-12f), _CMP_GT_OQ));
    if (keep != 0xff) {
      for (int q = 0; q < 8; q++) {
        if (!(keep & (1 << q))) {
          const float *c00 = cells + b.c00[k + q];
          b.nx[k + q] = c00[0];
          b.ny[k + q] = c00[1];
          b.nz[k + q] = c00[2];
        }
      }
    }
  }
  return k;
}
#endif

}  // namespace hairdyn
