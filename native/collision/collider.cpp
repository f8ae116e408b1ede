#include "collision/collider.hh"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <memory>
#include <sstream>
#include <tuple>

#if defined(HAIRDYN_COLLISION_AVX2)
#include <immintrin.h>
#endif

#include "core/cpu.hh"
#include "core/parallel.hh"

namespace hairdyn {

std::vector<vec3> error_sample_points(const Span<vec3> vertices, const Span<ivec3> triangles,
                                      const float offset, const int64_t max_points_num)
{
  std::vector<vec3> points;
  const int64_t stride = std::max<int64_t>(1, (2 * triangles.size() + max_points_num - 1) /
                                                  std::max<int64_t>(max_points_num, 1));
  for (int64_t t = 0; t < triangles.size(); t += stride) {
    const ivec3 tri = triangles[t];
    const vec3 a = vertices[tri.x], b = vertices[tri.y], c = vertices[tri.z];
    const vec3 n = glm::cross(b - a, c - a);
    const float len = glm::length(n);
    if (!(len > 0.0f)) {
      continue;
    }
    const vec3 centroid = (a + b + c) / 3.0f;
    points.push_back(centroid + n * (offset / len));
    points.push_back(centroid - n * (offset / len));
  }
  return points;
}

std::string find_collider_error(const ColliderMesh &mesh, const Span<int32_t> part_offsets,
                                const Span<int32_t> part_vertices, const int64_t part_frames_num)
{
  std::ostringstream msg;
  if (mesh.triangles_num() == 0) {
    return "the collider mesh has no usable faces";
  }
  if (part_offsets.is_empty()) {
    if (!part_vertices.is_empty()) {
      return "part vertices were given without part offsets";
    }
    if (part_frames_num > 1) {
      return "one map frame is needed for the whole mesh, not " + std::to_string(part_frames_num);
    }
    return {};
  }
  const int64_t parts_num = part_offsets.size() - 1;
  if (parts_num < 1 || part_offsets[0] != 0 || part_offsets.last() != part_vertices.size()) {
    msg << "part offsets must start at 0 and end at the number of part vertices ("
        << part_vertices.size() << ")";
    return msg.str();
  }
  if (part_frames_num != 0 && part_frames_num != parts_num) {
    msg << "there are " << parts_num << " parts but " << part_frames_num << " map frames";
    return msg.str();
  }
  std::vector<uint8_t> in_part(size_t(mesh.vertices_num()));
  for (int64_t p = 0; p < parts_num; p++) {
    if (part_offsets[p + 1] < part_offsets[p]) {
      msg << "part offsets must not decrease (part " << p << ")";
      return msg.str();
    }
    if (part_offsets[p + 1] == part_offsets[p]) {
      msg << "part " << p << " has no vertices";
      return msg.str();
    }
    std::fill(in_part.begin(), in_part.end(), 0);
    for (int32_t i = part_offsets[p]; i < part_offsets[p + 1]; i++) {
      const int32_t v = part_vertices[i];
      if (v < 0 || v >= mesh.vertices_num()) {
        msg << "part " << p << " uses vertex " << v << " but the mesh has " << mesh.vertices_num()
            << " vertices";
        return msg.str();
      }
      in_part[size_t(v)] = 1;
    }
    bool has_triangle = false;
    for (const auto face : mesh.mesh().faces()) {
      bool all = true;
      for (const auto vertex : mesh.mesh().fv_range(face)) {
        all = all && in_part[size_t(vertex.idx())];
      }
      if (all) {
        has_triangle = true;
        break;
      }
    }
    if (!has_triangle) {
      msg << "part " << p
          << " selects no triangle (a triangle needs all three of its vertices in the part)";
      return msg.str();
    }
  }
  return {};
}

Collider::Collider(const ColliderMesh &mesh, const Span<int32_t> part_offsets,
                   const Span<int32_t> part_vertices, const CollisionParams &params,
                   const Span<MapFrame> part_frames) :
    params_(params),
    boundary_edges_num_(mesh.boundary_edges_num()),
    skipped_triangles_num_(mesh.skipped_triangles_num())
{
  assert(find_collider_error(mesh, part_offsets, part_vertices, part_frames.size()).empty());
  const auto start = std::chrono::steady_clock::now();
  const TriMesh &trimesh = mesh.mesh();
  vertices_.reserve(trimesh.n_vertices());
  for (const auto vertex : trimesh.vertices()) {
    const TriMesh::Point &p = trimesh.point(vertex);
    vertices_.emplace_back(p[0], p[1], p[2]);
  }
  triangles_.reserve(trimesh.n_faces());
  for (const auto face : trimesh.faces()) {
    ivec3 tri;
    int k = 0;
    for (const auto vertex : trimesh.fv_range(face)) {
      tri[k++] = vertex.idx();
    }
    triangles_.push_back(tri);
  }

  const int64_t parts_num = part_offsets.is_empty() ? 1 : part_offsets.size() - 1;
  parts_.resize(size_t(parts_num));
  std::vector<uint8_t> in_part(vertices_.size());
  for (int64_t p = 0; p < parts_num; p++) {
    Part &part = parts_[size_t(p)];
    if (part_offsets.is_empty()) {
      part.triangles = triangles_;
    }
    else {
      std::fill(in_part.begin(), in_part.end(), 0);
      for (int32_t i = part_offsets[p]; i < part_offsets[p + 1]; i++) {
        in_part[size_t(part_vertices[i])] = 1;
      }
      for (const ivec3 &tri : triangles_) {
        if (in_part[size_t(tri.x)] && in_part[size_t(tri.y)] && in_part[size_t(tri.z)]) {
          part.triangles.push_back(tri);
        }
      }
    }
    if (!part_frames.is_empty()) {
      part.explicit_frame = true;
      part.frame =
          make_frame(part_frames[p].origin, part_frames[p].axis, part_frames[p].reference);
    }
  }
  for (Part &part : parts_) {
    build_part(part, true);
  }
  exact_ = MeshDistance(vertices_, triangles_);
  size_ = glm::length(exact_.bvh().bounds_max() - exact_.bvh().bounds_min());
  set_transform(object_to_world_);
  build_ms_ =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

MapFrame Collider::part_frame(const Part &part) const
{
  if (part.explicit_frame) {
    return part.frame;
  }
  const MapFrame fitted = fit_frame(vertices_, part.triangles);
  switch (params_.axis_mode) {
  case AxisMode::ObjectX:
    return make_frame(fitted.origin, vec3(1, 0, 0), vec3(0, 1, 0));
  case AxisMode::ObjectY:
    return make_frame(fitted.origin, vec3(0, 1, 0), vec3(0, 0, 1));
  case AxisMode::ObjectZ:
    return make_frame(fitted.origin, vec3(0, 0, 1), vec3(1, 0, 0));
  case AxisMode::Fitted:
  default:
    return fitted;
  }
}

void Collider::build_part(Part &part, const bool choose_kind)
{
  part.frame = part_frame(part);
  const TriangleBVH bvh(vertices_, part.triangles);
  const int32_t m = params_.azimuth_num, n = params_.height_num;
  const MapKind kind = choose_kind ? params_.map_kind : part.map.kind;
  part.map = PartMap{};
  if (kind == MapKind::Cylinder || kind == MapKind::Auto) {
    part.map.cylinder = CylinderMap(bvh, vertices_, part.triangles, part.frame, m, n);
  }
  if (kind == MapKind::Sphere || kind == MapKind::Auto) {
    part.map.sphere = SphereMap(bvh, vertices_, part.triangles, part.frame, m, n);
  }
  if (kind != MapKind::Auto) {
    part.map.kind = kind;
    return;
  }
  /* Automatic choice: the map with the smaller mean depth error against the exact part
   * surface, measured 2% of the part's size inside and outside its triangles. */
  const MeshDistance exact(vertices_, part.triangles);
  const float part_size = glm::length(bvh.bounds_max() - bvh.bounds_min());
  const std::vector<vec3> points =
      error_sample_points(vertices_, part.triangles, 0.02f * part_size, 2000);
  part.cylinder_error = mean_depth_error(part.map.cylinder, exact, points);
  part.sphere_error = mean_depth_error(part.map.sphere, exact, points);
  if (part.sphere_error < part.cylinder_error) {
    part.map.kind = MapKind::Sphere;
    part.map.cylinder = CylinderMap();
  }
  else {
    part.map.kind = MapKind::Cylinder;
    part.map.sphere = SphereMap();
  }
}

void Collider::rebuild(const Span<vec3> vertices_object)
{
  assert(vertices_object.size() == int64_t(vertices_.size()));
  const auto start = std::chrono::steady_clock::now();
  std::copy(vertices_object.begin(), vertices_object.end(), vertices_.begin());
  for (Part &part : parts_) {
    build_part(part, false);
  }
  exact_ = MeshDistance(vertices_, triangles_);
  size_ = glm::length(exact_.bvh().bounds_max() - exact_.bvh().bounds_min());
  set_transform(object_to_world_);
  build_ms_ =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

void Collider::set_transform(const mat4 &object_to_world)
{
  object_to_world_ = object_to_world;
  world_to_object_ = glm::inverse(object_to_world);
  /* Similarity test: the columns of the linear part are orthogonal and of equal length. */
  const mat3 linear(object_to_world);
  const mat3 gram = glm::transpose(linear) * linear;
  const float scale_sq = (gram[0][0] + gram[1][1] + gram[2][2]) / 3.0f;
  float off = 0.0f;
  for (int i = 0; i < 3; i++) {
    for (int j = 0; j < 3; j++) {
      off = std::max(off, std::abs(gram[i][j] - (i == j ? scale_sq : 0.0f)));
    }
  }
  similarity_scale_ = scale_sq > 0.0f && off <= 1e-5f * scale_sq ? std::sqrt(scale_sq) : 0.0f;
  for (Part &part : parts_) {
    const MapFrame &frame = part.map.frame();
    const mat4 map_to_world = object_to_world * frame.map_to_object();
    part.world_to_map = Affine::from(frame.object_to_map() * world_to_object_);
    part.map_to_world = Affine::from(map_to_world);
    part.normal_to_world = glm::transpose(glm::inverse(mat3(map_to_world)));
  }
}

float ColliderSet::size_wo() const
{
  float size = 0.0f;
  for (size_t i = 0; i < colliders_.size(); i++) {
    size = i == 0 ? colliders_[i]->size_wo() : std::min(size, colliders_[i]->size_wo());
  }
  return size;
}

PenetrationStats ColliderSet::penetration_stats(const Span<vec3> points_wo,
                                                const float tolerance_wo,
                                                const Span<int32_t> curve_offsets) const
{
  std::vector<float> depths(size_t(points_wo.size()), 0.0f);
  for (const std::shared_ptr<Collider> &collider : colliders_) {
    accumulate_penetration_depths(collider->exact(), collider->object_to_world(), points_wo,
                                  depths);
  }
  if (curve_offsets.is_empty()) {
    return hairdyn::penetration_stats(depths, tolerance_wo);
  }
  /* Roots apart: their depths out of the list, counted on their own. */
  std::vector<float> others;
  others.reserve(depths.size());
  int64_t roots_inside = 0;
  float roots_depth_max = 0.0f;
  for (int64_t curve = 0; curve + 1 < curve_offsets.size(); curve++) {
    const int32_t root = curve_offsets[curve];
    if (curve_offsets[curve + 1] == root) {
      continue;
    }
    roots_inside += depths[size_t(root)] > tolerance_wo ? 1 : 0;
    roots_depth_max = std::max(roots_depth_max, depths[size_t(root)]);
    others.insert(others.end(), depths.begin() + root + 1,
                  depths.begin() + curve_offsets[curve + 1]);
  }
  PenetrationStats stats = hairdyn::penetration_stats(others, tolerance_wo);
  stats.roots_inside = roots_inside;
  stats.roots_depth_max = roots_depth_max;
  return stats;
}

namespace {

/* Whether the AVX2 code runs: where the CPU has it (HAIRDYN_COLLISION_AVX2 where it is built). */
bool avx2_built_and_available()
{
#if defined(HAIRDYN_COLLISION_AVX2)
  return cpu_has_avx2();
#else
  return false;
#endif
}

std::atomic<bool> use_avx2{ avx2_built_and_available() };

using OutputSpans = std::tuple<MutableSpan<uint8_t>, MutableSpan<float>, MutableSpan<vec3>,
                               MutableSpan<vec3>>;

#if defined(HAIRDYN_COLLISION_AVX2)
/* ContactBatch::load eight points at a time: load_xyz4's shuffles on two groups of four points
 * at once (points k .. k + 3 in the low halves, k + 4 .. k + 7 in the high halves). */
__attribute__((target("avx2"))) void load_avx2(ContactBatch<map_batch_size> &contacts,
                                               const Span<vec3> points_wo)
{
  contacts.size = points_wo.size();
  contacts.fresh = true;
  const int64_t size = contacts.size;
  int64_t k = 0;
  for (; k + 8 <= size; k += 8) {
    const float *f = &points_wo[k].x;
    const __m256 a = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(f)),
                                          _mm_loadu_ps(f + 12), 1);
    const __m256 b = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(f + 4)),
                                          _mm_loadu_ps(f + 16), 1);
    const __m256 c = _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_loadu_ps(f + 8)),
                                          _mm_loadu_ps(f + 20), 1);
    const __m256 x2y2z2x3 = _mm256_shuffle_ps(b, c, _MM_SHUFFLE(1, 0, 3, 2));
    _mm256_storeu_ps(contacts.px + k, _mm256_shuffle_ps(a, x2y2z2x3, _MM_SHUFFLE(3, 0, 3, 0)));
    const __m256 y0y1 = _mm256_shuffle_ps(a, b, _MM_SHUFFLE(0, 0, 1, 1));
    const __m256 y2y3 = _mm256_shuffle_ps(b, c, _MM_SHUFFLE(2, 2, 3, 3));
    _mm256_storeu_ps(contacts.py + k, _mm256_shuffle_ps(y0y1, y2y3, _MM_SHUFFLE(2, 0, 2, 0)));
    const __m256 z0z1 = _mm256_shuffle_ps(a, b, _MM_SHUFFLE(1, 1, 2, 2));
    const __m256 z2z3 = _mm256_shuffle_ps(c, c, _MM_SHUFFLE(3, 3, 0, 0));
    _mm256_storeu_ps(contacts.pz + k, _mm256_shuffle_ps(z0z1, z2z3, _MM_SHUFFLE(2, 0, 2, 0)));
  }
  for (; k < size; k++) {
    contacts.px[k] = points_wo[k].x;
    contacts.py[k] = points_wo[k].y;
    contacts.pz[k] = points_wo[k].z;
  }
}

/* store_xyz4 on two groups of four points at once (as load_avx2). */
__attribute__((target("avx2"))) inline void store_xyz8(vec3 *p, const __m256 x, const __m256 y,
                                                       const __m256 z)
{
  float *f = &p->x;
  const __m256 xy01 = _mm256_unpacklo_ps(x, y), xy23 = _mm256_unpackhi_ps(x, y);
  const __m256 z0x1 = _mm256_shuffle_ps(z, xy01, _MM_SHUFFLE(2, 2, 0, 0));
  const __m256 a = _mm256_shuffle_ps(xy01, z0x1, _MM_SHUFFLE(2, 0, 1, 0));
  const __m256 y1z1 = _mm256_shuffle_ps(xy01, z, _MM_SHUFFLE(1, 1, 3, 3));
  const __m256 b = _mm256_shuffle_ps(y1z1, xy23, _MM_SHUFFLE(1, 0, 2, 0));
  const __m256 z2x3 = _mm256_shuffle_ps(z, xy23, _MM_SHUFFLE(2, 2, 2, 2));
  const __m256 y3z3 = _mm256_shuffle_ps(xy23, z, _MM_SHUFFLE(3, 3, 3, 3));
  const __m256 c = _mm256_shuffle_ps(z2x3, y3z3, _MM_SHUFFLE(2, 0, 2, 0));
  _mm_storeu_ps(f, _mm256_castps256_ps128(a));
  _mm_storeu_ps(f + 4, _mm256_castps256_ps128(b));
  _mm_storeu_ps(f + 8, _mm256_castps256_ps128(c));
  _mm_storeu_ps(f + 12, _mm256_extractf128_ps(a, 1));
  _mm_storeu_ps(f + 16, _mm256_extractf128_ps(b, 1));
  _mm_storeu_ps(f + 20, _mm256_extractf128_ps(c, 1));
}

/* ContactBatch::store eight points at a time. */
__attribute__((target("avx2"))) void store_avx2(ContactBatch<map_batch_size> &contacts,
                                                const int64_t start,
                                                const MutableSpan<uint8_t> r_hit,
                                                const MutableSpan<float> r_depth,
                                                const MutableSpan<vec3> r_normal_wo,
                                                const MutableSpan<vec3> r_surface_point_wo)
{
  contacts.set_untouched();
  const int64_t size = contacts.size;
  int64_t k = 0;
  for (; k + 8 <= size; k += 8) {
    const int64_t i = start + k;
    /* hit is 0 or 1: eight bytes. */
    const __m256i h = _mm256_loadu_si256(reinterpret_cast<const __m256i *>(contacts.hit + k));
    const __m128i h16 = _mm_packs_epi32(_mm256_castsi256_si128(h), _mm256_extracti128_si256(h, 1));
    _mm_storel_epi64(reinterpret_cast<__m128i *>(r_hit.data() + i), _mm_packus_epi16(h16, h16));
    _mm256_storeu_ps(r_depth.data() + i, _mm256_loadu_ps(contacts.depth + k));
    store_xyz8(r_normal_wo.data() + i, _mm256_loadu_ps(contacts.nx + k),
               _mm256_loadu_ps(contacts.ny + k), _mm256_loadu_ps(contacts.nz + k));
    store_xyz8(r_surface_point_wo.data() + i, _mm256_loadu_ps(contacts.sx + k),
               _mm256_loadu_ps(contacts.sy + k), _mm256_loadu_ps(contacts.sz + k));
  }
  for (; k < size; k++) {
    const int64_t i = start + k;
    r_hit[i] = uint8_t(contacts.hit[k]);
    r_depth[i] = contacts.depth[k];
    r_normal_wo[i] = vec3(contacts.nx[k], contacts.ny[k], contacts.nz[k]);
    r_surface_point_wo[i] = vec3(contacts.sx[k], contacts.sy[k], contacts.sz[k]);
  }
}
#endif

/* The batches of one range of the parallel query: load, every collider, store. */
template<bool avx2> HAIRDYN_BATCH_INLINE void find_contacts_range(
    const ColliderSet &colliders, const Span<vec3> points_wo, const IndexRange range,
    ContactBatch<map_batch_size> &contacts, MapBatch<map_batch_size> &scratch,
    const OutputSpans &outputs)
{
  scratch.avx2 = avx2;
  for (int64_t start = range.start; start < range.one_after_last(); start += map_batch_size) {
    const int64_t size = std::min(map_batch_size, range.one_after_last() - start);
#if defined(HAIRDYN_COLLISION_AVX2)
    if constexpr (avx2) {
      load_avx2(contacts, points_wo.slice(start, size));
    }
    else
#endif
    {
      contacts.load(points_wo.slice(start, size));
    }
    colliders.accumulate_contacts(contacts, scratch);
    /* A point inside nothing: depth 0, normal 0, itself (ContactBatch::set_untouched). */
#if defined(HAIRDYN_COLLISION_AVX2)
    if constexpr (avx2) {
      store_avx2(contacts, start, std::get<0>(outputs), std::get<1>(outputs),
                 std::get<2>(outputs), std::get<3>(outputs));
      continue;
    }
#endif
    contacts.store(start, std::get<0>(outputs), std::get<1>(outputs), std::get<2>(outputs),
                   std::get<3>(outputs));
  }
}

/* The range compiled twice: for AVX2 (8 lanes, and RadialTable::blend_avx2) and for the
 * x86-64 baseline (SSE2, 4 lanes), chosen at run time by use_avx2. The same IEEE operations
 * in the same order (no FMA: -std=c++17 leaves contraction off, and target("avx2") does not
 * enable FMA), so both give the same bits; CollisionRobustness checks it. */
#if defined(HAIRDYN_COLLISION_AVX2)
__attribute__((target("avx2"))) void find_contacts_range_avx2(
    const ColliderSet &colliders, const Span<vec3> points_wo, const IndexRange range,
    ContactBatch<map_batch_size> &contacts, MapBatch<map_batch_size> &scratch,
    const OutputSpans &outputs)
{
  find_contacts_range<true>(colliders, points_wo, range, contacts, scratch, outputs);
}
#endif

void find_contacts_range_baseline(const ColliderSet &colliders, const Span<vec3> points_wo,
                                  const IndexRange range, ContactBatch<map_batch_size> &contacts,
                                  MapBatch<map_batch_size> &scratch, const OutputSpans &outputs)
{
  find_contacts_range<false>(colliders, points_wo, range, contacts, scratch, outputs);
}

}  // namespace

bool collision_avx2_available()
{
  return avx2_built_and_available();
}

void set_collision_avx2(const bool enabled)
{
  use_avx2 = enabled && avx2_built_and_available();
}

bool collision_avx2_used()
{
  return use_avx2;
}

void find_contacts_serial(const ColliderSet &colliders, const Span<vec3> points_wo,
                          const MutableSpan<uint8_t> r_hit, const MutableSpan<float> r_depth,
                          const MutableSpan<vec3> r_normal_wo,
                          const MutableSpan<vec3> r_surface_point_wo,
                          ContactBatch<map_batch_size> &contacts, MapBatch<map_batch_size> &scratch)
{
  const OutputSpans outputs{ r_hit, r_depth, r_normal_wo, r_surface_point_wo };
  const IndexRange range{ 0, points_wo.size() };
#if defined(HAIRDYN_COLLISION_AVX2)
  if (use_avx2) {
    find_contacts_range_avx2(colliders, points_wo, range, contacts, scratch, outputs);
    return;
  }
#endif
  find_contacts_range_baseline(colliders, points_wo, range, contacts, scratch, outputs);
}

void find_contacts(const ColliderSet &colliders, const Span<vec3> points_wo,
                   const MutableSpan<uint8_t> r_hit, const MutableSpan<float> r_depth,
                   const MutableSpan<vec3> r_normal_wo, const MutableSpan<vec3> r_surface_point_wo)
{
  parallel_for(points_wo.size(), 4096, [&](const IndexRange range) {
    /* About 30 KB of batch arrays: per thread, off the (small) worker stacks; left
     * uninitialised (every stage writes what the next reads). */
    const std::unique_ptr<ContactBatch<map_batch_size>> contacts(
        new ContactBatch<map_batch_size>);
    const std::unique_ptr<MapBatch<map_batch_size>> scratch(new MapBatch<map_batch_size>);
    find_contacts_serial(colliders, points_wo.slice(range.start, range.size),
                         r_hit.slice(range.start, range.size),
                         r_depth.slice(range.start, range.size),
                         r_normal_wo.slice(range.start, range.size),
                         r_surface_point_wo.slice(range.start, range.size), *contacts, *scratch);
  });
}

}  // namespace hairdyn
