/* Strands against a collider: the reaction constraint (Kurihara 1993, eq. 12–15) and the
 * no-penetration projection (Ward & Lin 2003 §5.5) wired into the strand solver. */
#include <gtest/gtest.h>

#include <memory>

#include "collision/collider.hh"
#include "collision_test_shapes.hh"
#include "groom/metrics.hh"
#include "strands/strand_solver.hh"

using namespace hairdyn;

namespace {

constexpr float radius = 0.1f;

/* Strands rooted on the top of a sphere of `radius` at the origin, combed out horizontally
 * so that gravity drapes them over it. */
struct Drape {
  std::vector<int32_t> offsets{0};
  std::vector<vec3> positions;
  std::vector<vec3> normals;
  Drape()
  {
    for (int s = 0; s < 8; s++) {
      const float angle = 2.0f * float(M_PI) * float(s) / 8.0f;
      const vec3 out(std::cos(angle), std::sin(angle), 0.0f);
      const vec3 root = vec3(0.0f, 0.0f, radius * 1.01f) + 0.02f * out;
      for (int i = 0; i <= 16; i++) {
        positions.push_back(root + out * (0.3f * float(i) / 16.0f));
      }
      offsets.push_back(int32_t(positions.size()));
      normals.push_back(vec3(0.0f, 0.0f, 1.0f));
    }
  }
};

struct Result {
  float depth_max = 0.0f;
  float stretch = 0.0f;
  int64_t contacts = 0;
  int64_t projections = 0;
  float lowest_z = 1.0f;
};

Result drape(const bool with_collision)
{
  const test::TestMesh sphere = test::uv_sphere(radius, 48, 24);
  const ColliderMesh mesh(sphere.vertices, sphere.triangles);
  CollisionParams collision;
  ColliderSet colliders;
  colliders.add(std::make_shared<Collider>(mesh, Span<int32_t>(), Span<int32_t>(), collision));

  const Drape groom;
  StrandParams params;
  params.model = StrandModel::Kurihara1993;
  params.k_theta = params.k_phi = 1e-9f; /* soft hair: gravity wins */
  StrandSolver solver(groom.offsets, groom.positions, mat4(1.0f), groom.normals, params);
  if (with_collision) {
    solver.set_colliders(&colliders, collision);
  }
  Result result;
  for (int frame = 0; frame < 48; frame++) {
    solver.step(1.0f / 24.0f, mat4(1.0f));
    result.contacts += solver.contacts_num();
    result.projections += solver.projections_num();
    for (const vec3 &p : solver.positions()) {
      result.depth_max = std::max(result.depth_max, radius - glm::length(p));
      result.lowest_z = std::min(result.lowest_z, p.z);
    }
  }
  result.stretch = max_relative_stretch(groom.offsets, groom.positions, solver.positions());
  return result;
}

}  // namespace

TEST(StrandsCollision, HairDrapesOverTheSphereInsteadOfFallingThrough)
{
  const Result free_fall = drape(false);
  const Result collide = drape(true);
  /* Without collision the strands swing down through the sphere. */
  EXPECT_GT(free_fall.depth_max, 0.5f * radius);
  /* With it, no node is deeper than the map's resolution allows (the sphere's maps are
   * 40 × 40: chords of 2π r / 40 sag by about r (1 - cos(π / 40)) ≈ 0.3 mm). */
  EXPECT_LT(collide.depth_max, 1.5e-3f) << collide.depth_max;
  EXPECT_GT(collide.contacts, 0);
  /* The strands still hang down around the sphere: collision does not freeze them. */
  EXPECT_LT(collide.lowest_z, 0.0f);
  EXPECT_LT(collide.stretch, 1e-5f);
}

TEST(StrandsCollision, DrapedHairStaysQuietWhateverTheConstraintsStiffness)
{
  /* The default model draped over the sphere, 4 substeps a frame, at the default constraint
   * stiffness and at 30 times it: over the sixth to tenth seconds no node moves more than
   * 3 mm in a frame. With the reaction constraint's spring taken at the step's start, the
   * stiff constraint threw the nodes resting on the sphere off it and the hair thrashed (13 mm
   * a frame on average, 43 mm at most); at the default stiffness it moved up to 0.8 mm, now up
   * to 2.1 mm (a cycle of projections onto the sphere's maps, not fixed). */
  const test::TestMesh sphere = test::uv_sphere(radius, 48, 24);
  const ColliderMesh mesh(sphere.vertices, sphere.triangles);
  const Drape groom;
  for (const float stiffness : {1.0e4f, 3.0e5f}) {
    CollisionParams collision;
    collision.stiffness = stiffness;
    ColliderSet colliders;
    colliders.add(std::make_shared<Collider>(mesh, Span<int32_t>(), Span<int32_t>(), collision));
    StrandSolver solver(groom.offsets, groom.positions, mat4(1.0f), groom.normals,
                        StrandParams());
    solver.set_colliders(&colliders, collision);
    float largest_move = 0.0f; /* m in a frame */
    for (int frame = 0; frame < 240; frame++) {
      const std::vector<vec3> before(solver.positions().begin(), solver.positions().end());
      solver.step(1.0f / 24.0f, mat4(1.0f));
      ASSERT_EQ(solver.diverged_num(), 0);
      for (size_t i = 0; frame >= 120 && i < before.size(); i++) {
        largest_move =
            std::max(largest_move, glm::length(solver.positions()[int64_t(i)] - before[i]));
      }
    }
    EXPECT_LT(largest_move, 3e-3f) << "stiffness " << stiffness;
  }
}

TEST(StrandsCollision, LanesGiveEachStrandItsOwnBits)
{
  /* The articulated model steps strands of one point count four at a time, their double-
   * precision recursions in one vector (chain_lanes.hh). Each strand must come out with the
   * bits it has when simulated alone, through everything a step does: contacts with the
   * sphere and the projection's impulses, the predictor steps after them, steps cut short
   * while the head shakes, and a last group that is not full. Here 7 strands of 16 segments
   * and 4 of 8, interleaved, draped over the sphere while the head turns back and forth. */
  const test::TestMesh sphere = test::uv_sphere(radius, 48, 24);
  const ColliderMesh mesh(sphere.vertices, sphere.triangles);
  CollisionParams collision;
  ColliderSet colliders;
  colliders.add(std::make_shared<Collider>(mesh, Span<int32_t>(), Span<int32_t>(), collision));
  struct Groom {
    std::vector<int32_t> offsets{0};
    std::vector<vec3> positions, normals;
  };
  std::vector<Groom> alone(11);
  Groom together;
  for (int s = 0; s < 11; s++) {
    const float angle = 2.0f * float(M_PI) * float(s) / 11.0f;
    const vec3 out(std::cos(angle), std::sin(angle), 0.0f);
    const vec3 root = vec3(0.0f, 0.0f, radius * 1.01f) + 0.02f * out;
    const int segments = s % 3 == 1 ? 8 : 16;
    for (Groom *groom : {&alone[size_t(s)], &together}) {
      for (int i = 0; i <= segments; i++) {
        groom->positions.push_back(root + out * (0.25f * float(i) / float(segments)));
      }
      groom->offsets.push_back(int32_t(groom->positions.size()));
      groom->normals.push_back(vec3(0.0f, 0.0f, 1.0f));
    }
  }
  StrandParams params;
  params.model = StrandModel::Articulated;
  const auto head = [](const int frame) {
    return glm::rotate(mat4(1.0f), 1.2f * std::sin(float(frame) * 0.6f), vec3(0, 0, 1));
  };
  StrandSolver solver(together.offsets, together.positions, mat4(1.0f), together.normals,
                      params);
  solver.set_colliders(&colliders, collision);
  std::vector<std::unique_ptr<StrandSolver>> solvers;
  for (const Groom &groom : alone) {
    solvers.push_back(std::make_unique<StrandSolver>(groom.offsets, groom.positions,
                                                     mat4(1.0f), groom.normals, params));
    solvers.back()->set_colliders(&colliders, collision);
  }
  int64_t contacts = 0, projections = 0;
  for (int frame = 1; frame <= 36; frame++) {
    solver.step(1.0f / 24.0f, head(frame));
    contacts += solver.contacts_num();
    projections += solver.projections_num();
    ASSERT_EQ(solver.diverged_num(), 0);
    int64_t point = 0;
    for (size_t s = 0; s < solvers.size(); s++) {
      solvers[s]->step(1.0f / 24.0f, head(frame));
      for (const vec3 &p : solvers[s]->positions()) {
        ASSERT_EQ(p, solver.positions()[point]) << "frame " << frame << ", strand " << s;
        ASSERT_EQ(solvers[s]->velocities()[point - together.offsets[s]],
                  solver.velocities()[point]);
        point++;
      }
    }
  }
  EXPECT_GT(contacts, 0);
  EXPECT_GT(projections, 0);
}
