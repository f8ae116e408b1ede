/* Kinematic baseline throughput: points placed per second for a head transform. */
#include <benchmark/benchmark.h>

#include "core/parallel.hh"
#include "groom/follow.hh"

using namespace hairdyn;

static void BM_FollowStep(benchmark::State &state)
{
  const int64_t strands = state.range(0);
  const int64_t points_per_strand = 17;
  set_thread_num(int(state.range(1)));
  std::vector<vec3> rest(size_t(strands * points_per_strand));
  std::vector<int32_t> offsets(size_t(strands + 1));
  for (int64_t i = 0; i < int64_t(rest.size()); i++) {
    rest[size_t(i)] = vec3(float(i % 97), float(i % 89), float(i % 83)) * 0.01f;
  }
  for (int64_t c = 0; c <= strands; c++) {
    offsets[size_t(c)] = int32_t(c * points_per_strand);
  }
  FollowSolver solver(offsets, rest, mat4(1.0f));
  float angle = 0.0f;
  for (auto _ : state) {
    angle += 0.01f;
    solver.step(glm::rotate(mat4(1.0f), angle, vec3(0, 1, 0)));
    benchmark::DoNotOptimize(solver.positions().data());
  }
  state.SetItemsProcessed(state.iterations() * int64_t(rest.size()));
  set_thread_num(0);
}
BENCHMARK(BM_FollowStep)->Args({10000, 1})->Args({10000, 2})->Unit(benchmark::kMicrosecond);
