/* Strands under abuse (issue 11): 500 frames of the violent head shake that sent LCP's
 * particles to 1e30 m, on a groom colliding with the head. */
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include "collision/collider.hh"
#include "collision_test_shapes.hh"
#include "groom/groom.hh"
#include "groom/metrics.hh"
#include "lcp_scenes.hh"
#include "lod_sintel_scene.hh"
#include "strands/strand_solver.hh"

using namespace hairdyn;

namespace {

constexpr float head_radius = 0.1f;
constexpr float strand_length = 0.2f;

/* 48 strands 20 cm long in 16 segments, rooted on the top of the head (polar angle up to
 * 60°) and growing along the normal. */
struct Cap {
  std::vector<int32_t> offsets{ 0 };
  std::vector<vec3> positions;
  std::vector<vec3> normals;
  Cap()
  {
    for (int ring = 1; ring <= 4; ring++) {
      for (int s = 0; s < 12; s++) {
        const float polar = float(ring) / 4.0f * float(M_PI) / 3.0f;
        const float azimuth = 2.0f * float(M_PI) * (float(s) + 0.5f * float(ring)) / 12.0f;
        const vec3 normal(std::sin(polar) * std::cos(azimuth), std::sin(polar) * std::sin(azimuth),
                          std::cos(polar));
        for (int i = 0; i <= 16; i++) {
          positions.push_back(normal * (head_radius * 1.01f + strand_length * float(i) / 16.0f));
        }
        offsets.push_back(int32_t(positions.size()));
        normals.push_back(normal);
      }
    }
  }
};

struct Soak {
  float max_reach = 0.0f;   /* m, farthest node from the head's centre */
  float max_depth = 0.0f;   /* m, deepest node inside the head */
  float max_stretch = 0.0f; /* relative, worst segment over all frames */
  float peak_speed = 0.0f;  /* m/s, fastest node during the shake */
  float speed_after = 0.0f; /* m/s, fastest node 48 frames after the head stopped */
};

Soak soak(const StrandModel model)
{
  const test::TestMesh sphere = test::uv_sphere(head_radius, 48, 24);
  const ColliderMesh mesh(sphere.vertices, sphere.triangles);
  CollisionParams collision;
  ColliderSet colliders;
  auto head = std::make_shared<Collider>(mesh, Span<int32_t>(), Span<int32_t>(), collision);
  colliders.add(head);

  const Cap groom;
  StrandParams params;
  params.model = model;
  StrandSolver solver(groom.offsets, groom.positions, mat4(1.0f), groom.normals, params);
  solver.set_colliders(&colliders, collision);
  Soak result;
  for (int frame = 1; frame <= 548; frame++) {
    const mat4 head_to_world = lcp_scenes::violent_shake(std::min(frame, 500));
    head->set_transform(head_to_world);
    solver.step(1.0f / 24.0f, head_to_world);
    if (solver.diverged_num() != 0) {
      ADD_FAILURE() << solver.diverged_num() << " strands diverged at frame " << frame;
      break;
    }
    for (const vec3 &v : solver.velocities()) {
      result.peak_speed = std::max(result.peak_speed, glm::length(v));
    }
    const mat4 to_head = glm::inverse(head_to_world);
    for (const vec3 &p : solver.positions()) {
      const float distance = glm::length(vec3(to_head * vec4(p, 1.0f)));
      result.max_reach = std::max(result.max_reach, distance);
      result.max_depth = std::max(result.max_depth, head_radius - distance);
    }
    result.max_stretch =
        std::max(result.max_stretch,
                 max_relative_stretch(groom.offsets, groom.positions, solver.positions()));
  }
  for (const vec3 &v : solver.velocities()) {
    result.speed_after = std::max(result.speed_after, glm::length(v));
  }
  return result;
}

}  // namespace

/* Issue 11, "Also": no strand diverges over 500 frames of yaw ±170° and pitch ±45° every 4
 * frames (the head turns at up to 35 rad/s); segments keep their length; no node leaves the
 * reach of its root (head radius plus strand length); collision keeps the nodes out of the
 * head (within 5 mm: the 40 × 40 maps resolve the sphere to about 1 cm); once the head stops
 * the hair comes to rest. Both strand models. The articulated model survives it since its
 * velocity products are taken at mid-step, contacts stop a tip by an impulse through the
 * chain's inertia, and the air's form drag acts on a whipped tip (issue 12; before, strands
 * diverged within 6 frames), and it comes to rest since a projected segment turns alone
 * (before, the strand beyond it swung with it, and tips lying on the head kept flicking at
 * 0.28 m/s). */
TEST(StrandsRobustness, SurviveFiveHundredFramesOfViolentShake)
{
  for (const StrandModel model : { StrandModel::Kurihara1993, StrandModel::Articulated }) {
    SCOPED_TRACE(model == StrandModel::Articulated ? "articulated" : "kurihara1993");
    const Soak result = soak(model);
    std::printf("%s: reach %.4f m, depth %.4f m, stretch %.2e, peak speed %.2f m/s, speed 48 "
                "frames after the shake %.4f m/s\n",
                model == StrandModel::Articulated ? "articulated" : "kurihara1993",
                result.max_reach, result.max_depth, result.max_stretch, result.peak_speed,
                result.speed_after);
    EXPECT_GT(result.peak_speed, 1.0f) << "the shake must fling the hair";
    EXPECT_LE(result.max_reach, head_radius * 1.01f + strand_length + 1e-3f);
    EXPECT_LE(result.max_stretch, 1e-4f);
    EXPECT_LE(result.max_depth, 0.005f);
    EXPECT_LT(result.speed_after, 0.1f);
  }
}

/* Every strand of Ward & Lin 2003's Table 1 scene simulated (lod_sintel_scene.hh: 9,120
 * strands interpolated around Sintel's guides, many lying along the bust, wind blowing at
 * 3 m/s): no strand runs away and is put back at rest, and no node moves at 25 m/s. Before
 * the child of a projected segment took back at most StrandSolver::max_kept_turn, 280 strands
 * ran away over these 12 frames and the fastest node of the others moved at 34 m/s (22 m/s
 * now: a tail that swings with a segment pushed out by more than max_kept_turn). */
TEST(StrandsRobustness, NoStrandRunsAwayAlongSintelsBust)
{
  const test::SintelScene &s = test::sintel();
  if (!s.loaded) {
    GTEST_SKIP() << "the Sintel assets are missing (folder " << test::sintel_folder << ")";
  }
  StrandSolver solver(s.offsets, s.positions, mat4(1.0f), {}, StrandParams(), test::sintel_wind());
  solver.set_colliders(s.colliders.get(), CollisionParams());
  int64_t diverged = 0;
  float fastest = 0.0f;
  for (int frame = 0; frame < 12; frame++) {
    solver.step(test::sintel_frame_dt, mat4(1.0f));
    diverged += solver.diverged_num();
    for (const vec3 &v : solver.velocities()) {
      fastest = std::max(fastest, glm::length(v));
    }
  }
  std::printf("%lld strands ran away over 12 frames, fastest node %.2f m/s\n", (long long)diverged,
              fastest);
  EXPECT_EQ(diverged, 0);
  EXPECT_LT(fastest, 25.0f);
  /* Two strands of it that never touch the bust, each alone (a strand keeps its bits alone),
   * over 40 frames: with the mid-step acceleration extrapolated through a sign flip, their
   * near-root hinges zigzagged faster and faster and they ran away at frames 29 and 35. */
  for (const int64_t curve : { 5854, 5981 }) {
    const IndexRange points = curve_points(s.offsets, curve);
    const std::vector<vec3> rest(s.positions.begin() + points.start,
                                 s.positions.begin() + points.one_after_last());
    const std::vector<int32_t> offsets{ 0, int32_t(rest.size()) };
    StrandSolver alone(offsets, rest, mat4(1.0f), {}, StrandParams(), test::sintel_wind());
    alone.set_colliders(s.colliders.get(), CollisionParams());
    for (int frame = 0; frame < 40; frame++) {
      alone.step(test::sintel_frame_dt, mat4(1.0f));
      ASSERT_EQ(alone.diverged_num(), 0) << "strand " << curve << ", frame " << frame;
      ASSERT_EQ(alone.contacts_num(), 0) << "strand " << curve << ", frame " << frame;
    }
  }
}
