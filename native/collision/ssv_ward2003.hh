#pragma once
/* Swept sphere volumes (Ward & Lin 2003 §5.1–5.2, after Larsen et al. 2000): a core skeleton
 * C grown by a sphere S of radius r,
 *
 *   B = C ⊕ S = {c + s | c ∈ C, s ∈ S}                        (Ward & Lin 2003, §5.1)
 *
 * with a point (PSS), a line segment (LSS: a strand or cluster segment) or a rectangle (RSS: a
 * strip segment) as the core. Two SSVs intersect when the distance between their cores is
 * smaller than the sum of their radii (§5.1: "a distance test between their corresponding core
 * skeletons, then subtract the radius of each SSV"), so everything here is an exact
 * closest-point query between cores: point, segment, rectangle and triangle, in any pair.
 *
 * The queries are closed forms, computed in double precision inside: segment–segment by
 * Ericson (Real-Time Collision Detection, 5.1.9, which handles parallel and zero-length
 * segments); a segment against a planar convex polygon (rectangle, triangle) is either 0 where
 * it pierces the polygon, or the smallest of its endpoints against the polygon and the segment
 * against each edge (the closest pair of two convex sets lies on the boundary of one of them);
 * polygon against polygon is the smallest of
 * each one's edges against the other. */
#include <cmath>
#include <cstdint>

#include "core/math.hh"
#include "core/params.hh"

namespace hairdyn {

/* Point swept sphere. */
struct PointSS {
  vec3 center{0.0f};
  float radius = 0.0f;
};

/* Line swept sphere: the segment a–b grown by radius (a == b is a PSS). */
struct LineSS {
  vec3 a{0.0f}, b{0.0f};
  float radius = 0.0f;
};

/* Rectangle swept sphere: the rectangle {corner + s·edge_u + t·edge_v | s, t ∈ [0, 1]} grown
 * by radius. edge_u and edge_v must be orthogonal (either may be zero: a degenerate rectangle
 * is a segment or a point). */
struct RectSS {
  vec3 corner{0.0f};
  vec3 edge_u{0.0f}, edge_v{0.0f};
  float radius = 0.0f;

  /* The RSS of a strip segment: the rectangle spanned by the segment a–b and the strip's
   * width direction `across` (made orthogonal to the segment), centred on the segment. */
  static RectSS from_segment(const vec3 &a, const vec3 &b, const vec3 &across, float width,
                             float radius);
};

/* The closest points of two cores and their distance (≥ 0). */
struct CoreDistance {
  float distance = 0.0f;
  vec3 point_a{0.0f}; /* on the first core */
  vec3 point_b{0.0f}; /* on the second core */
  float s = 0.0f;     /* Parameter of point_a along the first core when it is a segment (a + s (b − a)). */
  float t = 0.0f;     /* Parameter of point_b along the second core when it is a segment. */
};

/* Closest point of segment a–b to p: a + s (b − a) with s in [0, 1] (0 for a zero segment). */
float closest_segment_parameter(const vec3 &p, const vec3 &a, const vec3 &b);

/* The exact closest points between cores. Triangles are given by their corners. */
CoreDistance point_segment_distance(const vec3 &p, const vec3 &a, const vec3 &b);
CoreDistance segment_segment_distance(const vec3 &a0, const vec3 &a1, const vec3 &b0,
                                      const vec3 &b1);
CoreDistance point_rectangle_distance(const vec3 &p, const RectSS &rect);
CoreDistance segment_rectangle_distance(const vec3 &a, const vec3 &b, const RectSS &rect);
CoreDistance rectangle_rectangle_distance(const RectSS &x, const RectSS &y);
CoreDistance point_triangle_distance(const vec3 &p, const vec3 &t0, const vec3 &t1,
                                     const vec3 &t2);
CoreDistance segment_triangle_distance(const vec3 &a, const vec3 &b, const vec3 &t0,
                                       const vec3 &t1, const vec3 &t2);
CoreDistance rectangle_triangle_distance(const RectSS &rect, const vec3 &t0, const vec3 &t1,
                                         const vec3 &t2);

/* Separation of two SSVs, core distance − r1 − r2 (Ward & Lin 2003 §5.3's "overlap"): negative
 * when they intersect. */
inline float separation(const PointSS &x, const PointSS &y)
{
  return glm::length(x.center - y.center) - x.radius - y.radius;
}
float separation(const LineSS &x, const LineSS &y);
float separation(const LineSS &x, const PointSS &y);
float separation(const LineSS &x, const RectSS &y);
float separation(const RectSS &x, const RectSS &y);
float separation(const RectSS &x, const PointSS &y);

/* Which body collision the strands use (Ward & Lin 2003 §5.4 against Kurihara 1993 §3). */
enum class BodyCollision : int32_t {
  Maps = 0,         /* Nodes against the cylindrical/spherical maps (fast). */
  SweptSpheres = 1, /* Every segment's LSS against a BVH of the mesh (exact). */
  Both = 2,         /* Maps for the response, swept spheres for the final guarantee. */
};

/* Parameters of the swept-sphere collision passes: hair–hair (§5.3) and hair–object (§5.4),
 * run in that order after every strand substep (§5.5). */
struct SweptSphereParams {
  /* Hair–hair collision on the segment grid (§5.3). */
  bool hair_hair = false;
  /* m, r: each strand segment's LSS radius where the groom gives none (§5.2). */
  float thickness = 5e-4f;
  /* rad: overlapping segments closer to parallel than this get their velocities averaged
   * instead of being pushed apart (§5.3). */
  float near_parallel_angle = 0.26179939f;
  /* Share of the paper's push (half the overlap each, §5.3) applied per substep. */
  float push_strength = 1.0f;
  BodyCollision body_collision = BodyCollision::Maps;
  /* μ_f: friction against colliders, opposing the tangential acceleration (§5.4). */
  float friction = 0.3f;
  /* m: segments this close to a collider keep no velocity into it (§5.4). */
  float distance_threshold = 1e-3f;

  bool uses_swept_spheres() const { return body_collision != BodyCollision::Maps; }
  bool uses_maps() const { return body_collision != BodyCollision::SweptSpheres; }

  template<typename Fn> static void for_each_field(Fn &&fn)
  {
    fn(&SweptSphereParams::hair_hair,
       ParamInfo{"hair_hair", "", "", 0.0, 1.0,
                 "Hair–hair collision: every segment a line swept sphere on a grid, overlapping "
                 "pairs pushed apart or moved together (Ward & Lin 2003 §5.3)"}
           .labeled("Hair–Hair"));
    fn(&SweptSphereParams::thickness,
       ParamInfo{"thickness", "r", "m", 0.0, 0.1,
                 "Radius of each strand segment's swept sphere where the hair has no radius "
                 "attribute (Ward & Lin 2003 §5.2)"}
           .shown_as(1e3, "mm")
           .soft(0.0, 0.005)
           .labeled("Strand Thickness"));
    fn(&SweptSphereParams::near_parallel_angle,
       ParamInfo{"near_parallel_angle", "", "rad", 0.0, 1.5707963,
                 "Overlapping segments closer to parallel than this angle share their average "
                 "velocity instead of being pushed apart (Ward & Lin 2003 §5.3)"}
           .shown_as(180.0 / M_PI, "°")
           .soft(0.0, 0.7853982).labeled("Parallel Angle"));
    fn(&SweptSphereParams::push_strength,
       ParamInfo{"push_strength", "", "", 0.0, 1.0,
                 "Share of the overlap removed per substep, half on each segment (Ward & Lin "
                 "2003 §5.3 uses 1)"});
    fn(&SweptSphereParams::body_collision,
       ParamInfo{"body_collision", "", "", 0.0, 2.0,
                 "Body collision: node maps (Kurihara 1993, fast), segment swept spheres on a "
                 "BVH (Ward & Lin 2003 §5.4, exact), or both (maps respond, swept spheres "
                 "guarantee no segment ends inside)",
                 "maps,swept_spheres,both"});
    fn(&SweptSphereParams::friction,
       ParamInfo{"friction", "μ_f", "", 0.0, 1.0,
                 "Friction against colliders, opposing the tangential acceleration (Ward & Lin "
                 "2003 §5.4)"});
    fn(&SweptSphereParams::distance_threshold,
       ParamInfo{"distance_threshold", "", "m", 0.0, 0.1,
                 "Segments within this distance of a collider keep no velocity into it (Ward & "
                 "Lin 2003 §5.4)"}
           .shown_as(1e3, "mm")
           .soft(0.0, 0.01).labeled("Max Distance"));
  }
};

}  // namespace hairdyn
