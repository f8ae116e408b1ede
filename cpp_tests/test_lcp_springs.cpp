/* Loose connections of Bando 2003, §3.2-3.3: alignment (eq. 6), pruning, constant E (eq. 9-14),
 * direction update (eq. 15). */
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/spatial_grid.hh"
#include "lcp/implicit_springs.hh"
#include "lcp/interactions_bando2003.hh"
#include "lcp/springs_bando2003.hh"

using namespace hairdyn;

namespace {

/* A jittered block of hair along +Z: 7 × 7 × 16 particles of spacing a; the bottom layer is
 * the roots. */
struct Block {
  std::vector<vec3> positions, directions;
  std::vector<uint8_t> is_root;
};

Block hair_block(const float a)
{
  Block block;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> jitter(-0.1f * a, 0.1f * a);
  for (int z = 0; z < 16; z++) {
    for (int y = 0; y < 7; y++) {
      for (int x = 0; x < 7; x++) {
        block.positions.push_back(vec3(float(x), float(y), float(z)) * a +
                                  vec3(jitter(rng), jitter(rng), jitter(rng)));
        block.directions.push_back(vec3(0.0f, 0.0f, 1.0f));
        block.is_root.push_back(z == 0 ? 1 : 0);
      }
    }
  }
  return block;
}

}  // namespace

TEST(LcpSprings, AlignmentOfEq6)
{
  const vec3 z(0.0f, 0.0f, 1.0f);
  EXPECT_NEAR(alignment(z, z, z * 0.01f), 1.0f, 1e-6f);      /* In a row. */
  EXPECT_EQ(alignment(z, z, vec3(0.01f, 0.0f, 0.0f)), 0.0f); /* Side by side. */
  EXPECT_EQ(alignment(z, -z, z * 0.01f), 0.0f);              /* Opposite hair. */
  EXPECT_NEAR(alignment(z, z, vec3(1.0f, 0.0f, 1.0f)), std::sqrt(0.5f), 1e-6f);
}

TEST(LcpSprings, ConnectionsAreAlignedPrunedAndOriented)
{
  const float a = 0.01f;
  const Block block = hair_block(a);
  const LcpConnections c =
      build_connections(block.positions, block.directions, block.is_root, 1.3f * a, 0.5f, 12);
  ASSERT_GT(c.size(), 0);
  std::vector<int> degree(block.positions.size(), 0);
  for (int64_t p = 0; p < c.size(); p++) {
    const vec3 x =
        block.positions[size_t(c.tip[size_t(p)])] - block.positions[size_t(c.root[size_t(p)])];
    EXPECT_GT(x.z, 0.0f) << "tip end must be nearer the hair tip";
    EXPECT_LT(glm::length(x), 2.0f * 1.3f * a);
    EXPECT_GE(c.strength[size_t(p)] / c.rest_length[size_t(p)], 0.5f - 1e-6f); /* a_ij ≥ a₀. */
    EXPECT_FALSE(block.is_root[size_t(c.root[size_t(p)])] &&
                 block.is_root[size_t(c.tip[size_t(p)])]);
    degree[size_t(c.root[size_t(p)])]++;
    degree[size_t(c.tip[size_t(p)])]++;
  }
  /* Pruning: nobody keeps many more than N_n, unless its partners would drop below N_n. */
  int above = 0;
  for (const int d : degree) {
    above += d > 12 ? 1 : 0;
  }
  EXPECT_LT(above, int(degree.size()) / 4);
}

TEST(LcpSprings, AlphaKeepsYoungsModulusConstantAsPairsMoveApart)
{
  const float a = 0.01f, h1 = 1.3f * a, E = 1e4f;
  const Block block = hair_block(a);
  const LcpConnections c =
      build_connections(block.positions, block.directions, block.is_root, h1, 0.5f, 12);
  const int64_t n = int64_t(block.positions.size());
  const std::vector<float> area(size_t(n), cross_section(1e-5f, 1300.0f));
  std::vector<float> k(size_t(c.size())), alpha_k(size_t(c.size())), sums(size_t(2 * n));
  std::vector<float> e_root(static_cast<size_t>(n)), e_tip(static_cast<size_t>(n));
  std::vector<float> rest_alpha;
  for (const float stretch : { 1.0f, 1.2f, 1.4f, 1.6f, 1.8f }) {
    /* Pull the block apart along and across the hair: every pair weakens (eq. 7). */
    std::vector<vec3> moved(block.positions);
    for (vec3 &p : moved) {
      p *= stretch;
    }
    compute_spring_coefficients(c, moved, area, h1, E, k, alpha_k, sums);
    compute_tensile_moduli(c, alpha_k, area, e_root, e_tip);
    /* Without the α scaling (α kept at its rest value) E would fall with k. */
    if (rest_alpha.empty()) {
      for (int64_t p = 0; p < c.size(); p++) {
        rest_alpha.push_back(k[size_t(p)] > 0.0f ? alpha_k[size_t(p)] / k[size_t(p)] : 0.0f);
      }
    }
    std::vector<float> unscaled(size_t(c.size()));
    for (int64_t p = 0; p < c.size(); p++) {
      unscaled[size_t(p)] = rest_alpha[size_t(p)] * k[size_t(p)];
    }
    std::vector<float> e_root_unscaled(static_cast<size_t>(n)),
        e_tip_unscaled(static_cast<size_t>(n));
    compute_tensile_moduli(c, unscaled, area, e_root_unscaled, e_tip_unscaled);
    double worst = 0.0, mean_deviation = 0.0, worst_eq13 = 0.0, unscaled_mean = 0.0;
    int interior = 0;
    for (int64_t i = 0; i < n; i++) {
      const vec3 p = block.positions[size_t(i)] / a;
      /* Interior particles: both groups N_r and N_t are full. */
      if (p.x < 1.5f || p.x > 4.5f || p.y < 1.5f || p.y > 4.5f || p.z < 2.5f || p.z > 12.5f) {
        continue;
      }
      interior++;
      worst = std::max(worst, double(std::abs(e_root[size_t(i)] / E - 1.0f)));
      worst = std::max(worst, double(std::abs(e_tip[size_t(i)] / E - 1.0f)));
      mean_deviation += 0.5 * double(std::abs(e_root[size_t(i)] / E - 1.0f) +
                                     std::abs(e_tip[size_t(i)] / E - 1.0f));
      /* Eq. 13 alone: α_r,i = E A_i / Σ_{N_r(i)} l k makes eq. 10 hold exactly. */
      for (int side = 0; side < 2; side++) {
        const float sum_lk = sums[size_t(2 * i + side)];
        const float alpha = E * area[size_t(i)] / sum_lk;
        worst_eq13 =
            std::max(worst_eq13, double(std::abs(alpha * sum_lk / area[size_t(i)] / E - 1.0f)));
      }
      unscaled_mean += double(e_root_unscaled[size_t(i)] / E);
    }
    ASSERT_GT(interior, 20);
    unscaled_mean /= interior;
    mean_deviation /= interior;
    EXPECT_LT(worst_eq13, 1e-5) << "stretch " << stretch;
    /* Eq. 14 averages the α of the two ends, so E per particle is kept on average, not
     * exactly: mean deviation under 10 %, none beyond 60 %. */
    EXPECT_LT(mean_deviation, 0.1) << "stretch " << stretch;
    EXPECT_LT(worst, 0.6) << "stretch " << stretch;
    if (stretch >= 1.6f) {
      EXPECT_LT(unscaled_mean, 0.6) << "the test would not notice a missing α";
    }
  }
}

TEST(LcpSprings, DirectionsFollowTheConnections)
{
  const float a = 0.01f;
  const Block block = hair_block(a);
  const LcpConnections c =
      build_connections(block.positions, block.directions, block.is_root, 1.3f * a, 0.5f, 12);
  const int64_t n = int64_t(block.positions.size());
  /* Rotate the whole block by 0.5 rad about X: eq. 15 turns every free direction with it. */
  const mat3 turn = glm::mat3_cast(glm::angleAxis(0.5f, vec3(1.0f, 0.0f, 0.0f)));
  std::vector<vec3> moved(block.positions);
  for (vec3 &p : moved) {
    p = turn * p;
  }
  const std::vector<float> area(size_t(n), cross_section(1e-5f, 1300.0f));
  std::vector<float> k(size_t(c.size())), alpha_k(size_t(c.size())), sums(size_t(2 * n));
  compute_spring_coefficients(c, moved, area, 1.3f * a, 1e4f, k, alpha_k, sums);
  std::vector<vec3> directions(block.directions);
  const std::vector<uint8_t> none(static_cast<size_t>(n), 0);
  const vec3 expected = turn * vec3(0.0f, 0.0f, 1.0f);
  /* One update turns every direction most of the way (from cos 0.5 = 0.88); repeated, as
   * every substep does, eq. 15 reaches its fixed point, the turned direction. */
  update_directions(c, moved, alpha_k, none, directions);
  for (int64_t i = 0; i < n; i++) {
    EXPECT_GT(glm::dot(directions[size_t(i)], expected), 0.94f) << i;
  }
  for (int iteration = 0; iteration < 30; iteration++) {
    update_directions(c, moved, alpha_k, none, directions);
  }
  for (int64_t i = 0; i < n; i++) {
    EXPECT_GT(glm::dot(directions[size_t(i)], expected), 0.995f) << i;
  }
}

namespace {

/* A hanging chain: particle 0 fixed at the origin, `n` more below it at spacing a, directions
 * −Z, connected to their next neighbours only (2h₁ = 1.5 a). */
struct Chain {
  std::vector<vec3> positions, directions, velocities;
  std::vector<uint8_t> is_fixed;
  std::vector<float> masses;
  LcpConnections connections;
};

Chain hanging_chain(const int n, const float a, const float mass)
{
  Chain chain;
  for (int i = 0; i <= n; i++) {
    chain.positions.push_back(vec3(0.0f, 0.0f, -a * float(i)));
    chain.directions.push_back(vec3(0.0f, 0.0f, -1.0f));
    chain.velocities.push_back(vec3(0.0f));
    chain.is_fixed.push_back(i == 0 ? 1 : 0);
    chain.masses.push_back(mass);
  }
  chain.connections =
      build_connections(chain.positions, chain.directions, chain.is_fixed, 0.75f * a, 0.5f, 12);
  return chain;
}

}  // namespace

/* Backward Euler (lcp/implicit_springs.hh) at a time step 50 times past the explicit limit:
 * the chain settles where each spring carries the weight below it, as the statics say. */
TEST(LcpImplicitSprings, HangingChainReachesItsStaticStretchAtAHugeTimeStep)
{
  const int n = 10;
  const float a = 0.01f, mass = 1e-4f, kappa = 10.0f, g = 9.81f;
  Chain chain = hanging_chain(n, a, mass);
  ASSERT_EQ(chain.connections.size(), n);
  const std::vector<float> alpha_k(size_t(n), kappa);
  /* Explicit limit: ω² ≤ 4κ/m, dt < 2/ω. */
  const float dt = 50.0f * 2.0f / std::sqrt(4.0f * kappa / mass);
  ImplicitSprings springs;
  springs.velocity_tolerance = 1e-8f;
  for (int step = 0; step < 400; step++) {
    for (int i = 1; i <= n; i++) {
      chain.velocities[size_t(i)].z -= dt * g; /* gravity, explicit */
    }
    const ImplicitSprings::Result result =
        springs.step(chain.connections, chain.positions, alpha_k, 0.005f, chain.masses,
                     chain.is_fixed, dt, nullptr, chain.velocities);
    ASSERT_LE(result.iterations, 100);
    for (int i = 0; i <= n; i++) {
      chain.positions[size_t(i)] += dt * chain.velocities[size_t(i)];
    }
  }
  EXPECT_EQ(chain.velocities[0], vec3(0.0f)) << "the fixed particle moved";
  for (int i = 1; i <= n; i++) {
    const float length = glm::length(chain.positions[size_t(i)] - chain.positions[size_t(i - 1)]);
    /* Spring i carries the n − i + 1 particles below it. */
    const float expected = a + float(n - i + 1) * mass * g / kappa;
    EXPECT_NEAR(length, expected, 1e-3f * a) << "spring " << i;
    EXPECT_NEAR(chain.positions[size_t(i)].x, 0.0f, 1e-6f);
  }
}

/* Without gravity a stretched chain only loses energy, step after step, however large the
 * time step: backward Euler dissipates, it never adds. */
TEST(LcpImplicitSprings, EnergyNeverGrows)
{
  const int n = 8;
  const float a = 0.01f, mass = 1e-4f, kappa = 10.0f;
  Chain chain = hanging_chain(n, a, mass);
  const std::vector<float> alpha_k(size_t(chain.connections.size()), kappa);
  for (int i = 1; i <= n; i++) {
    chain.positions[size_t(i)] *= 1.3f;                    /* stretched by 30 % */
    chain.positions[size_t(i)].x += 0.002f * float(i % 2); /* and bent */
  }
  const auto energy = [&]() {
    double e = 0.0;
    for (int64_t p = 0; p < chain.connections.size(); p++) {
      const float r = glm::length(chain.positions[size_t(chain.connections.tip[size_t(p)])] -
                                  chain.positions[size_t(chain.connections.root[size_t(p)])]);
      const float stretch = r - chain.connections.rest_length[size_t(p)];
      e += 0.5 * double(kappa) * double(stretch) * double(stretch);
    }
    for (int i = 0; i <= n; i++) {
      e += 0.5 * double(mass) *
           double(glm::dot(chain.velocities[size_t(i)], chain.velocities[size_t(i)]));
    }
    return e;
  };
  ImplicitSprings springs;
  for (const float dt : { 1e-4f, 1e-2f }) {
    double previous = energy();
    const double start = previous;
    for (int step = 0; step < 50; step++) {
      springs.step(chain.connections, chain.positions, alpha_k, 0.0f, chain.masses, chain.is_fixed,
                   dt, nullptr, chain.velocities);
      for (int i = 0; i <= n; i++) {
        chain.positions[size_t(i)] += dt * chain.velocities[size_t(i)];
      }
      const double now = energy();
      EXPECT_LE(now, previous * (1.0 + 1e-4)) << "dt " << dt << ", step " << step;
      previous = now;
    }
    if (dt > 1e-3f) {
      EXPECT_LT(previous, 0.5 * start) << "a large step damps the stiff modes";
    }
  }
}

/* A block of hair particles under the springs and the pressure of eq. 16, one backward-Euler
 * step of a whole frame (implicit pressure): the coarse correction of the two-level
 * preconditioner reaches the velocities that block-Jacobi alone reaches, in under half the
 * iterations. The reference is block-Jacobi run to a tolerance 10⁵ times tighter. */
TEST(LcpImplicitSprings, CoarseCorrectionConvergesInFewerIterations)
{
  const float a = 0.005f, h = 0.92f * a, dt = 1.0f / 24.0f;
  const int side = 14;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> jitter(-0.15f * a, 0.15f * a);
  std::vector<vec3> positions, directions, velocities;
  std::vector<uint8_t> is_fixed;
  for (int z = 0; z < side; z++) {
    for (int y = 0; y < side; y++) {
      for (int x = 0; x < side; x++) {
        positions.push_back(a * vec3(float(x), float(y), -float(z)) +
                            vec3(jitter(rng), jitter(rng), jitter(rng)));
        directions.push_back(vec3(0.0f, 0.0f, -1.0f));
        is_fixed.push_back(z == 0 ? 1 : 0);
        /* Falling for a frame, and stirred. */
        velocities.push_back(z == 0 ? vec3(0.0f)
                                    : vec3(0.0f, 0.0f, -9.81f * dt) +
                                          40.0f * vec3(jitter(rng), jitter(rng), jitter(rng)));
      }
    }
  }
  const std::vector<float> masses(positions.size(), 10.0f * a * a * a); /* ρ_h = 10 kg/m³ */
  const LcpConnections connections =
      build_connections(positions, directions, is_fixed, 1.33f * a, 0.5f, 12);
  /* α k = E A / l with E = 10⁴ Pa and A of eq. 9 (δ = 1,300 kg/m³), as the solver has them. */
  const float area = std::pow(masses[0] / 1300.0f, 2.0f / 3.0f);
  const std::vector<float> alpha_k(size_t(connections.size()), 1.0e4f * area / a);
  SpatialGrid grid;
  grid.build(positions, 2.0f * h);
  NeighborList neighbors;
  find_neighbors(grid, positions, 2.0f * h, true, neighbors);
  std::vector<float> density(positions.size());
  compute_density(positions, masses, neighbors, h, density);
  DensityJacobian pressure;
  compute_density_jacobian(positions, masses, density, neighbors, h, 0.2f, 8.0f, pressure);

  const auto solve = [&](const float group_cell, const float tolerance, int &r_iterations) {
    ImplicitSprings springs;
    springs.group_cell = group_cell;
    springs.velocity_tolerance = tolerance;
    springs.max_iterations = 5000;
    std::vector<vec3> v = velocities;
    const ImplicitSprings::Result result =
        springs.step(connections, positions, alpha_k, 0.005f, masses, is_fixed, dt, &pressure, v);
    EXPECT_LE(result.max_correction, tolerance) << "group cell " << group_cell;
    r_iterations = result.iterations;
    return v;
  };
  const float tolerance = 1e-4f * h / dt; /* the LCP solver's */
  int reference_iterations = 0, jacobi_iterations = 0, coarse_iterations = 0;
  const std::vector<vec3> reference = solve(0.0f, 1e-5f * tolerance, reference_iterations);
  const std::vector<vec3> jacobi = solve(0.0f, tolerance, jacobi_iterations);
  const std::vector<vec3> coarse = solve(4.0f * h, tolerance, coarse_iterations);
  float jacobi_error = 0.0f, coarse_error = 0.0f, speed = 0.0f;
  for (size_t i = 0; i < positions.size(); i++) {
    jacobi_error = std::max(jacobi_error, glm::length(jacobi[i] - reference[i]));
    coarse_error = std::max(coarse_error, glm::length(coarse[i] - reference[i]));
    speed = std::max(speed, glm::length(reference[i]));
  }
  std::printf("iterations: block-Jacobi %d, with the coarse correction %d (reference %d); "
              "largest velocity error %g and %g m/s (tolerance %g, fastest %g m/s)\n",
              jacobi_iterations, coarse_iterations, reference_iterations, double(jacobi_error),
              double(coarse_error), double(tolerance), double(speed));
  EXPECT_LT(2 * coarse_iterations, jacobi_iterations);
  EXPECT_LE(coarse_error, std::max(jacobi_error, 10.0f * tolerance));
}

/* The first guess of the implicit springs' solve is the Galerkin projection of the solution
 * onto the last steps' solutions (lcp/implicit_springs.hh, history_). Three motions of a block
 * of hair (7 × 7 × 16 particles, roots fixed), 84 steps of 6 ms each: a push growing steadily
 * (the impulse grows step by step: a line through the last two solutions predicts it), a
 * swaying root (smooth), and a stretched block let go without damping (the springs ring, about
 * a quarter period a step: Δv turns from one step to the next, and extrapolating it would
 * miss). Counted: every matrix product, the first guess's included. */
TEST(LcpImplicitSprings, FirstGuessFromTheLastTwoSolutionsSavesProducts)
{
  const float a = 0.005f, dt = 0.006f;
  const Block block = hair_block(a);
  const int64_t n = int64_t(block.positions.size());
  const std::vector<float> masses(size_t(n), 10.0f * a * a * a);
  const LcpConnections connections =
      build_connections(block.positions, block.directions, block.is_root, 1.33f * a, 0.5f, 12);
  const float area = std::pow(masses[0] / 1300.0f, 2.0f / 3.0f);
  const std::vector<float> alpha_k(size_t(connections.size()), 1.0e4f * area / a);
  enum class Motion { Pushed, Swayed, Ringing };
  const auto products = [&](const Motion motion, const int history) {
    std::vector<vec3> positions = block.positions, velocities(size_t(n), vec3(0.0f));
    if (motion == Motion::Ringing) {
      for (int64_t i = 0; i < n; i++) {
        positions[size_t(i)].z *= 1.3f; /* stretched by 30% */
      }
    }
    ImplicitSprings springs;
    springs.guess_history = history;
    springs.velocity_tolerance = 1e-4f * a / dt; /* the LCP solver's */
    int total = 0;
    for (int step = 0; step < 84; step++) {
      const float t = float(step) * dt;
      for (int64_t i = 0; i < n; i++) {
        if (block.is_root[size_t(i)]) {
          if (motion == Motion::Swayed) { /* 2 cm at 3 Hz, moved by the step's end */
            positions[size_t(i)].x =
                block.positions[size_t(i)].x + 0.02f * std::sin(6.0f * 3.14159f * (t + dt));
          }
        }
        else if (motion != Motion::Ringing) { /* hanging along +Z, and pushed along X */
          velocities[size_t(i)] +=
              dt * vec3(motion == Motion::Pushed ? 40.0f * t : 0.0f, 0.0f, 9.81f);
        }
      }
      const ImplicitSprings::Result result =
          springs.step(connections, positions, alpha_k, motion == Motion::Ringing ? 0.0f : 0.005f,
                       masses, block.is_root, dt, nullptr, velocities);
      EXPECT_LE(result.max_correction, springs.velocity_tolerance);
      total += result.products;
      for (int64_t i = 0; i < n; i++) {
        positions[size_t(i)] += dt * velocities[size_t(i)];
      }
    }
    return total;
  };
  for (const Motion motion : { Motion::Pushed, Motion::Swayed, Motion::Ringing }) {
    const int none = products(motion, 0), last = products(motion, 1), two = products(motion, 2);
    std::printf("motion %d: matrix products from zero %d, from the last solution %d, from the "
                "last two %d\n",
                int(motion), none, last, two);
    /* The projection onto two solutions costs one product more than onto the last alone
     * (two more than from zero): it pays where the motion is smooth, and costs little where
     * the springs ring and backward Euler damps Δv away within a few steps. Before it, the
     * solve started from the last solution unscaled: 1,237, 2,144 and 1,234 products. */
    if (motion == Motion::Ringing) {
      EXPECT_LE(two, last + last / 8);
      EXPECT_LE(two, none + none / 8);
    }
    else {
      EXPECT_LE(two, last) << "motion " << int(motion);
      EXPECT_LT(2 * two, none) << "motion " << int(motion);
    }
  }
}
