#pragma once
/* What the solvers use for hair–object collision.
 *
 * A Collider is one collider object: its triangles in object space, split into parts (vertex
 * groups: head, neck, torso...), each described by a cylindrical (Kurihara 1993 §3.1) or
 * spherical (§5) map built once in object space. Per frame it gets the object's
 * object-to-world matrix; rigid motion is handled by taking query points into map space, so
 * nothing is rebuilt. A deforming collider calls rebuild() with its new vertex positions
 * (build_ms() reports what that cost). It also keeps the exact mesh distance for the
 * penetration report.
 *
 * A ColliderSet is the scene's colliders; find_contact() is the call the strand and LCP
 * solvers make for every node: a few table look-ups per part, no allocation, cost independent
 * of the meshes. */
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "collision/collision_params.hh"
#include "collision/contact.hh"
#include "collision/cylinder_map_kurihara1993.hh"
#include "collision/mesh.hh"
#include "collision/mesh_distance.hh"
#include "collision/sphere_map.hh"

namespace hairdyn {

/* One part's map: whichever kind describes it (the other stays empty). */
struct PartMap {
  MapKind kind = MapKind::Cylinder; /* Cylinder or Sphere, never Auto. */
  CylinderMap cylinder;
  SphereMap sphere;

  const MapFrame &frame() const
  {
    return kind == MapKind::Sphere ? sphere.frame() : cylinder.frame();
  }
  bool evaluate(const vec3 &p_object, MapSample &r_sample) const
  {
    return kind == MapKind::Sphere ? sphere.evaluate(p_object, r_sample)
                                   : cylinder.evaluate(p_object, r_sample);
  }
  bool find_contact_map(const vec3 &p_map, MapSample &r_sample) const
  {
    return kind == MapKind::Sphere ? sphere.find_contact_map(p_map, r_sample)
                                   : cylinder.find_contact_map(p_map, r_sample);
  }
  /* The map kind is resolved once per batch. */
  template<bool inside_only, int64_t N> HAIRDYN_BATCH_INLINE void sample(MapBatch<N> &b) const
  {
    if (kind == MapKind::Sphere) {
      sphere.template sample<inside_only>(b);
    }
    else {
      cylinder.template sample<inside_only>(b);
    }
  }
};

/* a where mask is all ones, b where it is 0, by the bits: GCC would turn a `take ? a : b`
 * stored back into its own array into a branch around the store, which does not vectorise. */
HAIRDYN_BATCH_INLINE float select_bits(const int32_t mask, const float a, const float b)
{
  int32_t bits_a, bits_b;
  std::memcpy(&bits_a, &a, sizeof(float));
  std::memcpy(&bits_b, &b, sizeof(float));
  const int32_t bits = (bits_a & mask) | (bits_b & ~mask);
  float result;
  std::memcpy(&result, &bits, sizeof(float));
  return result;
}

#if defined(__SSE2__)
static_assert(sizeof(vec3) == 12, "packed vec3: four of them are three 16-byte vectors");

/* Four packed vec3 (x0 y0 z0 x1 | y1 z1 x2 y2 | z2 x3 y3 z3) as the vectors x, y, z. */
HAIRDYN_BATCH_INLINE void load_xyz4(const vec3 *p, __m128 &r_x, __m128 &r_y, __m128 &r_z)
{
  const float *f = &p->x;
  const __m128 a = _mm_loadu_ps(f), b = _mm_loadu_ps(f + 4), c = _mm_loadu_ps(f + 8);
  const __m128 x2y2z2x3 = _mm_shuffle_ps(b, c, _MM_SHUFFLE(1, 0, 3, 2));
  r_x = _mm_shuffle_ps(a, x2y2z2x3, _MM_SHUFFLE(3, 0, 3, 0));
  const __m128 y0y1 = _mm_shuffle_ps(a, b, _MM_SHUFFLE(0, 0, 1, 1));
  const __m128 y2y3 = _mm_shuffle_ps(b, c, _MM_SHUFFLE(2, 2, 3, 3));
  r_y = _mm_shuffle_ps(y0y1, y2y3, _MM_SHUFFLE(2, 0, 2, 0));
  const __m128 z0z1 = _mm_shuffle_ps(a, b, _MM_SHUFFLE(1, 1, 2, 2));
  const __m128 z2z3 = _mm_shuffle_ps(c, c, _MM_SHUFFLE(3, 3, 0, 0));
  r_z = _mm_shuffle_ps(z0z1, z2z3, _MM_SHUFFLE(2, 0, 2, 0));
}

/* The inverse of load_xyz4. */
HAIRDYN_BATCH_INLINE void store_xyz4(vec3 *p, const __m128 x, const __m128 y, const __m128 z)
{
  float *f = &p->x;
  const __m128 xy01 = _mm_unpacklo_ps(x, y), xy23 = _mm_unpackhi_ps(x, y);
  const __m128 z0x1 = _mm_shuffle_ps(z, xy01, _MM_SHUFFLE(2, 2, 0, 0));
  _mm_storeu_ps(f, _mm_shuffle_ps(xy01, z0x1, _MM_SHUFFLE(2, 0, 1, 0)));
  const __m128 y1z1 = _mm_shuffle_ps(xy01, z, _MM_SHUFFLE(1, 1, 3, 3));
  _mm_storeu_ps(f + 4, _mm_shuffle_ps(y1z1, xy23, _MM_SHUFFLE(1, 0, 2, 0)));
  const __m128 z2x3 = _mm_shuffle_ps(z, xy23, _MM_SHUFFLE(2, 2, 2, 2));
  const __m128 y3z3 = _mm_shuffle_ps(xy23, z, _MM_SHUFFLE(3, 3, 3, 3));
  _mm_storeu_ps(f + 8, _mm_shuffle_ps(z2x3, y3z3, _MM_SHUFFLE(2, 0, 2, 0)));
}
#endif

/* The deepest contacts found so far for a batch of world points (structure of arrays, as
 * MapBatch): hit, depth, normal n and surface point s, world space. */
template<int64_t N> struct ContactBatch {
  int64_t size = 0;
  /* No part has been looked up since load(): hit and the contact arrays are not set yet (the
   * first part sets them without reading them; set_untouched sets them otherwise). */
  bool fresh = false;
  float px[N], py[N], pz[N];
  int32_t hit[N];
  float depth[N], nx[N], ny[N], nz[N], sx[N], sy[N], sz[N];

  HAIRDYN_BATCH_INLINE void load(const Span<vec3> points_wo)
  {
    size = points_wo.size();
    int64_t k = 0;
#if defined(__SSE2__)
    for (; N >= 4 && k + 4 <= size; k += 4) {
      __m128 x, y, z;
      load_xyz4(points_wo.data() + k, x, y, z);
      _mm_storeu_ps(px + k, x);
      _mm_storeu_ps(py + k, y);
      _mm_storeu_ps(pz + k, z);
    }
#endif
    for (; k < size; k++) {
      px[k] = points_wo[k].x;
      py[k] = points_wo[k].y;
      pz[k] = points_wo[k].z;
    }
    fresh = true;
    if constexpr (N == 1) {
      /* A single point (the per-point calls) is set at once: as cheap, and plain to the
       * compiler's uninitialised-use analysis. */
      set_untouched();
    }
  }
  /* Inside nothing yet: hit 0, depth 0, normal 0, the point itself. */
  HAIRDYN_BATCH_INLINE void set_untouched()
  {
    if (!fresh) {
      return;
    }
    fresh = false;
    for (int64_t k = 0; k < size; k++) {
      hit[k] = 0;
      depth[k] = nx[k] = ny[k] = nz[k] = 0.0f;
      sx[k] = px[k];
      sy[k] = py[k];
      sz[k] = pz[k];
    }
  }
  /* Writes the batch to the outputs of find_contacts, from index `start` on. */
  HAIRDYN_BATCH_INLINE void store(const int64_t start, const MutableSpan<uint8_t> r_hit,
                                  const MutableSpan<float> r_depth,
                                  const MutableSpan<vec3> r_normal_wo,
                                  const MutableSpan<vec3> r_surface_point_wo)
  {
    set_untouched();
    int64_t k = 0;
#if defined(__SSE2__)
    for (; N >= 4 && k + 4 <= size; k += 4) {
      const int64_t i = start + k;
      const __m128i h = _mm_loadu_si128(reinterpret_cast<const __m128i *>(hit + k));
      const __m128i h16 = _mm_packs_epi32(h, h);
      const int32_t h8 = _mm_cvtsi128_si32(_mm_packus_epi16(h16, h16));
      std::memcpy(r_hit.data() + i, &h8, 4);
      _mm_storeu_ps(r_depth.data() + i, _mm_loadu_ps(depth + k));
      store_xyz4(r_normal_wo.data() + i, _mm_loadu_ps(nx + k), _mm_loadu_ps(ny + k),
                 _mm_loadu_ps(nz + k));
      store_xyz4(r_surface_point_wo.data() + i, _mm_loadu_ps(sx + k), _mm_loadu_ps(sy + k),
                 _mm_loadu_ps(sz + k));
    }
#endif
    for (; k < size; k++) {
      const int64_t i = start + k;
      r_hit[i] = uint8_t(hit[k]);
      r_depth[i] = depth[k];
      r_normal_wo[i] = vec3(nx[k], ny[k], nz[k]);
      r_surface_point_wo[i] = vec3(sx[k], sy[k], sz[k]);
    }
  }
  bool read(const int64_t k, Contact &r_contact)
  {
    set_untouched();
    if (!hit[k]) {
      return false;
    }
    r_contact.depth = depth[k];
    r_contact.normal_wo = vec3(nx[k], ny[k], nz[k]);
    r_contact.surface_point_wo = vec3(sx[k], sy[k], sz[k]);
    return true;
  }
};

/* Points to measure a map against the exact surface: the centroids of (at most
 * max_points_num / 2 evenly strided) triangles, moved by ±offset along the face normal. */
std::vector<vec3> error_sample_points(Span<vec3> vertices, Span<ivec3> triangles, float offset,
                                      int64_t max_points_num);

/* Mean |map depth - exact depth| over points (object space), in object units. Where the map
 * is undefined (out of range, empty cells) a point inside the mesh counts its full depth (a
 * missed collision) and a point outside counts 0. Map: CylinderMap, SphereMap or PartMap. */
template<typename Map> float mean_depth_error(const Map &map, const MeshDistance &exact,
                                              const Span<vec3> points_object)
{
  double sum = 0.0;
  for (const vec3 &p : points_object) {
    const float exact_depth = -exact.signed_distance(p);
    MapSample sample;
    if (map.evaluate(p, sample)) {
      sum += std::abs(double(sample.depth) - double(exact_depth));
    }
    else {
      sum += std::max(double(exact_depth), 0.0);
    }
  }
  return points_object.is_empty() ? 0.0f : float(sum / double(points_object.size()));
}

/* The per-point query of a Collider or a ColliderSet: the batched query with a batch of one. */
template<typename Colliders> bool find_contact_of(const Colliders &colliders, const vec3 &p_wo,
                                                  Contact &r_contact)
{
  ContactBatch<1> contacts;
  contacts.load(Span<vec3>(&p_wo, 1));
  MapBatch<1> scratch;
  colliders.accumulate_contacts(contacts, scratch);
  return contacts.read(0, r_contact);
}

/* A rigid or affine map between spaces, applied as linear * p + translation. */
struct Affine {
  mat3 linear{ 1.0f };
  vec3 translation{ 0.0f };
  vec3 apply(const vec3 &p) const { return linear * p + translation; }
  static Affine from(const mat4 &m) { return { mat3(m), vec3(m[3]) }; }
};

class Collider {
 public:
  /* Parts: part p has the vertices part_vertices[part_offsets[p] .. part_offsets[p + 1]); a
   * triangle belongs to a part when all three of its vertices do. No offsets = one part, the
   * whole mesh. part_frames: explicit map frames (object space), one per part, or empty to
   * take them from params.axis_mode. Must pass find_collider_error. */
  Collider(const ColliderMesh &mesh, Span<int32_t> part_offsets, Span<int32_t> part_vertices,
           const CollisionParams &params, Span<MapFrame> part_frames = {});

  /* New vertex positions (object space, same count and triangles) of a deforming collider:
   * rebuilds every part's map with the kind chosen at construction, refits fitted axes, and
   * rebuilds the exact distance. */
  void rebuild(Span<vec3> vertices_object);
  /* The object's object-to-world matrix for the current frame (no rebuild). */
  void set_transform(const mat4 &object_to_world);

  /* The deepest contact of p with any part; false when p is inside none. */
  bool find_contact(const vec3 &p_wo, Contact &r_contact) const
  {
    return find_contact_of(*this, p_wo, r_contact);
  }

  /* Updates each point of `contacts` that is inside a part deeper than its contact so far
   * (the batched query: per part, one pass of each stage over the batch). */
  template<int64_t N> HAIRDYN_BATCH_INLINE void accumulate_contacts(ContactBatch<N> &contacts,
                                                                    MapBatch<N> &scratch) const
  {
    const int64_t size = contacts.size;
    scratch.size = size;
    for (const Part &part : parts_) {
      const mat3 l = part.world_to_map.linear;
      const vec3 t = part.world_to_map.translation;
      for (int64_t k = 0; k < size; k++) {
        const float x = contacts.px[k], y = contacts.py[k], z = contacts.pz[k];
        scratch.x[k] = l[0][0] * x + l[1][0] * y + l[2][0] * z + t.x;
        scratch.y[k] = l[0][1] * x + l[1][1] * y + l[2][1] * z + t.y;
        scratch.z[k] = l[0][2] * x + l[1][2] * y + l[2][2] * z + t.z;
      }
      part.map.template sample<true>(scratch);
      if constexpr (N == 1) {
        if (!scratch.valid[0]) {
          continue;
        }
      }
      /* Whether the transform is a similarity is resolved once per part, not per point. */
      if (contacts.fresh) {
        /* The first part: no contact to compare with. */
        contacts.fresh = false;
        if (similarity_scale_ > 0.0f) {
          take_contacts<true, true>(part, similarity_scale_, contacts, scratch);
        }
        else {
          take_contacts<false, true>(part, similarity_scale_, contacts, scratch);
        }
      }
      else if (similarity_scale_ > 0.0f) {
        take_contacts<true, false>(part, similarity_scale_, contacts, scratch);
      }
      else {
        take_contacts<false, false>(part, similarity_scale_, contacts, scratch);
      }
    }
  }

  int64_t parts_num() const { return int64_t(parts_.size()); }
  const PartMap &part_map(int64_t part) const { return parts_[size_t(part)].map; }
  /* Mean depth errors measured when choosing the map kind automatically (object units);
   * -1 when not measured (a kind was forced). */
  float part_cylinder_error(int64_t part) const { return parts_[size_t(part)].cylinder_error; }
  float part_sphere_error(int64_t part) const { return parts_[size_t(part)].sphere_error; }
  /* Milliseconds the last construction or rebuild took (maps, BVHs, exact distance). */
  double build_ms() const { return build_ms_; }
  /* Length of the bounding-box diagonal, in object and in world units. */
  float size() const { return size_; }
  float size_wo() const { return size_ * uniform_scale(object_to_world_); }
  const mat4 &object_to_world() const { return object_to_world_; }
  const mat4 &world_to_object() const { return world_to_object_; }
  const MeshDistance &exact() const { return exact_; }
  /* What ColliderMesh reported at construction, for the caller to warn about. */
  int64_t boundary_edges_num() const { return boundary_edges_num_; }
  int64_t skipped_triangles_num() const { return skipped_triangles_num_; }
  const CollisionParams &params() const { return params_; }
  Span<vec3> vertices() const { return vertices_; }
  Span<ivec3> triangles() const { return triangles_; }

 private:
  struct Part {
    std::vector<ivec3> triangles;
    bool explicit_frame = false;
    MapFrame frame;
    PartMap map;
    float cylinder_error = -1.0f, sphere_error = -1.0f;
    Affine world_to_map, map_to_world;
    mat3 normal_to_world{ 1.0f };
  };
  /* T in world space for a part's map samples, and the deeper contacts taken. A similarity
   * (rotation, translation, uniform scale) keeps distances and normals up to the scale; other
   * affine maps need the lengths measured again. */
  /* With first, the batch holds no contact yet (ContactBatch::fresh): the same values as
   * comparing with set_untouched's, without reading them. */
  template<bool similarity, bool first, int64_t N> static HAIRDYN_BATCH_INLINE void take_contacts(
      const Part &part, const float scale, ContactBatch<N> &contacts, const MapBatch<N> &scratch)
  {
    const int64_t size = contacts.size;
    const mat3 m = part.map_to_world.linear;
    const vec3 mt = part.map_to_world.translation;
    const mat3 nm = part.normal_to_world;
    for (int64_t k = 0; k < size; k++) {
      const float d = scratch.depth[k];
      const float mx = scratch.x[k] + d * scratch.nx[k], my = scratch.y[k] + d * scratch.ny[k],
                  mz = scratch.z[k] + d * scratch.nz[k];
      const float sx = m[0][0] * mx + m[1][0] * my + m[2][0] * mz + mt.x;
      const float sy = m[0][1] * mx + m[1][1] * my + m[2][1] * mz + mt.y;
      const float sz = m[0][2] * mx + m[1][2] * my + m[2][2] * mz + mt.z;
      const float ax = scratch.nx[k], ay = scratch.ny[k], az = scratch.nz[k];
      const float nx = nm[0][0] * ax + nm[1][0] * ay + nm[2][0] * az;
      const float ny = nm[0][1] * ax + nm[1][1] * ay + nm[2][1] * az;
      const float nz = nm[0][2] * ax + nm[1][2] * ay + nm[2][2] * az;
      float depth_wo, n_scale;
      if constexpr (similarity) {
        depth_wo = d * scale;
        n_scale = scale;
      }
      else {
        const float ex = sx - contacts.px[k], ey = sy - contacts.py[k], ez = sz - contacts.pz[k];
        depth_wo = std::sqrt(ex * ex + ey * ey + ez * ez);
        const float n_length = std::sqrt(nx * nx + ny * ny + nz * nz);
        n_scale = 1.0f / (n_length > 0.0f ? n_length : 1.0f);
      }
      if constexpr (first) {
        const int32_t take = scratch.valid[k] != 0 ? 1 : 0;
        const int32_t mask = -take;
        contacts.hit[k] = take;
        contacts.depth[k] = select_bits(mask, depth_wo, 0.0f);
        contacts.nx[k] = select_bits(mask, nx * n_scale, 0.0f);
        contacts.ny[k] = select_bits(mask, ny * n_scale, 0.0f);
        contacts.nz[k] = select_bits(mask, nz * n_scale, 0.0f);
        contacts.sx[k] = select_bits(mask, sx, contacts.px[k]);
        contacts.sy[k] = select_bits(mask, sy, contacts.py[k]);
        contacts.sz[k] = select_bits(mask, sz, contacts.pz[k]);
      }
      else {
        const bool take = (scratch.valid[k] != 0) &
                          ((contacts.hit[k] == 0) | (depth_wo > contacts.depth[k]));
        const int32_t mask = -int32_t(take);
        contacts.hit[k] |= int32_t(take);
        contacts.depth[k] = select_bits(mask, depth_wo, contacts.depth[k]);
        contacts.nx[k] = select_bits(mask, nx * n_scale, contacts.nx[k]);
        contacts.ny[k] = select_bits(mask, ny * n_scale, contacts.ny[k]);
        contacts.nz[k] = select_bits(mask, nz * n_scale, contacts.nz[k]);
        contacts.sx[k] = select_bits(mask, sx, contacts.sx[k]);
        contacts.sy[k] = select_bits(mask, sy, contacts.sy[k]);
        contacts.sz[k] = select_bits(mask, sz, contacts.sz[k]);
      }
    }
  }
  void build_part(Part &part, bool choose_kind);
  MapFrame part_frame(const Part &part) const;

  CollisionParams params_;
  std::vector<vec3> vertices_;
  std::vector<ivec3> triangles_;
  std::vector<Part> parts_;
  MeshDistance exact_;
  float size_ = 0.0f;
  mat4 object_to_world_{ 1.0f };
  mat4 world_to_object_{ 1.0f }; /* its inverse */
  float similarity_scale_ = 1.0f; /* Uniform scale of object_to_world_, 0 if not a similarity. */
  double build_ms_ = 0.0;
  int64_t boundary_edges_num_ = 0;
  int64_t skipped_triangles_num_ = 0;
};

/* Empty when a Collider can be built from the mesh and parts; otherwise one sentence (no
 * usable faces, bad part offsets, a part with no vertices, a vertex index out of range, a part
 * that selects no triangle, a wrong number of explicit frames). Open meshes and meshes with
 * non-manifold triangles are accepted (documented fallback): the maps keep the outermost hit
 * and leave cells empty where rays escape through a hole; skipped non-manifold triangles are
 * counted by ColliderMesh for the caller to report. */
std::string find_collider_error(const ColliderMesh &mesh, Span<int32_t> part_offsets,
                                Span<int32_t> part_vertices, int64_t part_frames_num = 0);

class ColliderSet {
 public:
  void add(std::shared_ptr<Collider> collider) { colliders_.push_back(std::move(collider)); }
  int64_t colliders_num() const { return int64_t(colliders_.size()); }
  const Collider &collider(const int64_t i) const { return *colliders_[size_t(i)]; }
  Collider &collider_for_write(const int64_t i) { return *colliders_[size_t(i)]; }

  /* The deepest contact of p_wo with any collider; false when p_wo is inside none. */
  bool find_contact(const vec3 &p_wo, Contact &r_contact) const
  {
    return find_contact_of(*this, p_wo, r_contact);
  }
  /* The batched query over every collider (the deepest contact wins; ties keep the first). */
  template<int64_t N> HAIRDYN_BATCH_INLINE void accumulate_contacts(ContactBatch<N> &contacts,
                                                                    MapBatch<N> &scratch) const
  {
    for (const std::shared_ptr<Collider> &collider : colliders_) {
      collider->accumulate_contacts(contacts, scratch);
    }
  }
  /* The smallest collider's size in world units (for tolerances relative to collider size). */
  float size_wo() const;
  /* Exact penetration of points into the real triangles of all colliders (deepest per point).
   * Given the strands' curve offsets (valid for points_wo), the roots are left out of
   * max_depth, share and points_num and reported in roots_inside and roots_depth_max. */
  PenetrationStats penetration_stats(Span<vec3> points_wo, float tolerance_wo,
                                     Span<int32_t> curve_offsets = {}) const;

 private:
  std::vector<std::shared_ptr<Collider>> colliders_;
};

/* Whether find_contacts and the hair–hair pass run their AVX2 code: by default where the CPU
 * has AVX2. Turning it off runs the baseline (SSE2) code, for the tests that both give the same
 * bits; not to be changed while a query runs. */
bool collision_avx2_available();
void set_collision_avx2(bool enabled);
bool collision_avx2_used();

/* Contacts for many points: r_hit[i] = 1 and the contact where points_wo[i] is inside; 0, depth
 * 0, normal 0 and the point itself where it is not. */
void find_contacts(const ColliderSet &colliders, Span<vec3> points_wo, MutableSpan<uint8_t> r_hit,
                   MutableSpan<float> r_depth, MutableSpan<vec3> r_normal_wo,
                   MutableSpan<vec3> r_surface_point_wo);
/* The same on the calling thread alone, with the caller's batch arrays (about 30 KB, left
 * uninitialised: every stage writes what the next reads), for callers inside a parallel loop
 * (the strand solver's lanes): a few hundred points cost a quarter per point of what batches
 * of eight do. */
void find_contacts_serial(const ColliderSet &colliders, Span<vec3> points_wo,
                          MutableSpan<uint8_t> r_hit, MutableSpan<float> r_depth,
                          MutableSpan<vec3> r_normal_wo, MutableSpan<vec3> r_surface_point_wo,
                          ContactBatch<map_batch_size> &contacts,
                          MapBatch<map_batch_size> &scratch);

}  // namespace hairdyn
