/* The strand solver's substep seam (strands/substep_pass.hh) and its divergence report: passes
 * run after every substep, their corrections come back into the angles with lengths kept and
 * roots carried by the head, and a diverging strand never hands out NaN. */
#include <gtest/gtest.h>

#include <cstring>
#include <memory>

#include "collision/collider.hh"
#include "collision_test_shapes.hh"
#include "groom/groom.hh"
#include "groom/metrics.hh"
#include "strands/strand_solver.hh"

using namespace hairdyn;

namespace {

struct Groom {
  std::vector<int32_t> offsets{0};
  std::vector<vec3> positions;
};

/* Wavy strands hanging from the top of a 0.1 m sphere. */
Groom wavy_groom(const int strands_num)
{
  Groom groom;
  for (int s = 0; s < strands_num; s++) {
    const float angle = 6.2831853f * float(s) / float(strands_num);
    const vec3 out(std::cos(angle), std::sin(angle), 0.0f);
    vec3 p = vec3(0.0f, 0.0f, 0.101f) + 0.03f * out;
    for (int i = 0; i <= 12; i++) {
      groom.positions.push_back(p);
      p += 0.02f * glm::normalize(out + vec3(0.0f, 0.3f * std::sin(float(i)), -0.5f));
    }
    groom.offsets.push_back(int32_t(groom.positions.size()));
  }
  return groom;
}

mat4 swaying_head(const int frame)
{
  const float t = float(frame) / 24.0f;
  return glm::rotate(glm::translate(mat4(1.0f), vec3(0.05f * std::sin(5.0f * t), 0.0f, 0.0f)),
                     0.6f * std::sin(4.0f * t), vec3(0.0f, 0.0f, 1.0f));
}

class CountingPass : public SubstepPass {
 public:
  const char *name() const override { return "nothing"; }
  void apply(const SubstepState &state) override
  {
    calls++;
    points = state.positions_wo.size();
  }
  int calls = 0;
  int64_t points = 0;
};

/* Pushes every node but the roots 1 mm along +X (and gives it that velocity). */
class PushPass : public SubstepPass {
 public:
  const char *name() const override { return "push"; }
  void apply(const SubstepState &state) override
  {
    for (int64_t curve = 0; curve + 1 < state.curve_offsets.size(); curve++) {
      for (int32_t i = state.curve_offsets[curve] + 1; i < state.curve_offsets[curve + 1]; i++) {
        state.positions_wo[i].x += 1e-3f;
        state.velocities_wo[i].x += 1e-3f / state.h;
      }
    }
  }
};

}  // namespace

TEST(StrandsPasses, APassThatChangesNothingChangesNoBit)
{
  /* With a pass the solver advances substep by substep over all strands and takes the nodes
   * back into angles; a pass that leaves the nodes alone must give the bits of the fast path
   * without passes (which runs each strand's substeps in a row). */
  const Groom groom = wavy_groom(40);
  StrandParams params;
  params.substeps = 3;
  WindParams wind;
  wind.speed = 2.0f;
  std::vector<std::vector<vec3>> results;
  CountingPass pass;
  for (const bool with_pass : {false, true}) {
    StrandSolver solver(groom.offsets, groom.positions, mat4(1.0f), {}, params, wind);
    if (with_pass) {
      solver.add_pass(&pass);
    }
    for (int frame = 0; frame < 12; frame++) {
      solver.step(1.0f / 24.0f, swaying_head(frame));
    }
    results.emplace_back(solver.positions().begin(), solver.positions().end());
  }
  EXPECT_EQ(pass.calls, 12 * 3);
  EXPECT_EQ(pass.points, int64_t(groom.positions.size()));
  EXPECT_EQ(std::memcmp(results[0].data(), results[1].data(), results[0].size() * sizeof(vec3)),
            0);
}

TEST(StrandsPasses, CorrectionsComeBackWithLengthsKeptAndRootsOnTheHead)
{
  const Groom groom = wavy_groom(20);
  StrandParams params;
  params.substeps = 2;
  StrandSolver plain(groom.offsets, groom.positions, mat4(1.0f), {}, params);
  StrandSolver pushed(groom.offsets, groom.positions, mat4(1.0f), {}, params);
  PushPass push;
  CountingPass nothing;
  pushed.add_pass(&push);
  pushed.add_pass(&nothing);
  for (int frame = 0; frame < 24; frame++) {
    plain.step(1.0f / 24.0f, swaying_head(frame));
    pushed.step(1.0f / 24.0f, swaying_head(frame));
  }
  EXPECT_GE(pushed.pass_ms("push"), 0.0);
  EXPECT_EQ(pushed.pass_ms("no such pass"), 0.0);
  EXPECT_LE(max_relative_stretch(groom.offsets, groom.positions, pushed.positions()), 1e-5f);
  double shift = 0.0;
  for (int64_t curve = 0; curve < plain.curves_num(); curve++) {
    const IndexRange points = curve_points(plain.curve_offsets(), curve);
    /* Roots stay where the head carries them. */
    EXPECT_EQ(pushed.positions()[points.start], plain.positions()[points.start]);
    const int64_t tip = points.one_after_last() - 1;
    shift += double(pushed.positions()[tip].x - plain.positions()[tip].x);
  }
  EXPECT_GT(shift / double(plain.curves_num()), 0.002) << "the pushes did not come back";
  EXPECT_EQ(pushed.diverged_num(), 0);
  pushed.clear_passes();
  EXPECT_EQ(pushed.passes().size(), 0);
}

TEST(StrandsDivergence, StiffExplicitHingesAreReportedNotFedToTheColliders)
{
  /* Issue 11, row 2: explicit integrator, substeps = 1, k = 1e6 N·m/rad, with collision: the
   * hinges run away within a frame. The solver counts the strands, puts them back at rest,
   * and no NaN reaches the maps or the output. */
  const Groom groom = wavy_groom(16);
  const test::TestMesh sphere = test::uv_sphere(0.1f, 32, 16);
  const ColliderMesh mesh(sphere.vertices, sphere.triangles);
  CollisionParams collision;
  ColliderSet colliders;
  colliders.add(std::make_shared<Collider>(mesh, Span<int32_t>(), Span<int32_t>(), collision));
  StrandParams params;
  params.integrator = Integrator::Explicit;
  params.substeps = 1;
  params.k_theta = params.k_phi = 1e6f;
  StrandSolver solver(groom.offsets, groom.positions, mat4(1.0f), {}, params);
  solver.set_colliders(&colliders, collision);
  int64_t diverged = 0;
  for (int frame = 0; frame < 24; frame++) {
    solver.step(1.0f / 24.0f, swaying_head(frame));
    diverged += solver.diverged_num();
    ASSERT_EQ(count_nonfinite(solver.positions()), 0) << "frame " << frame;
    ASSERT_EQ(count_nonfinite(solver.velocities()), 0) << "frame " << frame;
  }
  EXPECT_GT(diverged, 0);
  /* The same settings, implicit: nothing diverges. */
  params.integrator = Integrator::Implicit;
  solver.set_params(params);
  solver.reset();
  for (int frame = 0; frame < 24; frame++) {
    solver.step(1.0f / 24.0f, swaying_head(frame));
    EXPECT_EQ(solver.diverged_num(), 0);
  }
}
