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
  /* The articulated model steps strands of one point count eight at a time, their double-
   * precision recursions in one vector (chain_lanes.hh). Each strand must come out with the
   * bits it has when simulated alone (in a group of one, the other lanes repeating it; the
   * same bits as the scalar step before the lanes: BM_StrandStep's result_hash), whatever its
   * lane and its neighbours, through everything a step does: contacts with the
   * sphere and the projection's impulses, the predictor steps after them, steps cut short
   * while the head shakes, and a last group that is not full; with each vector code the CPU
   * runs (AVX-512, AVX2, baseline) against the widest's. Here 9 strands of 16 segments (a full
   * vector and one more) and 5 of 8, interleaved, draped over the sphere while the head turns
   * back and forth. */
  const test::TestMesh sphere = test::uv_sphere(radius, 48, 24);
  const ColliderMesh mesh(sphere.vertices, sphere.triangles);
  CollisionParams collision;
  ColliderSet colliders;
  colliders.add(std::make_shared<Collider>(mesh, Span<int32_t>(), Span<int32_t>(), collision));
  struct Groom {
    std::vector<int32_t> offsets{0};
    std::vector<vec3> positions, normals;
  };
  std::vector<Groom> alone(14);
  Groom together;
  for (int s = 0; s < 14; s++) {
    const float angle = 2.0f * float(M_PI) * float(s) / 14.0f;
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
  const int frames_num = 36;
  /* Per frame, every strand's positions and velocities, one after the other. */
  const auto run = [&](const std::vector<Groom> &grooms, int64_t &r_contacts,
                       int64_t &r_projections) {
    std::vector<std::unique_ptr<StrandSolver>> solvers;
    for (const Groom &groom : grooms) {
      solvers.push_back(std::make_unique<StrandSolver>(groom.offsets, groom.positions,
                                                       mat4(1.0f), groom.normals, params));
      solvers.back()->set_colliders(&colliders, collision);
    }
    std::vector<std::vector<vec3>> frames;
    r_contacts = r_projections = 0;
    for (int frame = 1; frame <= frames_num; frame++) {
      const mat4 head = glm::rotate(mat4(1.0f), 1.2f * std::sin(float(frame) * 0.6f),
                                    vec3(0, 0, 1));
      frames.emplace_back();
      for (const std::unique_ptr<StrandSolver> &solver : solvers) {
        solver->step(1.0f / 24.0f, head);
        EXPECT_EQ(solver->diverged_num(), 0);
        r_contacts += solver->contacts_num();
        r_projections += solver->projections_num();
        frames.back().insert(frames.back().end(), solver->positions().begin(),
                             solver->positions().end());
        frames.back().insert(frames.back().end(), solver->velocities().begin(),
                             solver->velocities().end());
      }
    }
    return frames;
  };
  int64_t contacts = 0, projections = 0;
  const std::vector<std::vector<vec3>> expected = run(alone, contacts, projections);
  EXPECT_GT(contacts, 0);
  EXPECT_GT(projections, 0);
  const VectorCode used = articulated_vector_code();
  for (const VectorCode code : {VectorCode::Avx512, VectorCode::Avx2, VectorCode::Baseline}) {
    set_articulated_vector_code(code); /* the CPU's widest where it has not this one */
    const std::vector<std::vector<vec3>> frames = run({together}, contacts, projections);
    for (int frame = 0; frame < frames_num; frame++) {
      /* `together` lists positions then velocities of all; `alone` strand by strand. */
      std::vector<vec3> reordered;
      const size_t points = together.positions.size();
      for (int pass = 0; pass < 2; pass++) {
        size_t offset = 0;
        for (const Groom &groom : alone) {
          const size_t n = groom.positions.size();
          reordered.insert(reordered.end(),
                           expected[size_t(frame)].begin() + int64_t(2 * offset + pass * n),
                           expected[size_t(frame)].begin() + int64_t(2 * offset + pass * n + n));
          offset += n;
        }
      }
      ASSERT_EQ(reordered.size(), 2 * points);
      for (size_t i = 0; i < reordered.size(); i++) {
        ASSERT_EQ(frames[size_t(frame)][i], reordered[i])
            << "frame " << frame + 1 << ", " << (i < points ? "position" : "velocity") << " of point "
            << i % points << ", vector code " << int(articulated_vector_code());
      }
    }
  }
  set_articulated_vector_code(used);
}
