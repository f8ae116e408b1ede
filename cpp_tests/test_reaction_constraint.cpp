/* Reaction constraint (Kurihara 1993, eq. 12–15), friction, and the hard projection. */
#include <gtest/gtest.h>

#include <random>

#include "collision/reaction_constraint_kurihara1993.hh"
#include "collision_test_shapes.hh"

using namespace hairdyn;
using namespace hairdyn::test;

namespace {

Contact contact_at(const vec3 &p, const vec3 &normal, const float depth)
{
  return {depth, normal, p + depth * normal};
}

ColliderSet sphere_set(const float radius)
{
  const TestMesh m = uv_sphere(radius, 96, 48);
  CollisionParams params;
  params.map_kind = MapKind::Sphere;
  params.azimuth_num = 96;
  params.height_num = 48;
  ColliderSet set;
  set.add(std::make_shared<Collider>(ColliderMesh(m.vertices, m.triangles), Span<int32_t>(),
                                     Span<int32_t>(), params));
  return set;
}

}  // namespace

TEST(ReactionConstraint, DefaultDampingIsThePapersCriticalValue)
{
  CollisionParams params;
  params.stiffness = 800.0f;
  EXPECT_FLOAT_EQ(params.damping_or_critical(), std::sqrt(2.0f * 800.0f));
  EXPECT_FLOAT_EQ(ReactionConstants::from(params, 0.01f).damping, 40.0f);
  params.damping = 3.0f;
  EXPECT_FLOAT_EQ(ReactionConstants::from(params, 0.01f).damping, 3.0f);
}

/* At the surface (depth 0) and at rest along N, the response removes exactly the inward
 * normal component and keeps the tangential part untouched. */
TEST(ReactionConstraint, RemovesOnlyTheInwardNormalComponent)
{
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> c(-1.0f, 1.0f);
  const ReactionConstants constants{500.0f, std::sqrt(1000.0f), 0.0f, 0.01f};
  for (int i = 0; i < 1000; i++) {
    const vec3 n = glm::normalize(vec3(c(rng), c(rng), c(rng)));
    vec3 force(c(rng), c(rng), c(rng));
    if (glm::dot(force, n) > -0.05f) {
      force -= (glm::dot(force, n) + 0.5f) * n; /* Make it push inwards. */
    }
    vec3 velocity(c(rng), c(rng), c(rng));
    velocity -= glm::dot(velocity, n) * n; /* Sliding, no normal motion. */
    const vec3 out = reaction_constraint_force(force, velocity, contact_at(vec3(0.0f), n, 0.0f), constants);
    const vec3 tangential = force - glm::dot(force, n) * n;
    /* V·N is zero to rounding (1e-7), which stopping it within the step divides by h. */
    ASSERT_NEAR(glm::length(out - tangential), 0.0f, 1e-4f);
  }
}

/* In depth and moving: eq. 15 with eq. 13's spring and damper taken at the end of the step,
 * F_out = F - (F·N) N + (k d - (c + h k) V·N) / (1 + h c + h² k) N, which is eq. 15 itself as
 * h → 0. */
TEST(ReactionConstraint, MatchesEquation15)
{
  const vec3 n = glm::normalize(vec3(1, 2, 2));
  const vec3 force(0.3f, -4.0f, 1.0f), velocity(0.5f, -0.7f, 0.2f);
  const float depth = 0.02f;
  for (const float h : {0.01f, 1e-6f}) {
    const ReactionConstants constants{400.0f, std::sqrt(800.0f), 0.0f, h};
    const float k = constants.stiffness, c = constants.damping;
    const vec3 out =
        reaction_constraint_force(force, velocity, contact_at(vec3(1.0f), n, depth), constants);
    const vec3 expected = force - glm::dot(force, n) * n +
                          (k * depth - (c + h * k) * glm::dot(velocity, n)) /
                              (1.0f + h * c + h * h * k) * n;
    EXPECT_NEAR(glm::length(out - expected), 0.0f, 1e-5f) << "h " << h;
    /* The spring pushes outwards, the damper opposes the inward velocity. */
    EXPECT_GT(glm::dot(out, n), 0.0f);
    if (h < 1e-3f) { /* eq. 15 as the paper writes it */
      const vec3 paper = force - glm::dot(force, n) * n +
                         (k * depth - c * glm::dot(velocity, n)) * n;
      EXPECT_NEAR(glm::length(out - paper), 0.0f, 1e-3f);
    }
  }
}

/* A node dropped onto a body at 96 steps a second, where the default constants give
 * h² k = 1.1 and h c = 1.5, and at a 30 times stiffer constraint: with the spring and damper
 * taken at the step's start it overshot, out of the surface and back in every few steps, the
 * more the stiffer (a hair tip lying on the head chattered by millimetres, by centimetres at
 * k = 3·10⁵). Taken at the end, it stays within 2 g h² of the surface (2 mm: pushed onto the
 * surface exactly, out of contact, it falls back in by a step's free fall); allowed to rest
 * within rest_depth (the strands' projection tolerance, here 1 mm), it comes to rest there:
 * over the last 100 steps it moves by less than a micrometre a step. */
TEST(ReactionConstraint, ANodeOnABodyComesToRestAtCoarseSteps)
{
  const ColliderSet set = sphere_set(1.0f);
  for (const float rest_depth : {0.0f, 1e-3f}) {
    for (const float stiffness : {1.0e4f, 3.0e5f}) {
      CollisionParams params;
      params.stiffness = stiffness;
      params.friction = 0.5f; /* on top of the sphere, an unstable equilibrium */
      const ReactionConstants constants = ReactionConstants::from(params, 1.0f / 96.0f,
                                                                  rest_depth);
      ASSERT_GT(constants.dt * constants.dt * constants.stiffness, 1.0f);
      std::vector<vec3> x{{0.0f, 1.01f, 0.0f}}, v{{0.0f, 0.0f, 0.0f}}, f(1);
      const std::vector<vec3> gravity{{0.0f, -9.81f, 0.0f}};
      float farthest = 0.0f; /* from the surface, over the last 100 steps */
      float largest_move = 0.0f;
      for (int step = 0; step < 300; step++) {
        apply_reaction_constraint(set, x, v, gravity, constants, f);
        v[0] += f[0] * constants.dt;
        x[0] += v[0] * constants.dt;
        if (step >= 200) {
          farthest = std::max(farthest, std::abs(glm::length(x[0]) - 1.0f));
          largest_move = std::max(largest_move, glm::length(v[0]) * constants.dt);
        }
      }
      SCOPED_TRACE(testing::Message() << "k " << stiffness << ", rest depth " << rest_depth);
      EXPECT_LT(farthest, std::max(rest_depth, 2.0f * 9.81f * constants.dt * constants.dt));
      if (rest_depth > 0.0f) {
        EXPECT_LT(largest_move, 1e-6f);
      }
    }
  }
}

/* Inelastic: a force that lifts the node off the surface is left alone, whatever the depth
 * and velocity. */
TEST(ReactionConstraint, LiftingForceIsUntouched)
{
  const ReactionConstants constants{400.0f, 28.0f, 0.5f, 0.01f};
  const vec3 n(0, 1, 0);
  const vec3 force(0.4f, 2.0f, -0.3f), velocity(1.0f, 0.5f, 0.0f);
  const vec3 out = reaction_constraint_force(force, velocity, contact_at(vec3(0.0f), n, 0.1f), constants);
  EXPECT_EQ(out, force);
}

TEST(ReactionConstraint, FrictionOpposesSlidingAndNeverReversesIt)
{
  const vec3 n(0, 1, 0);
  const vec3 force(0.0f, -10.0f, 0.0f); /* Gravity pressing onto the surface. */
  const Contact contact = contact_at(vec3(0.0f), n, 0.0f);
  /* Fast sliding along x: kinetic friction μ × normal load (10), against the motion. */
  const ReactionConstants slippery{1000.0f, 0.0f, 0.0f, 0.01f};
  const ReactionConstants rough{1000.0f, 0.0f, 0.3f, 0.01f};
  const vec3 fast(5.0f, 0.0f, 0.0f);
  const vec3 without = reaction_constraint_force(force, fast, contact, slippery);
  const vec3 with = reaction_constraint_force(force, fast, contact, rough);
  EXPECT_NEAR(without.x, 0.0f, 1e-6f);
  EXPECT_NEAR(with.x, -0.3f * 10.0f, 1e-5f);
  EXPECT_NEAR(with.y, without.y, 1e-6f);
  /* Slow sliding: friction stops it within the step, no more. */
  const vec3 slow(0.01f, 0.0f, 0.0f);
  const vec3 stopped = reaction_constraint_force(force, slow, contact, rough);
  EXPECT_NEAR(slow.x + stopped.x * rough.dt, 0.0f, 1e-6f);
  /* Static: a small tangential push on a node at rest is cancelled; a large one is reduced by μ N. */
  const vec3 small_push = reaction_constraint_force(force + vec3(2.0f, 0, 0), vec3(0.0f), contact, rough);
  EXPECT_NEAR(small_push.x, 0.0f, 1e-5f);
  const vec3 big_push = reaction_constraint_force(force + vec3(20.0f, 0, 0), vec3(0.0f), contact, rough);
  EXPECT_NEAR(big_push.x, 20.0f - 3.0f, 1e-4f);
}

TEST(ReactionConstraint, KernelOverSpansTouchesOnlyNodesInContact)
{
  const ColliderSet set = sphere_set(1.0f);
  const std::vector<vec3> positions{{0.0f, 0.98f, 0.0f}, {0.0f, 1.5f, 0.0f}, {0.0f, 0.5f, 0.0f}};
  const std::vector<vec3> velocities(3, vec3(0.0f, -1.0f, 0.0f));
  const std::vector<vec3> forces(3, vec3(0.1f, -9.81f, 0.0f));
  std::vector<vec3> out(3);
  const ReactionConstants constants{1000.0f, std::sqrt(2000.0f), 0.0f, 0.01f};
  EXPECT_EQ(apply_reaction_constraint(set, positions, velocities, forces, constants, out), 2);
  EXPECT_EQ(out[1], forces[1]);
  EXPECT_GT(out[0].y, 0.0f);
  Contact c;
  ASSERT_TRUE(set.find_contact(positions[0], c));
  const vec3 n = c.normal_wo;
  EXPECT_NEAR(glm::length((out[0] - glm::dot(out[0], n) * n) - (forces[0] - glm::dot(forces[0], n) * n)), 0.0f, 1e-4f);
  EXPECT_GT(out[2].y, out[0].y); /* Deeper: a stronger push. */
}

/* A node falling on a sphere under gravity comes to rest on top of it, k·d = g deep (a little
 * friction keeps it from sliding off the top, an unstable equilibrium). */
TEST(ReactionConstraint, NodeComesToRestOnTheSurface)
{
  const ColliderSet set = sphere_set(1.0f);
  /* Allowed to rest 1 mm deep, as the strands allow their projection tolerance. */
  const ReactionConstants constants{1.0e4f, std::sqrt(2.0e4f), 0.5f, 1e-3f, 1e-3f};
  std::vector<vec3> x{{0.0f, 1.2f, 0.0f}}, v{{0.0f, 0.0f, 0.0f}}, f(1);
  const std::vector<vec3> gravity{{0.0f, -9.81f, 0.0f}};
  float lowest = 2.0f;
  for (int step = 0; step < 3000; step++) {
    apply_reaction_constraint(set, x, v, gravity, constants, f);
    v[0] += f[0] * constants.dt;
    x[0] += v[0] * constants.dt;
    lowest = std::min(lowest, x[0].y);
  }
  EXPECT_NEAR(x[0].y, 1.0f - 9.81f / 1.0e4f, 2e-3f);
  EXPECT_LT(std::abs(x[0].x) + std::abs(x[0].z), 1e-3f);
  EXPECT_LT(std::abs(v[0].y), 1e-2f);
  EXPECT_GT(lowest, 0.95f); /* It never sank far into the sphere. */
}

/* Ward & Lin §5.5: nodes deeper than the tolerance end on the surface with no inward velocity;
 * shallower nodes and nodes outside are left alone. */
TEST(ReactionConstraint, ProjectionGuaranteesNoDeepNode)
{
  const ColliderSet set = sphere_set(1.0f);
  std::vector<vec3> x{{0.0f, 0.5f, 0.0f}, {0.0f, 0.9995f, 0.0f}, {0.0f, 1.5f, 0.0f}, {0.3f, -0.2f, 0.1f}};
  std::vector<vec3> v{{1.0f, -2.0f, 0.0f}, {0.0f, -1.0f, 0.0f}, {0.0f, -1.0f, 0.0f}, {0.0f, 0.0f, 0.0f}};
  const std::vector<vec3> x0 = x, v0 = v;
  const float tolerance = 0.002f;
  Contact before;
  ASSERT_TRUE(set.find_contact(x[0], before));
  EXPECT_EQ(project_out_of_colliders(set, tolerance, x, v), 2);
  EXPECT_NEAR(x[0].y, 1.0f, 2e-3f);
  EXPECT_EQ(x[0], before.surface_point_wo);
  /* Inward velocity removed, tangential velocity kept (N is the facet normal at the pole). */
  const vec3 n = before.normal_wo;
  EXPECT_NEAR(glm::dot(v[0], n), 0.0f, 1e-5f);
  EXPECT_NEAR(glm::length((v[0] - glm::dot(v[0], n) * n) - (v0[0] - glm::dot(v0[0], n) * n)), 0.0f, 1e-5f);
  EXPECT_NEAR(v[0].x, 1.0f, 0.1f);
  EXPECT_EQ(x[1], x0[1]);
  EXPECT_EQ(v[1], v0[1]);
  EXPECT_EQ(x[2], x0[2]);
  EXPECT_NEAR(glm::length(x[3]), 1.0f, 2e-3f);
  /* After projection nothing is deeper than the tolerance. */
  for (const vec3 &p : x) {
    Contact c;
    EXPECT_FALSE(set.find_contact(p, c) && c.depth > tolerance);
  }
  /* Exact penetration report over the same points agrees. */
  const PenetrationStats stats = set.penetration_stats(x, 0.01f);
  EXPECT_EQ(stats.deeper_num, 0);
  EXPECT_LT(stats.max_depth, 0.01f);
}
