/* Petrovic, Henne and Anderson 2006: the density grid (eq. 1), velocity smoothing (§5.1), the
 * density force of §5.2 (eq. 3) and the hair-shell normals (§4.1, eq. 2), as properties of the
 * kernels, without the strand solver. */
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "core/parallel.hh"
#include "volume/density_grid_petrovic2006.hh"
#include "volume/density_target_petrovic2006.hh"
#include "volume/hair_shell_petrovic2006.hh"
#include "volume/velocity_smoothing_petrovic2006.hh"
#include "volume/volume_pass.hh"

using namespace hairdyn;
using glm::vec2;

namespace {

std::vector<vec3> random_points(const int64_t n, const vec3 &lo, const vec3 &hi,
                                const unsigned seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<vec3> points(static_cast<size_t>(n));
  for (vec3 &p : points) {
    p = lo + (hi - lo) * vec3(u(rng), u(rng), u(rng));
  }
  return points;
}

GridFrame grid_of(const Span<vec3> points, const float cell, const int margin,
                  const mat4 &head_to_world = mat4(1.0f))
{
  return grid_around(head_box(points, glm::inverse(head_to_world)), cell, margin, head_to_world);
}

std::vector<float> density_of(const GridFrame &grid, const Span<vec3> points)
{
  PointBins bins;
  bin_points(grid, points, bins);
  std::vector<float> density(static_cast<size_t>(grid.vertices_num()));
  std::vector<float> scratch;
  splat_density(grid, bins, density, scratch);
  return density;
}

double kinetic_energy(const Span<vec3> velocities)
{
  double sum = 0.0;
  for (const vec3 &v : velocities) {
    sum += 0.5 * double(glm::dot(v, v));
  }
  return sum;
}

/* Grid velocity at every point and the drag of §5.1 on all of them. */
void smooth(const Span<vec3> points, const float cell, const int radius, const float strength,
            std::vector<vec3> &velocities)
{
  const GridFrame grid = grid_of(points, cell, radius + 1);
  PointBins bins;
  bin_points(grid, points, bins);
  VelocityGrids grids;
  smooth_grid_velocity(grid, bins, velocities, radius, grids);
  std::vector<vec3> positions(points.begin(), points.end());
  drag_toward(grid, bins, grids, strength, 0.01f, {}, positions, velocities);
}

}  // namespace

/* eq. 1: a node exactly on a vertex has weight 1 there and 0 at every other vertex. The values
 * are exact binary fractions, so the node is exactly on the lattice. */
TEST(VolumeDensity, NodeAtVertexGivesDensityOne)
{
  const mat4 head = glm::translate(mat4(1.0f), vec3(0.5f, -1.0f, 2.0f));
  const std::vector<vec3> points = {vec3(0.5f, 0.75f, 1.0f) + vec3(head[3]),
                                    vec3(1.5f, 1.5f, 1.75f) + vec3(head[3])};
  const GridFrame grid = grid_of(points, 0.25f, 1, head);
  const std::vector<float> density = density_of(grid, points);
  const vec3 g = grid.to_grid(points[0]);
  ASSERT_EQ(g, glm::floor(g));
  const int64_t at = grid.vertex_index(int(g.x), int(g.y), int(g.z));
  EXPECT_EQ(density[size_t(at)], 1.0f);
  double others = 0.0;
  for (size_t v = 0; v < density.size(); v++) {
    others += v == size_t(at) ? 0.0 : density[v];
  }
  EXPECT_EQ(others, 1.0); /* the second node, on a vertex too */
}

/* eq. 1: the tent weights of a node sum to 1 over its cell's corners, so the grid's total is
 * the number of nodes inside it, whatever the grid's placement. */
TEST(VolumeDensity, TotalDensityIsNodesInside)
{
  const std::vector<vec3> points = random_points(5000, vec3(-0.2f), vec3(0.2f), 1);
  GridFrame grid = grid_of(points, 0.03f, 1);
  grid.origin += ivec3(3, 2, 4); /* a grid that cuts through the cloud */
  grid.size -= ivec3(6, 7, 5);
  int64_t inside = 0;
  for (const vec3 &p : points) {
    const vec3 g = grid.to_grid(p);
    inside += glm::all(glm::greaterThanEqual(g, vec3(0.0f))) &&
              glm::all(glm::lessThanEqual(g, vec3(grid.size - 1)));
  }
  ASSERT_GT(inside, 1000);
  ASSERT_LT(inside, 5000);
  double total = 0.0;
  for (const float d : density_of(grid, points)) {
    total += d;
  }
  EXPECT_NEAR(total, double(inside), 1e-6 * double(inside));
}

/* A splat of several chunks (more than splat_chunk_points points) whose chunks each reach only
 * a slab of the grid, as a groom's do, gives at every vertex the plain sum of eq. 1's terms. */
TEST(VolumeDensity, ChunkedSplatIsThePlainSum)
{
  std::vector<vec3> points = random_points(3 * splat_chunk_points + 123, vec3(-0.2f),
                                           vec3(0.2f), 4);
  std::sort(points.begin(), points.end(), [](const vec3 &a, const vec3 &b) { return a.z < b.z; });
  const GridFrame grid = grid_of(points, 0.02f, 1);
  std::vector<double> expected(size_t(grid.vertices_num()), 0.0);
  for (const vec3 &p : points) {
    const vec3 g = grid.to_grid(p);
    const ivec3 cell = glm::min(ivec3(g), grid.size - 2);
    for (int c = 0; c < 8; c++) {
      const ivec3 v = cell + ivec3(c & 1, (c >> 1) & 1, c >> 2);
      const vec3 w = 1.0f - glm::abs(g - vec3(v));
      expected[size_t(grid.vertex_index(v.x, v.y, v.z))] += double(w.x) * w.y * w.z;
    }
  }
  const std::vector<float> density = density_of(grid, points);
  for (size_t v = 0; v < density.size(); v++) {
    ASSERT_NEAR(density[v], expected[v], 1e-5 * (1.0 + expected[v])) << "vertex " << v;
  }
}

/* The gather splat and the smoothing give the same bits on 1 and 2 threads. */
TEST(VolumeDensity, SameBitsOnOneAndTwoThreads)
{
  const std::vector<vec3> points = random_points(40000, vec3(-0.15f), vec3(0.15f), 2);
  const std::vector<vec3> start = random_points(40000, vec3(-1.0f), vec3(1.0f), 3);
  const GridFrame grid = grid_of(points, 0.01f, 2);
  std::vector<float> density[2];
  std::vector<vec3> velocities[2];
  for (int threads = 1; threads <= 2; threads++) {
    set_thread_num(threads);
    density[threads - 1] = density_of(grid, points);
    velocities[threads - 1] = start;
    smooth(points, 0.01f, 2, 0.5f, velocities[threads - 1]);
  }
  set_thread_num(0);
  ASSERT_EQ(density[0].size(), density[1].size());
  EXPECT_EQ(std::memcmp(density[0].data(), density[1].data(), density[0].size() * sizeof(float)), 0);
  EXPECT_EQ(std::memcmp(velocities[0].data(), velocities[1].data(), start.size() * sizeof(vec3)),
            0);
}

/* A grid that would be too large takes a coarser cell rather than the memory. */
TEST(VolumeDensity, HugeBoxCoarsensTheCell)
{
  HeadBox box;
  box.lo = vec3(-100.0f);
  box.hi = vec3(100.0f);
  const GridFrame grid = grid_around(box, 0.01f, 1, mat4(1.0f));
  EXPECT_LE(grid.vertices_num(), max_grid_vertices);
  EXPECT_GT(grid.cell_size, 0.01f);
}

/* §5.1: the drag toward the filtered grid velocity never adds kinetic energy (the map is
 * symmetric with eigenvalues in [0, 1]), for any strength and filter width. */
TEST(VolumeSmoothing, NeverAddsKineticEnergy)
{
  const std::vector<vec3> points = random_points(3000, vec3(-0.1f), vec3(0.1f), 4);
  const std::vector<vec3> start = random_points(3000, vec3(-1.0f), vec3(1.0f), 5);
  const double before = kinetic_energy(start);
  for (const int radius : {0, 1, 2}) {
    for (const float strength : {0.1f, 0.5f, 1.0f}) {
      std::vector<vec3> velocities = start;
      smooth(points, 0.02f, radius, strength, velocities);
      const double after = kinetic_energy(velocities);
      EXPECT_LE(after, before * (1.0 + 1e-6)) << "radius " << radius << " s " << strength;
      EXPECT_LT(after, before) << "random velocities lose energy to smoothing";
    }
  }
  /* A single fast node among still ones slows down (the paper's example). */
  std::vector<vec3> velocities(points.size(), vec3(0.0f));
  velocities[17] = vec3(1.0f, 0.0f, 0.0f);
  smooth(points, 0.02f, 1, 0.5f, velocities);
  EXPECT_LT(glm::length(velocities[17]), 0.6f);
}

/* §5.1: a uniform velocity field is unchanged (the filter preserves constants where there is
 * hair). */
TEST(VolumeSmoothing, UniformFieldUnchanged)
{
  const std::vector<vec3> points = random_points(3000, vec3(-0.1f), vec3(0.1f), 6);
  const vec3 v0(0.3f, -0.2f, 0.1f);
  for (const int radius : {0, 2}) {
    std::vector<vec3> velocities(points.size(), v0);
    smooth(points, 0.015f, radius, 1.0f, velocities);
    for (const vec3 &v : velocities) {
      ASSERT_LT(glm::length(v - v0), 1e-6f);
    }
  }
}

/* The force after eq. 3 is −∂E/∂P: compared with central differences of E in grid units, for
 * nodes inside cells (the reference differentiates eq. 3 numerically). */
TEST(VolumeTarget, ForceIsMinusGradientOfEnergy)
{
  std::vector<vec3> points = random_points(200, vec3(-0.1f), vec3(0.1f), 7);
  const std::vector<vec3> target_points = random_points(200, vec3(-0.08f), vec3(0.12f), 8);
  DensityTarget target(target_points, mat4(1.0f));
  HeadBox box = head_box(points, mat4(1.0f));
  box.include(target.box());
  box.lo -= 0.05f; /* room for the moved node */
  box.hi += 0.05f;
  const GridFrame grid = grid_around(box, 0.04f, 1, mat4(1.0f));
  TargetGrids grids;
  PointBins bins;
  const auto energy = [&]() {
    bin_points(grid, points, bins);
    return target_error(grid, bins, target, grids);
  };
  const double e0 = energy();
  EXPECT_GT(e0, 1.0);
  std::vector<vec3> forces(points.size());
  density_forces(grid, bins, grids.difference, forces);
  const float eps = 1e-3f * grid.cell_size;
  for (const size_t i : {size_t(0), size_t(50), size_t(123)}) {
    for (int axis = 0; axis < 3; axis++) {
      const vec3 p = points[i];
      points[i][axis] = p[axis] + eps;
      const double plus = energy();
      points[i][axis] = p[axis] - eps;
      const double minus = energy();
      points[i] = p;
      const double numeric = -(plus - minus) / (2.0 * double(eps) / double(grid.cell_size));
      EXPECT_NEAR(forces[i][axis], numeric, 2e-2 * std::max(1.0, std::abs(numeric)))
          << "node " << i << " axis " << axis;
    }
  }
}

/* §4.1: fast sweeping gives the distance to a sphere. The density is threshold + (R − r), whose
 * iso-surface at the threshold is the sphere of radius R; S must be r − R. */
TEST(VolumeShell, FastSweepingSolvesEikonalForASphere)
{
  const ivec3 size(41, 41, 41);
  const float h = 0.01f, radius = 0.12f;
  const vec3 center = 0.5f * h * vec3(size - 1) + vec3(0.0013f, -0.0021f, 0.0007f);
  std::vector<float> density(static_cast<size_t>(size.x * size.y * size.z));
  for (int k = 0; k < size.z; k++) {
    for (int j = 0; j < size.y; j++) {
      for (int i = 0; i < size.x; i++) {
        const float r = glm::length(h * vec3(i, j, k) - center);
        density[size_t((k * size.y + j) * size.x + i)] = 2.0f + (radius - r);
      }
    }
  }
  std::vector<float> distance(density.size());
  signed_distance_fast_sweeping(size, h, density, 2.0f, distance);
  float worst = 0.0f;
  for (int k = 0; k < size.z; k++) {
    for (int j = 0; j < size.y; j++) {
      for (int i = 0; i < size.x; i++) {
        const float r = glm::length(h * vec3(i, j, k) - center);
        const size_t v = size_t((k * size.y + j) * size.x + i);
        worst = std::max(worst, std::abs(distance[v] - (r - radius)));
      }
    }
  }
  /* The closest points are refined onto the trilinear shell: errors of a few percent of a cell. */
  EXPECT_LT(worst, 0.25f * h);
}

namespace {

/* Vertical strands filling a ball of radius R about `center`: chords on a square lattice of
 * spacing `spacing`, nodes `step` apart. */
void ball_of_strands(const vec3 &center, const float radius, const float spacing, const float step,
                     std::vector<int32_t> &r_offsets, std::vector<vec3> &r_positions)
{
  r_offsets.assign(1, 0);
  r_positions.clear();
  const int n = int(radius / spacing);
  for (int a = -n; a <= n; a++) {
    for (int b = -n; b <= n; b++) {
      const vec2 xy = spacing * vec2(float(a), float(b)) + vec2(0.3f, 0.1f) * spacing;
      const float half = std::sqrt(std::max(radius * radius - glm::dot(xy, xy), 0.0f));
      const int nodes = int(2.0f * half / step) + 1;
      if (nodes < 2) {
        continue;
      }
      for (int i = 0; i < nodes; i++) {
        const float z = -half + 2.0f * half * float(i) / float(nodes - 1);
        r_positions.push_back(center + vec3(xy, z));
      }
      r_offsets.push_back(int32_t(r_positions.size()));
    }
  }
}

}  // namespace

/* §4.1, eq. 2: for strands filling a ball densely, the shell is a sphere and the normals of the nodes at
 * the surface are radial to within 5°. */
TEST(VolumeShell, BallNormalsAreRadial)
{
  const vec3 center(0.02f, -0.03f, 1.5f);
  const float radius = 0.1f;
  std::vector<int32_t> offsets;
  std::vector<vec3> positions;
  /* About 30 nodes per grid vertex inside; the shell at a quarter of that, the density blurred
   * over 3 cells so that the shell is the ball's and not the chords' sampling pattern. */
  ball_of_strands(center, radius, 0.004f, 0.004f, offsets, positions);
  VolumeParams params;
  params.shell_cell_size = 0.0125f;
  params.shell_threshold = 8.0f;
  params.shell_blur = 3;
  const HairShell shell(offsets, positions, mat4(1.0f), params);
  int surface_nodes = 0;
  float worst_degrees = 0.0f;
  for (size_t i = 0; i < positions.size(); i++) {
    const vec3 radial = positions[i] - center;
    if (glm::length(radial) < 0.9f * radius) {
      continue;
    }
    surface_nodes++;
    const float c = glm::dot(shell.rest_normals()[int64_t(i)], glm::normalize(radial));
    worst_degrees = std::max(worst_degrees, std::acos(std::min(c, 1.0f)) * 180.0f / float(M_PI));
  }
  EXPECT_GT(surface_nodes, 500);
  EXPECT_LT(worst_degrees, 5.0f);
  std::printf("ball of %d strands: worst angle to radial at the surface %.2f° over %d nodes\n",
              int(offsets.size() - 1), worst_degrees, surface_nodes);
}

/* §4.1, last paragraph: for a groom turned and moved rigidly with the head, the normals carried
 * by parallel transport are the rotated rest normals. */
TEST(VolumeShell, TransportFollowsRigidMotion)
{
  std::vector<int32_t> offsets{0};
  std::vector<vec3> rest;
  for (int s = 0; s < 60; s++) {
    const float a = 0.3f * float(s);
    const vec3 root(0.08f * std::cos(a), 0.08f * std::sin(a), 0.02f * float(s % 7));
    vec3 p = root;
    for (int i = 0; i < 12; i++) {
      rest.push_back(p);
      p += 0.015f * glm::normalize(vec3(std::cos(a) + 0.3f * std::sin(float(i)), std::sin(a),
                                        -1.0f + 0.2f * std::cos(1.7f * float(i))));
    }
    offsets.push_back(int32_t(rest.size()));
  }
  const mat4 head_rest = glm::translate(mat4(1.0f), vec3(0.1f, 0.0f, 1.6f));
  for (vec3 &p : rest) {
    p = transform_point(head_rest, p);
  }
  VolumeParams params;
  params.shell_threshold = 0.5f;
  const HairShell shell(offsets, rest, head_rest, params);

  const mat4 motion = glm::rotate(glm::translate(mat4(1.0f), vec3(-0.3f, 0.2f, 0.1f)), 1.1f,
                                  glm::normalize(vec3(0.3f, -0.5f, 0.8f)));
  std::vector<vec3> moved(rest.size());
  for (size_t i = 0; i < rest.size(); i++) {
    moved[i] = transform_point(motion, rest[i]);
  }
  std::vector<vec3> normals(rest.size());
  shell.transport(moved, motion * head_rest, normals);
  float worst = 0.0f;
  for (size_t i = 0; i < rest.size(); i++) {
    worst = std::max(worst, glm::length(normals[i] - mat3(motion) * shell.rest_normals()[int64_t(i)]));
  }
  EXPECT_LT(worst, 1e-4f);
  std::printf("transported normals against the rotated rest normals: largest difference %.2e\n",
              worst);
  /* At the rest pose the transport gives the rest normals back. */
  shell.transport(rest, head_rest, normals);
  for (size_t i = 0; i < rest.size(); i++) {
    ASSERT_LT(glm::length(normals[i] - shell.rest_normals()[int64_t(i)]), 1e-5f);
  }
}
