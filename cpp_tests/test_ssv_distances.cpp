/* Exact core distances of the swept sphere volumes (Ward & Lin 2003 §5.1–5.2) against an
 * independent brute-force reference.
 *
 * How the reference is computed: in double precision, the distance from a point to a convex
 * polygon (project onto the plane; inside → the plane distance, else the nearest edge) is
 * exact; the distance from the moving point a + s (b − a) to a convex set is a convex function
 * of s, so its minimum over [0, 1] is found by golden-section search to 1e-20 in s. Polygon
 * against polygon minimises the convex function of the first polygon's two coordinates by
 * nested golden-section searches. Inputs are floats in [−1, 1]³ (scale 1); the tolerance is
 * 1e-6 of that scale. */
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>

#include "collision/ssv_ward2003.hh"

using namespace hairdyn;

namespace {

using dvec3 = glm::dvec3;

dvec3 d(const vec3 &v)
{
  return dvec3(v);
}

double ref_point_segment(const dvec3 &p, const dvec3 &a, const dvec3 &b)
{
  const dvec3 ab = b - a;
  const double len_sq = glm::dot(ab, ab);
  const double t = len_sq > 0.0 ? std::clamp(glm::dot(p - a, ab) / len_sq, 0.0, 1.0) : 0.0;
  return glm::length(p - (a + t * ab));
}

double ref_point_polygon(const dvec3 &p, const std::vector<dvec3> &corners)
{
  const size_t n = corners.size();
  dvec3 normal(0.0);
  for (size_t k = 1; k + 1 < n; k++) {
    normal += glm::cross(corners[k] - corners[0], corners[k + 1] - corners[0]);
  }
  const double len = glm::length(normal);
  if (len > 1e-300) {
    normal /= len;
    const dvec3 q = p - glm::dot(p - corners[0], normal) * normal;
    bool inside = true;
    for (size_t k = 0; k < n; k++) {
      const dvec3 &c = corners[k], &next = corners[(k + 1) % n];
      inside = inside && glm::dot(glm::cross(next - c, q - c), normal) >= 0.0;
    }
    if (inside) {
      return glm::length(p - q);
    }
  }
  double best = INFINITY;
  for (size_t k = 0; k < n; k++) {
    best = std::min(best, ref_point_segment(p, corners[k], corners[(k + 1) % n]));
  }
  return best;
}

/* Minimum of a convex function on [0, 1] by golden-section search. */
double golden_min(const std::function<double(double)> &f, const int iterations = 110)
{
  const double g = (std::sqrt(5.0) - 1.0) / 2.0;
  double lo = 0.0, hi = 1.0;
  double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
  double f1 = f(x1), f2 = f(x2);
  for (int i = 0; i < iterations; i++) {
    if (f1 <= f2) {
      hi = x2;
      x2 = x1;
      f2 = f1;
      x1 = hi - g * (hi - lo);
      f1 = f(x1);
    }
    else {
      lo = x1;
      x1 = x2;
      f1 = f2;
      x2 = lo + g * (hi - lo);
      f2 = f(x2);
    }
  }
  return std::min({f1, f2, f(0.0), f(1.0)});
}

double ref_segment_set(const vec3 &a, const vec3 &b,
                       const std::function<double(const dvec3 &)> &distance_to_set)
{
  const dvec3 da = d(a), db = d(b);
  return golden_min([&](const double s) { return distance_to_set(da + s * (db - da)); });
}

std::vector<dvec3> rect_corners(const RectSS &r)
{
  return {d(r.corner), d(r.corner) + d(r.edge_u), d(r.corner) + d(r.edge_u) + d(r.edge_v),
          d(r.corner) + d(r.edge_v)};
}

struct Random {
  std::mt19937 rng{12345};
  std::uniform_real_distribution<float> uniform{-1.0f, 1.0f};
  vec3 point() { return {uniform(rng), uniform(rng), uniform(rng)}; }
  float unit() { return 0.5f * (uniform(rng) + 1.0f); }
  int pick(const int n) { return int(rng() % uint32_t(n)); }

  /* Segments of every kind: general, zero-length, short, long, and (with `other`) parallel to
   * it or lying on its line. */
  std::pair<vec3, vec3> segment(const vec3 *other_a = nullptr, const vec3 *other_b = nullptr)
  {
    const vec3 a = point();
    switch (pick(other_a ? 6 : 4)) {
      case 0:
        return {a, a}; /* zero length */
      case 1:
        return {a, a + 1e-4f * point()}; /* very short */
      case 4: {
        const vec3 dir = *other_b - *other_a;
        return {a, a + (2.0f * uniform(rng)) * dir}; /* parallel */
      }
      case 5: {
        const vec3 dir = *other_b - *other_a;
        const vec3 start = *other_a + uniform(rng) * dir;
        return {start, start + (2.0f * uniform(rng)) * dir}; /* on the same line */
      }
      default:
        return {a, point()};
    }
  }
  RectSS rect()
  {
    const vec3 u = point();
    vec3 v = point();
    v -= glm::dot(v, u) / std::max(glm::dot(u, u), 1e-12f) * u;
    switch (pick(5)) {
      case 0:
        return {point(), u, vec3(0.0f), 0.0f}; /* degenerate: a segment */
      case 1:
        return {point(), vec3(0.0f), vec3(0.0f), 0.0f}; /* degenerate: a point */
      default:
        return {point(), u, v, 0.0f};
    }
  }
};

/* The reported closest points lie on their cores and are `distance` apart. */
void expect_consistent(const CoreDistance &r, const double seg_to_a, const double b_to_core)
{
  EXPECT_NEAR(glm::length(r.point_a - r.point_b), r.distance, 1e-6f);
  EXPECT_LE(seg_to_a, 1e-6);
  EXPECT_LE(b_to_core, 1e-6);
}

constexpr int pairs_num = 100000;
constexpr double tolerance = 1e-6; /* × the scale of the inputs (1) */

/* |computed − reference| for a segment against a convex polygon (corners); every 97th case
 * also checks that the closest points lie on the segment and the polygon. */
double segment_polygon_error(const int i, const std::pair<vec3, vec3> &seg, const CoreDistance &r,
                             const std::vector<dvec3> &corners)
{
  const double ref = ref_segment_set(
      seg.first, seg.second, [&](const dvec3 &p) { return ref_point_polygon(p, corners); });
  if (i % 97 == 0) {
    expect_consistent(r, ref_point_segment(d(r.point_a), d(seg.first), d(seg.second)),
                      ref_point_polygon(d(r.point_b), corners));
  }
  return std::abs(double(r.distance) - ref);
}

}  // namespace

TEST(SsvDistances, SegmentSegmentMatchesBruteForce)
{
  Random random;
  double worst = 0.0;
  for (int i = 0; i < pairs_num; i++) {
    const auto [a0, a1] = random.segment();
    const auto [b0, b1] = random.segment(&a0, &a1);
    const CoreDistance r = segment_segment_distance(a0, a1, b0, b1);
    const double ref = ref_segment_set(
        a0, a1, [&](const dvec3 &p) { return ref_point_segment(p, d(b0), d(b1)); });
    worst = std::max(worst, std::abs(double(r.distance) - ref));
    if (i % 97 == 0) {
      expect_consistent(r, ref_point_segment(d(r.point_a), d(a0), d(a1)),
                        ref_point_segment(d(r.point_b), d(b0), d(b1)));
    }
  }
  EXPECT_LE(worst, tolerance);
}

TEST(SsvDistances, SegmentRectangleMatchesBruteForce)
{
  Random random;
  double worst = 0.0;
  for (int i = 0; i < pairs_num; i++) {
    const RectSS rect = random.rect();
    /* A third of the segments pierce the rectangle or lie in its plane. */
    std::pair<vec3, vec3> seg = random.segment();
    const vec3 inside = rect.corner + random.unit() * rect.edge_u + random.unit() * rect.edge_v;
    if (i % 3 == 1) {
      seg.first = inside + random.point();
      seg.second = 2.0f * inside - seg.first;
    }
    else if (i % 3 == 2) {
      seg.first = inside;
      seg.second = rect.corner + 2.0f * random.uniform(random.rng) * rect.edge_u +
                   2.0f * random.uniform(random.rng) * rect.edge_v;
    }
    const CoreDistance r = segment_rectangle_distance(seg.first, seg.second, rect);
    worst = std::max(worst, segment_polygon_error(i, seg, r, rect_corners(rect)));
  }
  EXPECT_LE(worst, tolerance);
}

TEST(SsvDistances, SegmentTriangleMatchesBruteForce)
{
  Random random;
  double worst = 0.0;
  for (int i = 0; i < pairs_num; i++) {
    const vec3 t0 = random.point(), t1 = random.point();
    /* Every fifth triangle is degenerate (collinear corners). */
    const vec3 t2 = i % 5 == 0 ? t0 + random.uniform(random.rng) * (t1 - t0) : random.point();
    std::pair<vec3, vec3> seg = random.segment(&t0, &t1);
    if (i % 3 == 1) { /* piercing */
      const vec3 inside = (t0 + t1 + t2) / 3.0f;
      seg.first = inside + random.point();
      seg.second = 2.0f * inside - seg.first;
    }
    const CoreDistance r = segment_triangle_distance(seg.first, seg.second, t0, t1, t2);
    worst = std::max(worst, segment_polygon_error(i, seg, r, {d(t0), d(t1), d(t2)}));
  }
  EXPECT_LE(worst, tolerance);
}

TEST(SsvDistances, RectangleRectangleAndTriangleMatchBruteForce)
{
  Random random;
  double worst = 0.0;
  for (int i = 0; i < 3000; i++) {
    const RectSS x = random.rect();
    const RectSS y = random.rect();
    const vec3 t0 = random.point(), t1 = random.point(), t2 = random.point();
    const std::vector<dvec3> y_corners = rect_corners(y), tri{d(t0), d(t1), d(t2)};
    /* min over (u, v) of the distance from x's point (u, v) to the other polygon: convex. */
    const auto ref = [&](const std::vector<dvec3> &other) {
      return golden_min(
          [&](const double u) {
            return golden_min(
                [&](const double v) {
                  return ref_point_polygon(d(x.corner) + u * d(x.edge_u) + v * d(x.edge_v), other);
                },
                70);
          },
          70);
    };
    worst = std::max(worst, std::abs(double(rectangle_rectangle_distance(x, y).distance) -
                                     ref(y_corners)));
    worst = std::max(worst, std::abs(double(rectangle_triangle_distance(x, t0, t1, t2).distance) -
                                     ref(tri)));
  }
  EXPECT_LE(worst, tolerance);
}

TEST(SsvDistances, SeparationSubtractsTheRadii)
{
  /* Two crossing LSSs 0.3 apart (x and y axes at z = 0 and z = 0.3). */
  const LineSS x{vec3(-1, 0, 0), vec3(1, 0, 0), 0.1f};
  const LineSS y{vec3(0, -1, 0.3f), vec3(0, 1, 0.3f), 0.15f};
  EXPECT_NEAR(separation(x, y), 0.05f, 1e-6f);
  const PointSS p{vec3(0, 0, -0.5f), 0.2f};
  EXPECT_NEAR(separation(x, p), 0.2f, 1e-6f);
  /* An RSS strip in the plane z = 0.5 over [0, 1]²: 0.4 from the point under its corner. */
  const RectSS strip{vec3(0, 0, 0.5f), vec3(1, 0, 0), vec3(0, 1, 0), 0.05f};
  EXPECT_NEAR(separation(strip, PointSS{vec3(0.5f, 0.5f, 0.0f), 0.05f}), 0.4f, 1e-6f);
  EXPECT_NEAR(separation(x, strip), 0.35f, 1e-6f);
  const RectSS built = RectSS::from_segment(vec3(0, 0, 0), vec3(0, 0, 1), vec3(1, 1, 0), 0.2f, 0.0f);
  EXPECT_NEAR(glm::length(built.edge_v), 0.2f, 1e-6f);
  EXPECT_NEAR(glm::dot(built.edge_u, built.edge_v), 0.0f, 1e-7f);
  EXPECT_NEAR(separation(built, PointSS{vec3(1, 1, 0.5f), 0.0f}), std::sqrt(2.0f) - 0.1f, 1e-6f);
}
