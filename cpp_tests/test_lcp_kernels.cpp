/* SPH kernel of Bando 2003 eq. 2, density eq. 1 and the uniform-grid neighbour search. */
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "core/parallel.hh"
#include "core/spatial_grid.hh"
#include "core/sph_kernels.hh"
#include "lcp/interactions_bando2003.hh"

using namespace hairdyn;

TEST(LcpKernels, KernelIntegratesToOne)
{
  for (const float h : { 0.003f, 0.011f, 0.5f }) {
    /* ∫ W(r, h) 4π r² dr over [0, 2h], midpoint rule in double. */
    const int steps = 20000;
    double sum = 0.0;
    for (int k = 0; k < steps; k++) {
      const double r = (double(k) + 0.5) * 2.0 * double(h) / steps;
      sum += double(sph_kernel(float(r), h)) * 4.0 * M_PI * r * r * (2.0 * double(h) / steps);
    }
    EXPECT_NEAR(sum, 1.0, 1e-4) << "h = " << h;
    EXPECT_EQ(sph_kernel(2.0f * h, h), 0.0f);
    EXPECT_GT(sph_kernel(1.99f * h, h), 0.0f);
  }
}

TEST(LcpKernels, KernelIsContinuousAndGradientMatchesFiniteDifference)
{
  const float h = 0.01f;
  const float w_h = sph_kernel(h, h);
  EXPECT_NEAR(sph_kernel(h * (1.0f - 1e-5f), h) / w_h, sph_kernel(h * (1.0f + 1e-5f), h) / w_h,
              1e-4f);
  for (const float r : { 0.002f, 0.007f, 0.012f, 0.018f }) {
    const float eps = 1e-6f;
    const float fd = (sph_kernel(r + eps, h) - sph_kernel(r - eps, h)) / (2.0f * eps);
    EXPECT_NEAR(sph_kernel_derivative(r, h), fd, 2e-3f * std::abs(fd) + 1.0f) << r;
    EXPECT_LE(sph_kernel_derivative(r, h), 0.0f);
    /* The second derivative of the implicit pressure's pair springs. */
    const float eps2 = 1e-5f;
    const float fd2 =
        (sph_kernel_derivative(r + eps2, h) - sph_kernel_derivative(r - eps2, h)) / (2.0f * eps2);
    EXPECT_NEAR(sph_kernel_second_derivative(r, h), fd2, 1e-2f * std::abs(fd2)) << r;
  }
  /* ∂W/∂x_i points from j toward i's side: moving i toward j raises W. */
  const vec3 x_ij(0.008f, 0.0f, 0.0f);
  EXPECT_GT(sph_kernel_gradient_i(x_ij, h).x, 0.0f);
}

TEST(LcpKernels, DensityOfALatticeMatchesTheAnalyticSum)
{
  /* A cubic lattice of spacing a and particle mass m: inside, eq. 1 is the sum of m W over
   * the lattice offsets, and with h ≥ a that sum is close to m / a³. */
  const float a = 0.01f, h = 0.012f, m = 2e-5f;
  const int n = 13;
  std::vector<vec3> points;
  for (int z = 0; z < n; z++) {
    for (int y = 0; y < n; y++) {
      for (int x = 0; x < n; x++) {
        points.push_back(vec3(float(x), float(y), float(z)) * a);
      }
    }
  }
  double analytic = 0.0;
  for (int z = -3; z <= 3; z++) {
    for (int y = -3; y <= 3; y++) {
      for (int x = -3; x <= 3; x++) {
        analytic += double(m * sph_kernel(a * glm::length(vec3(float(x), float(y), float(z))), h));
      }
    }
  }
  SpatialGrid grid;
  grid.build(points, 2.0f * h);
  NeighborList neighbors;
  find_neighbors(grid, points, 2.0f * h, true, neighbors);
  std::vector<float> masses(points.size(), m), density(points.size());
  compute_density(points, masses, neighbors, h, density);
  const int center = (n / 2) * n * n + (n / 2) * n + n / 2;
  EXPECT_NEAR(double(density[size_t(center)]), analytic, 1e-5 * analytic);
  EXPECT_NEAR(analytic, double(m / (a * a * a)), 0.05 * double(m / (a * a * a)));
  /* A corner particle misses seven eighths of its neighbours: clearly lower density. */
  EXPECT_LT(density[0], 0.6f * density[size_t(center)]);
}

TEST(LcpKernels, GridFindsExactlyTheBruteForceNeighboursWithoutACap)
{
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-0.05f, 0.05f);
  std::vector<vec3> points(3000);
  for (vec3 &p : points) {
    p = vec3(u(rng), u(rng), u(rng));
  }
  /* A dense clump: far more neighbours than any fixed cap would allow. */
  for (int k = 0; k < 400; k++) {
    points.push_back(vec3(0.001f * u(rng), 0.001f * u(rng), 0.001f * u(rng)));
  }
  const float radius = 0.012f;
  SpatialGrid grid;
  grid.build(points, radius);
  NeighborList list;
  std::vector<int32_t> first_order; /* the rows' order, which must not depend on the threads */
  for (const int threads : { 1, 2 }) {
    set_thread_num(threads);
    find_neighbors(grid, points, radius, true, list);
    if (first_order.empty()) {
      first_order = list.indices;
    }
    ASSERT_EQ(list.indices, first_order) << "threads " << threads;
    for (size_t i = 0; i < points.size(); i += 7) {
      std::vector<int32_t> expected;
      for (size_t j = 0; j < points.size(); j++) {
        if (j != i && glm::length(points[j] - points[i]) < radius) {
          expected.push_back(int32_t(j));
        }
      }
      std::vector<int32_t> found(list.neighbors_of(int64_t(i)).begin(),
                                 list.neighbors_of(int64_t(i)).end());
      std::sort(found.begin(), found.end());
      ASSERT_EQ(found, expected) << "point " << i;
    }
  }
  set_thread_num(0);
  EXPECT_GE(list.neighbors_of(int64_t(points.size()) - 1).size(), 399);
}
