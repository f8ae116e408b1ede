#pragma once
/* A triangle bounding volume hierarchy for the build-time and report-time queries of
 * collision: ray casts (all hits, farthest hit along a ray) and closest points.
 *
 * Why a BVH: the maps cast m × n rays per part at build time and the penetration report asks
 * for one closest point per hair node; both need sub-linear queries on meshes of up to a few
 * million triangles, and a BVH is the simplest structure that gives O(log T) for both kinds of
 * query (a uniform grid does poorly on closest points far from the surface). The simulation's
 * per-step queries never touch it: they use the maps, whose cost does not depend on the mesh.
 *
 * Binary tree over axis-aligned boxes (median_split_tree), nodes stored depth-first in one
 * array; the triangles are copied in leaf order, so a leaf is a contiguous range. */
#include <vector>

#include "collision/mesh.hh"
#include "core/math.hh"
#include "core/span.hh"

namespace hairdyn {

struct RayHit {
  float t = 0.0f;         /* Hit point = origin + t * direction. */
  int32_t triangle = -1;  /* Index into the triangles the BVH was built from. */
  float u = 0.0f, v = 0.0f; /* Barycentric weights of the triangle's second and third vertex. */
};

/* Which feature of a triangle the closest point lies on: the face's interior, an edge
 * (0 = v0v1, 1 = v1v2, 2 = v2v0) or a vertex (0, 1, 2). Used for the angle-weighted
 * pseudo-normal of mesh_distance. */
enum class TriangleFeature : int8_t { Face, Edge, Vertex };

struct ClosestPoint {
  vec3 point{0.0f};
  float distance_sq = 0.0f;
  int32_t triangle = -1;
  TriangleFeature feature = TriangleFeature::Face;
  int8_t feature_index = 0; /* Edge or vertex index inside the triangle. */
};

/* Closest point on triangle (a, b, c) to p (Ericson, Real-Time Collision Detection, 5.1.5). */
ClosestPoint closest_point_on_triangle(const vec3 &p, const vec3 &a, const vec3 &b, const vec3 &c);

/* Two-sided ray/triangle intersection (Möller and Trumbore 1997). Barycentric bounds are
 * widened by a relative epsilon so a ray through a shared edge or vertex hits at least one of
 * the triangles that meet there (it may hit several at the same t). */
bool intersect_ray_triangle(const vec3 &origin, const vec3 &direction, const vec3 &a,
                            const vec3 &b, const vec3 &c, RayHit &r_hit);

/* One node of the tree both triangle hierarchies share (TriangleBVH here, SsvBVH of the
 * swept-sphere pass): it covers the triangles order[begin, end) of median_split_tree. */
struct SplitNode {
  int32_t begin = 0, end = 0;
  /* Inner node: its right child's index (the left child is the next node); leaf: 0. */
  int32_t right = 0;
  bool is_leaf() const { return right == 0; }
};

/* The nodes a depth-first walk of a median_split_tree has still to visit, starting at the root.
 * A tree of at most 2^31 triangles is at most 32 levels deep and the walk keeps at most one
 * pending sibling per level: 64 entries always suffice (no allocation per query, which cost as
 * much as the walk on small meshes). */
struct PendingNodes {
  int32_t nodes[64];
  int size = 1;
  PendingNodes() { nodes[0] = 0; }
  bool empty() const { return size == 0; }
  int32_t pop() { return nodes[--size]; }
  /* Visited next: `second`, then `first`. */
  void push(const int32_t first, const int32_t second)
  {
    nodes[size++] = first;
    nodes[size++] = second;
  }
};

/* Binary tree over the triangles, nodes stored depth-first: each node is split at the median
 * centroid along its centroids' longest axis (ties by triangle index, so the tree does not
 * depend on the sort), at most `leaf_size` triangles per leaf. r_order receives the triangle
 * indices in leaf order. Indices must be valid (see find_mesh_error). */
std::vector<SplitNode> median_split_tree(Span<vec3> vertices, Span<ivec3> triangles,
                                         int leaf_size, std::vector<int32_t> &r_order);

class TriangleBVH {
 public:
  TriangleBVH() = default;
  /* Indices must be valid (see find_mesh_error); degenerate triangles are allowed. */
  TriangleBVH(Span<vec3> vertices, Span<ivec3> triangles, int leaf_size = 4);

  int64_t triangles_num() const { return int64_t(triangle_ids_.size()); }
  bool is_empty() const { return triangle_ids_.empty(); }
  /* Bounds of all triangles. */
  vec3 bounds_min() const { return nodes_.empty() ? vec3(0.0f) : nodes_[0].min; }
  vec3 bounds_max() const { return nodes_.empty() ? vec3(0.0f) : nodes_[0].max; }

  /* Every hit with t in [0, t_max], sorted by t, appended to r_hits (cleared first). */
  void ray_hits(const vec3 &origin, const vec3 &direction, float t_max,
                std::vector<RayHit> &r_hits) const;
  /* Whether the ray hits anything with t in [0, t_max] (stops at the first hit found). With
   * `r_leaf`, the hit triangle's place in the tree (for ray_hits_leaf), or -1 on a miss. */
  bool ray_hits_any(const vec3 &origin, const vec3 &direction, float t_max,
                    int32_t *r_leaf = nullptr) const;
  /* Whether the ray hits the triangle at `leaf` (a ray_hits_any answer) with t in
   * [0, t_max]: a hit it reports is a hit ray_hits_any could have found. */
  bool ray_hits_leaf(const vec3 &origin, const vec3 &direction, float t_max, int32_t leaf) const;
  /* The hit with the largest t >= 0 (the outermost surface along a ray cast outwards).
   * False when the ray misses. */
  bool ray_farthest_hit(const vec3 &origin, const vec3 &direction, RayHit &r_hit) const;
  /* The closest point of the mesh to p. The BVH must not be empty. */
  ClosestPoint closest_point(const vec3 &p) const;
  /* Same, but only looks closer than sqrt(max_distance_sq); triangle = -1 when none is. */
  ClosestPoint closest_point(const vec3 &p, float max_distance_sq) const;

 private:
  /* fn(leaf, hit) for the ray's hits with t in [0, t_max], in the tree's order, until it
   * returns true (then true); leaf: the triangle's place in corners_. */
  template<typename Fn>
  bool for_each_ray_hit(const vec3 &origin, const vec3 &direction, float t_max,
                        const Fn &fn) const;
  /* The ray's hit with the triangle at `leaf` (corners_ order), t in [0, t_max]. */
  bool hit_leaf(const vec3 &origin, const vec3 &direction, float t_max, int32_t leaf,
                RayHit &r_hit) const;

  struct Node {
    vec3 min, max;
    /* Leaf: first triangle and count (count > 0). Inner: right child index, count == 0; the
     * left child is the next node. */
    int32_t first_or_right = 0;
    int32_t count = 0;
  };
  std::vector<Node> nodes_;
  /* Triangle corners in leaf order, and the original index of each. */
  std::vector<vec3> corners_;
  std::vector<int32_t> triangle_ids_;
};

}  // namespace hairdyn
