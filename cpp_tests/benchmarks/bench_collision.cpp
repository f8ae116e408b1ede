/* Collision query throughput (Kurihara 1993: cost independent of the mesh) and build cost.
 *
 * BM_FindContact/<triangles>: ColliderSet::find_contact per point on one core, for a UV sphere
 * of about 1,000 and 1,000,000 triangles, queried at points in a shell around the surface
 * (half inside: every query takes the full look-up path). items/s = queries per second.
 * BM_FindContactsBatch/<triangles>/<threads>: the parallel span kernel (avx2 = 1 where it runs
 * its AVX2 code).
 * BM_BuildCollider/<triangles>: what a deforming collider pays per frame (BVH, maps with the
 * automatic choice, exact distance).
 * BM_PenetrationStats/<triangles>: the report's exact penetration check (a BVH closest point
 * and pseudo-normal sign per point) over 4,800 points, head_shake.blend's node count, on one
 * core. items/s = points per second. */
#include <benchmark/benchmark.h>

#include <random>

#include "collision/collider.hh"
#include "core/parallel.hh"
#include "../collision_test_shapes.hh"

using namespace hairdyn;
using namespace hairdyn::test;

namespace {

/* 2 · segments · (rings - 1) triangles: 1,000 or 1,000,000. */
TestMesh sphere_with_triangles(const int64_t triangles_num)
{
  return triangles_num <= 1000 ? uv_sphere(1.0f, 25, 21) : uv_sphere(1.0f, 1000, 501);
}

/* The sphere, moved and turned: queries go through the world-to-map transform. */
ColliderSet make_set(const int64_t triangles_num)
{
  const TestMesh m = sphere_with_triangles(triangles_num);
  ColliderSet set;
  auto collider = std::make_shared<Collider>(ColliderMesh(m.vertices, m.triangles),
                                             Span<int32_t>(), Span<int32_t>(), CollisionParams{});
  collider->set_transform(glm::translate(mat4(1.0f), vec3(0.5f, 2.0f, -1.0f)) *
                          glm::rotate(mat4(1.0f), 0.4f, vec3(0, 0, 1)));
  set.add(collider);
  return set;
}

std::vector<vec3> shell_points(const int64_t num)
{
  std::mt19937 rng(1);
  std::normal_distribution<float> gauss;
  std::uniform_real_distribution<float> radius(0.9f, 1.1f);
  const mat4 placement = glm::translate(mat4(1.0f), vec3(0.5f, 2.0f, -1.0f)) *
                         glm::rotate(mat4(1.0f), 0.4f, vec3(0, 0, 1));
  std::vector<vec3> points(static_cast<size_t>(num));
  for (vec3 &p : points) {
    p = transform_point(placement, glm::normalize(vec3(gauss(rng), gauss(rng), gauss(rng))) * radius(rng));
  }
  return points;
}

}  // namespace

static void BM_FindContact(benchmark::State &state)
{
  const ColliderSet set = make_set(state.range(0));
  const std::vector<vec3> points = shell_points(1 << 16);
  int64_t hits = 0;
  for (auto _ : state) {
    for (const vec3 &p : points) {
      Contact contact;
      hits += set.find_contact(p, contact) ? 1 : 0;
      benchmark::DoNotOptimize(contact);
    }
  }
  state.SetItemsProcessed(state.iterations() * int64_t(points.size()));
  state.counters["inside_share"] = double(hits) / double(state.iterations() * int64_t(points.size()));
}
BENCHMARK(BM_FindContact)->Arg(1000)->Arg(1000000);

static void BM_FindContactsBatch(benchmark::State &state)
{
  const ColliderSet set = make_set(state.range(0));
  set_thread_num(int(state.range(1)));
  const std::vector<vec3> points = shell_points(1 << 18);
  std::vector<uint8_t> hit(points.size());
  std::vector<float> depth(points.size());
  std::vector<vec3> normal(points.size()), surface(points.size());
  for (auto _ : state) {
    find_contacts(set, points, hit, depth, normal, surface);
    benchmark::DoNotOptimize(depth.data());
  }
  state.SetItemsProcessed(state.iterations() * int64_t(points.size()));
  state.counters["avx2"] = collision_avx2_used() ? 1.0 : 0.0;
  set_thread_num(0);
}
BENCHMARK(BM_FindContactsBatch)
    ->Args({1000, 1})
    ->Args({1000, 2})
    ->Args({1000000, 1})
    ->Args({1000000, 2})
    ->UseRealTime();

static void BM_PenetrationStats(benchmark::State &state)
{
  set_thread_num(1);
  const ColliderSet set = make_set(state.range(0));
  const std::vector<vec3> points = shell_points(4800);
  for (auto _ : state) {
    benchmark::DoNotOptimize(set.penetration_stats(points, 1e-3f).max_depth);
  }
  state.SetItemsProcessed(state.iterations() * int64_t(points.size()));
  set_thread_num(0);
}
BENCHMARK(BM_PenetrationStats)->Arg(1000)->Arg(1000000)->Unit(benchmark::kMillisecond);

static void BM_BuildCollider(benchmark::State &state)
{
  const TestMesh m = sphere_with_triangles(state.range(0));
  const ColliderMesh mesh(m.vertices, m.triangles);
  for (auto _ : state) {
    Collider collider(mesh, {}, {}, CollisionParams{});
    benchmark::DoNotOptimize(collider.size());
  }
  state.SetItemsProcessed(state.iterations() * int64_t(m.triangles.size()));
}
BENCHMARK(BM_BuildCollider)->Arg(1000)->Arg(1000000)->Unit(benchmark::kMillisecond)->UseRealTime();
