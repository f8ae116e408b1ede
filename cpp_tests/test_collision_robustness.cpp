/* Hostile input for the collision queries: NaN, infinite and huge points, colliders scaled to
 * zero or by a singular matrix, colliders built from vertices near 1e19, random transforms. A
 * query must never index outside a map's table (the sanitizer suite turns such a read, or a
 * NaN cast to a cell index, into a failure), never report a contact at a point that is not a
 * finite number, and never return a contact that is not finite. The batched query must give
 * the same bits as the per-point query. */
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <limits>
#include <random>

#include "collision/collider.hh"
#include "collision_test_shapes.hh"
#include "core/parallel.hh"

using namespace hairdyn;
using namespace hairdyn::test;

namespace {

constexpr float nan_f = std::numeric_limits<float>::quiet_NaN();
constexpr float inf_f = std::numeric_limits<float>::infinity();
constexpr float max_f = std::numeric_limits<float>::max();

std::shared_ptr<Collider> sphere_collider(const MapKind kind, const float radius = 1.0f)
{
  const TestMesh m = uv_sphere(radius, 24, 13);
  CollisionParams params;
  params.map_kind = kind;
  return std::make_shared<Collider>(ColliderMesh(m.vertices, m.triangles), Span<int32_t>(),
                                    Span<int32_t>(), params);
}

/* Coordinates a query may meet: special values, the edges of float's range, and ordinary ones. */
std::vector<vec3> hostile_points(const float scale)
{
  const float values[] = {
    nan_f,  -nan_f, inf_f,        -inf_f,        max_f,
    -max_f, 1e19f,  -1e19f,       1e38f,         std::numeric_limits<float>::denorm_min(),
    0.0f,   -0.0f,  0.5f * scale, -0.3f * scale, 2.0f * scale
  };
  std::vector<vec3> points;
  for (const float x : values) {
    for (const float y : values) {
      for (const float z : { values[0], values[2], values[6], values[10], values[12] }) {
        points.emplace_back(x, y, z);
        points.emplace_back(z, x, y);
        points.emplace_back(y, z, x);
      }
    }
  }
  return points;
}

/* Every query of `set` at `points`, per point and batched: a contact only at finite points,
 * every contact finite with a unit normal, the batch equal to the per-point answers bit for
 * bit. Returns the number of contacts. */
int64_t check_queries(const ColliderSet &set, const std::vector<vec3> &points)
{
  const size_t n = points.size();
  std::vector<uint8_t> hit(n);
  std::vector<float> depth(n);
  std::vector<vec3> normal(n), surface(n);
  find_contacts(set, points, hit, depth, normal, surface);
  int64_t hits = 0;
  for (size_t i = 0; i < n; i++) {
    Contact contact;
    const bool found = set.find_contact(points[i], contact);
    EXPECT_EQ(found, hit[i] != 0) << "point " << i;
    if (!found) {
      /* Inside nothing: depth 0, normal 0 and the point itself (NaN included: by the bits). */
      EXPECT_EQ(depth[i], 0.0f);
      EXPECT_EQ(normal[i], vec3(0.0f)) << "point " << i;
      EXPECT_EQ(std::memcmp(&surface[i], &points[i], sizeof(vec3)), 0) << "point " << i;
      continue;
    }
    hits++;
    EXPECT_TRUE(is_finite(points[i])) << "a contact at a point that is not finite, " << i;
    EXPECT_TRUE(std::isfinite(contact.depth) && is_finite(contact.normal_wo) &&
                is_finite(contact.surface_point_wo))
        << "point " << i;
    EXPECT_NEAR(glm::length(contact.normal_wo), 1.0f, 1e-3f) << "point " << i;
    /* Same bits from the batch (AVX2 or SSE2 clone) as from the per-point call. */
    EXPECT_EQ(depth[i], contact.depth) << "point " << i;
    EXPECT_EQ(normal[i], contact.normal_wo) << "point " << i;
    EXPECT_EQ(surface[i], contact.surface_point_wo) << "point " << i;
  }
  return hits;
}

}  // namespace

TEST(CollisionRobustness, NonFiniteAndHugePointsNeverIndexOutsideTheTable)
{
  for (const MapKind kind : { MapKind::Cylinder, MapKind::Sphere }) {
    ColliderSet set;
    set.add(sphere_collider(kind));
    const std::vector<vec3> points = hostile_points(1.0f);
    const int64_t hits = check_queries(set, points);
    /* (0.5, -0.3, 0), (0, ±0, ...) and friends are inside the unit sphere: the hostile
     * neighbours did not stop the ordinary points from being answered. */
    EXPECT_GT(hits, 0);
  }
}

TEST(CollisionRobustness, ColliderScaledToZeroOrSingularFindsNoContact)
{
  for (const MapKind kind : { MapKind::Cylinder, MapKind::Sphere }) {
    const auto collider = sphere_collider(kind);
    ColliderSet set;
    set.add(collider);
    const mat4 zero_scale = glm::scale(mat4(1.0f), vec3(0.0f));
    mat4 flattened(1.0f); /* Projects onto the xz plane: rank 2. */
    flattened[1] = vec4(0.0f);
    mat4 one_axis_zero = glm::scale(mat4(1.0f), vec3(1.0f, 0.0f, 1.0f));
    one_axis_zero[3] = vec4(2.0f, 0.0f, 0.0f, 1.0f);
    for (const mat4 &m : { zero_scale, flattened, one_axis_zero }) {
      collider->set_transform(m);
      std::vector<vec3> points = hostile_points(1.0f);
      points.emplace_back(0.0f);
      points.emplace_back(2.0f, 0.0f, 0.0f);
      check_queries(set, points);
    }
    /* Back to an invertible transform: the collider answers again. */
    collider->set_transform(mat4(1.0f));
    Contact contact;
    EXPECT_TRUE(set.find_contact(vec3(0.5f, 0.0f, 0.0f), contact));
  }
}

TEST(CollisionRobustness, HugeCollidersAreRefusedOrAnswer)
{
  /* Near 1e19 the exact distance's products overflow (the sanitizer suite caught a read past
   * the BVH): such a mesh is refused with a sentence. At the largest accepted size the maps
   * build and answer hostile points. */
  const TestMesh huge = uv_sphere(1e19f, 24, 13);
  EXPECT_NE(find_mesh_error(huge.vertices, huge.triangles).find("farther than"),
            std::string::npos);
  for (const MapKind kind : { MapKind::Auto, MapKind::Cylinder, MapKind::Sphere }) {
    ColliderSet set;
    set.add(sphere_collider(kind, 0.5f * max_mesh_coordinate));
    check_queries(set, hostile_points(0.5f * max_mesh_coordinate));
  }
}

TEST(CollisionRobustness, RandomTransformsAndPointsAgreeBatchedAndPerPoint)
{
  /* Random affine transforms (some singular, some huge, some with NaN) and points spread over
   * many orders of magnitude; two colliders so that the deepest contact is chosen across
   * colliders and parts. */
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::uniform_int_distribution<int> exponent(-30, 30);
  const auto wild = [&]() {
    const int pick = int(rng() % 16);
    if (pick == 0) {
      return nan_f;
    }
    if (pick == 1) {
      return inf_f * (rng() % 2 ? 1.0f : -1.0f);
    }
    return unit(rng) * std::ldexp(1.0f, pick < 8 ? exponent(rng) : 0);
  };
  const auto a = sphere_collider(MapKind::Cylinder);
  const auto b = sphere_collider(MapKind::Sphere, 0.7f);
  ColliderSet set;
  set.add(a);
  set.add(b);
  int64_t hits = 0;
  for (int trial = 0; trial < 40; trial++) {
    mat4 m(1.0f);
    if (trial % 4 != 0) { /* Every fourth trial keeps an ordinary rigid placement. */
      for (int c = 0; c < 4; c++) {
        for (int r = 0; r < 3; r++) {
          m[c][r] = trial % 4 == 1 ? unit(rng) : wild();
        }
      }
    }
    else {
      m = glm::rotate(glm::translate(mat4(1.0f), vec3(unit(rng), unit(rng), unit(rng))),
                      unit(rng) * 3.0f, glm::normalize(vec3(unit(rng), unit(rng), 1.0f)));
    }
    a->set_transform(m);
    b->set_transform(trial % 2 ? m : mat4(1.0f));
    std::vector<vec3> points(600);
    for (size_t i = 0; i < points.size(); i++) {
      points[i] =
          i % 3 == 0 ? vec3(wild(), wild(), wild()) : vec3(unit(rng), unit(rng), unit(rng)) * 1.2f;
    }
    hits += check_queries(set, points);
  }
  EXPECT_GT(hits, 100); /* The ordinary trials found contacts, and they agreed. */
}

namespace {

/* Two placements that take depth and normal to world space the two ways: a similarity and a
 * shear. */
std::vector<mat4> similarity_and_shear()
{
  mat4 shear(1.0f);
  shear[1][0] = 0.3f;
  const mat4 similarity =
      glm::scale(glm::rotate(glm::translate(mat4(1.0f), vec3(0.1f, -0.2f, 0.05f)), 0.7f,
                             glm::normalize(vec3(1, 2, 3))),
                 vec3(1.2f));
  return { similarity, shear };
}

/* points in a shell of radius up to 1.3 around the origin, normally spread in direction. */
std::vector<vec3> shell_points(const unsigned seed, const size_t n)
{
  std::mt19937 rng(seed);
  std::normal_distribution<float> gauss;
  std::uniform_real_distribution<float> radius(0.0f, 1.3f);
  std::vector<vec3> points(n);
  for (vec3 &p : points) {
    p = glm::normalize(vec3(gauss(rng), gauss(rng), gauss(rng))) * radius(rng);
  }
  return points;
}

/* find_contacts' answers for n points. */
struct Contacts {
  std::vector<uint8_t> hit;
  std::vector<float> depth;
  std::vector<vec3> normal, surface;

  explicit Contacts(const size_t n) : hit(n), depth(n), normal(n), surface(n) {}
  void find(const ColliderSet &set, const Span<vec3> points)
  {
    find_contacts(set, points, hit, depth, normal, surface);
  }
};

void expect_same_bits(const Contacts &a, const Contacts &b)
{
  const size_t n = a.hit.size();
  EXPECT_EQ(a.hit, b.hit);
  EXPECT_EQ(std::memcmp(a.depth.data(), b.depth.data(), n * sizeof(float)), 0);
  EXPECT_EQ(std::memcmp(a.normal.data(), b.normal.data(), n * sizeof(vec3)), 0);
  EXPECT_EQ(std::memcmp(a.surface.data(), b.surface.data(), n * sizeof(vec3)), 0);
}

}  // namespace

TEST(CollisionRobustness, BatchedQueryHasTheSameBitsOnOneAndTwoThreads)
{
  /* Many points in a shell around two overlapping spheres (a cylinder map and a sphere map),
   * with a similarity placement and a sheared one (the two ways depth and normal are taken
   * to world space): several parallel chunks and a partial last batch. Every answer equals the
   * per-point query's, and one and two threads give the same bits. */
  std::vector<vec3> points = shell_points(11, 3 * 4096 + 1000);
  /* Points on the axes and poles of the maps. */
  for (const float r : { 0.0f, 0.3f, 0.9f }) {
    points.emplace_back(0.0f, r, 0.0f);
    points.emplace_back(0.0f, -r, 0.0f);
  }
  for (const mat4 &m : similarity_and_shear()) {
    const auto a = sphere_collider(MapKind::Cylinder);
    const auto b = sphere_collider(MapKind::Sphere, 0.8f);
    a->set_transform(m);
    b->set_transform(glm::translate(mat4(1.0f), vec3(0.2f, 0.1f, 0.0f)));
    ColliderSet set;
    set.add(a);
    set.add(b);
    const size_t n = points.size();
    Contacts one(n), two(n);
    set_thread_num(1);
    one.find(set, points);
    set_thread_num(2);
    two.find(set, points);
    set_thread_num(0);
    expect_same_bits(one, two);
    const int64_t hits = check_queries(set, points);
    EXPECT_GT(hits, int64_t(n / 4));
    EXPECT_LT(hits, int64_t(n));
  }
}

TEST(CollisionRobustness, PenetrationReportsRootsInsideApart)
{
  /* Unit sphere (24 × 13 facets: depths within about 3% of the radius of the analytic ones).
   * Strand 0's root starts 0.1 inside, the rest of it is outside; strand 1's root is outside
   * and its middle point 0.05 inside. */
  ColliderSet set;
  set.add(sphere_collider(MapKind::Auto));
  const std::vector<vec3> points = { { 0.9f, 0, 0 }, { 1.2f, 0, 0 },  { 1.5f, 0, 0 },
                                     { 0, 1.1f, 0 }, { 0, 0.95f, 0 }, { 0, 1.3f, 0 } };
  const std::vector<int32_t> offsets = { 0, 3, 6 };
  const float tolerance = 0.01f;
  const PenetrationStats all = set.penetration_stats(points, tolerance);
  EXPECT_EQ(all.points_num, 6);
  EXPECT_EQ(all.deeper_num, 2);
  EXPECT_NEAR(all.max_depth, 0.1f, 0.03f);
  EXPECT_EQ(all.roots_inside, 0); /* Not asked for: nothing counted apart. */

  const PenetrationStats apart = set.penetration_stats(points, tolerance, offsets);
  EXPECT_EQ(apart.roots_inside, 1);
  EXPECT_NEAR(apart.roots_depth_max, 0.1f, 0.03f);
  EXPECT_EQ(apart.points_num, 4);
  EXPECT_EQ(apart.deeper_num, 1);
  EXPECT_NEAR(apart.max_depth, 0.05f, 0.03f);
  EXPECT_LT(apart.max_depth, apart.roots_depth_max);
  EXPECT_FLOAT_EQ(apart.share, 0.25f);
}

TEST(CollisionRobustness, BatchedQueryHasTheSameBitsWithAndWithoutAvx2)
{
  /* find_contacts' AVX2 code (8 lanes, RadialTable::blend_avx2) against the baseline code
   * (SSE2, 4 lanes) on this CPU, bit for bit: both map kinds, a similarity placement and a
   * sheared one, two parts of one collider, points near the poles, the wrap of the azimuth and
   * the ends of the height range, hostile points, and a partial last batch. */
  if (!collision_avx2_available()) {
    GTEST_SKIP() << "the CPU has no AVX2";
  }
  std::vector<vec3> points = shell_points(5, 2 * 4096 + 777);
  std::mt19937 rng(5);
  std::normal_distribution<float> gauss;
  for (int k = 0; k < 200; k++) {
    /* Near the poles (φ within half a row) and near θ = 0 from both sides (the wrap). */
    const float r = 0.5f + 0.005f * float(k);
    points.emplace_back(1e-3f * gauss(rng), r, 1e-3f * gauss(rng));
    points.emplace_back(1e-3f * gauss(rng), -r, 1e-3f * gauss(rng));
    points.emplace_back(r, 0.01f * gauss(rng), 1e-4f * gauss(rng));
  }
  const std::vector<vec3> hostile = hostile_points(1.0f);
  points.insert(points.end(), hostile.begin(), hostile.end());
  const TestMesh capsule = closed_cylinder(0.6f, 1.6f, 20, 8);
  std::vector<int32_t> part_vertices, part_offsets = { 0 };
  for (const float y_cut : { -0.1f, 0.1f }) {
    /* Two overlapping parts: below y = 0.1 and above y = -0.1. */
    for (int32_t v = 0; v < int32_t(capsule.vertices.size()); v++) {
      const float y = capsule.vertices[size_t(v)].y;
      if (y_cut > 0.0f ? y <= y_cut : y >= y_cut) {
        part_vertices.push_back(v);
      }
    }
    part_offsets.push_back(int32_t(part_vertices.size()));
  }
  const bool avx2_was_used = collision_avx2_used();
  for (const MapKind kind : { MapKind::Cylinder, MapKind::Sphere }) {
    for (const mat4 &m : similarity_and_shear()) {
      CollisionParams params;
      params.map_kind = kind;
      const auto parts = std::make_shared<Collider>(
          ColliderMesh(capsule.vertices, capsule.triangles), part_offsets, part_vertices, params);
      const auto sphere = sphere_collider(kind, 0.9f);
      parts->set_transform(m);
      sphere->set_transform(glm::translate(mat4(1.0f), vec3(0.2f, 0.1f, 0.0f)));
      ColliderSet set;
      set.add(sphere);
      set.add(parts);
      const size_t n = points.size();
      Contacts baseline(n), avx2(n);
      set_collision_avx2(false);
      EXPECT_FALSE(collision_avx2_used());
      baseline.find(set, points);
      set_collision_avx2(true);
      EXPECT_TRUE(collision_avx2_used());
      avx2.find(set, points);
      set_collision_avx2(avx2_was_used);
      expect_same_bits(baseline, avx2);
      const int64_t hits = std::count(baseline.hit.begin(), baseline.hit.end(), uint8_t(1));
      EXPECT_GT(hits, int64_t(n / 4));
      EXPECT_LT(hits, int64_t(n));
    }
  }
}
