#include "collision/ssv_ward2003.hh"

#include <algorithm>
#include <limits>


namespace hairdyn {

namespace {

/* The queries work in double precision on the float inputs (products of floats are exact in
 * double): closest parameters of nearly parallel or crossing segments and the planes of thin
 * triangles stay accurate to far below 1e-6 of the scale. */
using dvec3 = glm::dvec3;

constexpr float zero_length_sq = 1e-30f;
constexpr double zero_length_sq_d = 1e-60;

double clamp01(const double x)
{
  return std::min(std::max(x, 0.0), 1.0);
}

struct Closest {
  double distance_sq = std::numeric_limits<double>::infinity();
  dvec3 point_a{0.0}, point_b{0.0};
  double s = 0.0, t = 0.0;
};

CoreDistance to_core(const Closest &c)
{
  return {float(std::sqrt(c.distance_sq)), vec3(c.point_a), vec3(c.point_b), float(c.s),
          float(c.t)};
}

Closest make(const dvec3 &pa, const dvec3 &pb, const double s = 0.0, const double t = 0.0)
{
  const dvec3 d = pa - pb;
  return {glm::dot(d, d), pa, pb, s, t};
}

void keep_closer(const Closest &candidate, Closest &r_best)
{
  if (candidate.distance_sq < r_best.distance_sq) {
    r_best = candidate;
  }
}

Closest point_segment(const dvec3 &p, const dvec3 &a, const dvec3 &b)
{
  const dvec3 d = b - a;
  const double len_sq = glm::dot(d, d);
  const double t = len_sq > zero_length_sq_d ? clamp01(glm::dot(p - a, d) / len_sq) : 0.0;
  return make(p, a + t * d, 0.0, t);
}

/* Ericson, Real-Time Collision Detection, 5.1.9: minimise |a(s) − b(t)|² over the unit square;
 * the unconstrained minimum is clamped to s, t is re-solved for it and clamped, and s
 * re-solved for a clamped t. For parallel segments any pair over their common stretch is
 * closest: the middle of that stretch is taken. */
Closest segment_segment(const dvec3 &a0, const dvec3 &a1, const dvec3 &b0, const dvec3 &b1)
{
  const dvec3 d1 = a1 - a0, d2 = b1 - b0, r = a0 - b0;
  const double a = glm::dot(d1, d1), e = glm::dot(d2, d2), f = glm::dot(d2, r);
  double s = 0.0, t = 0.0;
  if (a <= zero_length_sq_d && e <= zero_length_sq_d) {
    /* two points */
  }
  else if (a <= zero_length_sq_d) {
    t = clamp01(f / e);
  }
  else {
    const double c = glm::dot(d1, r);
    if (e <= zero_length_sq_d) {
      s = clamp01(-c / a);
    }
    else {
      const double b = glm::dot(d1, d2);
      /* a e − b² = |d1 × d2|², from the cross product: no cancellation when nearly parallel. */
      const dvec3 cross = glm::cross(d1, d2);
      const double denom = glm::dot(cross, cross);
      if (denom > 1e-24 * a * e) {
        s = clamp01((b * f - c * e) / denom);
      }
      else {
        /* Parallel: the stretch of a covered by b's projection, [−c, b − c] / a. */
        const double lo = clamp01(std::min(-c, b - c) / a), hi = clamp01(std::max(-c, b - c) / a);
        s = 0.5 * (lo + hi);
      }
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = clamp01(-c / a);
      }
      else if (t > 1.0) {
        t = 1.0;
        s = clamp01((b - c) / a);
      }
    }
  }
  return make(a0 + s * d1, b0 + t * d2, s, t);
}

/* A planar convex polygon (a rectangle or a triangle) with its unit normal, or a zero normal
 * when it is degenerate (a sliver thinner than 1e-12 of its edges: then it is only its
 * edges). */
struct Polygon {
  dvec3 corners[4];
  int corners_num = 0;
  dvec3 normal{0.0};

  Polygon(const vec3 &t0, const vec3 &t1, const vec3 &t2)
      : corners{dvec3(t0), dvec3(t1), dvec3(t2), dvec3(t2)}, corners_num(3)
  {
    set_normal(corners[1] - corners[0], corners[2] - corners[0]);
  }
  explicit Polygon(const RectSS &r) : corners_num(4)
  {
    const dvec3 c(r.corner), u(r.edge_u), v(r.edge_v);
    corners[0] = c;
    corners[1] = c + u;
    corners[2] = c + u + v;
    corners[3] = c + v;
    set_normal(u, v);
  }
  void set_normal(const dvec3 &e1, const dvec3 &e2)
  {
    const dvec3 n = glm::cross(e1, e2);
    const double len_sq = glm::dot(n, n);
    normal = len_sq > 1e-24 * glm::dot(e1, e1) * glm::dot(e2, e2) && len_sq > zero_length_sq_d ?
                 n / std::sqrt(len_sq) :
                 dvec3(0.0);
  }
  const dvec3 &corner(const int k) const { return corners[k]; }
  const dvec3 &next(const int k) const { return corners[(k + 1) % corners_num]; }
  bool is_flat() const { return normal != dvec3(0.0); }

  /* Whether a point of the polygon's plane lies inside it (boundary included). */
  bool contains_in_plane(const dvec3 &q) const
  {
    for (int k = 0; k < corners_num; k++) {
      if (glm::dot(glm::cross(next(k) - corner(k), q - corner(k)), normal) < 0.0) {
        return false;
      }
    }
    return true;
  }
};

Closest point_polygon(const dvec3 &p, const Polygon &poly)
{
  if (poly.is_flat()) {
    const dvec3 q = p - glm::dot(p - poly.corner(0), poly.normal) * poly.normal;
    if (poly.contains_in_plane(q)) {
      return make(p, q);
    }
  }
  Closest best;
  for (int k = 0; k < poly.corners_num; k++) {
    keep_closer(make(p, point_segment(p, poly.corner(k), poly.next(k)).point_b), best);
  }
  return best;
}

/* Segment a–b against a planar convex polygon: 0 where the segment pierces it; otherwise the
 * closest pair involves an endpoint of the segment or an edge of the polygon. */
Closest segment_polygon(const dvec3 &a, const dvec3 &b, const Polygon &poly)
{
  if (poly.is_flat()) {
    const double da = glm::dot(a - poly.corner(0), poly.normal);
    const double db = glm::dot(b - poly.corner(0), poly.normal);
    if (((da <= 0.0 && db >= 0.0) || (da >= 0.0 && db <= 0.0)) && da != db) {
      const double s = da / (da - db);
      const dvec3 x = a + s * (b - a);
      if (poly.contains_in_plane(x - glm::dot(x - poly.corner(0), poly.normal) * poly.normal)) {
        return {0.0, x, x, s, 0.0};
      }
    }
  }
  Closest best = point_polygon(a, poly);
  best.s = 0.0;
  Closest at_b = point_polygon(b, poly);
  at_b.s = 1.0;
  keep_closer(at_b, best);
  for (int k = 0; k < poly.corners_num; k++) {
    keep_closer(segment_segment(a, b, poly.corner(k), poly.next(k)), best);
  }
  return best;
}

/* Polygon against polygon: the smallest of each one's edges against the other (two convex
 * polygons that intersect have an edge of one piercing or touching the other). */
Closest polygon_polygon(const Polygon &x, const Polygon &y)
{
  Closest best;
  for (int k = 0; k < x.corners_num; k++) {
    keep_closer(segment_polygon(x.corner(k), x.next(k), y), best);
  }
  for (int k = 0; k < y.corners_num; k++) {
    Closest swapped = segment_polygon(y.corner(k), y.next(k), x);
    std::swap(swapped.point_a, swapped.point_b);
    keep_closer(swapped, best);
  }
  return best;
}

}  // namespace

RectSS RectSS::from_segment(const vec3 &a, const vec3 &b, const vec3 &across, const float width,
                            const float radius)
{
  const vec3 axis = b - a;
  const float axis_sq = glm::dot(axis, axis);
  vec3 side = axis_sq > zero_length_sq ? across - (glm::dot(across, axis) / axis_sq) * axis :
                                         across;
  const float side_len = glm::length(side);
  side = side_len > 0.0f ? side * (width / side_len) : vec3(0.0f);
  return {a - 0.5f * side, axis, side, radius};
}

float closest_segment_parameter(const vec3 &p, const vec3 &a, const vec3 &b)
{
  return float(point_segment(dvec3(p), dvec3(a), dvec3(b)).t);
}

CoreDistance point_segment_distance(const vec3 &p, const vec3 &a, const vec3 &b)
{
  return to_core(point_segment(dvec3(p), dvec3(a), dvec3(b)));
}

CoreDistance segment_segment_distance(const vec3 &a0, const vec3 &a1, const vec3 &b0,
                                      const vec3 &b1)
{
  return to_core(segment_segment(dvec3(a0), dvec3(a1), dvec3(b0), dvec3(b1)));
}

CoreDistance point_rectangle_distance(const vec3 &p, const RectSS &rect)
{
  /* Edges orthogonal: the closest point clamps each local coordinate separately. */
  const dvec3 d = dvec3(p) - dvec3(rect.corner), u(rect.edge_u), v(rect.edge_v);
  const double uu = glm::dot(u, u), vv = glm::dot(v, v);
  const double s = uu > zero_length_sq_d ? clamp01(glm::dot(d, u) / uu) : 0.0;
  const double t = vv > zero_length_sq_d ? clamp01(glm::dot(d, v) / vv) : 0.0;
  return to_core(make(dvec3(p), dvec3(rect.corner) + s * u + t * v));
}

CoreDistance segment_rectangle_distance(const vec3 &a, const vec3 &b, const RectSS &rect)
{
  return to_core(segment_polygon(dvec3(a), dvec3(b), Polygon(rect)));
}

CoreDistance rectangle_rectangle_distance(const RectSS &x, const RectSS &y)
{
  return to_core(polygon_polygon(Polygon(x), Polygon(y)));
}

CoreDistance point_triangle_distance(const vec3 &p, const vec3 &t0, const vec3 &t1,
                                     const vec3 &t2)
{
  return to_core(point_polygon(dvec3(p), Polygon(t0, t1, t2)));
}

CoreDistance segment_triangle_distance(const vec3 &a, const vec3 &b, const vec3 &t0,
                                       const vec3 &t1, const vec3 &t2)
{
  return to_core(segment_polygon(dvec3(a), dvec3(b), Polygon(t0, t1, t2)));
}

CoreDistance rectangle_triangle_distance(const RectSS &rect, const vec3 &t0, const vec3 &t1,
                                         const vec3 &t2)
{
  return to_core(polygon_polygon(Polygon(rect), Polygon(t0, t1, t2)));
}

float separation(const LineSS &x, const LineSS &y)
{
  return segment_segment_distance(x.a, x.b, y.a, y.b).distance - x.radius - y.radius;
}

float separation(const LineSS &x, const PointSS &y)
{
  return point_segment_distance(y.center, x.a, x.b).distance - x.radius - y.radius;
}

float separation(const LineSS &x, const RectSS &y)
{
  return segment_rectangle_distance(x.a, x.b, y).distance - x.radius - y.radius;
}

float separation(const RectSS &x, const RectSS &y)
{
  return rectangle_rectangle_distance(x, y).distance - x.radius - y.radius;
}

float separation(const RectSS &x, const PointSS &y)
{
  return point_rectangle_distance(y.center, x).distance - x.radius - y.radius;
}

}  // namespace hairdyn
