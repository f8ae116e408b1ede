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

  const MapFrame &frame() const { return kind == MapKind::Sphere ? sphere.frame() : cylinder.frame(); }
  bool evaluate(const vec3 &p_object, MapSample &r_sample) const
  {
    return kind == MapKind::Sphere ? sphere.evaluate(p_object, r_sample) :
                                     cylinder.evaluate(p_object, r_sample);
  }
  bool find_contact_map(const vec3 &p_map, MapSample &r_sample) const
  {
    return kind == MapKind::Sphere ? sphere.find_contact_map(p_map, r_sample) :
                                     cylinder.find_contact_map(p_map, r_sample);
  }
};

/* Points to measure a map against the exact surface: the centroids of (at most
 * max_points_num / 2 evenly strided) triangles, moved by ±offset along the face normal. */
std::vector<vec3> error_sample_points(Span<vec3> vertices, Span<ivec3> triangles, float offset,
                                      int64_t max_points_num);

/* Mean |map depth - exact depth| over points (object space), in object units. Where the map
 * is undefined (out of range, empty cells) a point inside the mesh counts its full depth (a
 * missed collision) and a point outside counts 0. Map: CylinderMap, SphereMap or PartMap. */
template<typename Map>
float mean_depth_error(const Map &map, const MeshDistance &exact, const Span<vec3> points_object)
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

/* A rigid or affine map between spaces, applied as linear * p + translation. */
struct Affine {
  mat3 linear{1.0f};
  vec3 translation{0.0f};
  vec3 apply(const vec3 &p) const { return linear * p + translation; }
  static Affine from(const mat4 &m) { return {mat3(m), vec3(m[3])}; }
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
    bool found = false;
    for (const Part &part : parts_) {
      MapSample sample;
      if (!part.map.find_contact_map(part.world_to_map.apply(p_wo), sample)) {
        continue;
      }
      const vec3 surface_wo = part.map_to_world.apply(sample.surface_point);
      /* A similarity (rotation, translation, uniform scale) keeps distances and normals up to
       * the scale; other affine maps need the lengths measured again. */
      const float depth_wo = similarity_scale_ > 0.0f ? sample.depth * similarity_scale_ :
                                                        glm::length(surface_wo - p_wo);
      if (found && depth_wo <= r_contact.depth) {
        continue;
      }
      found = true;
      r_contact.depth = depth_wo;
      r_contact.surface_point_wo = surface_wo;
      const vec3 normal_wo = part.normal_to_world * sample.normal;
      r_contact.normal_wo = similarity_scale_ > 0.0f ? normal_wo * similarity_scale_ :
                                                       glm::normalize(normal_wo);
    }
    return found;
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
    mat3 normal_to_world{1.0f};
  };
  void build_part(Part &part, bool choose_kind);
  MapFrame part_frame(const Part &part) const;

  CollisionParams params_;
  std::vector<vec3> vertices_;
  std::vector<ivec3> triangles_;
  std::vector<Part> parts_;
  MeshDistance exact_;
  float size_ = 0.0f;
  mat4 object_to_world_{1.0f};
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
    bool found = false;
    for (const std::shared_ptr<Collider> &collider : colliders_) {
      Contact contact;
      if (collider->find_contact(p_wo, contact) && (!found || contact.depth > r_contact.depth)) {
        r_contact = contact;
        found = true;
      }
    }
    return found;
  }
  /* The smallest collider's size in world units (for tolerances relative to collider size). */
  float size_wo() const;
  /* Exact penetration of points into the real triangles of all colliders (deepest per point). */
  PenetrationStats penetration_stats(Span<vec3> points_wo, float tolerance_wo) const;

 private:
  std::vector<std::shared_ptr<Collider>> colliders_;
};

/* Contacts for many points: r_hit[i] = 1 and the contact where points_wo[i] is inside; 0, depth
 * 0, normal 0 and the point itself where it is not. */
void find_contacts(const ColliderSet &colliders, Span<vec3> points_wo, MutableSpan<uint8_t> r_hit,
                   MutableSpan<float> r_depth, MutableSpan<vec3> r_normal_wo,
                   MutableSpan<vec3> r_surface_point_wo);

}  // namespace hairdyn
