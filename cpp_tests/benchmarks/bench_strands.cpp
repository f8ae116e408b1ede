/* Strand dynamics throughput: vertex-substeps per second (segments advanced per second) for
 * 10,000 strands × 16 segments on a head that turns and sways, on 1 and 2 threads, for the
 * articulated model (kurihara:0) and the kurihara1993 model (kurihara:1), both implicit. */
#include <benchmark/benchmark.h>

#include <cmath>

#include "core/parallel.hh"
#include "result_hash.hh"
#include "strands/strand_solver.hh"

using namespace hairdyn;

namespace {

/* Wavy strands 0.3 m long rooted over the upper half of a 0.1 m sphere. */
void make_groom(const int64_t strands_num, const int segments_num,
                std::vector<int32_t> &r_offsets, std::vector<vec3> &r_positions)
{
  r_offsets.assign(1, 0);
  r_positions.clear();
  const float golden = float(M_PI) * (3.0f - std::sqrt(5.0f));
  for (int64_t s = 0; s < strands_num; s++) {
    const float z = 1.0f - float(s) / float(strands_num);
    const float r = std::sqrt(1.0f - z * z);
    const vec3 normal(r * std::cos(golden * float(s)), r * std::sin(golden * float(s)), z);
    const vec3 side = glm::normalize(glm::cross(normal, vec3(0.0f, 0.0f, 1.0f)) + vec3(1e-3f));
    vec3 p = 0.1f * normal;
    for (int i = 0; i <= segments_num; i++) {
      r_positions.push_back(p);
      const float t = float(i) / float(segments_num);
      const vec3 direction = glm::normalize(glm::mix(normal, vec3(0.0f, 0.0f, -1.0f), t) +
                                            0.3f * std::sin(12.0f * t) * side);
      p += (0.3f / float(segments_num)) * direction;
    }
    r_offsets.push_back(int32_t(r_positions.size()));
  }
}

}  // namespace

/* The benchmarks' head at `frame` (24 fps): ±0.5 rad about the vertical, ±5 cm along x. */
static mat4 bench_head(const int frame)
{
  const float t = float(frame) / 24.0f;
  return glm::rotate(glm::translate(mat4(1.0f), vec3(0.05f * std::sin(3.0f * t), 0, 0)),
                     0.5f * std::sin(2.0f * t), vec3(0, 0, 1));
}

static void BM_StrandStep(benchmark::State &state)
{
  const int64_t strands_num = state.range(0);
  const int segments_num = 16;
  set_thread_num(int(state.range(1)));
  std::vector<int32_t> offsets;
  std::vector<vec3> positions;
  make_groom(strands_num, segments_num, offsets, positions);
  StrandParams params;
  params.model = StrandModel(state.range(2));
  WindParams wind;
  wind.speed = 2.0f;
  StrandSolver solver(offsets, positions, mat4(1.0f), {}, params, wind);
  int frame = 0;
  for (auto _ : state) {
    solver.step(1.0f / 24.0f, bench_head(frame++));
    benchmark::DoNotOptimize(solver.positions().data());
  }
  state.SetItemsProcessed(state.iterations() * strands_num * segments_num * params.substeps);
  /* The result's bits after a fixed number of frames (the timed loop's count varies). */
  StrandSolver fixed(offsets, positions, mat4(1.0f), {}, params, wind);
  for (int f = 0; f < 4; f++) {
    fixed.step(1.0f / 24.0f, bench_head(f));
  }
  state.counters["result_hash"] = double(result_hash({fixed.positions(), fixed.velocities()}));
  set_thread_num(0);
}
BENCHMARK(BM_StrandStep)
    ->ArgNames({"strands", "threads", "kurihara"})
    ->Args({10000, 1, 0})
    ->Args({10000, 2, 0})
    ->Args({10000, 1, 1})
    ->Args({10000, 2, 1})
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

/* The cost of pinned points (groom/pins.hh) on 300 strands × 16 segments, one thread: no pins,
 * or every strand's tip pinned (AMD's ponytail pins both ends of its back strands). */
static void BM_StrandStepPinned(benchmark::State &state)
{
  const int64_t strands_num = 300;
  const int segments_num = 16;
  set_thread_num(1);
  std::vector<int32_t> offsets;
  std::vector<vec3> positions;
  make_groom(strands_num, segments_num, offsets, positions);
  StrandParams params;
  params.model = StrandModel(state.range(0));
  StrandSolver solver(offsets, positions, mat4(1.0f), {}, params);
  if (state.range(1)) {
    std::vector<uint8_t> pinned(positions.size(), 0);
    for (size_t c = 1; c < offsets.size(); c++) {
      pinned[size_t(offsets[c] - 1)] = 1;
    }
    solver.set_pinned(pinned);
  }
  int frame = 0;
  for (auto _ : state) {
    solver.step(1.0f / 24.0f, bench_head(frame++));
    benchmark::DoNotOptimize(solver.positions().data());
  }
  state.SetItemsProcessed(state.iterations() * strands_num * segments_num * params.substeps);
  set_thread_num(0);
}
BENCHMARK(BM_StrandStepPinned)
    ->ArgNames({"kurihara", "pinned"})
    ->Args({0, 0})
    ->Args({0, 1})
    ->Args({1, 0})
    ->Args({1, 1})
    ->Unit(benchmark::kMillisecond);
