/* The particle skin (Bando 2003, §4; lcp/strand_skin_bando2003.hh): strands carried by the LCP
 * particles near their (u, v, s), lengths kept, swung out of the body. */
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <random>

#include "collision/collider.hh"
#include "collision_test_shapes.hh"
#include "lcp/strand_skin_bando2003.hh"
#include "lcp_scenes.hh"

using namespace hairdyn;

namespace {

/* 4 × 4 straight strands 6 cm apart hanging 12 cm from z = 0, 1 cm segments, and their
 * particles (spacing 1 cm). */
struct Groom {
  std::vector<int32_t> offsets{0};
  std::vector<vec3> points;
  LcpParticles particles;
  Groom()
  {
    for (int a = 0; a < 4; a++) {
      for (int b = 0; b < 4; b++) {
        for (int k = 0; k <= 12; k++) {
          points.emplace_back(0.06f * float(a), 0.06f * float(b), -0.01f * float(k));
        }
        offsets.push_back(int32_t(points.size()));
      }
    }
    LcpParams params = lcp_scenes::params_for_spacing(0.01f);
    particles = sample_groom_particles(offsets, points, {}, params);
  }
  ParticleSkin skin(const mat4 &head = mat4(1.0f)) const
  {
    return ParticleSkin(offsets, transformed(head), particles_at(head), directions(head),
                        particles.u, particles.v, particles.s, head);
  }
  std::vector<vec3> transformed(const mat4 &m) const { return transform(m, points); }
  std::vector<vec3> particles_at(const mat4 &m) const { return transform(m, particles.positions); }
  static std::vector<vec3> transform(const mat4 &m, const std::vector<vec3> &points)
  {
    std::vector<vec3> result;
    for (const vec3 &p : points) {
      result.push_back(vec3(m * vec4(p, 1.0f)));
    }
    return result;
  }
  std::vector<vec3> directions(const mat4 &m) const
  {
    std::vector<vec3> result;
    for (const vec3 &t : particles.directions) {
      result.push_back(mat3(m) * t);
    }
    return result;
  }
};

float max_length_error(const Groom &groom, Span<vec3> points)
{
  float error = 0.0f;
  for (size_t c = 0; c + 1 < groom.offsets.size(); c++) {
    for (int32_t i = groom.offsets[c] + 1; i < groom.offsets[c + 1]; i++) {
      const float rest = glm::length(groom.points[size_t(i)] - groom.points[size_t(i) - 1]);
      error = std::max(error, std::abs(glm::length(points[i] - points[i - 1]) - rest));
    }
  }
  return error;
}

}  // namespace

/* The grid's k nearest are the brute-force k nearest, in the 4D distance, ties by index. */
TEST(LcpSkin, GridNearestMatchesBruteForce)
{
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
  std::vector<vec3> points(500), queries(200);
  std::vector<float> points_w(500), queries_w(200);
  for (size_t i = 0; i < points.size(); i++) {
    points[i] = vec3(uniform(rng), uniform(rng), 0.1f * uniform(rng)); /* a flat cloud */
    points_w[i] = uniform(rng);
  }
  for (size_t i = 0; i < queries.size(); i++) {
    queries[i] = vec3(2.0f * uniform(rng), uniform(rng), uniform(rng)); /* some outside */
    queries_w[i] = uniform(rng);
  }
  const int k = 5;
  std::vector<int32_t> indices;
  std::vector<float> distances;
  find_k_nearest(points, points_w, queries, queries_w, k, indices, distances);
  for (size_t q = 0; q < queries.size(); q++) {
    std::vector<std::pair<float, int32_t>> all;
    for (size_t j = 0; j < points.size(); j++) {
      const vec3 d = points[j] - queries[q];
      const float dw = points_w[j] - queries_w[q];
      all.emplace_back(std::sqrt(glm::dot(d, d) + dw * dw), int32_t(j));
    }
    std::sort(all.begin(), all.end());
    for (int c = 0; c < k; c++) {
      ASSERT_EQ(indices[q * k + size_t(c)], all[size_t(c)].second) << "query " << q;
    }
  }
}

/* At rest the groom is returned as it is; a head moved rigidly with its particles carries the
 * groom exactly. */
TEST(LcpSkin, RestAndRigidHeadMotionAreExact)
{
  const Groom groom;
  const mat4 rest_head = glm::translate(mat4(1.0f), vec3(0.1f, 0.0f, 1.5f));
  ParticleSkin skin = groom.skin(rest_head);
  std::vector<vec3> out(groom.points.size());
  skin.apply(groom.particles_at(rest_head), rest_head, nullptr, out);
  const std::vector<vec3> rest = groom.transformed(rest_head);
  for (size_t i = 0; i < out.size(); i++) {
    ASSERT_LT(glm::length(out[i] - rest[i]), 1e-6f) << i;
  }
  const mat4 head = glm::translate(mat4(1.0f), vec3(-0.2f, 0.3f, 1.4f)) *
                    glm::rotate(mat4(1.0f), 0.7f, glm::normalize(vec3(1.0f, 2.0f, 0.5f)));
  skin.apply(groom.particles_at(head), head, nullptr, out);
  const std::vector<vec3> carried = groom.transformed(head);
  for (size_t i = 0; i < out.size(); i++) {
    ASSERT_LT(glm::length(out[i] - carried[i]), 1e-5f) << i;
  }
}

/* Strands that stick out sideways over particles that hang from the same roots (particles
 * sampled apart from the groom, as over the scalp): carried by displacements they keep sticking
 * out at rest; with shape_from_particles they hang in the particles' column, each point at its
 * own arc length below the root, and follow the column when it swings, lengths kept. */
TEST(LcpSkin, ShapeFromParticlesPutsTheStrandsInTheVolume)
{
  const Groom hanging;
  std::vector<vec3> sideways;
  for (size_t c = 0; c + 1 < hanging.offsets.size(); c++) {
    const vec3 root = hanging.points[size_t(hanging.offsets[c])];
    for (int32_t i = hanging.offsets[c]; i < hanging.offsets[c + 1]; i++) {
      sideways.push_back(root + vec3(0.01f * float(i - hanging.offsets[c]), 0.0f, 0.0f));
    }
  }
  const LcpParticles &particles = hanging.particles;
  const auto skin = [&](const bool shape_from_particles) {
    return ParticleSkin(hanging.offsets, sideways, particles.positions, particles.directions,
                        particles.u, particles.v, particles.s, mat4(1.0f), 4,
                        shape_from_particles);
  };
  std::vector<vec3> out(sideways.size());
  ParticleSkin carried = skin(false);
  carried.apply(particles.positions, mat4(1.0f), nullptr, out);
  for (size_t i = 0; i < out.size(); i++) {
    ASSERT_LT(glm::length(out[i] - sideways[i]), 1e-6f) << i;
  }
  ParticleSkin volume = skin(true);
  volume.apply(particles.positions, mat4(1.0f), nullptr, out, particles.directions);
  /* Within a tenth of the strands' 6 cm spacing: a blend may reach a neighbour column's
   * particle (one tip, 5 mm); on average within 0.1 mm. */
  float largest = 0.0f, sum = 0.0f;
  for (size_t i = 0; i < out.size(); i++) {
    largest = std::max(largest, glm::length(out[i] - hanging.points[i]));
    sum += glm::length(out[i] - hanging.points[i]);
  }
  EXPECT_LT(largest, 0.006f);
  EXPECT_LT(sum / float(out.size()), 1e-4f);
  /* Every particle swings by 0.4 rad about the x axis through its strand's root. */
  const mat3 swing = glm::mat3_cast(glm::angleAxis(0.4f, vec3(1.0f, 0.0f, 0.0f)));
  std::vector<vec3> x = particles.positions, t = particles.directions;
  for (size_t j = 0; j < x.size(); j++) {
    const vec3 root(x[j].x, x[j].y, 0.0f);
    x[j] = root + swing * (x[j] - root);
    t[j] = swing * t[j];
  }
  volume.apply(x, mat4(1.0f), nullptr, out, t);
  for (size_t c = 0; c + 1 < hanging.offsets.size(); c++) {
    const int32_t tip = hanging.offsets[c + 1] - 1;
    const vec3 root = hanging.points[size_t(hanging.offsets[c])];
    const vec3 expected = root + swing * (hanging.points[size_t(tip)] - root);
    EXPECT_LT(glm::length(out[size_t(tip)] - expected), 0.006f) << c; /* it moves 4.7 cm */
  }
  EXPECT_LT(max_length_error(hanging, out), 1e-6f);
}

/* Strand 5's particles (those on its axis) swing by 0.4 rad about its root: the strand follows
 * them, keeps its segment lengths, and the strands 6 cm away, whose particles did not move,
 * do not move. */
TEST(LcpSkin, StrandFollowsItsOwnParticlesAndKeepsItsLength)
{
  const Groom groom;
  ParticleSkin skin = groom.skin();
  const int strand = 5;
  const vec3 root = groom.points[size_t(groom.offsets[strand])];
  const mat3 swing = glm::mat3_cast(glm::angleAxis(0.4f, vec3(1.0f, 0.0f, 0.0f)));
  std::vector<vec3> x = groom.particles.positions;
  for (vec3 &p : x) {
    if (glm::length(vec2(p) - vec2(root)) < 1e-3f) {
      p = root + swing * (p - root);
    }
  }
  std::vector<vec3> out(groom.points.size());
  skin.apply(x, mat4(1.0f), nullptr, out);
  const vec3 tip_rest = groom.points[size_t(groom.offsets[strand + 1] - 1)];
  const vec3 tip_expected = root + swing * (tip_rest - root);
  const vec3 tip = out[size_t(groom.offsets[strand + 1] - 1)];
  /* The tip moves most of the way (the blend of 4 particles within ~1 cm of arc length). */
  EXPECT_LT(glm::length(tip - tip_expected), 0.2f * glm::length(tip_expected - tip_rest));
  EXPECT_LT(max_length_error(groom, out), 1e-6f);
  for (int c = 0; c < 16; c++) {
    if (c == strand) {
      continue;
    }
    for (int32_t i = groom.offsets[size_t(c)]; i < groom.offsets[size_t(c) + 1]; i++) {
      ASSERT_LT(glm::length(out[size_t(i)] - groom.points[size_t(i)]), 1e-6f) << c;
    }
  }
}

/* A 3 cm sphere 2 cm beside strand 5's axis, 8 cm down: the straight strand goes through it at
 * rest; the skin swings it out (no point deeper than the map's 2 mm resolution) with its
 * lengths kept. */
TEST(LcpSkin, StrandIsSwungOutOfTheBody)
{
  const Groom groom;
  ParticleSkin skin = groom.skin();
  const int strand = 5;
  const vec3 root = groom.points[size_t(groom.offsets[strand])];
  const vec3 center = root + vec3(0.02f, 0.0f, -0.08f);
  const float radius = 0.03f;
  const test::TestMesh sphere = test::uv_sphere(radius, 48, 24);
  std::vector<vec3> vertices = sphere.vertices;
  for (vec3 &v : vertices) {
    v += center;
  }
  const ColliderMesh mesh(vertices, sphere.triangles);
  ColliderSet colliders;
  colliders.add(std::make_shared<Collider>(mesh, Span<int32_t>(), Span<int32_t>(),
                                           CollisionParams{}));
  const auto deepest = [&](Span<vec3> points) {
    float depth = 0.0f;
    for (const vec3 &p : points) {
      depth = std::max(depth, radius - glm::length(p - center));
    }
    return depth;
  };
  ASSERT_GT(deepest(groom.points), 0.009f) << "the scene does not put the strand inside";
  std::vector<vec3> out(groom.points.size());
  skin.apply(groom.particles.positions, mat4(1.0f), &colliders, out);
  EXPECT_LT(deepest(out), 2e-3f);
  EXPECT_LT(max_length_error(groom, out), 1e-6f);
}
