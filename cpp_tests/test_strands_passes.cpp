/* The strand solver's substep seam (strands/substep_pass.hh) and its divergence report: passes
 * run after every substep, their corrections come back into the angles with lengths kept and
 * roots carried by the head, and a diverging strand never hands out NaN. */
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <utility>

#include "collision/collider.hh"
#include "collision_test_shapes.hh"
#include "groom/groom.hh"
#include "groom/metrics.hh"
#include "strand_scenes.hh"
#include "strands/strand_solver.hh"

using namespace hairdyn;

namespace {

using strand_scenes::Groom;

/* 12 segments of 2 cm; a sway (yaw at 4 rad/s, sliding at 5 rad/s). */
Groom wavy_groom(const int strands_num)
{
  return strand_scenes::wavy_groom(strands_num, 12, 0.02f);
}

mat4 swaying_head(const int frame)
{
  return strand_scenes::swaying_head(frame, 4.0f, 5.0f);
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

/* Once, at the first substep it sees: adds `delta_v` to every node but the roots (and moves
 * them by h delta_v, as the volume and collision passes do). */
class KickPass : public SubstepPass {
 public:
  explicit KickPass(const vec3 &delta_v) : delta_v_(delta_v) {}
  const char *name() const override { return "kick"; }
  void apply(const SubstepState &state) override
  {
    if (done_) {
      return;
    }
    done_ = true;
    for (int64_t curve = 0; curve + 1 < state.curve_offsets.size(); curve++) {
      for (int32_t i = state.curve_offsets[curve] + 1; i < state.curve_offsets[curve + 1]; i++) {
        state.velocities_wo[i] += delta_v_;
        state.positions_wo[i] += state.h * delta_v_;
      }
    }
  }

 private:
  vec3 delta_v_;
  bool done_ = false;
};

/* At its first substep, makes strand 0's tip velocity not a number (the strand diverges);
 * at every substep, moves every node but the roots 1 cm along +X, as a pass may. */
class PoisonThenShovePass : public SubstepPass {
 public:
  const char *name() const override { return "poison"; }
  void apply(const SubstepState &state) override
  {
    if (calls++ == 0) {
      state.velocities_wo[state.curve_offsets[1] - 1].x = std::nanf("");
    }
    for (int64_t curve = 0; curve + 1 < state.curve_offsets.size(); curve++) {
      for (int32_t i = state.curve_offsets[curve] + 1; i < state.curve_offsets[curve + 1]; i++) {
        state.positions_wo[i].x += 0.01f;
      }
    }
  }
  int calls = 0;
};

}  // namespace

/* A strand that diverged in a substep stays on its rest shape, carried by the head, through
 * the frame's later substeps: the passes' moves of its nodes don't stretch it. */
TEST(StrandsPasses, ADivergedStrandKeepsItsRestShapeWhateverThePassesDo)
{
  const Groom groom = wavy_groom(2);
  StrandParams params;
  params.substeps = 4;
  for (const StrandModel model : { StrandModel::Articulated, StrandModel::Kurihara1993 }) {
    SCOPED_TRACE(model == StrandModel::Articulated ? "articulated" : "kurihara1993");
    params.model = model;
    StrandSolver solver(groom.offsets, groom.positions, mat4(1.0f), {}, params);
    PoisonThenShovePass pass;
    solver.add_pass(&pass);
    const mat4 head = swaying_head(1);
    solver.step(1.0f / 24.0f, head);
    EXPECT_EQ(solver.diverged_num(), 1);
    EXPECT_EQ(pass.calls, 4);
    const Span<vec3> positions = solver.positions();
    for (int32_t i = groom.offsets[0]; i < groom.offsets[1]; i++) {
      const vec3 rest = transform_point(head, groom.positions[size_t(i)]);
      EXPECT_LT(glm::length(positions[i] - rest), 1e-5f) << "node " << i;
    }
    EXPECT_LT(max_relative_stretch(groom.offsets, groom.positions, solver.positions()), 1e-5f);
  }
}

namespace {

/* A straight strand of 10 segments of 2 cm hanging along −Z, limp, with no forces at all. */
std::unique_ptr<StrandSolver> forceless_strand(const StrandModel model)
{
  std::vector<int32_t> offsets{ 0, 11 };
  std::vector<vec3> positions;
  for (int i = 0; i <= 10; i++) {
    positions.push_back(vec3(0.0f, 0.0f, -0.02f * float(i)));
  }
  StrandParams params;
  params.model = model;
  params.youngs_modulus = 1e3f; /* limp */
  params.bending_damping = 0.0f;
  params.k_theta = params.k_phi = 1e-12f;
  params.damping = 0.0f;
  params.gravity = vec3(0.0f);
  params.air_drag = 0.0f;
  params.form_drag = 0.0f;
  params.substeps = 1;
  return std::make_unique<StrandSolver>(offsets, positions, mat4(1.0f), Span<vec3>(), params);
}

/* The nodes' velocities over a short step with nothing acting (finite differences). */
std::vector<vec3> velocities_over_short_step(StrandSolver &solver)
{
  const std::vector<vec3> before(solver.positions().begin(), solver.positions().end());
  const float dt = 1e-4f;
  solver.step(dt, mat4(1.0f));
  std::vector<vec3> velocities;
  for (size_t i = 0; i < before.size(); i++) {
    velocities.push_back((solver.positions()[i] - before[i]) / dt);
  }
  return velocities;
}

/* Once, at the first substep it sees: halves every node's velocity (a braking correction). */
class HalvePass : public SubstepPass {
 public:
  const char *name() const override { return "halve"; }
  void apply(const SubstepState &state) override
  {
    if (!std::exchange(done_, true)) {
      for (vec3 &v : state.velocities_wo) {
        v *= 0.5f;
      }
    }
  }

 private:
  bool done_ = false;
};

}  // namespace

TEST(StrandsPasses, AVelocityCorrectionComesBackAsThatVelocity)
{
  /* A pass gives every node of a straight, limp strand at rest the same velocity. The hinge
   * rates are relative to the parent segment, which carries the rest of the strand: the
   * first hinge alone turns the strand, the others must turn back so that each node moves at
   * the velocity the pass gave, not the tip n times as fast. Measured over a short step with
   * no forces. The articulated model only: Kurihara 1993's hinges are only ever slowed by a
   * pass (next test). Also with the first hinge turned past its chart's pole (θ = 2.6 rad,
   * cos θ < 0: a limp strand blown back over itself), where Δφ̇ = (Δv · e_φ) / (d cos θ) is
   * negative for a positive push along e_φ; a hinge read as "at the pole" there lost the
   * push's e_φ part. */
  for (const float theta : {0.0f, 2.6f}) {
    const std::unique_ptr<StrandSolver> solver = forceless_strand(StrandModel::Articulated);
    std::vector<vec2> angles(11, vec2(0.0f)), rates(11, vec2(0.0f));
    angles[1] = vec2(theta, 0.7f);
    solver->set_curve_state(0, angles, rates);
    /* Across the (straight) strand: no rate can give a change along it. */
    const vec3 along = glm::normalize(solver->positions()[10] - solver->positions()[0]);
    const vec3 push(0.1f, 0.05f, 0.0f);
    const vec3 delta_v = push - glm::dot(push, along) * along;
    KickPass kick(delta_v);
    solver->add_pass(&kick);
    solver->step(1e-3f, mat4(1.0f));
    const std::vector<vec3> velocities = velocities_over_short_step(*solver);
    for (int i = 1; i <= 10; i++) {
      EXPECT_LT(glm::length(velocities[size_t(i)] - delta_v), 0.03f * glm::length(delta_v))
          << "θ = " << theta << ", node " << i << " moves at (" << velocities[size_t(i)].x
          << ", " << velocities[size_t(i)].y << ", " << velocities[size_t(i)].z << ")";
    }
  }
}

TEST(StrandsPasses, KuriharaHingesAreOnlySlowedByAPass)
{
  /* Kurihara 1993's model: a braking correction comes back whole, and a kick of a strand at
   * rest moves its nodes (positions come back whole) but sets none of its hinges turning. */
  const int64_t points_num = 11;
  std::vector<vec2> angles(size_t(points_num), vec2(0.0f));
  std::vector<vec2> rates(size_t(points_num), vec2(3.0f, -2.0f)); /* rad/s, every hinge */
  /* The strand curls at these rates; halving every node's velocity halves them. */
  const std::unique_ptr<StrandSolver> free = forceless_strand(StrandModel::Kurihara1993);
  const std::unique_ptr<StrandSolver> braked = forceless_strand(StrandModel::Kurihara1993);
  free->set_curve_state(0, angles, rates);
  braked->set_curve_state(0, angles, rates);
  HalvePass halve;
  braked->add_pass(&halve);
  braked->step(1e-4f, mat4(1.0f));
  free->step(1e-4f, mat4(1.0f));
  const std::vector<vec3> free_velocities = velocities_over_short_step(*free);
  const std::vector<vec3> braked_velocities = velocities_over_short_step(*braked);
  for (int i = 1; i < points_num; i++) {
    const vec3 expected = 0.5f * free_velocities[size_t(i)];
    EXPECT_LT(glm::length(braked_velocities[size_t(i)] - expected), 0.03f * glm::length(expected))
        << "node " << i;
    EXPECT_NEAR(braked->angular_velocities()[i].x, 1.5f, 1e-3f) << "hinge " << i;
    EXPECT_NEAR(braked->angular_velocities()[i].y, -1.0f, 1e-3f) << "hinge " << i;
  }

  const vec3 delta_v(0.1f, 0.05f, 0.0f);
  const std::unique_ptr<StrandSolver> resting = forceless_strand(StrandModel::Kurihara1993);
  const std::vector<vec3> rest(resting->positions().begin(), resting->positions().end());
  KickPass kick(delta_v);
  resting->add_pass(&kick);
  const float h = 1e-3f;
  resting->step(h, mat4(1.0f));
  for (int i = 1; i < points_num; i++) {
    EXPECT_EQ(resting->angular_velocities()[i], vec2(0.0f)) << "hinge " << i;
  }
  /* The kick's move, h Δv, kept with the segment lengths: the first segment turns toward it. */
  EXPECT_GT(glm::dot(resting->positions()[1] - rest[1], delta_v),
            0.5f * h * glm::dot(delta_v, delta_v));
}

TEST(StrandsPasses, APushOfAFewMetresPerSecondDoesNotRunAway)
{
  /* A collision or volume pass may move a node by centimetres in one substep (3 m/s over
   * 1/96 s is 3 cm, on segments of 1.25 cm): the first segment of an articulated strand then
   * turns by more than a radian per substep, and its explicit velocity products (centripetal,
   * gyroscopic) would feed on a direction it has long left. The strand takes shorter steps
   * while it turns fast, and nothing runs away; the same push on Kurihara's model. */
  std::vector<int32_t> offsets{ 0 };
  std::vector<vec3> positions;
  for (int s = 0; s < 20; s++) {
    for (int i = 0; i <= 12; i++) {
      positions.push_back(vec3(0.01f * float(s), 0.0f, -0.0125f * float(i)));
    }
    offsets.push_back(int32_t(positions.size()));
  }
  for (const StrandModel model : { StrandModel::Articulated, StrandModel::Kurihara1993 }) {
    StrandParams params;
    params.model = model;
    StrandSolver solver(offsets, positions, mat4(1.0f), {}, params);
    KickPass kick(vec3(3.0f, 0.0f, 0.0f));
    solver.add_pass(&kick);
    for (int frame = 0; frame < 24; frame++) {
      solver.step(1.0f / 24.0f, mat4(1.0f));
      ASSERT_EQ(solver.diverged_num(), 0) << "model " << int(model) << ", frame " << frame;
    }
    EXPECT_LE(max_relative_stretch(offsets, positions, solver.positions()), 1e-5f)
        << "model " << int(model);
  }
}

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
  params.model = StrandModel::Kurihara1993;
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

TEST(StrandsFarFromOrigin, HeadRelativeCoordinatesDoNotDependOnWhereTheCharacterStands)
{
  /* Issue 11, row 5: a head at x = 1e8 m. In world single precision the groom cannot even be
   * written down (a float steps by 8 m there). Given relative to origin_wo (the head's rest
   * position, in double), the simulation is the one at the world origin, bit for bit, and
   * origin_wo + positions is the world answer to double precision. */
  const Groom groom = wavy_groom(12);
  StrandParams params;
  WindParams wind;
  wind.speed = 3.0f;
  std::vector<std::vector<vec3>> results;
  for (const double x : {0.0, 1e8}) {
    StrandSolver solver(groom.offsets, groom.positions, mat4(1.0f), {}, params, wind,
                        glm::dvec3(x, -2.5e7, 0.0));
    EXPECT_EQ(solver.origin().x, x);
    for (int frame = 0; frame < 24; frame++) {
      solver.step(1.0f / 24.0f, swaying_head(frame));
    }
    results.emplace_back(solver.positions().begin(), solver.positions().end());
  }
  EXPECT_EQ(std::memcmp(results[0].data(), results[1].data(), results[0].size() * sizeof(vec3)),
            0);
  EXPECT_LE(max_relative_stretch(groom.offsets, groom.positions, results[1]), 1e-5f);
  /* What world single precision would have done: the groom's points collapse. */
  const float far = 1e8f;
  EXPECT_EQ(far + groom.positions[1].x, far + groom.positions[0].x);
}
