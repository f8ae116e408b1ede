/* Swept spheres (Ward & Lin 2003 §5.3–5.5) inside the strand solver's substeps: two sheets of
 * strands swept through each other cross far less with hair–hair collision; a strand dragged
 * across a thin blade cuts it with node maps, not with swept spheres. */
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "collision/hair_hair_ward2003.hh"
#include "collision/ssv_object_ward2003.hh"
#include "collision_test_shapes.hh"
#include "strand_scenes.hh"
#include "strands/strand_solver.hh"

using namespace hairdyn;

namespace {

/* A strand 0.3 m long (16 segments of 1.9 cm) hanging from a root that is dragged 10 cm along
 * x over a horizontal blade 2 mm thick whose edge (x = 3 cm) stands 20 cm below the root: the
 * strand meets the edge and must bend around it. Returns the most segments cutting the blade
 * in one frame. */
int64_t drag_across_blade(const BodyCollision mode, const StrandModel model)
{
  const test::TestMesh box = test::box(vec3(0.05f, 0.05f, 0.001f));
  const ColliderMesh mesh(box.vertices, box.triangles);
  CollisionParams collision;
  ColliderSet colliders;
  auto blade = std::make_shared<Collider>(mesh, Span<int32_t>(), Span<int32_t>(), collision);
  blade->set_transform(glm::translate(mat4(1.0f), vec3(0.08f, 0.0f, -0.2f)));
  colliders.add(blade);

  std::vector<int32_t> offsets{0, 17};
  std::vector<vec3> positions;
  for (int i = 0; i <= 16; i++) {
    positions.push_back(vec3(0.0f, 0.0f, -0.3f * float(i) / 16.0f));
  }
  StrandParams params;
  params.model = model;
  StrandSolver solver(offsets, positions, mat4(1.0f), {}, params);
  SweptSphereParams ssv;
  ssv.body_collision = mode;
  ssv.thickness = 2e-4f;
  if (ssv.uses_maps()) {
    solver.set_colliders(&colliders, collision);
  }
  SsvObjectPass pass(&colliders, ssv);
  solver.add_pass(&pass);
  int64_t worst = 0;
  for (int frame = 1; frame <= 36; frame++) {
    const float x = 0.1f * std::min(1.0f, float(frame) / 24.0f);
    solver.step(1.0f / 24.0f, glm::translate(mat4(1.0f), vec3(x, 0.0f, 0.0f)));
    /* A segment cuts the blade when some point of it is inside deeper than 0.1 mm. */
    const float share = segment_penetration_share(offsets, solver.positions(), colliders, 1e-4f);
    worst = std::max(worst, int64_t(std::lround(share * 16.0f)));
  }
  return worst;
}

}  // namespace

TEST(SsvDynamics, SweptSpheresStopASegmentCuttingAThinBlade)
{
  for (const StrandModel model : {StrandModel::Kurihara1993, StrandModel::Articulated}) {
    SCOPED_TRACE(model == StrandModel::Articulated ? "articulated" : "kurihara1993");
    EXPECT_GT(drag_across_blade(BodyCollision::Maps, model), 0)
        << "node maps let a segment cut the blade";
    EXPECT_EQ(drag_across_blade(BodyCollision::SweptSpheres, model), 0);
    EXPECT_EQ(drag_across_blade(BodyCollision::Both, model), 0);
  }
}

/* The test: two sheets of strands swept through each other (Petrovic 2006's Fig. 4
 * scene, strand_scenes::run_crossing_sheets) cross at least 5× less often with hair–hair
 * collision than without, and no segment stretches; on a second configuration too (strands
 * closer together, sheet B farther out along sheet A, where A's segments sweep faster). The
 * crossings are counted geometrically between frames, apart from the pass. On both strand
 * models. In Kurihara 1993's, limp strands pushed apart every substep gained energy until
 * 9–13 of them ran away, until a pass could only slow its hinges (take_back_strand); the
 * fastest node is checked for that. */
TEST(SsvDynamics, HairHairKeepsTwoSheetsFromCrossing)
{
  strand_scenes::CrossingSheets fast;
  fast.strands_per_sheet = 14;
  fast.spacing = 0.007f;
  fast.plane_x = 0.1f;
  for (const StrandModel model : { StrandModel::Articulated, StrandModel::Kurihara1993 }) {
    const char *model_name = model == StrandModel::Articulated ? "articulated" : "kurihara1993";
    for (const strand_scenes::CrossingSheets &scene : { strand_scenes::CrossingSheets(), fast }) {
      SCOPED_TRACE(std::string(model_name) +
                   (scene.plane_x == fast.plane_x ? ", fast" : ", default"));
      const strand_scenes::SheetsResult off =
          strand_scenes::run_crossing_sheets(model, nullptr, scene);
      SweptSphereParams params;
      params.hair_hair = true;
      HairHairPass pass(params);
      const strand_scenes::SheetsResult on =
          strand_scenes::run_crossing_sheets(model, &pass, scene);
      std::printf("%s, sheet B at x = %.2f m, strands %.0f mm apart: %lld crossings off, %lld "
                  "on (%lld pairs pushed, %lld had crossed in a substep); A's tips fell %.3f m "
                  "off, %.3f m on; worst stretch %.2g; fastest node %.2f m/s off, %.2f on\n",
                  model_name, scene.plane_x, 1e3 * scene.spacing, (long long)off.crossings,
                  (long long)on.crossings, (long long)pass.stats().pushed_num,
                  (long long)pass.stats().crossed_num, off.tip_drop, on.tip_drop, on.worst_stretch,
                  off.fastest, on.fastest);
      EXPECT_GT(off.crossings, 30) << "the sheets must sweep through each other";
      EXPECT_LE(5 * on.crossings, off.crossings);
      EXPECT_GT(pass.stats().crossed_num, 0) << "the continuous detection must have acted";
      EXPECT_EQ(on.diverged, 0);
      EXPECT_LT(on.worst_stretch, 1e-3f) << "a strand stretched";
      /* The collisions take energy out: no node ends a frame much faster than without them. */
      EXPECT_LT(on.fastest, 1.5f * off.fastest);
      /* The sheets still meet and move: A falls onto B instead of hanging still. */
      EXPECT_GT(on.tip_drop, 0.02f);
    }
  }
}

/* 300 articulated strands of 8 segments (2.75 cm) packed on a cap of a 10 cm sphere, in wind,
 * with hair–hair collision at many substeps: none runs away. Before the take-back bounded the
 * strands' kinetic energy and φ̇ near the chart's pole, the pass's pushes and velocity
 * averages fed the chains: 35 strands ran away in the first frame at 5 m/s and 200 substeps. */
TEST(SsvDynamics, HairHairInWindAtManySubstepsRunsNoStrandAway)
{
  std::vector<int32_t> offsets{0};
  std::vector<vec3> positions, normals;
  const float golden = float(M_PI) * (3.0f - std::sqrt(5.0f));
  for (int s = 0; s < 300; s++) { /* a Fibonacci cap down to 66° from the top */
    const float z = 1.0f - 0.6f * (float(s) + 0.5f) / 300.0f, r = std::sqrt(1.0f - z * z);
    const vec3 out(r * std::cos(golden * float(s)), r * std::sin(golden * float(s)), z);
    const vec3 down = glm::normalize(out + vec3(0.0f, 0.0f, -1.0f));
    for (int i = 0; i <= 8; i++) {
      positions.push_back(0.1f * out + 0.0275f * float(i) * down);
    }
    offsets.push_back(int32_t(positions.size()));
    normals.push_back(out);
  }
  for (const auto &[speed, substeps] : { std::pair{5.0f, 200}, {40.0f, 32}, {20.0f, 64} }) {
    SCOPED_TRACE(std::to_string(speed) + " m/s, " + std::to_string(substeps) + " substeps");
    StrandParams params;
    params.model = StrandModel::Articulated;
    params.substeps = substeps;
    WindParams wind;
    wind.speed = speed;
    StrandSolver solver(offsets, positions, mat4(1.0f), normals, params, wind);
    SweptSphereParams swept;
    swept.hair_hair = true;
    HairHairPass pass(swept);
    solver.add_pass(&pass);
    for (int frame = 0; frame < 3; frame++) {
      solver.step(1.0f / 24.0f, mat4(1.0f));
      ASSERT_EQ(solver.diverged_num(), 0) << "frame " << frame;
    }
    EXPECT_GT(pass.stats().pairs_num, 0) << "the strands must meet";
  }
}
