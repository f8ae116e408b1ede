/* Pinned groom points in LCP (groom/pins.hh): particles sampled where the groom is pinned are
 * held by the head like the roots, and the particle skin carries pinned strand points with the
 * head, the chain before them reaching them with every length kept. */
#include <gtest/gtest.h>

#include <algorithm>

#include "lcp/lcp_solver.hh"
#include "lcp/sampling_bando2003.hh"
#include "lcp/strand_skin_bando2003.hh"
#include "lcp_scenes.hh"

using namespace hairdyn;

namespace {

/* 4 × 4 zigzag strands 3 cm apart hanging 12 cm from z = 0 (segments of 1.08 cm, slack
 * enough that a chain between two pins can move), the last three points of each pinned. */
struct PinnedGroom {
  std::vector<int32_t> offsets{ 0 };
  std::vector<vec3> points;
  std::vector<uint8_t> pinned;
  PinnedGroom()
  {
    for (int a = 0; a < 4; a++) {
      for (int b = 0; b < 4; b++) {
        for (int k = 0; k <= 12; k++) {
          points.emplace_back(0.03f * float(a) + 0.004f * float(k % 2), 0.03f * float(b),
                              -0.01f * float(k));
          pinned.push_back(k >= 10 ? 1 : 0);
        }
        offsets.push_back(int32_t(points.size()));
      }
    }
  }
};

/* A shake: ±0.5 rad about a tilted axis and ±4 cm sideways, no scale (LCP's frame has none). */
mat4 shaking_head(const int frame)
{
  const float t = float(frame) / 24.0f;
  return glm::rotate(glm::translate(mat4(1.0f), vec3(0.04f * std::sin(9.0f * t), 0.0f, 0.0f)),
                     0.5f * std::sin(7.0f * t), glm::normalize(vec3(0.3f, 1.0f, 0.2f)));
}

std::vector<vec3> transformed(const mat4 &m, Span<vec3> points)
{
  std::vector<vec3> result;
  for (const vec3 &p : points) {
    result.push_back(vec3(m * vec4(p, 1.0f)));
  }
  return result;
}

}  // namespace

TEST(LcpPins, ParticlesNearestToPinnedPointsAreFixed)
{
  const PinnedGroom groom;
  const LcpParams params = lcp_scenes::params_for_spacing(0.01f);
  const LcpParticles particles =
      sample_groom_particles(groom.offsets, groom.points, {}, params, groom.pinned);
  ASSERT_EQ(int64_t(particles.fixed.size()), particles.size());
  int64_t fixed = 0;
  for (int64_t i = 0; i < particles.size(); i++) {
    /* Points 10..12 are pinned: arc length from 9.5 segments on is nearest to one of them. */
    const float segment = glm::length(vec2(0.004f, 0.01f));
    const bool expected = particles.s[size_t(i)] > 9.5f * segment;
    const bool borderline = std::abs(particles.s[size_t(i)] - 9.5f * segment) < 1e-4f;
    if (!borderline) {
      EXPECT_EQ(bool(particles.fixed[size_t(i)]), expected) << "s = " << particles.s[size_t(i)];
    }
    fixed += particles.fixed[size_t(i)];
  }
  EXPECT_GT(fixed, 16);
  /* Without pins nothing is marked. */
  EXPECT_TRUE(sample_groom_particles(groom.offsets, groom.points, {}, params).fixed.empty());
}

TEST(LcpPins, FixedParticlesStayCarriedByTheHead)
{
  const PinnedGroom groom;
  LcpParams params = lcp_scenes::params_for_spacing(0.01f);
  const LcpParticles particles =
      sample_groom_particles(groom.offsets, groom.points, {}, params, groom.pinned);
  LcpSolver solver(params, particles, mat4(1.0f));
  const std::vector<vec3> rest(solver.positions().begin(), solver.positions().end());
  float fixed_drift = 0.0f, free_motion = 0.0f;
  for (int frame = 1; frame <= 48; frame++) {
    const mat4 head = shaking_head(frame);
    ASSERT_TRUE(solver.step(1.0f / 24.0f, head)) << solver.failure();
    const std::vector<vec3> carried = transformed(head, rest);
    for (int64_t i = 0; i < solver.particles_num(); i++) {
      const float off = glm::length(solver.positions()[i] - carried[size_t(i)]);
      if (solver.is_fixed()[i]) {
        fixed_drift = std::max(fixed_drift, off);
      }
      else {
        free_motion = std::max(free_motion, off);
      }
    }
  }
  EXPECT_LE(fixed_drift, 1e-5f) << "fixed particles left the head";
  EXPECT_GT(free_motion, 0.005f) << "the free particles do not move: a vacuous test";
}

TEST(LcpPins, SkinCarriesPinnedPointsWithTheHeadAndKeepsLengths)
{
  PinnedGroom groom;
  /* Only the tip and the middle point pinned here. */
  std::fill(groom.pinned.begin(), groom.pinned.end(), 0);
  for (size_t c = 0; c + 1 < groom.offsets.size(); c++) {
    groom.pinned[size_t(groom.offsets[c] + 6)] = 1;
    groom.pinned[size_t(groom.offsets[c + 1] - 1)] = 1;
  }
  const LcpParams params = lcp_scenes::params_for_spacing(0.01f);
  const LcpParticles particles = sample_groom_particles(groom.offsets, groom.points, {}, params);
  ParticleSkin skin(groom.offsets, groom.points, particles.positions, particles.directions,
                    particles.u, particles.v, particles.s, mat4(1.0f));
  skin.set_pinned(groom.pinned);
  /* The particles swing 0.4 rad about x at the roots while the head shakes. */
  const mat3 swing = glm::mat3_cast(glm::angleAxis(0.4f, vec3(1.0f, 0.0f, 0.0f)));
  const mat4 head = shaking_head(5);
  std::vector<vec3> x;
  for (const vec3 &p : particles.positions) {
    x.push_back(vec3(head * vec4(swing * p, 1.0f)));
  }
  std::vector<vec3> out(groom.points.size());
  skin.apply(x, head, nullptr, out);
  float drift = 0.0f, free_motion = 0.0f, length_error = 0.0f;
  for (size_t c = 0; c + 1 < groom.offsets.size(); c++) {
    for (int32_t i = groom.offsets[c]; i < groom.offsets[c + 1]; i++) {
      const vec3 carried = vec3(head * vec4(groom.points[size_t(i)], 1.0f));
      const float off = glm::length(out[size_t(i)] - carried);
      if (groom.pinned[size_t(i)]) {
        drift = std::max(drift, off);
      }
      else {
        free_motion = std::max(free_motion, off);
      }
      if (i > groom.offsets[c]) {
        const float rest = glm::length(groom.points[size_t(i)] - groom.points[size_t(i) - 1]);
        length_error = std::max(length_error,
                                std::abs(glm::length(out[size_t(i)] - out[size_t(i) - 1]) - rest));
      }
    }
  }
  EXPECT_LE(drift, 1e-5f) << "pinned strand points left the head";
  EXPECT_GT(free_motion, 1e-3f) << "the points between do not move: a vacuous test";
  EXPECT_LE(length_error, 1e-5f);
  /* Without pins the same tip swings with its particles. */
  skin.set_pinned({});
  skin.apply(x, head, nullptr, out);
  const int32_t tip = groom.offsets[1] - 1;
  EXPECT_GT(glm::length(out[size_t(tip)] - vec3(head * vec4(groom.points[size_t(tip)], 1.0f))),
            0.01f);
}
