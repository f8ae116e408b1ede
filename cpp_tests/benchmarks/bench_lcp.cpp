/* LCP (Bando 2003) throughput: simulated frames per second (1/24 s frames) for 2,000 and
 * 20,000 particles of back hair under gravity with a swaying head, on 1 and 2 threads.
 * Arguments: target particle count, threads, implicit springs (1) or explicit (0), implicit
 * pressure (1) or explicit (0). The counter "substeps" is the substeps per frame,
 * "cg_per_substep" the conjugate-gradient iterations of the implicit springs per substep and
 * "products_per_substep" their matrix products (the iterations' and the first guess's),
 * "searches_per_frame" the neighbour searches a frame (core/spatial_grid.hh's Verlet list). */
#include <benchmark/benchmark.h>

#include <cmath>

#include "../lcp_scenes.hh"
#include "core/parallel.hh"

using namespace hairdyn;
using namespace hairdyn::lcp_scenes;

static void BM_LcpFrame(benchmark::State &state)
{
  const int64_t target = state.range(0);
  set_thread_num(int(state.range(1)));
  /* Back hair: a 20 × 10 cm scalp, 20 cm long: about 4.4e-3 m³ of hair. */
  const double volume = 0.2 * 0.1 * 0.22;
  const float spacing = float(std::cbrt(0.573 * volume / double(target)));
  LcpParams params = params_for_spacing(spacing);
  params.particle_num = int32_t(target);
  params.max_length = 0.2f;
  params.root_depth = 0.02f;
  params.implicit_springs = state.range(2) != 0;
  params.implicit_pressure = state.range(3) != 0;
  const LcpParticles particles = sample(down_facing_rectangle(0.2f, 0.1f, 20, 10), params);
  LcpSolver solver(params, particles, mat4(1.0f));
  /* Settle so the measured frames are the steady state. */
  for (int frame = 0; frame < 4; frame++) {
    solver.step(1.0f / 24.0f, mat4(1.0f));
  }
  int frame = 0;
  const int64_t searches_before = solver.neighbor_searches();
  double substeps = 0.0, iterations = 0.0, products = 0.0;
  for (auto _ : state) {
    const float angle = 0.3f * std::sin(float(frame++) * 0.2f);
    solver.step(1.0f / 24.0f, glm::rotate(mat4(1.0f), angle, vec3(0.0f, 0.0f, 1.0f)));
    substeps += solver.substeps_used();
    iterations += solver.spring_iterations();
    products += solver.spring_products();
    benchmark::DoNotOptimize(solver.positions().data());
  }
  state.counters["particles"] = double(solver.particles_num());
  state.counters["pairs"] = double(solver.pairs_num());
  state.counters["substeps"] = substeps / double(state.iterations());
  state.counters["searches_per_frame"] =
      double(solver.neighbor_searches() - searches_before) / double(state.iterations());
  state.counters["cg_per_substep"] = substeps > 0.0 ? iterations / substeps : 0.0;
  state.counters["products_per_substep"] = substeps > 0.0 ? products / substeps : 0.0;
  state.counters["frames_per_s"] =
      benchmark::Counter(double(state.iterations()), benchmark::Counter::kIsRate);
  set_thread_num(0);
}
BENCHMARK(BM_LcpFrame)
    ->Args({ 2000, 1, 1, 0 })
    ->Args({ 2000, 2, 1, 0 })
    ->Args({ 20000, 2, 1, 0 })
    ->Args({ 2000, 2, 1, 1 })
    ->Args({ 20000, 2, 1, 1 })
    ->Args({ 2000, 2, 0, 0 })
    ->Args({ 20000, 2, 0, 0 })
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2.0);
