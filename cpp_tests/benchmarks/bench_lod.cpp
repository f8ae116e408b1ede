/* Ward & Lin 2003, Tables 1 and 2, in form: a groom of 9,120 strands (Sintel's 228 guides,
 * 40 children around each, 32 points per strand) on Sintel's bust, wind blowing, 24 frames at
 * 24 fps. Per configuration, processor milliseconds per frame of the whole step with
 * hair-object collision, of the same step without it (dynamics; the level of detail's
 * selection still sees the bust hide hair), and their difference (collision):
 *
 *   FineStrands      every artist strand simulated (32 points each)
 *   FineStrandsHairHair  FineStrands with hair–hair collision (§5.3) between the artist
 *                    strands' swept spheres, counted as collision, as Ward's tables count it
 *                    (his fine strands' collision, 7.6 s against 0.1 s of dynamics, holds
 *                    hair–hair); the first 6 frames, as Lod/close_hair_hair
 *   FinestSkeletons  every skeleton of the hierarchy's finest level (Ward's "Fine Strands")
 *   CoarseStrips     only the top strips
 *   Lod/close        the level of detail, camera 0.45 m from the face (Table 1)
 *   Lod/zoom_out     the level of detail, camera moving from 0.45 m to 8 m (Table 2)
 *                    (the argument is the coarsest level, where hidden hair goes: 0, the
 *                    top strips; 2, the clusters of the finest strips' quadrants (these
 *                    strips split once); 3, their quadrants)
 *   Lod/close_coarser  Lod/close with the hair the camera sees at coarser levels too: the
 *                    camera's 0.45 m between distance_near 0.1 m and distance_far 0.5 m, and
 *                    motion asking for finer levels only from 2 m/s (velocity_slow) to 10 m/s
 *                    (velocity_fast): how error and speed trade once visible hair is not all
 *                    at the finest level (Ward's continuous levels, Table 1)
 *   Lod/close_hair_hair  Lod/close with hair–hair collision (§5.3) between the groups'
 *                    swept spheres, counted as collision (as Ward's tables count it); its
 *                    fine simulation has it too (the argument as for zoom_out)
 *
 * and for the level of detail fine_ms, the whole step of its fine simulation (the same solver
 * with the level of detail off: every finest skeleton stepped, with the same collision and
 * passes, and every artist strand placed around its skeleton as the level of detail places
 * it), speedup (fine_ms over total_ms: Ward's ratio, like for like), and lod_error: the mean distance (mm, and % of the mean strand
 * length) of its output from a fine simulation of the same frames (the same hierarchy with
 * the level of detail off: the finest level everywhere), over all strands and over the
 * strands whose skeleton the camera sees (visible_error_pct) and over those a top strip drives
 * (strip_error_pct), and the top strips' skeletons from the mean of their finest skeletons
 * (strip_skeleton_error_pct); and chaos_pct, the mean distance (% of the mean strand length)
 * between the fine simulation and its twin whose head is turned by 1 µrad (its strands start
 * about 0.2 µm apart): how far a perturbation that small grows, a floor under lod_error that no
 * approximation can go below. Skipped when the Sintel assets are missing. */
#include <benchmark/benchmark.h>

#include <cstdio>
#include <ctime>

#include "../lod_sintel_scene.hh"
#include "collision/hair_hair_ward2003.hh"
#include "groom/groom.hh"
#include "lod/lod_solver_ward2003.hh"

using namespace hairdyn;
using namespace hairdyn::test;

namespace {

/* A StrandSolver over the given skeletons of the hierarchy (the same shared root normal per
 * tree as LodSolver uses). */
StrandSolver skeleton_solver(const LodHierarchy &hierarchy, const std::vector<int32_t> &nodes)
{
  std::vector<int32_t> offsets{0};
  std::vector<vec3> rest, normals;
  for (const int32_t node : nodes) {
    const Span<vec3> skeleton = hierarchy.rest_skeleton(node);
    rest.insert(rest.end(), skeleton.begin(), skeleton.end());
    offsets.push_back(int32_t(rest.size()));
    normals.push_back(hierarchy.root_normal(hierarchy.top_node(node)));
  }
  return StrandSolver(offsets, rest, mat4(1.0f), normals, StrandParams(), sintel_wind());
}

/* Mean distance (m) of each active top strip's control points from the strand-weighted mean of
 * its finest skeletons in the fine simulation: whether the strip's skeleton moves as its
 * strands do on average (strip_error_pct then measures how far its strands spread from that
 * average, which one skeleton cannot show). 0 when no top strip is active. */
double strip_skeleton_error(const LodSolver &lod, const LodSolver &fine)
{
  const LodHierarchy &hierarchy = lod.hierarchy();
  const int32_t n = hierarchy.skeleton_points_num();
  std::vector<vec3> mean(static_cast<size_t>(n));
  double sum = 0.0;
  int64_t points = 0;
  const std::vector<int32_t> finest = hierarchy.level_nodes(hierarchy.max_depth());
  for (int64_t top = 0; top < hierarchy.top_nodes_num(); top++) {
    if (!lod.active()[top]) {
      continue;
    }
    std::fill(mean.begin(), mean.end(), vec3(0.0f));
    float weight = 0.0f;
    for (const int32_t node : finest) {
      if (hierarchy.top_node(node) == top) {
        const float strands = float(hierarchy.strands(node).size());
        for (int32_t k = 0; k < n; k++) {
          mean[size_t(k)] += strands * fine.skeleton(node)[k];
        }
        weight += strands;
      }
    }
    for (int32_t k = 0; k < n; k++) {
      sum += double(glm::length(lod.skeleton(top)[k] - mean[size_t(k)] / weight));
      points++;
    }
  }
  return points > 0 ? sum / double(points) : 0.0;
}

/* Processor time of the whole process (all threads), in ms: on a shared machine the wall
 * clock measures the other jobs too. Run with OMP_NUM_THREADS=1 for single-core figures. */
double milliseconds_since(const std::clock_t start)
{
  return 1000.0 * double(std::clock() - start) / double(CLOCKS_PER_SEC);
}

enum class Config {
  FineStrands,
  FineStrandsHairHair,
  FinestSkeletons,
  CoarseStrips,
  LodClose,
  LodCloseCoarser,
  LodZoomOut,
  LodCloseHairHair
};

/* ms per frame of `sintel_frames_num` frames (the first 6 with hair–hair: seconds a frame on
 * this dense groom), with and without collision. */
void run(benchmark::State &state, const Config config, const int coarsest_level = 0)
{
  const SintelScene &s = sintel();
  if (!s.loaded) {
    state.SkipWithError("the Sintel assets are missing (HAIRDYN_SHARED_DATA/sintel)");
    return;
  }
  const bool hair_hair_config =
      config == Config::LodCloseHairHair || config == Config::FineStrandsHairHair;
  const int frames_num = hair_hair_config ? 6 : sintel_frames_num;
  const bool lod = config != Config::FineStrands && config != Config::FineStrandsHairHair &&
                   config != Config::FinestSkeletons && config != Config::CoarseStrips;
  for (auto _ : state) {
    double ms[2] = {0.0, 0.0};
    double fine_ms = 0.0; /* the fine simulation's whole step (the level of detail's only) */
    double error_sum = 0.0, visible_error_sum = 0.0, strip_error_sum = 0.0;
    double strip_skeleton_error_sum = 0.0, chaos_sum = 0.0;
    double skeletons_sum = 0.0;
    int64_t switches = 0;
    for (const bool collide : {true, false}) {
      const ColliderSet *colliders = collide ? s.colliders.get() : nullptr;
      /* Hair–hair counts as collision: the runs without collision go without it. */
      SweptSphereParams hair_hair;
      hair_hair.hair_hair = true;
      HairHairPass pass(hair_hair), fine_pass(hair_hair);
      const bool with_hair_hair = hair_hair_config && collide;
      if (lod) {
        LodParams params = sintel_lod_params();
        params.coarsest_level = coarsest_level;
        if (config == Config::LodCloseCoarser) {
          params.distance_near = 0.1f;
          params.distance_far = 0.5f;
          params.velocity_slow = 2.0f;
          params.velocity_fast = 10.0f;
        }
        LodSolver solver(s.offsets, s.positions, {}, {}, mat4(1.0f), StrandParams(), sintel_wind(),
                         params);
        solver.set_colliders(colliders, CollisionParams());
        /* Without collision the bust still hides hair: the same selection as with it. */
        solver.set_occluders(s.colliders.get());
        /* The fine simulation of the same frames: the finest level everywhere. */
        LodParams fine_params = sintel_lod_params();
        fine_params.enabled = false;
        LodSolver fine(s.offsets, s.positions, {}, {}, mat4(1.0f), StrandParams(), sintel_wind(),
                       fine_params);
        fine.set_colliders(colliders, CollisionParams());
        /* Its twin, the head turned by 1 µrad (its strands start 0.2 µm apart): chaos_pct. */
        LodSolver twin(s.offsets, s.positions, {}, {}, mat4(1.0f), StrandParams(), sintel_wind(),
                       fine_params);
        twin.set_colliders(colliders, CollisionParams());
        HairHairPass twin_pass(hair_hair);
        if (with_hair_hair) {
          solver.add_pass(&pass, hair_hair.thickness);
          fine.add_pass(&fine_pass, hair_hair.thickness);
          twin.add_pass(&twin_pass, hair_hair.thickness);
        }
        const mat4 nudged = glm::rotate(mat4(1.0f), 1e-6f, vec3(0.0f, 0.0f, 1.0f));
        for (int frame = 0; frame < frames_num; frame++) {
          const std::clock_t start = std::clock();
          solver.step(sintel_frame_dt, mat4(1.0f),
                      sintel_camera(s, frame, config == Config::LodZoomOut));
          ms[collide] += milliseconds_since(start);
          if (collide) {
            const std::clock_t fine_start = std::clock();
            fine.step(sintel_frame_dt, mat4(1.0f), mat4(1.0f));
            fine_ms += milliseconds_since(fine_start);
            error_sum += mean_distance(solver.positions(), fine.positions());
            twin.step(sintel_frame_dt, nudged, mat4(1.0f));
            chaos_sum += mean_distance(twin.positions(), fine.positions());
            /* The same over the strands whose skeleton the camera sees, and over those a top
             * strip drives. */
            double visible_sum = 0.0, strip_sum = 0.0;
            int64_t visible_points = 0, strip_points = 0;
            for (int64_t c = 0; c + 1 < int64_t(s.offsets.size()); c++) {
              const int32_t node = solver.strand_nodes()[c];
              const bool visible = solver.visible()[node];
              const bool strip = solver.hierarchy().depth(node) == 0;
              for (int32_t i = s.offsets[size_t(c)]; i < s.offsets[size_t(c) + 1]; i++) {
                const double distance =
                    double(glm::length(solver.positions()[i] - fine.positions()[i]));
                visible_sum += visible ? distance : 0.0;
                visible_points += visible ? 1 : 0;
                strip_sum += strip ? distance : 0.0;
                strip_points += strip ? 1 : 0;
              }
            }
            visible_error_sum += visible_points > 0 ? visible_sum / double(visible_points) : 0.0;
            strip_error_sum += strip_points > 0 ? strip_sum / double(strip_points) : 0.0;
            strip_skeleton_error_sum += strip_skeleton_error(solver, fine);
            skeletons_sum += double(solver.active_num());
            switches += solver.splits_num() + solver.merges_num() + solver.collapses_num();
          }
        }
        continue;
      }
      const LodHierarchy hierarchy(s.offsets, s.positions, {}, {}, sintel_lod_params());
      std::vector<int32_t> nodes;
      if (config == Config::FinestSkeletons) {
        nodes = hierarchy.level_nodes(hierarchy.max_depth());
      }
      else if (config == Config::CoarseStrips) {
        nodes = hierarchy.level_nodes(0);
      }
      StrandSolver solver =
          config == Config::FineStrands || config == Config::FineStrandsHairHair
              ? StrandSolver(s.offsets, s.positions, mat4(1.0f), {}, StrandParams(), sintel_wind())
              : skeleton_solver(hierarchy, nodes);
      solver.set_colliders(colliders, CollisionParams());
      if (with_hair_hair) {
        solver.add_pass(&pass);
      }
      skeletons_sum = double(solver.curves_num()) * frames_num;
      for (int frame = 0; frame < frames_num; frame++) {
        const std::clock_t start = std::clock();
        solver.step(sintel_frame_dt, mat4(1.0f));
        ms[collide] += milliseconds_since(start);
      }
    }
    state.counters["total_ms"] = ms[1] / frames_num;
    state.counters["dynamics_ms"] = ms[0] / frames_num;
    state.counters["collision_ms"] = (ms[1] - ms[0]) / frames_num;
    state.counters["skeletons"] = skeletons_sum / frames_num;
    if (lod) {
      state.counters["lod_error_mm"] = 1000.0 * error_sum / frames_num;
      state.counters["lod_error_pct"] = 100.0 * error_sum / frames_num / s.mean_length;
      state.counters["visible_error_pct"] =
          100.0 * visible_error_sum / frames_num / s.mean_length;
      state.counters["strip_error_pct"] = 100.0 * strip_error_sum / frames_num / s.mean_length;
      state.counters["strip_skeleton_error_pct"] =
          100.0 * strip_skeleton_error_sum / frames_num / s.mean_length;
      state.counters["lod_switches"] = double(switches);
      state.counters["chaos_pct"] = 100.0 * chaos_sum / frames_num / s.mean_length;
      state.counters["fine_ms"] = fine_ms / frames_num;
      state.counters["speedup"] = fine_ms / ms[1];
    }
    state.counters["strands"] = double(s.offsets.size() - 1);
  }
}

}  // namespace

static void BM_LodSintel_FineStrands(benchmark::State &state) { run(state, Config::FineStrands); }
static void BM_LodSintel_FineStrandsHairHair(benchmark::State &state)
{
  run(state, Config::FineStrandsHairHair);
}
static void BM_LodSintel_FinestSkeletons(benchmark::State &state)
{
  run(state, Config::FinestSkeletons);
}
static void BM_LodSintel_CoarseStrips(benchmark::State &state) { run(state, Config::CoarseStrips); }
static void BM_LodSintel_Lod_CameraClose(benchmark::State &state)
{
  run(state, Config::LodClose, int(state.range(0)));
}
static void BM_LodSintel_Lod_CameraCloseCoarser(benchmark::State &state)
{
  run(state, Config::LodCloseCoarser, int(state.range(0)));
}
static void BM_LodSintel_Lod_ZoomOut(benchmark::State &state)
{
  run(state, Config::LodZoomOut, int(state.range(0)));
}
static void BM_LodSintel_Lod_CameraCloseHairHair(benchmark::State &state)
{
  run(state, Config::LodCloseHairHair, int(state.range(0)));
}

BENCHMARK(BM_LodSintel_FineStrands)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LodSintel_FineStrandsHairHair)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LodSintel_FinestSkeletons)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LodSintel_CoarseStrips)->Iterations(1)->Unit(benchmark::kMillisecond);
/* The coarsest level, where hidden hair goes: the top strips (the default), and finer. */
static void coarsest_levels(benchmark::internal::Benchmark *b)
{
  b->ArgName("coarsest")->Arg(0)->Arg(2)->Arg(3)->Iterations(1)->Unit(benchmark::kMillisecond);
}
BENCHMARK(BM_LodSintel_Lod_CameraClose)->Apply(coarsest_levels);
BENCHMARK(BM_LodSintel_Lod_CameraCloseCoarser)
    ->ArgName("coarsest")
    ->Arg(0)
    ->Arg(2)
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LodSintel_Lod_ZoomOut)->Apply(coarsest_levels);
BENCHMARK(BM_LodSintel_Lod_CameraCloseHairHair)->Apply(coarsest_levels);
