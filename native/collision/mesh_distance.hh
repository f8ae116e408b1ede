#pragma once
/* Exact signed distance to a triangle mesh, for the penetration report (never for the
 * per-step queries, which use the maps). Closest point from a BVH; inside/outside from the
 * angle-weighted pseudo-normal of the closest feature (Bærentzen and Aanæs 2005): the face
 * normal, the sum of the two face normals of an edge, or the angle-weighted sum of a vertex's
 * face normals. Exact for closed, consistently wound meshes; on an open mesh the sign is that
 * of the nearest surface's front side, which is still right near the surface. */
#include <memory>
#include <mutex>
#include <vector>

#include "collision/bvh.hh"
#include "core/math.hh"
#include "core/span.hh"

namespace hairdyn {

class MeshDistance {
 public:
  MeshDistance() = default;
  /* Valid indices (find_mesh_error); at least one triangle. */
  MeshDistance(Span<vec3> vertices, Span<ivec3> triangles);

  /* < 0 inside, > 0 outside, in object units. */
  float signed_distance(const vec3 &p) const;
  /* Depth inside the mesh (> 0), or 0 outside; cheap for points outside the bounding box. */
  float depth(const vec3 &p) const;
  /* Whether depth() exceeds `tolerance` at any of the samples + 1 evenly spaced points from a
   * to b (both ends included). The signed distance is 1-Lipschitz, so the points within
   * (signed distance + tolerance) of a sample are no deeper than the tolerance and are not
   * queried: the same answer as each point's depth() for a few queries a segment. */
  bool deeper_on_segment(const vec3 &a, const vec3 &b, int samples, float tolerance) const;
  /* r_depth[i] = max(r_depth[i], depth(world_to_object · points_wo[i]) · scale). Each call
   * remembers, per index, a point and a lower bound of its signed distance; the signed
   * distance is 1-Lipschitz (|S(p) − S(q)| ≤ |p − q|), so a point that cannot have reached the
   * surface since (bound − distance moved > 0) is outside without a query. Hair moves
   * millimetres per frame and mostly stays centimetres out, so most queries of a frame's
   * penetration report are skipped, and the depths are the same. A point within rounding
   * (1e-5 of the mesh's size) of where it was last asked, as a root carried with the head
   * is, keeps that answer, off by at most that distance. Safe from several threads. */
  void accumulate_depths(const mat4 &world_to_object, float scale, Span<vec3> points_wo,
                         MutableSpan<float> r_depth) const;
  const TriangleBVH &bvh() const { return bvh_; }

 private:
  struct Bounds {
    std::mutex mutex;
    std::vector<vec3> points;     /* object space */
    std::vector<float> distances; /* the signed distance there, or a lower bound of it
                                   * where positive (NaN: unknown) */
  };
  std::shared_ptr<Bounds> bounds_ = std::make_shared<Bounds>();

  TriangleBVH bvh_;
  std::vector<vec3> face_normals_;   /* Unit, per triangle. */
  std::vector<vec3> edge_normals_;   /* Per triangle corner k: edge (k, k+1). */
  std::vector<vec3> vertex_normals_; /* Per triangle corner k: its vertex's pseudo-normal. */
};

struct PenetrationStats {
  float max_depth = 0.0f;   /* Deepest point inside, scene units (0 if none is inside). */
  float share = 0.0f;       /* Share of points deeper than the tolerance, 0..1. */
  int64_t deeper_num = 0;   /* Points deeper than the tolerance. */
  int64_t points_num = 0;
  /* With curve offsets, the strands' roots are counted apart (they are kinematic: a root that
   * starts inside a collider stays inside, and is not the solver's penetration). */
  int64_t roots_inside = 0;     /* Roots deeper than the tolerance. */
  float roots_depth_max = 0.0f; /* Deepest root, scene units. */
};

/* r_depth_wo[i] = max(r_depth_wo[i], depth of points_wo[i] inside the mesh placed by
 * object_to_world). Depths are exact for rigid transforms with uniform scale (object depth ×
 * scale). Start from zeros; call once per collider. */
void accumulate_penetration_depths(const MeshDistance &mesh, const mat4 &object_to_world,
                                   Span<vec3> points_wo, MutableSpan<float> r_depth_wo);
/* Maximum and share of depths deeper than tolerance_wo (scene units). */
PenetrationStats penetration_stats(Span<float> depths_wo, float tolerance_wo);
/* Both steps for one mesh. */
PenetrationStats penetration_stats(const MeshDistance &mesh, const mat4 &object_to_world,
                                   Span<vec3> points_wo, float tolerance_wo);

/* Uniform scale of a transform: cube root of |det| of its 3x3 part. */
float uniform_scale(const mat4 &m);

}  // namespace hairdyn
