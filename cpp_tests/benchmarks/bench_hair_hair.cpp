/* Hair–hair collision (Ward & Lin 2003 §5.3) on 10,000 strands × 16 segments: the pass's time
 * per substep against the strand solver's own substep on the same groom (the goal:
 * hair–hair at most 1× the strand step; Ward's Table 1 had collision 70× the dynamics).
 *
 * The groom: strands rooted on a jittered grid over the top of a 0.1 m head sphere, combed
 * down and back with a gentle curl, then let settle for a few frames so that the contacts are
 * those of hanging hair. */
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <random>

#include "collision/hair_hair_ward2003.hh"
#include "core/parallel.hh"
#include "result_hash.hh"
#include "strands/strand_solver.hh"

using namespace hairdyn;

namespace {

constexpr int segments_num = 16;

/* The head's turn at `frame`: about Z at 0.02 rad a frame. */
mat4 head(const int frame)
{
  return glm::rotate(mat4(1.0f), 0.02f * float(frame), vec3(0, 0, 1));
}

struct SettledGroom {
  std::vector<int32_t> offsets{0};
  std::vector<vec3> rest;
  std::unique_ptr<StrandSolver> solver;
  /* The frame the head's turn has reached: the benchmarks that step the groom go on from it
   * (starting each call from frame 12 again, the head jumped back by up to a radian within
   * one frame, and the whipped strands took hundreds of turn-limited steps). */
  int frame = 12;

  /* With `pass`, the groom settles with it (hair–hair on, as a user runs it). */
  explicit SettledGroom(const int64_t strands_num, SubstepPass *pass = nullptr)
  {
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> jitter(-0.5f, 0.5f);
    const int side = int(std::ceil(std::sqrt(double(strands_num))));
    for (int64_t s = 0; s < strands_num; s++) {
      /* Root: a grid cell over the cap of the sphere (polar angle up to 80°). */
      const float u = (float(s % side) + 0.5f + jitter(rng)) / float(side);
      const float v = (float(s / side) + 0.5f + jitter(rng)) / float(side);
      const float polar = 1.4f * std::sqrt(u), azimuth = 2.0f * float(M_PI) * v;
      const vec3 normal(std::sin(polar) * std::cos(azimuth), std::sin(polar) * std::sin(azimuth),
                        std::cos(polar));
      vec3 p = 0.1f * normal;
      for (int i = 0; i <= segments_num; i++) {
        rest.push_back(p);
        const float t = float(i) / float(segments_num);
        const vec3 down = glm::normalize(glm::mix(normal, vec3(0.0f, -0.3f, -1.0f), t));
        const vec3 curl = 0.2f * std::sin(9.0f * t + float(s)) * glm::normalize(glm::cross(down, vec3(0.3f, 0.2f, 1.0f)));
        p += (0.3f / float(segments_num)) * glm::normalize(down + curl);
      }
      offsets.push_back(int32_t(rest.size()));
    }
    StrandParams params;
    params.substeps = 1;
    solver = std::make_unique<StrandSolver>(offsets, rest, mat4(1.0f), Span<vec3>(), params);
    if (pass != nullptr) {
      solver->add_pass(pass);
    }
    for (int f = 0; f < frame; f++) {
      solver->step(1.0f / 96.0f, head(f));
    }
  }
};

SettledGroom &groom()
{
  static SettledGroom settled(10000);
  return settled;
}

}  // namespace

/* One hair–hair pass (one substep's worth) over the settled groom. */
static void BM_HairHairSubstep(benchmark::State &state)
{
  set_thread_num(int(state.range(0)));
  const SettledGroom &g = groom();
  std::vector<vec3> positions, velocities;
  SweptSphereParams params;
  params.hair_hair = true;
  SegmentGridScratch scratch;
  std::vector<SegmentContact> contacts;
  HairHairStats stats;
  /* The settled groom's state, fresh for each call (the pass moves the nodes). */
  const auto settled_state = [&]() {
    positions.assign(g.solver->positions().begin(), g.solver->positions().end());
    velocities.assign(g.solver->velocities().begin(), g.solver->velocities().end());
    SubstepState s;
    s.h = 1.0f / 96.0f;
    s.curve_offsets = g.offsets;
    s.positions_wo = positions;
    s.velocities_wo = velocities;
    return s;
  };
  /* The pass keeps its scratch from substep to substep: the timed calls reuse it. */
  resolve_hair_hair(params, settled_state(), scratch, contacts);
  for (auto _ : state) {
    state.PauseTiming();
    const SubstepState s = settled_state();
    state.ResumeTiming();
    stats = resolve_hair_hair(params, s, scratch, contacts);
    benchmark::DoNotOptimize(positions.data());
  }
  /* The result's bits: equal across versions that change the speed but not the result. */
  const uint32_t hash = result_hash({positions, velocities});
  state.counters["result_hash"] = double(hash);
  state.counters["crossed"] = double(stats.crossed_num);
  state.counters["pairs"] = double(stats.pairs_num);
  state.counters["candidates"] = double(stats.candidates_num);
  /* The grid's cells across its columns. */
  state.counters["cell_u_mm"] = 1e3 * double(scratch.cell_size.y);
  state.counters["cell_v_mm"] = 1e3 * double(scratch.cell_size.z);
  set_thread_num(0);
}
BENCHMARK(BM_HairHairSubstep)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

/* The strand solver's own substep on the same groom (one frame of one substep). */
static void BM_StrandSubstepSameGroom(benchmark::State &state)
{
  set_thread_num(int(state.range(0)));
  SettledGroom &g = groom();
  for (auto _ : state) {
    g.solver->step(1.0f / 96.0f, head(g.frame++));
    benchmark::DoNotOptimize(g.solver->positions().data());
  }
  set_thread_num(0);
}
BENCHMARK(BM_StrandSubstepSameGroom)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

/* The pass as it runs in a simulation with hair–hair on: the groom settled with the pass (so
 * each substep starts where the last one's pass left the nodes, not from a groom that passed
 * through itself while it settled without it), then the same 12 frames of the head turn, one
 * substep each, from the settled state on every thread count (each run steps a copy: the
 * figures do not depend on which runs came before). Counters per substep, summed over the
 * timed frames: hair_hair_ms (the pass, as the solver times it), strand_ms (the rest of the
 * step: the strands' advance and the take-back of the pass's changes) and their ratio, share
 * (the goal: at most 1). */
static void BM_HairHairInSimulation(benchmark::State &state)
{
  set_thread_num(int(state.range(0)));
  SweptSphereParams params;
  params.hair_hair = true;
  static HairHairPass pass(params);
  static const SettledGroom g(10000, &pass);
  StrandSolver solver = *g.solver;
  int frame = g.frame;
  double pass_ms = 0.0, step_ms = 0.0;
  pass.reset_stats();
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    solver.step(1.0f / 96.0f, head(frame++));
    step_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                   .count();
    pass_ms += solver.pass_ms("hair_hair");
    benchmark::DoNotOptimize(solver.positions().data());
  }
  const double substeps = double(state.iterations());
  state.counters["hair_hair_ms"] = pass_ms / substeps;
  state.counters["strand_ms"] = (step_ms - pass_ms) / substeps;
  state.counters["share"] = pass_ms / (step_ms - pass_ms);
  state.counters["pairs"] = double(pass.stats().pairs_num) / substeps;
  state.counters["candidates"] = double(pass.stats().candidates_num) / substeps;
  state.counters["crossed"] = double(pass.stats().crossed_num) / substeps;
  set_thread_num(0);
}
BENCHMARK(BM_HairHairInSimulation)
    ->Arg(1)
    ->Arg(2)
    ->Iterations(12)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
