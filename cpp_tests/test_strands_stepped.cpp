/* The strand solver stepping a subset of its strands (StrandSolver::set_stepped), and a
 * strand's state written from outside and placed (set_curve_state): what the level of detail
 * (lod/lod_solver_ward2003.hh) needs to step only its active skeletons. */
#include <gtest/gtest.h>

#include <cmath>

#include "collision/hair_hair_ward2003.hh"
#include "groom/groom.hh"
#include "lod_scenes.hh"
#include "strands/strand_solver.hh"

using namespace hairdyn;
using namespace hairdyn::test;

namespace {

constexpr float frame_dt = 1.0f / 24.0f;

/* The head turning about its vertical axis (the head sphere stays where it is). */
mat4 turning_head(const int frame)
{
  const float angle = 0.6f * std::sin(2.0f * float(M_PI) * float(frame) / 24.0f);
  return glm::rotate(mat4(1.0f), angle, vec3(0.0f, 0.0f, 1.0f));
}

struct Twin {
  CapGroom groom{40, 10};
  std::shared_ptr<ColliderSet> colliders = head_colliders();
  StrandSolver solver;

  explicit Twin(const StrandModel model)
      : solver(groom.offsets, groom.positions, mat4(1.0f), groom.normals, params(model),
               wind())
  {
    solver.set_colliders(colliders.get(), CollisionParams());
  }
  static StrandParams params(const StrandModel model)
  {
    StrandParams p;
    p.model = model;
    return p;
  }
  static WindParams wind()
  {
    WindParams w;
    w.speed = 2.0f;
    w.turbulence = 0.5f;
    return w;
  }
  Span<vec3> strand(const Span<vec3> values, const int64_t curve) const
  {
    const IndexRange points = curve_points(Span<int32_t>(groom.offsets), curve);
    return values.slice(points.start, points.size);
  }
};

float max_change(const Span<vec3> a, const Span<vec3> b)
{
  float result = 0.0f;
  for (int64_t i = 0; i < a.size(); i++) {
    result = std::max(result, glm::length(a[i] - b[i]));
  }
  return result;
}

}  // namespace

TEST(StrandsStepped, AMaskOfEveryStrandGivesTheSameBits)
{
  for (const StrandModel model : {StrandModel::Kurihara1993, StrandModel::Articulated}) {
    Twin plain(model), masked(model);
    const std::vector<uint8_t> all(size_t(masked.groom.strands_num()), 1);
    masked.solver.set_stepped(all);
    for (int frame = 1; frame <= 12; frame++) {
      plain.solver.step(frame_dt, turning_head(frame));
      masked.solver.step(frame_dt, turning_head(frame));
    }
    EXPECT_EQ(masked.solver.stepped_num(), masked.groom.strands_num());
    EXPECT_EQ(plain.solver.stepped_num(), plain.groom.strands_num());
    EXPECT_EQ(max_change(plain.solver.positions(), masked.solver.positions()), 0.0f);
    EXPECT_EQ(max_change(plain.solver.velocities(), masked.solver.velocities()), 0.0f);
  }
}

TEST(StrandsStepped, HeldStrandsAreNotSteppedAndSteppedOnesAreUnchanged)
{
  /* Every third strand stepped: those follow the full simulation bit for bit (strands are
   * independent without passes); the others keep their state and their nodes. */
  for (const StrandModel model : {StrandModel::Kurihara1993, StrandModel::Articulated}) {
    Twin plain(model), masked(model);
    const int64_t curves = masked.groom.strands_num();
    std::vector<uint8_t> mask(size_t(curves), 0);
    int64_t stepped = 0;
    for (int64_t c = 0; c < curves; c += 3) {
      mask[size_t(c)] = 1;
      stepped++;
    }
    masked.solver.set_stepped(mask);
    const std::vector<vec3> held_positions(masked.solver.positions().begin(),
                                           masked.solver.positions().end());
    for (int frame = 1; frame <= 12; frame++) {
      plain.solver.step(frame_dt, turning_head(frame));
      masked.solver.step(frame_dt, turning_head(frame));
      EXPECT_EQ(masked.solver.stepped_num(), stepped);
    }
    for (int64_t c = 0; c < curves; c++) {
      if (mask[size_t(c)]) {
        EXPECT_EQ(max_change(masked.strand(plain.solver.positions(), c),
                             masked.strand(masked.solver.positions(), c)),
                  0.0f);
      }
      else {
        EXPECT_EQ(max_change(masked.strand(held_positions, c),
                             masked.strand(masked.solver.positions(), c)),
                  0.0f);
        const IndexRange points = curve_points(Span<int32_t>(masked.groom.offsets), c);
        for (int64_t i = points.start + 1; i < points.one_after_last(); i++) {
          EXPECT_EQ(masked.solver.angles()[i], vec2(0.0f));
          EXPECT_EQ(masked.solver.angular_velocities()[i], vec2(0.0f));
        }
      }
    }
  }
}

TEST(StrandsStepped, AStateTakenAfterALongHoldResumesWithoutAJump)
{
  /* One solver steps everything; the other holds strand 0 for a second while the head turns
   * (its nodes go stale), then takes the first one's state for it. Placed, it is where the
   * dynamics put the same state (to rounding), its velocities are the ones the rates give,
   * and it then moves on as the other one does. */
  for (const StrandModel model : {StrandModel::Kurihara1993, StrandModel::Articulated}) {
    Twin reference(model), held(model);
    const int64_t curves = held.groom.strands_num();
    std::vector<uint8_t> mask(size_t(curves), 1);
    mask[0] = 0;
    held.solver.set_stepped(mask);
    int frame = 1;
    for (; frame <= 30; frame++) {
      reference.solver.step(frame_dt, turning_head(frame));
      held.solver.step(frame_dt, turning_head(frame));
    }
    EXPECT_EQ(held.solver.stepped_num(), curves - 1);
    const float stale = max_change(held.strand(reference.solver.positions(), 0),
                                   held.strand(held.solver.positions(), 0));
    ASSERT_GT(stale, 0.01f); /* The head did move the held strand's place. */
    const IndexRange points = curve_points(Span<int32_t>(held.groom.offsets), 0);
    held.solver.set_curve_state(0, reference.solver.angles().slice(points.start, points.size),
                                reference.solver.angular_velocities().slice(points.start,
                                                                            points.size));
    EXPECT_LT(max_change(held.strand(reference.solver.positions(), 0),
                         held.strand(held.solver.positions(), 0)),
              1e-5f);
    /* The reference's velocities are the mean over its last substep, the placed ones the
     * instant's: close, not equal. */
    float speed = 0.0f;
    for (const vec3 &v : held.strand(reference.solver.velocities(), 0)) {
      speed = std::max(speed, glm::length(v));
    }
    ASSERT_GT(speed, 0.05f);
    EXPECT_LT(max_change(held.strand(reference.solver.velocities(), 0),
                         held.strand(held.solver.velocities(), 0)),
              0.1f * speed);
    held.solver.set_stepped({});
    float drift = 0.0f, motion = 0.0f;
    for (const int end = frame + 6; frame < end; frame++) {
      const std::vector<vec3> before(reference.solver.positions().begin(),
                                     reference.solver.positions().end());
      reference.solver.step(frame_dt, turning_head(frame));
      held.solver.step(frame_dt, turning_head(frame));
      motion = std::max(motion, max_change(held.strand(reference.solver.positions(), 0),
                                           held.strand(before, 0)));
      drift = std::max(drift, max_change(held.strand(reference.solver.positions(), 0),
                                         held.strand(held.solver.positions(), 0)));
    }
    EXPECT_GT(motion, 1e-3f);
    EXPECT_LT(drift, 0.02f * motion) << "model " << int(model);
  }
}

/* The substep passes see only the stepped strands (and of those only the ones `in_passes`
 * marks): with hair–hair collision on, the even strands of a groom, stepped while the odd ones
 * are held, take the same bits as a solver of the even strands alone; narrowed to every other
 * even strand, the pass sees those only. */
TEST(StrandsStepped, PassesSeeOnlyTheirStrands)
{
  const CapGroom groom(40, 10);
  SweptSphereParams params;
  params.hair_hair = true;
  params.thickness = 0.004f; /* thick enough that the strands meet */
  std::vector<uint8_t> even(40, 0), every_fourth(40, 0);
  CapGroom alone(0, 10);
  for (int64_t s = 0; s < 40; s += 2) {
    even[size_t(s)] = 1;
    every_fourth[size_t(s)] = s % 4 == 0;
    const IndexRange points = curve_points(Span<int32_t>(groom.offsets), s);
    alone.positions.insert(alone.positions.end(), groom.positions.begin() + points.start,
                           groom.positions.begin() + points.one_after_last());
    alone.offsets.push_back(int32_t(alone.positions.size()));
    alone.normals.push_back(groom.normals[size_t(s)]);
  }
  const auto colliders = head_colliders();
  StrandSolver masked(groom.offsets, groom.positions, mat4(1.0f), groom.normals, StrandParams());
  StrandSolver single(alone.offsets, alone.positions, mat4(1.0f), alone.normals, StrandParams());
  HairHairPass masked_pass(params), single_pass(params);
  for (StrandSolver *solver : {&masked, &single}) {
    solver->set_colliders(colliders.get(), CollisionParams());
  }
  masked.add_pass(&masked_pass);
  single.add_pass(&single_pass);
  masked.set_stepped(even);
  int64_t pairs = 0;
  for (int frame = 0; frame < 24; frame++) {
    masked.step(frame_dt, turning_head(frame));
    single.step(frame_dt, turning_head(frame));
    pairs += single_pass.stats().pairs_num;
    ASSERT_EQ(masked_pass.stats().pairs_num, single_pass.stats().pairs_num) << "frame " << frame;
    single_pass.reset_stats();
    masked_pass.reset_stats();
  }
  EXPECT_GT(pairs, 0) << "the strands must meet";
  for (int64_t s = 0; s < 20; s++) {
    const IndexRange mine = curve_points(Span<int32_t>(groom.offsets), 2 * s);
    const IndexRange theirs = curve_points(Span<int32_t>(alone.offsets), s);
    for (int64_t i = 0; i < mine.size; i++) {
      ASSERT_EQ(masked.positions()[mine.start + i], single.positions()[theirs.start + i])
          << "strand " << 2 * s << ", point " << i;
    }
  }
  /* What a pass sees: every stepped strand, or those in_passes marks. */
  struct SeenPass : public SubstepPass {
    const char *name() const override { return "seen"; }
    void apply(const SubstepState &state) override { curves = state.curve_offsets.size() - 1; }
    int64_t curves = 0;
  } seen;
  masked.clear_passes();
  masked.add_pass(&seen);
  masked.step(frame_dt, turning_head(24));
  EXPECT_EQ(seen.curves, 20);
  masked.set_stepped(even, every_fourth);
  masked.step(frame_dt, turning_head(25));
  EXPECT_EQ(seen.curves, 10);
  masked.set_stepped({});
  masked.step(frame_dt, turning_head(26));
  EXPECT_EQ(seen.curves, 40);
}
