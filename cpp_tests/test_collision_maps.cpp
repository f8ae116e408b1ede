/* Cylindrical (Kurihara 1993 §3.1) and spherical (§5) maps, the Collider and ColliderSet. */
#include <gtest/gtest.h>

#include <random>

#include "collision/collider.hh"
#include "collision_test_shapes.hh"

using namespace hairdyn;
using namespace hairdyn::test;

namespace {

struct MapErrors {
  /* Over points where map and shape agree the point is inside, within `near` of the surface:
   * eq. 11 measures depth to the tangent plane at Q, which departs from the true depth with
   * the curvature for deeper points, at any resolution. */
  float max_depth_error = 0.0f;
  int64_t misclassified = 0;    /* Inside/outside disagreements farther than `band` from the surface. */
  int64_t checked = 0;
};

/* Compares map contacts with an exact depth function over random points in a box. */
template<typename Map, typename ExactDepth, typename Sampler>
MapErrors compare_with_exact(const Map &map, const ExactDepth &exact_depth, const Sampler &sample,
                             const float band, const float near = 0.02f)
{
  std::mt19937 rng(7);
  MapErrors errors;
  for (int i = 0; i < 20000; i++) {
    const vec3 p = sample(rng);
    const float exact = exact_depth(p);
    MapSample s;
    const bool inside = map.evaluate(p, s) && s.inside;
    if (inside != (exact > 0.0f)) {
      errors.misclassified += std::abs(exact) > band ? 1 : 0;
      continue;
    }
    if (inside && exact < near) {
      errors.max_depth_error = std::max(errors.max_depth_error, std::abs(s.depth - exact));
      errors.checked++;
    }
  }
  return errors;
}

ColliderMesh make_mesh(const TestMesh &m)
{
  EXPECT_EQ(find_mesh_error(m.vertices, m.triangles), "");
  return ColliderMesh(m.vertices, m.triangles);
}

}  // namespace

TEST(CollisionMaps, FastAtan2MatchesStd)
{
  float max_error = 0.0f;
  for (int i = 0; i < 100000; i++) {
    const float angle = float(2.0 * M_PI * i / 100000.0);
    const float r = 0.001f + float(i % 7);
    const float y = r * std::sin(angle), x = r * std::cos(angle);
    max_error = std::max(max_error, std::abs(fast_atan2(y, x) - std::atan2(y, x)));
  }
  EXPECT_LT(max_error, 2e-6f);
  EXPECT_EQ(fast_atan2(0.0f, 0.0f), 0.0f);
}

TEST(CollisionMaps, FittedFrameFollowsTheLongAxis)
{
  /* A long cylinder along y, rotated so that its axis is (1, 1, 0) / √2, and moved. */
  TestMesh m = closed_cylinder(1.0f, 8.0f, 32, 8);
  const mat4 rotation = glm::rotate(mat4(1.0f), float(M_PI / 4), vec3(0, 0, -1));
  for (vec3 &v : m.vertices) {
    v = transform_point(rotation, v) + vec3(3, -2, 1);
  }
  const MapFrame frame = fit_frame(m.vertices, m.triangles);
  EXPECT_NEAR(std::abs(glm::dot(frame.axis, glm::normalize(vec3(1, 1, 0)))), 1.0f, 1e-4f);
  EXPECT_NEAR(glm::length(frame.origin - vec3(3, -2, 1)), 0.0f, 1e-3f);
  EXPECT_NEAR(glm::dot(frame.axis, frame.reference), 0.0f, 1e-5f);
  /* object_to_map and map_to_object are inverses. */
  const vec3 p(0.3f, 2.0f, -1.0f);
  EXPECT_NEAR(glm::length(transform_point(frame.map_to_object(), transform_point(frame.object_to_map(), p)) - p), 0.0f, 1e-5f);
}

/* A cylinder whose map axis is off its true axis (so r varies with θ): inside/outside and
 * depth match the exact shape within the discretisation error, which shrinks as m rises. */
TEST(CollisionMaps, CylinderMapMatchesOffsetCylinder)
{
  const float radius = 1.0f;
  const TestMesh m = closed_cylinder(radius, 4.0f, 1024, 4);
  const TriangleBVH bvh(m.vertices, m.triangles);
  const MapFrame frame = make_frame(vec3(0.4f, 0, 0), vec3(0, 1, 0), vec3(1, 0, 0));
  const auto exact = [&](const vec3 &p) { return radius - std::sqrt(p.x * p.x + p.z * p.z); };
  const auto sample = [](std::mt19937 &rng) {
    std::uniform_real_distribution<float> xz(-1.4f, 1.4f), y(-1.5f, 1.5f);
    return vec3(xz(rng), y(rng), xz(rng));
  };
  const CylinderMap coarse(bvh, m.vertices, m.triangles, frame, 16, 8);
  const CylinderMap fine(bvh, m.vertices, m.triangles, frame, 128, 8);
  EXPECT_EQ(coarse.table().empty_cells_num(), 0);
  const MapErrors e_coarse = compare_with_exact(coarse, exact, sample, 0.05f);
  const MapErrors e_fine = compare_with_exact(fine, exact, sample, 0.002f);
  std::printf("cylinder map depth error: m = 16: %.5f, m = 128: %.5f\n", e_coarse.max_depth_error,
              e_fine.max_depth_error);
  EXPECT_GT(e_fine.checked, 200);
  EXPECT_EQ(e_coarse.misclassified, 0);
  EXPECT_EQ(e_fine.misclassified, 0);
  EXPECT_LT(e_coarse.max_depth_error, 0.05f);
  EXPECT_LT(e_fine.max_depth_error, 0.002f);
  EXPECT_LT(e_fine.max_depth_error, 0.25f * e_coarse.max_depth_error);
  /* Points above and below the part's height range never collide. */
  MapSample s;
  EXPECT_FALSE(fine.find_contact_map(transform_point(frame.object_to_map(), vec3(0, 2.1f, 0)), s));
  EXPECT_TRUE(fine.find_contact_map(transform_point(frame.object_to_map(), vec3(0, 1.9f, 0)), s));
}

/* A sphere seen from an off-centre map centre (r varies with both angles). */
TEST(CollisionMaps, SphereMapMatchesOffsetSphere)
{
  const float radius = 1.0f;
  const TestMesh m = uv_sphere(radius, 512, 256);
  const TriangleBVH bvh(m.vertices, m.triangles);
  const MapFrame frame = make_frame(vec3(0.2f, 0.3f, -0.1f), vec3(0, 1, 0), vec3(1, 0, 0));
  const auto exact = [&](const vec3 &p) { return radius - glm::length(p); };
  const auto sample = [](std::mt19937 &rng) {
    std::uniform_real_distribution<float> c(-1.3f, 1.3f);
    return vec3(c(rng), c(rng), c(rng));
  };
  const SphereMap coarse(bvh, m.vertices, m.triangles, frame, 16, 8);
  const SphereMap fine(bvh, m.vertices, m.triangles, frame, 128, 64);
  EXPECT_EQ(fine.table().empty_cells_num(), 0);
  const MapErrors e_coarse = compare_with_exact(coarse, exact, sample, 0.08f);
  const MapErrors e_fine = compare_with_exact(fine, exact, sample, 0.003f);
  std::printf("sphere map depth error: 16 x 8: %.5f, 128 x 64: %.5f\n", e_coarse.max_depth_error,
              e_fine.max_depth_error);
  EXPECT_GT(e_fine.checked, 200);
  EXPECT_EQ(e_coarse.misclassified, 0);
  EXPECT_EQ(e_fine.misclassified, 0);
  EXPECT_LT(e_coarse.max_depth_error, 0.08f);
  EXPECT_LT(e_fine.max_depth_error, 0.003f);
  EXPECT_LT(e_fine.max_depth_error, 0.25f * e_coarse.max_depth_error);
}

/* Two nested closed cylinders: rays from the axis hit the inner wall and then the outer one;
 * the map keeps the outer (outermost) hit. */
TEST(CollisionMaps, OutermostHitIsUsed)
{
  TestMesh m = closed_cylinder(1.0f, 4.0f, 64, 2);
  append(m, closed_cylinder(2.0f, 4.0f, 64, 2));
  const TriangleBVH bvh(m.vertices, m.triangles);
  const MapFrame frame = make_frame(vec3(0.0f), vec3(0, 1, 0), vec3(1, 0, 0));
  std::vector<RayHit> hits;
  bvh.ray_hits(vec3(0.01f, 0.3f, 0.02f), vec3(0.6f, 0, 0.8f), 100.0f, hits);
  ASSERT_EQ(hits.size(), 2u);
  const CylinderMap map(bvh, m.vertices, m.triangles, frame, 40, 40);
  for (int i = 0; i < 40; i++) {
    EXPECT_NEAR(map.table().cell(i, 20).radius, 2.0f, 0.01f);
  }
  MapSample s;
  ASSERT_TRUE(map.find_contact_map(vec3(1.5f, 0.0f, 0.0f), s));
  EXPECT_NEAR(s.depth, 0.5f, 0.01f);
  EXPECT_NEAR(s.normal.x, 1.0f, 2e-3f); /* A facet normal, 2.8° off. */
}

/* Half a tube: rays towards the missing half escape, their cells are empty, and no point
 * there is reported inside, however close to the axis. */
TEST(CollisionMaps, EmptyCellsNeverReportCollisions)
{
  const TestMesh m = closed_cylinder(1.0f, 4.0f, 64, 4, 0.5);
  const TriangleBVH bvh(m.vertices, m.triangles);
  const MapFrame frame = make_frame(vec3(0.0f), vec3(0, 1, 0), vec3(1, 0, 0));
  for (const bool sphere : {false, true}) {
    const CylinderMap cylinder(bvh, m.vertices, m.triangles, frame, 40, 40);
    const SphereMap sphere_map(bvh, m.vertices, m.triangles, frame, 40, 40);
    const RadialTable &table = sphere ? sphere_map.table() : cylinder.table();
    EXPECT_GT(table.empty_cells_num(), 40 * 40 / 3);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> angle(float(M_PI) + 0.2f, float(2 * M_PI) - 0.2f);
    std::uniform_real_distribution<float> radius(0.01f, 0.99f), y(-0.5f, 0.5f);
    for (int i = 0; i < 2000; i++) {
      const float a = angle(rng), r = radius(rng);
      MapSample s;
      const vec3 p(r * std::cos(a), y(rng), r * std::sin(a));
      EXPECT_FALSE(sphere ? sphere_map.find_contact_map(p, s) : cylinder.find_contact_map(p, s));
    }
    /* The covered half still collides. */
    MapSample s;
    EXPECT_EQ(sphere ? sphere_map.find_contact_map(vec3(0.0f, 0.1f, 0.8f), s) :
                       cylinder.find_contact_map(vec3(0.0f, 0.1f, 0.8f), s),
              true);
  }
}

namespace {

struct SintelHead {
  TestMesh mesh;
  std::vector<ivec3> head_triangles;  /* All three vertices above the neck. */
  std::vector<ivec3> crown_triangles; /* The top of the head. */
  std::vector<int32_t> head_vertices;
};

bool load_sintel(SintelHead &r_head)
{
  if (!read_obj(sintel_bust_path, r_head.mesh)) {
    return false;
  }
  const float neck_y = 21.0f, crown_y = 40.0f;
  for (int32_t v = 0; v < int32_t(r_head.mesh.vertices.size()); v++) {
    if (r_head.mesh.vertices[size_t(v)].y > neck_y) {
      r_head.head_vertices.push_back(v);
    }
  }
  for (const ivec3 &t : r_head.mesh.triangles) {
    const vec3 a = r_head.mesh.vertices[size_t(t.x)], b = r_head.mesh.vertices[size_t(t.y)],
               c = r_head.mesh.vertices[size_t(t.z)];
    if (std::min(a.y, std::min(b.y, c.y)) > neck_y) {
      r_head.head_triangles.push_back(t);
      if ((a.y + b.y + c.y) / 3.0f > crown_y) {
        r_head.crown_triangles.push_back(t);
      }
    }
  }
  return true;
}

}  // namespace

/* On the real head: both maps stay within a bounded error of the exact mesh distance, and on
 * the crown the spherical map is the better one (Kurihara 1993 §5). */
TEST(CollisionMaps, SintelHeadMapErrorsAndCrown)
{
  SintelHead head;
  if (!load_sintel(head)) {
    GTEST_SKIP() << "the Sintel head is missing: no " << sintel_bust_path << " (folder "
                 << sintel_folder << ")";
  }
  ASSERT_EQ(head.mesh.vertices.size(), 3046u);
  ASSERT_EQ(head.mesh.triangles.size(), 5952u);
  const Span<vec3> vertices(head.mesh.vertices);
  const TriangleBVH bvh(vertices, head.head_triangles);
  const MeshDistance exact(vertices, head.head_triangles);
  const MapFrame frame = fit_frame(vertices, head.head_triangles);
  /* The head is taller than it is wide: the fitted axis is close to the model's up (y). */
  EXPECT_GT(std::abs(frame.axis.y), 0.8f);
  const CylinderMap cylinder(bvh, vertices, head.head_triangles, frame, 40, 40);
  const SphereMap sphere(bvh, vertices, head.head_triangles, frame, 40, 40);

  const float head_size = glm::length(bvh.bounds_max() - bvh.bounds_min());
  const float offset = 0.01f * head_size;
  const std::vector<vec3> all = error_sample_points(vertices, head.head_triangles, offset, 4000);
  const std::vector<vec3> crown = error_sample_points(vertices, head.crown_triangles, offset, 4000);
  ASSERT_GT(crown.size(), 50u);
  const float cylinder_all = mean_depth_error(cylinder, exact, all);
  const float sphere_all = mean_depth_error(sphere, exact, all);
  const float cylinder_crown = mean_depth_error(cylinder, exact, crown);
  const float sphere_crown = mean_depth_error(sphere, exact, crown);
  std::printf("head size %.2f; mean depth error: cylinder %.4f (crown %.4f), sphere %.4f (crown %.4f)\n",
              head_size, cylinder_all, cylinder_crown, sphere_all, sphere_crown);
  /* Bounded: 1% of the head's size over the whole head. */
  EXPECT_LT(cylinder_all, 0.01f * head_size);
  EXPECT_LT(sphere_all, 0.01f * head_size);
  EXPECT_LT(sphere_crown, cylinder_crown);

  /* The Collider's automatic choice keeps the map with the smaller error. */
  const ColliderMesh collider_mesh(head.mesh.vertices, head.mesh.triangles);
  const std::vector<int32_t> offsets{0, int32_t(head.head_vertices.size())};
  ASSERT_EQ(find_collider_error(collider_mesh, offsets, head.head_vertices), "");
  const Collider collider(collider_mesh, offsets, head.head_vertices, CollisionParams{});
  const float e_cyl = collider.part_cylinder_error(0), e_sph = collider.part_sphere_error(0);
  EXPECT_GE(e_cyl, 0.0f);
  EXPECT_GE(e_sph, 0.0f);
  EXPECT_EQ(collider.part_map(0).kind, e_sph < e_cyl ? MapKind::Sphere : MapKind::Cylinder);
  EXPECT_GT(collider.build_ms(), 0.0);
}

TEST(Collider, RigidMotionTransformsQueriesNotTheMaps)
{
  const TestMesh m = uv_sphere(1.0f, 64, 32);
  const ColliderMesh mesh = make_mesh(m);
  CollisionParams params;
  params.map_kind = MapKind::Sphere;
  Collider collider(mesh, {}, {}, params);
  ColliderSet set;
  set.add(std::make_shared<Collider>(collider));

  const vec3 p_object(0.3f, 0.5f, -0.2f);
  Contact at_rest;
  ASSERT_TRUE(set.find_contact(p_object, at_rest));
  EXPECT_NEAR(at_rest.depth, 1.0f - glm::length(p_object), 0.01f);
  EXPECT_NEAR(glm::length(at_rest.surface_point_wo), 1.0f, 0.01f);

  const mat4 motion = glm::translate(mat4(1.0f), vec3(5, -1, 2)) *
                      glm::rotate(mat4(1.0f), 0.7f, glm::normalize(vec3(1, 2, 3))) *
                      glm::scale(mat4(1.0f), vec3(2.0f));
  set.collider_for_write(0).set_transform(motion);
  Contact moved;
  ASSERT_TRUE(set.find_contact(transform_point(motion, p_object), moved));
  EXPECT_NEAR(moved.depth, 2.0f * at_rest.depth, 1e-4f);
  EXPECT_NEAR(glm::length(moved.surface_point_wo - transform_point(motion, at_rest.surface_point_wo)), 0.0f, 1e-4f);
  EXPECT_NEAR(glm::dot(moved.normal_wo, glm::normalize(mat3(motion) * at_rest.normal_wo)), 1.0f, 1e-5f);
  /* The untransformed point is now outside (the sphere moved away). */
  Contact none;
  EXPECT_FALSE(set.find_contact(p_object, none));
  EXPECT_NEAR(set.size_wo(), 2.0f * collider.size(), 1e-4f);
}

TEST(Collider, SetReturnsTheDeepestContact)
{
  const TestMesh a = uv_sphere(1.0f, 32, 16);
  const ColliderMesh mesh = make_mesh(a);
  CollisionParams params;
  params.map_kind = MapKind::Sphere;
  ColliderSet set;
  set.add(std::make_shared<Collider>(mesh, Span<int32_t>(), Span<int32_t>(), params));
  set.add(std::make_shared<Collider>(mesh, Span<int32_t>(), Span<int32_t>(), params));
  set.collider_for_write(1).set_transform(glm::translate(mat4(1.0f), vec3(1.5f, 0, 0)));
  /* x = 0.6: 0.4 deep in the first sphere, 0.1 in the second. */
  Contact c;
  ASSERT_TRUE(set.find_contact(vec3(0.6f, 0, 0), c));
  EXPECT_NEAR(c.depth, 0.4f, 0.01f);
  EXPECT_NEAR(c.normal_wo.x, 1.0f, 0.01f);
  ASSERT_TRUE(set.find_contact(vec3(0.9f, 0, 0), c));
  EXPECT_NEAR(c.depth, 0.4f, 0.01f);
  EXPECT_NEAR(c.normal_wo.x, -1.0f, 0.01f);

  std::vector<vec3> points{{0.6f, 0, 0}, {5, 5, 5}};
  std::vector<uint8_t> hit(2);
  std::vector<float> depth(2);
  std::vector<vec3> normal(2), surface(2);
  find_contacts(set, points, hit, depth, normal, surface);
  EXPECT_EQ(hit[0], 1);
  EXPECT_EQ(hit[1], 0);
  EXPECT_NEAR(depth[0], 0.4f, 0.01f);
  EXPECT_EQ(depth[1], 0.0f);
  EXPECT_EQ(surface[1], points[1]);
}

TEST(Collider, DeformingColliderRebuilds)
{
  const TestMesh m = uv_sphere(1.0f, 32, 16);
  const ColliderMesh mesh = make_mesh(m);
  Collider collider(mesh, {}, {}, CollisionParams{});
  Contact c;
  EXPECT_FALSE(collider.find_contact(vec3(0, 0, 1.3f), c));
  std::vector<vec3> grown = m.vertices;
  for (vec3 &v : grown) {
    v *= 1.5f;
  }
  collider.rebuild(grown);
  ASSERT_TRUE(collider.find_contact(vec3(0, 0, 1.3f), c));
  EXPECT_NEAR(c.depth, 0.2f, 0.02f);
  EXPECT_GT(collider.build_ms(), 0.0);
  EXPECT_NEAR(collider.size(), 1.5f * std::sqrt(12.0f), 0.05f);
}

TEST(Collider, ForcedKindsAndObjectAxes)
{
  const TestMesh m = closed_cylinder(1.0f, 20.0f, 64, 20);
  const ColliderMesh mesh = make_mesh(m);
  CollisionParams params;
  params.axis_mode = AxisMode::ObjectY;
  params.map_kind = MapKind::Cylinder;
  const Collider cylinder(mesh, {}, {}, params);
  EXPECT_EQ(cylinder.part_map(0).kind, MapKind::Cylinder);
  EXPECT_NEAR(cylinder.part_map(0).frame().axis.y, 1.0f, 1e-6f);
  EXPECT_EQ(cylinder.part_cylinder_error(0), -1.0f);
  Contact c;
  ASSERT_TRUE(cylinder.find_contact(vec3(0.7f, 6.0f, 0.0f), c));
  EXPECT_NEAR(c.depth, 0.3f, 0.01f);
  /* Automatic choice on a long cylinder (seen from its centre, its ends are grazed by the
   * spherical map's rays): the cylindrical map. */
  params.map_kind = MapKind::Auto;
  const Collider automatic(mesh, {}, {}, params);
  EXPECT_EQ(automatic.part_map(0).kind, MapKind::Cylinder);
  EXPECT_LT(automatic.part_cylinder_error(0), automatic.part_sphere_error(0));
  /* Explicit frame, axis along x: the long cylinder is then badly described but still built. */
  const std::vector<MapFrame> frames{make_frame(vec3(0.0f), vec3(1, 0, 0), vec3(0, 1, 0))};
  params.map_kind = MapKind::Cylinder;
  const Collider sideways(mesh, {}, {}, params, frames);
  EXPECT_NEAR(sideways.part_map(0).frame().axis.x, 1.0f, 1e-6f);
}

TEST(Collider, PartsSelectTheirTriangles)
{
  /* Two spheres in one mesh; the part is the second only. */
  TestMesh m = uv_sphere(1.0f, 32, 16);
  const int32_t first_num = int32_t(m.vertices.size());
  TestMesh second = uv_sphere(1.0f, 32, 16);
  for (vec3 &v : second.vertices) {
    v += vec3(4, 0, 0);
  }
  append(m, second);
  const ColliderMesh mesh = make_mesh(m);
  std::vector<int32_t> part;
  for (int32_t v = first_num; v < int32_t(m.vertices.size()); v++) {
    part.push_back(v);
  }
  const std::vector<int32_t> offsets{0, int32_t(part.size())};
  ASSERT_EQ(find_collider_error(mesh, offsets, part), "");
  const Collider collider(mesh, offsets, part, CollisionParams{});
  Contact c;
  EXPECT_FALSE(collider.find_contact(vec3(0.0f), c));
  EXPECT_TRUE(collider.find_contact(vec3(4.0f, 0.1f, 0.0f), c));
}

TEST(Collider, BadInputIsReportedNotFatal)
{
  const TestMesh m = uv_sphere(1.0f, 16, 8);
  const ColliderMesh mesh = make_mesh(m);
  const std::vector<int32_t> vertices{0, 1, 2};
  EXPECT_NE(find_collider_error(mesh, std::vector<int32_t>{0, 0}, {}).find("part 0 has no vertices"), std::string::npos);
  EXPECT_NE(find_collider_error(mesh, std::vector<int32_t>{0, 3, 3}, vertices).find("part 1 has no vertices"), std::string::npos);
  EXPECT_NE(find_collider_error(mesh, std::vector<int32_t>{0, 2}, vertices).find("offsets"), std::string::npos);
  EXPECT_NE(find_collider_error(mesh, std::vector<int32_t>{0, 1}, std::vector<int32_t>{9999}).find("vertex 9999"), std::string::npos);
  EXPECT_NE(find_collider_error(mesh, std::vector<int32_t>{0, 1}, std::vector<int32_t>{5}).find("selects no triangle"), std::string::npos);
  EXPECT_NE(find_collider_error(mesh, std::vector<int32_t>{0, 3}, vertices, 2).find("map frames"), std::string::npos);
  EXPECT_NE(find_collider_error(mesh, {}, vertices).find("without part offsets"), std::string::npos);
  /* A mesh whose every triangle is unusable (repeated vertices). */
  const std::vector<vec3> points{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const std::vector<ivec3> degenerate{{0, 0, 1}, {1, 2, 2}};
  ASSERT_EQ(find_mesh_error(points, degenerate), "");
  const ColliderMesh empty(points, degenerate);
  EXPECT_EQ(find_collider_error(empty, {}, {}), "the collider mesh has no usable faces");
  /* No faces at all is caught before a ColliderMesh exists. */
  EXPECT_EQ(find_mesh_error(points, {}), "the mesh has no faces");
}

/* Documented fallback: an open mesh (a bust cut at the chest) and a mesh with non-manifold
 * triangles still build; escaping rays just leave empty cells. */
TEST(Collider, OpenAndNonManifoldMeshesFallBack)
{
  const TestMesh open = closed_cylinder(1.0f, 4.0f, 32, 4, 0.5);
  const ColliderMesh open_mesh = make_mesh(open);
  EXPECT_GT(open_mesh.boundary_edges_num(), 0);
  ASSERT_EQ(find_collider_error(open_mesh, {}, {}), "");
  const Collider open_collider(open_mesh, {}, {}, CollisionParams{});
  Contact c;
  EXPECT_FALSE(open_collider.find_contact(vec3(0.0f, 0.0f, -0.5f), c));

  TestMesh nonmanifold = uv_sphere(1.0f, 16, 8);
  nonmanifold.vertices.emplace_back(0.0f, 2.0f, 0.0f);
  /* A fin on an existing edge: a third triangle on that edge. */
  const ivec3 t0 = nonmanifold.triangles[20];
  nonmanifold.triangles.emplace_back(t0.x, t0.y, int(nonmanifold.vertices.size()) - 1);
  const ColliderMesh nm_mesh = make_mesh(nonmanifold);
  EXPECT_EQ(nm_mesh.skipped_triangles_num(), 1);
  ASSERT_EQ(find_collider_error(nm_mesh, {}, {}), "");
  const Collider nm_collider(nm_mesh, {}, {}, CollisionParams{});
  EXPECT_TRUE(nm_collider.find_contact(vec3(0.1f, 0.2f, 0.0f), c));
}
