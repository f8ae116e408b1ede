/* Scalp map and particle initialisation of Bando 2003, §3.2. */
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "lcp_scenes.hh"

using namespace hairdyn;
using namespace hairdyn::lcp_scenes;

namespace {

void expect_bijective_on_square(const Patch &patch)
{
  ASSERT_EQ(find_scalp_error(patch.vertices, patch.triangles), "");
  std::vector<vec2> uv(patch.vertices.size());
  ASSERT_TRUE(compute_harmonic_map(patch.vertices, patch.triangles, uv));
  /* No flipped (or collapsed) triangle: all have the same, positive orientation. */
  for (const ivec3 &t : patch.triangles) {
    const vec2 e1 = uv[size_t(t.y)] - uv[size_t(t.x)], e2 = uv[size_t(t.z)] - uv[size_t(t.x)];
    EXPECT_GT(e1.x * e2.y - e1.y * e2.x, 0.0f);
  }
  /* Total area is the unit square: the triangles tile it without overlap. */
  double area = 0.0;
  for (const ivec3 &t : patch.triangles) {
    const vec2 e1 = uv[size_t(t.y)] - uv[size_t(t.x)], e2 = uv[size_t(t.z)] - uv[size_t(t.x)];
    area += 0.5 * double(e1.x * e2.y - e1.y * e2.x);
  }
  EXPECT_NEAR(area, 1.0, 1e-4);
  /* The boundary ring (the last `segments` vertices) lies on the square's edges. */
  int on_edge = 0;
  for (const vec2 &p : uv) {
    EXPECT_GE(p.x, -1e-6f);
    EXPECT_LE(p.x, 1.0f + 1e-6f);
    EXPECT_GE(p.y, -1e-6f);
    EXPECT_LE(p.y, 1.0f + 1e-6f);
    const float d = std::min(std::min(p.x, 1.0f - p.x), std::min(p.y, 1.0f - p.y));
    on_edge += d < 1e-6f ? 1 : 0;
  }
  EXPECT_EQ(on_edge, 32);
}

}  // namespace

TEST(LcpScalp, HarmonicMapOfADiscIsBijectiveWithBoundaryOnTheSquare)
{
  expect_bijective_on_square(disc_patch(8, 32, 0.1f));
}

TEST(LcpScalp, HarmonicMapOfAHemisphereIsBijectiveWithBoundaryOnTheSquare)
{
  expect_bijective_on_square(cap_patch(8, 32, 0.1f, 0.5f * pi_f));
}

TEST(LcpScalp, InverseMapReturnsThePatchPoints)
{
  const Patch patch = cap_patch(6, 24, 0.1f, 1.2f);
  const ScalpMap scalp(patch.vertices, patch.triangles, {});
  ASSERT_TRUE(scalp.is_valid());
  for (size_t v = 0; v < patch.vertices.size(); v += 5) {
    const ScalpPoint p = scalp.locate(scalp.uv()[int64_t(v)]);
    EXPECT_LT(glm::length(p.position - patch.vertices[v]), 1e-4f) << v;
    EXPECT_GT(glm::dot(p.normal, glm::normalize(patch.vertices[v])), 0.95f) << "outward normal";
  }
}

TEST(LcpScalp, BadPatchesAreRejectedWithASentence)
{
  EXPECT_NE(find_scalp_error({}, {}).find("no faces"), std::string::npos);
  /* A closed surface (tetrahedron) has no boundary. */
  const std::vector<vec3> tet{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const std::vector<ivec3> tet_faces{{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  EXPECT_NE(find_scalp_error(tet, tet_faces).find("no boundary"), std::string::npos);
  /* An annulus has two boundary loops. */
  Patch disc = disc_patch(3, 12, 1.0f);
  std::vector<ivec3> annulus(disc.triangles.begin() + 12, disc.triangles.end());
  std::vector<vec3> vertices(disc.vertices);
  vertices[0] = vec3(0.0f); /* Unused by the annulus. */
  EXPECT_NE(find_scalp_error(vertices, annulus).find("not used"), std::string::npos);
  std::vector<vec3> ring(vertices.begin() + 1, vertices.end());
  for (ivec3 &t : annulus) {
    t -= ivec3(1);
  }
  EXPECT_NE(find_scalp_error(ring, annulus).find("2 boundary loops"), std::string::npos);
}

TEST(LcpScalp, EmptyLengthMapIsRejected)
{
  const Patch patch = disc_patch(3, 12, 0.1f);
  const std::vector<float> zero(patch.vertices.size(), 0.0f);
  const ScalpMap scalp(patch.vertices, patch.triangles, zero);
  EXPECT_NE(find_length_map_error(scalp, LengthMap{}).find("empty"), std::string::npos);
  const std::vector<float> image(16, 0.0f);
  const ScalpMap ones(patch.vertices, patch.triangles, {});
  EXPECT_EQ(find_length_map_error(ones, LengthMap{}), "");
  EXPECT_NE(find_length_map_error(ones, LengthMap{image, 4, 4}).find("empty"), std::string::npos);
  EXPECT_NE(find_length_map_error(ones, LengthMap{image, 3, 4}).find("size"), std::string::npos);
}

TEST(LcpScalp, PoissonDiscSamplesKeepTheirDistanceAndAreDeterministic)
{
  LcpParams params = params_for_spacing(0.01f);
  params.max_length = 0.06f;
  const Patch patch = cap_patch(5, 20, 0.1f, 0.8f);
  const ScalpMap scalp(patch.vertices, patch.triangles, {});
  const LcpParticles a = sample_scalp_particles(scalp, LengthMap{}, params, vec3(0, 0, -1));
  const LcpParticles b = sample_scalp_particles(scalp, LengthMap{}, params, vec3(0, 0, -1));
  ASSERT_GT(a.size(), 100);
  ASSERT_EQ(a.size(), b.size());
  int roots = 0;
  for (int64_t i = 0; i < a.size(); i++) {
    EXPECT_EQ(a.positions[size_t(i)], b.positions[size_t(i)]);
    EXPECT_GE(a.s[size_t(i)], -params.root_depth - 1e-6f);
    EXPECT_LE(a.s[size_t(i)], params.max_length + 1e-6f);
    EXPECT_NEAR(glm::length(a.directions[size_t(i)]), 1.0f, 1e-4f);
    if (a.s[size_t(i)] < 0.0f) {
      roots++;
      /* Root particles are inside the scalp (beneath the sphere of radius 0.1). */
      EXPECT_LT(glm::length(a.positions[size_t(i)]), 0.1f + 1e-5f);
    }
  }
  EXPECT_GT(roots, 5);
  /* Eq. 3 distance: ‖φ⁻¹(u_i, v_i) − φ⁻¹(u_j, v_j)‖² + (s_i − s_j)² ≥ r². */
  for (int64_t i = 0; i < a.size(); i += 3) {
    const vec3 pi = scalp.locate(vec2(a.u[size_t(i)], a.v[size_t(i)])).position;
    for (int64_t j = i + 1; j < a.size(); j++) {
      const vec3 pj = scalp.locate(vec2(a.u[size_t(j)], a.v[size_t(j)])).position;
      const float ds = a.s[size_t(i)] - a.s[size_t(j)];
      ASSERT_GE(glm::dot(pi - pj, pi - pj) + ds * ds, 0.99f * 0.01f * 0.01f) << i << " " << j;
    }
  }
  /* A target count is met exactly. */
  params.particle_num = 300;
  EXPECT_EQ(sample_scalp_particles(scalp, LengthMap{}, params, vec3(0, 0, -1)).size(), 300);
}

TEST(LcpScalp, TheSamplingPlanForeseesTheCountAndRefusesWhatCannotBeHeld)
{
  LcpParams params = params_for_spacing(0.01f);
  params.max_length = 0.06f;
  const Patch patch = cap_patch(5, 20, 0.1f, 0.8f);
  const ScalpMap scalp(patch.vertices, patch.triangles, {});
  /* The volume: the cap's area (2π R² (1 − cos 0.8)) times s_r + L_max, within a few percent
   * (Monte Carlo, and the cap's flat triangles); the count about what the spacing places. */
  const ScalpSampling plan = plan_scalp_sampling(scalp, LengthMap{}, params);
  const double cap_area = 2.0 * glm::pi<double>() * 0.01 * (1.0 - std::cos(0.8));
  EXPECT_NEAR(plan.volume / (cap_area * double(params.root_depth + params.max_length)), 1.0,
              0.05);
  const int64_t placed = sample_scalp_particles(scalp, LengthMap{}, params, vec3(0, 0, -1)).size();
  EXPECT_NEAR(double(plan.count) / double(placed), 1.0, 0.25) << plan.count << " " << placed;
  EXPECT_EQ(find_sampling_size_error(plan, params), "");
  /* Too many particles, by count or by spacing: the sentence names the setting to change. */
  LcpParams many = params;
  many.particle_num = int32_t(max_lcp_particles + 1);
  EXPECT_NE(find_sampling_size_error(plan_scalp_sampling(scalp, LengthMap{}, many), many)
                .find("lower the count"),
            std::string::npos);
  LcpParams fine = params_for_spacing(1e-4f);
  fine.max_length = 0.06f;
  EXPECT_NE(find_sampling_size_error(plan_scalp_sampling(scalp, LengthMap{}, fine), fine)
                .find("raise the spacing"),
            std::string::npos);
  /* A count it may hold, but h₂ reaching across the whole cap: every particle a neighbour of
   * every other. */
  LcpParams wide = params;
  wide.particle_num = int32_t(max_lcp_particles);
  wide.h2 = 1.0f;
  EXPECT_NE(find_sampling_size_error(plan_scalp_sampling(scalp, LengthMap{}, wide), wide)
                .find("lower h₁ and h₂"),
            std::string::npos);
}

/* Both samplers hand out their particles in space order (Morton order of cells of h₂), so
 * that the neighbours the solver gathers lie near each other in memory: consecutive particles
 * are on average several times closer than two particles picked at random (the samplers' own
 * order), and within a few h₂. */
TEST(LcpScalp, SampledParticlesComeInSpaceOrder)
{
  const auto mean_step = [](const std::vector<vec3> &points) {
    double sum = 0.0;
    for (size_t i = 1; i < points.size(); i++) {
      sum += double(glm::length(points[i] - points[i - 1]));
    }
    return sum / double(points.size() - 1);
  };
  const auto check = [&](const LcpParticles &particles, const float h2) {
    ASSERT_GT(particles.size(), 200);
    std::vector<vec3> shuffled = particles.positions;
    std::shuffle(shuffled.begin(), shuffled.end(), std::mt19937(3));
    const double ordered = mean_step(particles.positions), random = mean_step(shuffled);
    EXPECT_LT(ordered, 0.3 * random) << "ordered " << ordered << " m, random " << random << " m";
    EXPECT_LT(ordered, 3.0 * double(h2));
  };
  LcpParams params = params_for_spacing(0.01f);
  params.max_length = 0.1f;
  {
    SCOPED_TRACE("scalp");
    const Patch patch = cap_patch(5, 20, 0.1f, 0.8f);
    const ScalpMap scalp(patch.vertices, patch.triangles, {});
    check(sample_scalp_particles(scalp, LengthMap{}, params, vec3(0, 0, -1)), params.h2);
  }
  {
    SCOPED_TRACE("groom");
    std::vector<int32_t> offsets{0};
    std::vector<vec3> points;
    for (int c = 0; c < 100; c++) {
      for (int k = 0; k < 11; k++) {
        points.push_back(vec3(0.01f * float(c % 10), 0.01f * float(c / 10), -0.01f * float(k)));
      }
      offsets.push_back(int32_t(points.size()));
    }
    check(sample_groom_particles(offsets, points, {}, params), params.h2);
  }
}

TEST(LcpScalp, CantileverBeamBendsTowardGravity)
{
  vec3 x, t;
  /* Horizontal hair under gravity droops; stiffer (longer b) droops less; no gravity
   * component across the hair keeps it straight. */
  cantilever_beam(vec3(0.0f), vec3(1, 0, 0), vec3(0, 0, -1), 0.2f, 0.2f, 0.1f, x, t);
  const float soft_drop = -x.z;
  EXPECT_GT(soft_drop, 0.01f);
  EXPECT_LT(t.z, 0.0f);
  EXPECT_LE(glm::length(x), 0.2f + 1e-5f);
  cantilever_beam(vec3(0.0f), vec3(1, 0, 0), vec3(0, 0, -1), 0.2f, 0.2f, 0.3f, x, t);
  EXPECT_LT(-x.z, soft_drop);
  cantilever_beam(vec3(0.0f), vec3(0, 0, -1), vec3(0, 0, -1), 0.2f, 0.15f, 0.1f, x, t);
  EXPECT_NEAR(x.z, -0.15f, 1e-5f);
  /* Eq. 4: the root direction tilts away from the whorl. */
  const vec3 n = glm::normalize(vec3(1, 0, 1));
  const vec3 tr = root_direction(n, vec3(0, 0, 1), 1.0f, 1.0f);
  EXPECT_GT(glm::dot(tr, n), 0.0f);
  EXPECT_LT(tr.z, n.z);
}

TEST(LcpScalp, GroomStrandsBecomeParticles)
{
  /* Ten straight strands hanging 0.1 m. */
  std::vector<int32_t> offsets{0};
  std::vector<vec3> points;
  std::vector<vec2> root_uv;
  for (int c = 0; c < 10; c++) {
    for (int k = 0; k < 11; k++) {
      points.push_back(vec3(0.01f * float(c), 0.0f, -0.01f * float(k)));
    }
    offsets.push_back(int32_t(points.size()));
    root_uv.push_back(vec2(0.1f * float(c), 0.5f));
  }
  LcpParams params = params_for_spacing(0.01f);
  const LcpParticles p = sample_groom_particles(offsets, points, root_uv, params);
  ASSERT_GT(p.size(), 50);
  for (int64_t i = 0; i < p.size(); i++) {
    EXPECT_NEAR(p.positions[size_t(i)].z, -p.s[size_t(i)], 1e-5f); /* s is arc length. */
    EXPECT_NEAR(p.directions[size_t(i)].z, -1.0f, 1e-5f);
    EXPECT_NEAR(p.u[size_t(i)], p.positions[size_t(i)].x * 10.0f, 1e-4f);
  }
  params.particle_num = 40;
  EXPECT_EQ(sample_groom_particles(offsets, points, root_uv, params).size(), 40);
}

/* Even spacing of the rest state: a clump of particles pressed against a floor (the body)
 * spreads out until no pair is closer than the minimum, fixed particles stay, and every moved
 * particle stays above the floor. */
TEST(LcpScalp, CloseParticlesAreSpacedOutAndKeptOutOfTheBody)
{
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> offset(-0.005f, 0.005f);
  std::vector<vec3> positions;
  std::vector<uint8_t> is_fixed;
  for (int i = 0; i < 200; i++) {
    positions.push_back(vec3(offset(rng), offset(rng), 0.0005f * float(i % 4)));
    is_fixed.push_back(i % 10 == 0 ? 1 : 0);
  }
  const std::vector<vec3> before = positions;
  const float min_distance = 0.004f;
  const int64_t left = separate_close_particles(
      positions, is_fixed, min_distance, 200, [](vec3 &p) { p.z = std::max(p.z, 0.0f); });
  EXPECT_EQ(left, 0);
  for (size_t i = 0; i < positions.size(); i++) {
    EXPECT_GE(positions[i].z, 0.0f);
    if (is_fixed[i]) {
      EXPECT_EQ(positions[i], before[i]);
    }
    for (size_t j = i + 1; j < positions.size(); j++) {
      if (!(is_fixed[i] && is_fixed[j])) {
        EXPECT_GE(glm::length(positions[i] - positions[j]), 0.99f * min_distance) << i << " " << j;
      }
    }
  }
}
