/* Triangle BVH queries against brute force, and exact signed distance on analytic shapes. */
#include <gtest/gtest.h>

#include <random>

#include "collision/bvh.hh"
#include "collision/mesh_distance.hh"
#include "collision_test_shapes.hh"

using namespace hairdyn;
using namespace hairdyn::test;

namespace {

/* A bumpy sphere plus a cloud of random triangles: no structure a BVH bug could hide behind. */
TestMesh random_mesh()
{
  TestMesh m = uv_sphere(1.0f, 24, 12);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> bump(0.8f, 1.2f), c(-2.0f, 2.0f), d(-0.3f, 0.3f);
  for (vec3 &v : m.vertices) {
    v *= bump(rng);
  }
  for (int i = 0; i < 300; i++) {
    const vec3 a(c(rng), c(rng), c(rng));
    const int base = int(m.vertices.size());
    m.vertices.push_back(a);
    m.vertices.push_back(a + vec3(d(rng), d(rng), d(rng)));
    m.vertices.push_back(a + vec3(d(rng), d(rng), d(rng)));
    m.triangles.emplace_back(base, base + 1, base + 2);
  }
  return m;
}

float box_sdf(const vec3 &p, const vec3 &h)
{
  const vec3 q = glm::abs(p) - h;
  return glm::length(glm::max(q, vec3(0.0f))) + std::min(std::max(q.x, std::max(q.y, q.z)), 0.0f);
}

}  // namespace

TEST(TriangleBVH, ClosestPointMatchesBruteForce)
{
  const TestMesh m = random_mesh();
  const TriangleBVH bvh(m.vertices, m.triangles);
  ASSERT_EQ(bvh.triangles_num(), int64_t(m.triangles.size()));
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> c(-3.0f, 3.0f);
  for (int i = 0; i < 2000; i++) {
    const vec3 p(c(rng), c(rng), c(rng));
    float best = std::numeric_limits<float>::max();
    for (const ivec3 &t : m.triangles) {
      best = std::min(best, closest_point_on_triangle(p, m.vertices[size_t(t.x)], m.vertices[size_t(t.y)],
                                                       m.vertices[size_t(t.z)]).distance_sq);
    }
    const ClosestPoint cp = bvh.closest_point(p);
    ASSERT_NEAR(cp.distance_sq, best, 1e-5f * (1.0f + best)) << "point " << i;
    ASSERT_NEAR(glm::dot(cp.point - p, cp.point - p), cp.distance_sq, 1e-4f);
  }
}

TEST(TriangleBVH, ClosestPointOnTriangleRegions)
{
  const vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  ClosestPoint cp = closest_point_on_triangle(vec3(0.2f, 0.2f, 1.0f), a, b, c);
  EXPECT_EQ(cp.feature, TriangleFeature::Face);
  EXPECT_NEAR(cp.distance_sq, 1.0f, 1e-6f);
  cp = closest_point_on_triangle(vec3(-1, -1, 0), a, b, c);
  EXPECT_EQ(cp.feature, TriangleFeature::Vertex);
  EXPECT_EQ(cp.feature_index, 0);
  cp = closest_point_on_triangle(vec3(1, 1, 0), a, b, c);
  EXPECT_EQ(cp.feature, TriangleFeature::Edge);
  EXPECT_EQ(cp.feature_index, 1);
  EXPECT_NEAR(glm::length(cp.point - vec3(0.5f, 0.5f, 0)), 0.0f, 1e-6f);
  cp = closest_point_on_triangle(vec3(-1, 0.5f, 0), a, b, c);
  EXPECT_EQ(cp.feature, TriangleFeature::Edge);
  EXPECT_EQ(cp.feature_index, 2);
}

TEST(TriangleBVH, RayHitsMatchBruteForce)
{
  const TestMesh m = random_mesh();
  const TriangleBVH bvh(m.vertices, m.triangles);
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> c(-2.5f, 2.5f);
  std::vector<RayHit> hits;
  int64_t total = 0;
  for (int i = 0; i < 1000; i++) {
    const vec3 origin(c(rng), c(rng), c(rng));
    const vec3 direction = glm::normalize(vec3(c(rng), c(rng), c(rng)));
    std::vector<float> expected;
    for (const ivec3 &t : m.triangles) {
      RayHit hit;
      if (intersect_ray_triangle(origin, direction, m.vertices[size_t(t.x)], m.vertices[size_t(t.y)],
                                 m.vertices[size_t(t.z)], hit)) {
        expected.push_back(hit.t);
      }
    }
    std::sort(expected.begin(), expected.end());
    bvh.ray_hits(origin, direction, 1e30f, hits);
    ASSERT_EQ(hits.size(), expected.size()) << "ray " << i;
    for (size_t k = 0; k < hits.size(); k++) {
      EXPECT_FLOAT_EQ(hits[k].t, expected[k]);
    }
    RayHit farthest;
    ASSERT_EQ(bvh.ray_farthest_hit(origin, direction, farthest), !expected.empty());
    if (!expected.empty()) {
      EXPECT_FLOAT_EQ(farthest.t, expected.back());
    }
    total += int64_t(expected.size());
  }
  EXPECT_GT(total, 200);
}

TEST(MeshDistance, SignedDistanceOnABoxIsExact)
{
  /* Twelve triangles describe the box exactly, so the only error is rounding; points near
   * edges and corners test the edge and vertex pseudo-normals. */
  const vec3 h(1.0f, 0.5f, 2.0f);
  const TestMesh m = box(h);
  const MeshDistance distance(m.vertices, m.triangles);
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> c(-2.5f, 2.5f);
  for (int i = 0; i < 5000; i++) {
    const vec3 p(c(rng), c(rng), c(rng));
    ASSERT_NEAR(distance.signed_distance(p), box_sdf(p, h), 1e-5f) << p.x << " " << p.y << " " << p.z;
  }
  /* Just outside a corner and an edge, just inside a face. */
  EXPECT_GT(distance.signed_distance(h + vec3(1e-3f)), 0.0f);
  EXPECT_GT(distance.signed_distance(vec3(h.x + 1e-3f, h.y + 1e-3f, 0.0f)), 0.0f);
  EXPECT_NEAR(distance.signed_distance(vec3(0.0f, 0.4f, 0.0f)), -0.1f, 1e-6f);
  EXPECT_NEAR(distance.depth(vec3(0.0f, 0.4f, 0.0f)), 0.1f, 1e-6f);
  EXPECT_EQ(distance.depth(vec3(5.0f, 0.0f, 0.0f)), 0.0f);
}

TEST(MeshDistance, SignedDistanceOnASphere)
{
  const float radius = 2.0f;
  const TestMesh m = uv_sphere(radius, 128, 64);
  const MeshDistance distance(m.vertices, m.triangles);
  /* Faceting error: the sagitta of a cell, R (1 - cos(π / 64)). */
  const float facet = radius * (1.0f - std::cos(float(M_PI) / 64.0f)) * 2.0f;
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> c(-3.0f, 3.0f);
  for (int i = 0; i < 3000; i++) {
    const vec3 p(c(rng), c(rng), c(rng));
    const float exact = glm::length(p) - radius;
    const float sd = distance.signed_distance(p);
    ASSERT_NEAR(sd, exact, facet) << i;
    if (std::abs(exact) > facet) {
      ASSERT_EQ(sd < 0.0f, exact < 0.0f);
    }
  }
}

TEST(MeshDistance, PenetrationStats)
{
  const vec3 h(1.0f);
  const TestMesh m = box(h);
  const MeshDistance distance(m.vertices, m.triangles);
  /* Depths 0.5, 0.05, 0 (outside), 1 (the centre). */
  const std::vector<vec3> points{{0.5f, 0, 0}, {0, 0.95f, 0}, {3, 0, 0}, {0, 0, 0}};
  PenetrationStats stats = penetration_stats(distance, mat4(1.0f), points, 0.1f);
  EXPECT_NEAR(stats.max_depth, 1.0f, 1e-6f);
  EXPECT_EQ(stats.deeper_num, 2);
  EXPECT_EQ(stats.points_num, 4);
  EXPECT_FLOAT_EQ(stats.share, 0.5f);
  /* The box moved and scaled by 3: world depths scale, points follow the transform. */
  const mat4 m_wo = glm::translate(mat4(1.0f), vec3(10, 0, 0)) * glm::scale(mat4(1.0f), vec3(3.0f));
  std::vector<vec3> moved;
  for (const vec3 &p : points) {
    moved.push_back(transform_point(m_wo, p));
  }
  stats = penetration_stats(distance, m_wo, moved, 0.1f);
  EXPECT_NEAR(stats.max_depth, 3.0f, 1e-5f);
  EXPECT_EQ(stats.deeper_num, 3);
  EXPECT_NEAR(uniform_scale(m_wo), 3.0f, 1e-6f);
  stats = penetration_stats(distance, mat4(1.0f), Span<vec3>(), 0.1f);
  EXPECT_EQ(stats.share, 0.0f);
}

/* The report's repeated calls skip points that cannot have reached the mesh since the last
 * call (the signed distance is 1-Lipschitz): over frames of a cloud that drifts by small steps,
 * jumps now and then, and moves with the mesh's transform, the depths are those of a fresh
 * query for every point. */
TEST(MeshDistance, RepeatedDepthsSkipOnlyPointsThatStayedOut)
{
  const TestMesh m = uv_sphere(1.0f, 48, 24);
  const MeshDistance distance(m.vertices, m.triangles);
  std::mt19937 rng(5);
  std::normal_distribution<float> gauss;
  std::vector<vec3> points(3000);
  for (vec3 &p : points) {
    p = 1.3f * vec3(gauss(rng), gauss(rng), gauss(rng));
  }
  int64_t inside_num = 0;
  for (int frame = 0; frame < 30; frame++) {
    const mat4 object_to_world = glm::translate(mat4(1.0f), vec3(0.02f * float(frame), 0, 0)) *
                                 glm::rotate(mat4(1.0f), 0.05f * float(frame), vec3(0, 0, 1));
    for (size_t i = 0; i < points.size(); i++) {
      const float step = i % 97 == size_t(frame) % 97 ? 1.0f : 0.03f; /* a few jump */
      points[i] += step * vec3(gauss(rng), gauss(rng), gauss(rng));
    }
    std::vector<float> depths(points.size(), 0.0f);
    accumulate_penetration_depths(distance, object_to_world, points, depths);
    const mat4 world_to_object = glm::inverse(object_to_world);
    for (size_t i = 0; i < points.size(); i++) {
      const float expected = distance.depth(transform_point(world_to_object, points[i]));
      ASSERT_EQ(depths[i], expected) << "frame " << frame << ", point " << i;
      inside_num += expected > 0.0f;
    }
  }
  EXPECT_GT(inside_num, 1000) << "the cloud must reach into the sphere";
}

/* Points carried with the mesh (roots on a turning head) come back to object space a rounding
 * apart each frame, and keep their first answer: within that rounding of a fresh query, the
 * ones inside counted inside every frame. */
TEST(MeshDistance, RepeatedDepthsOfPointsCarriedWithTheMesh)
{
  const TestMesh m = uv_sphere(1.0f, 48, 24);
  const MeshDistance distance(m.vertices, m.triangles);
  std::mt19937 rng(9);
  std::normal_distribution<float> gauss;
  /* On the surface, just inside and just outside, in object space. */
  std::vector<vec3> carried(600);
  for (size_t i = 0; i < carried.size(); i++) {
    const vec3 direction = glm::normalize(vec3(gauss(rng), gauss(rng), gauss(rng)));
    carried[i] = (0.99f + 0.01f * float(i % 3)) * direction;
  }
  const float slack = 1e-5f * 2.0f * std::sqrt(3.0f); /* as accumulate_depths, for this box */
  for (int frame = 0; frame < 40; frame++) {
    const mat4 object_to_world = glm::translate(mat4(1.0f), vec3(0.37f * float(frame), 0, 0)) *
                                 glm::rotate(mat4(1.0f), 0.11f * float(frame), vec3(0, 1, 1));
    std::vector<vec3> points;
    for (const vec3 &p : carried) {
      points.push_back(transform_point(object_to_world, p));
    }
    std::vector<float> depths(points.size(), 0.0f);
    accumulate_penetration_depths(distance, object_to_world, points, depths);
    const mat4 world_to_object = glm::inverse(object_to_world);
    for (size_t i = 0; i < points.size(); i++) {
      const float expected = distance.depth(transform_point(world_to_object, points[i]));
      ASSERT_NEAR(depths[i], expected, slack) << "frame " << frame << ", point " << i;
      ASSERT_EQ(depths[i] > 0.005f, i % 3 == 0) << "frame " << frame << ", point " << i;
    }
  }
}

/* A segment's samples deeper than a tolerance, found with the queries the Lipschitz bound
 * leaves (deeper_on_segment), give each sample's own answer: 20,000 random segments of up to
 * 1 m through and around a sphere of 1 m, 1 to 64 samples, tolerances 0 to 0.2 m. */
TEST(MeshDistance, DeeperOnASegmentAsEverySampleSays)
{
  const TestMesh m = uv_sphere(1.0f, 48, 24);
  const MeshDistance distance(m.vertices, m.triangles);
  std::mt19937 rng(8);
  std::normal_distribution<float> gauss;
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  int64_t deeper_num = 0, shallow_inside_num = 0;
  for (int i = 0; i < 20000; i++) {
    const vec3 a = 1.1f * vec3(gauss(rng), gauss(rng), gauss(rng));
    const vec3 b = a + 0.5f * unit(rng) * glm::normalize(vec3(gauss(rng), gauss(rng), gauss(rng)));
    const int samples = 1 + int(63.0f * unit(rng));
    const float tolerance = 0.2f * unit(rng) * unit(rng);
    bool expected = false, inside = false;
    for (int j = 0; j <= samples; j++) {
      const float depth = distance.depth(glm::mix(a, b, float(j) / float(samples)));
      expected = expected || depth > tolerance;
      inside = inside || depth > 0.0f;
    }
    ASSERT_EQ(distance.deeper_on_segment(a, b, samples, tolerance), expected) << "segment " << i;
    deeper_num += expected;
    shallow_inside_num += inside && !expected;
  }
  EXPECT_GT(deeper_num, 2000);
  EXPECT_GT(shallow_inside_num, 200) << "segments inside by less than the tolerance must occur";
}
