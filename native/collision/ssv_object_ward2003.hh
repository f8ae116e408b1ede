#pragma once
/* Hair–object collision of Ward & Lin 2003 §5.4 as a substep pass: every strand segment is a
 * line swept sphere (LSS) tested against a bounding volume hierarchy of SSVs over each
 * collider mesh, so a segment cannot cut through a thin part of a body (an ear, a blade) while
 * both of its nodes stay outside, which node maps cannot see.
 *
 * The hierarchy (§5.4: "a BVH of SSVs pre-computed offline") is binary, split at the median
 * centroid of the longest axis like collision/bvh's; every node is a point swept sphere (the
 * smallest SSV around its triangles' bounding box, centred on it), and the leaves hold
 * triangles. A query descends where the segment's core comes within the node's radius plus
 * the query distance and returns the triangles in contact with the exact segment–triangle
 * distance (collision/ssv_ward2003).
 *
 * The response, strand by strand from root to tip so that no segment changes length:
 * - a penetrating segment is pushed out along the object's normal by its penetration (§5.4):
 *   against a face, the normal of the face and the depth of the segment's deepest point over
 *   it (so a segment that pierces a thin body is lifted whole out of it); against an edge or a
 *   corner, along the closest-point vector. The segment's tip turns about its base (already
 *   placed) until no contact is left (a few iterations, each removing the shallowest
 *   penetration: a segment through a thin body near its edge leaves across the edge), which
 *   keeps the length exactly;
 * - a face counts only when the segment was on its front side at the substep's start (x − h v
 *   against the collider's previous pose): the far side of a thin body does not pull the
 *   segment through it; when no face within reach was met from the front (the segment was
 *   already inside), the faces met from behind push it out;
 * - within distance_threshold of the body, the nodes keep no velocity into it (§5.4), and
 *   friction μ_f opposes the tangential motion with the magnitude μ_f |a_t| h of the tangential
 *   acceleration a_t (measured from the velocities of the previous substep), never reversing
 *   it (§5.4).
 * A strip's segment (level of detail) is its rectangle swept sphere (§5.2: the segment widened
 * by the strip's half width both ways, grown by its radius), tested exactly against the
 * triangles (rectangle–triangle distance) and pushed by its deepest point over a face (the
 * rectangle clipped to the face's prism), its tip turned about its base as a strand's; the
 * strip's width direction turns with the head. With rest clearances
 * (SubstepState) a segment is held no farther out than its nodes lay at rest, up to its
 * radius: a group's skeleton rests nearer the body than the group is thick.
 * Order (§5.5): after hair–hair (a soft constraint), this pass is the hard one: no segment
 * ends the pass inside a body. */
#include <memory>
#include <vector>

#include "collision/collider.hh"
#include "collision/ssv_ward2003.hh"
#include "core/math.hh"
#include "core/span.hh"
#include "strands/substep_pass.hh"

namespace hairdyn {

/* A triangle within reach of a query segment. */
struct TriangleContact {
  int32_t triangle = -1; /* index into the triangles the hierarchy was built from */
  CoreDistance core;     /* point_a on the segment (at s), point_b on the triangle */
};

class SsvBVH {
 public:
  SsvBVH() = default;
  /* Indices must be valid (find_mesh_error). */
  SsvBVH(Span<vec3> vertices, Span<ivec3> triangles, int leaf_size = 4);

  bool is_empty() const { return nodes_.empty(); }
  int64_t nodes_num() const { return int64_t(nodes_.size()); }
  /* Every triangle whose distance to the segment a–b is at most max_distance, appended to
   * r_contacts (not cleared), in the hierarchy's order. With a non-zero `side` (orthogonal
   * to b − a), to the rectangle the segment spans widened by it both ways (a strip's core,
   * §5.2) instead; the contacts' core.s is then point_a's parameter along a–b. */
  void segment_contacts(const vec3 &a, const vec3 &b, float max_distance,
                        std::vector<TriangleContact> &r_contacts,
                        const vec3 &side = vec3(0.0f)) const;
  /* Unit outward normal of the triangle (zero for a degenerate one), and a corner. */
  const vec3 &normal(const int32_t triangle) const { return normals_[size_t(triangle)]; }
  const vec3 *corners(const int32_t triangle) const { return &corners_[size_t(triangle) * 3]; }

 private:
  struct Node {
    PointSS volume;
    /* Leaf: first entry of leaf_triangles_ and count (> 0); inner: right child, count 0. */
    int32_t first_or_right = 0;
    int32_t count = 0;
  };

  std::vector<Node> nodes_;
  std::vector<int32_t> leaf_triangles_; /* triangle ids in leaf order */
  std::vector<vec3> corners_;           /* per triangle (original order), 3 corners */
  std::vector<vec3> normals_;
};

struct HairObjectStats {
  int64_t pushed_num = 0;  /* segment-substeps pushed out of a body */
  int64_t near_num = 0;    /* segment-substeps within the distance threshold */
  int64_t unresolved_num = 0; /* segments still inside after the iterations */
  double ms = 0.0;
};

class SsvObjectPass : public SubstepPass {
 public:
  /* The colliders are the caller's and must outlive the pass; their meshes are read now (call
   * rebuild() after a collider's vertices change). */
  SsvObjectPass(const ColliderSet *colliders, const SweptSphereParams &params);
  const char *name() const override { return "hair_object"; }
  void apply(const SubstepState &state) override;

  /* Rebuilds every collider's hierarchy from its current vertices. */
  void rebuild();
  const SweptSphereParams &params() const { return params_; }
  void set_params(const SweptSphereParams &params) { params_ = params; }
  const HairObjectStats &stats() const { return stats_; }
  void reset_stats() { stats_ = {}; }

 private:
  struct Body {
    const Collider *collider = nullptr;
    SsvBVH bvh;
    mat4 previous_object_to_world{1.0f};
    bool has_previous = false;
  };
  const ColliderSet *colliders_ = nullptr;
  SweptSphereParams params_;
  std::vector<Body> bodies_;
  std::vector<vec3> previous_velocities_; /* per point, at the end of the last apply */
  std::vector<vec3> previous_positions_;  /* per point, at the end of the last apply */
  mat3 previous_head_turn_{1.0f};         /* the head's rotation then */
  HairObjectStats stats_;
};

/* Samples of a segment at most, in segment_penetration_share. */
constexpr int max_segment_samples = 64;
/* Share (0..1) of segments with a point deeper than tolerance_wo (≥ 0; 0: any depth) inside
 * any collider (exact signed distance, samples along the segment at most tolerance_wo / 4
 * apart and at most max_segment_samples: the distance is 1-Lipschitz, so a deeper point is
 * missed by at most the larger of a quarter of the tolerance and the segment's length / 128). */
float segment_penetration_share(Span<int32_t> curve_offsets, Span<vec3> positions_wo,
                                const ColliderSet &colliders, float tolerance_wo);

}  // namespace hairdyn
