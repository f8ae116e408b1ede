/* Grid work per substep of Petrovic 2006's volume pass for 10,000 strands × 16 segments, beside
 * one substep of the strand solver on the same groom, on 1 and 2 threads. The pass's share of
 * the strand step is BM_VolumePass / BM_StrandSubstep. */
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>

#include "core/parallel.hh"
#include "strands/strand_solver.hh"
#include "volume/volume_pass.hh"

using namespace hairdyn;

namespace {

constexpr int64_t strands_num = 10000;
constexpr int segments_num = 16;

/* Strands 0.3 m long hanging from the upper half of a 0.1 m sphere, bending outward and down,
 * with random velocities of about 0.5 m/s. */
struct BenchGroom {
  std::vector<int32_t> offsets{ 0 };
  std::vector<vec3> positions;
  std::vector<vec3> velocities;

  BenchGroom()
  {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (int64_t s = 0; s < strands_num; s++) {
      const float z = 0.05f + 0.95f * float(s) / float(strands_num);
      const float a = 2.39996f * float(s);
      const vec3 normal(std::sqrt(1.0f - z * z) * std::cos(a),
                        std::sqrt(1.0f - z * z) * std::sin(a), z);
      vec3 p = 0.1f * normal;
      for (int i = 0; i <= segments_num; i++) {
        positions.push_back(p);
        velocities.push_back(0.5f * vec3(u(rng), u(rng), u(rng)));
        const float t = float(i) / float(segments_num);
        p += (0.3f / float(segments_num)) * glm::normalize(glm::mix(normal, vec3(0, 0, -1), t));
      }
      offsets.push_back(int32_t(positions.size()));
    }
  }
};

}  // namespace

/* One substep of the pass: velocity smoothing, plus targeting when range(1) is 1. */
static void BM_VolumePass(benchmark::State &state)
{
  set_thread_num(int(state.range(0)));
  BenchGroom groom;
  VolumePass volume;
  if (state.range(1)) {
    std::vector<vec3> target = groom.positions;
    for (vec3 &p : target) {
      p += vec3(0.02f * std::sin(20.0f * p.z), 0.0f, 0.0f);
    }
    volume.set_target(target, mat4(1.0f));
  }
  SubstepState substep;
  substep.h = 1.0f / 96.0f;
  substep.curve_offsets = groom.offsets;
  substep.positions_wo = groom.positions;
  substep.velocities_wo = groom.velocities;
  const BenchGroom start;
  for (auto _ : state) {
    state.PauseTiming(); /* the same state every time: the pass moves the nodes */
    std::copy(start.positions.begin(), start.positions.end(), groom.positions.begin());
    std::copy(start.velocities.begin(), start.velocities.end(), groom.velocities.begin());
    state.ResumeTiming();
    volume.apply(substep);
    benchmark::DoNotOptimize(groom.velocities.data());
  }
  state.counters["density_max"] = volume.density_max();
  state.SetItemsProcessed(state.iterations() * int64_t(groom.positions.size()));
  set_thread_num(0);
}
BENCHMARK(BM_VolumePass)
    ->ArgsProduct({ { 1, 2 }, { 0, 1 } })
    ->ArgNames({ "threads", "target" })
    ->Unit(benchmark::kMillisecond);

/* One substep of the strand solver (implicit, wind on) on the same groom; with range(1) = 1 the
 * volume pass (smoothing) runs in it, and the counters give the pass's time and its share of
 * the rest of the substep. range(2) is the strand model: 0 articulated (the default, the
 * slower), 1 Kurihara 1993 (the cheaper step, against which the pass's share is largest). */
static void BM_StrandSubstep(benchmark::State &state)
{
  set_thread_num(int(state.range(0)));
  BenchGroom groom;
  StrandParams params;
  params.substeps = 1;
  params.model = state.range(2) ? StrandModel::Kurihara1993 : StrandModel::Articulated;
  WindParams wind;
  wind.speed = 2.0f;
  StrandSolver solver(groom.offsets, groom.positions, mat4(1.0f), {}, params, wind);
  VolumePass volume;
  if (state.range(1)) {
    solver.add_pass(&volume);
  }
  int substep = 0;
  double volume_ms = 0.0, total_ms = 0.0;
  for (auto _ : state) {
    const float t = float(substep++) / 96.0f;
    const mat4 head = glm::rotate(mat4(1.0f), 0.5f * std::sin(2.0f * t), vec3(0, 0, 1));
    const auto begin = std::chrono::steady_clock::now();
    solver.step(1.0f / 96.0f, head);
    total_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin)
                    .count();
    volume_ms += solver.pass_ms("volume");
    benchmark::DoNotOptimize(solver.positions().data());
  }
  if (state.range(1)) {
    state.counters["volume_ms"] = volume_ms / double(state.iterations());
    state.counters["volume_share"] = volume_ms / (total_ms - volume_ms);
  }
  state.SetItemsProcessed(state.iterations() * int64_t(groom.positions.size()));
  set_thread_num(0);
}
BENCHMARK(BM_StrandSubstep)
    ->ArgsProduct({ { 1, 2 }, { 0, 1 }, { 0, 1 } })
    ->ArgNames({ "threads", "volume", "kurihara" })
    ->Unit(benchmark::kMillisecond);
