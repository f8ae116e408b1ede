/* Ward & Lin 2003, Tables 1 and 2, in form: a groom of 9,120 strands (Sintel's 228 guides,
 * 40 children around each, 32 points per strand) on Sintel's bust, wind blowing, 24 frames at
 * 24 fps. Per configuration, processor milliseconds per frame of the whole step with
 * hair-object collision, of the same step without it (dynamics), and their difference
 * (collision):
 *
 *   FineStrands      every artist strand simulated (32 points each)
 *   FinestSkeletons  every skeleton of the hierarchy's finest level (Ward's "Fine Strands")
 *   CoarseStrips     only the top strips
 *   Lod/close        the level of detail, camera 0.45 m from the face (Table 1)
 *   Lod/zoom_out     the level of detail, camera moving from 0.45 m to 8 m (Table 2)
 *
 * and for the level of detail lod_error: the mean distance (mm, and % of the mean strand
 * length) of its output from a fine simulation of the same frames (the same hierarchy with
 * the level of detail off: the finest level everywhere), over all strands and over the
 * strands whose skeleton the camera sees (visible_error_pct). Skipped when the
 * Sintel assets are missing. */
#include <benchmark/benchmark.h>

#include <cstdio>
#include <ctime>
#include <cstring>
#include <fstream>
#include <iterator>

#include "../collision_test_shapes.hh"
#include "groom/children_kurihara1993.hh"
#include "groom/frames.hh"
#include "groom/groom.hh"
#include "lod/lod_solver_ward2003.hh"
#include "../lod_scenes.hh"

using namespace hairdyn;
using namespace hairdyn::test;

namespace {

constexpr float scale = 0.015f; /* The assets are about 40 units tall: a 0.6 m bust. */
constexpr float frame_dt = 1.0f / 24.0f;
constexpr int frames_num = 24;

/* File (Y up) to Blender (Z up) axes, as the add-on's importer does, and to meters. */
vec3 to_scene(const vec3 &p)
{
  return scale * vec3(p.x, -p.z, p.y);
}

struct SintelScene {
  std::vector<int32_t> offsets;
  std::vector<vec3> positions;
  std::shared_ptr<ColliderSet> colliders;
  vec3 head_centre{0.0f};
  float mean_length = 0.0f;
  bool loaded = false;
};

const SintelScene &sintel()
{
  static SintelScene scene = [] {
    SintelScene s;
    std::ifstream file(std::string(sintel_folder) + "/sintel_hair.tfx", std::ios::binary);
    TestMesh bust;
    if (!file || !read_obj(sintel_bust_path, bust)) {
      return s;
    }
    const std::vector<char> data((std::istreambuf_iterator<char>(file)),
                                 std::istreambuf_iterator<char>());
    /* TressFX 4.0: version, strands, points per strand, then the positions' offset. */
    uint32_t guides_num = 0, points_num = 0, positions_offset = 0;
    std::memcpy(&guides_num, data.data() + 4, 4);
    std::memcpy(&points_num, data.data() + 8, 4);
    std::memcpy(&positions_offset, data.data() + 12, 4);
    std::vector<int32_t> guide_offsets{0};
    std::vector<vec3> guides;
    for (uint32_t g = 0; g < guides_num; g++) {
      for (uint32_t i = 0; i < points_num; i++) {
        float xyzw[4];
        std::memcpy(xyzw, data.data() + positions_offset + 16 * (g * points_num + i), 16);
        guides.push_back(to_scene(vec3(xyzw[0], xyzw[1], xyzw[2])));
      }
      guide_offsets.push_back(int32_t(guides.size()));
    }
    std::vector<mat3> frames(guides_num);
    compute_root_frames(guide_offsets, guides, {}, frames);
    /* Kurihara 1993 §4's cluster model: 40 strands around each guide, within 1.2 cm. */
    ChildHairs children = ChildHairs::around_guides(guide_offsets, 40, 0.012f, 7);
    children.update(guides, frames);
    s.offsets.assign(children.curve_offsets().begin(), children.curve_offsets().end());
    s.positions.assign(children.positions().begin(), children.positions().end());
    for (vec3 &v : bust.vertices) {
      v = to_scene(v);
    }
    const ColliderMesh mesh(bust.vertices, bust.triangles);
    s.colliders = std::make_shared<ColliderSet>();
    s.colliders->add(std::make_shared<Collider>(mesh, Span<int32_t>(), Span<int32_t>(),
                                                CollisionParams()));
    vec3 root_sum(0.0f);
    double length = 0.0;
    for (size_t c = 0; c + 1 < s.offsets.size(); c++) {
      root_sum += s.positions[size_t(s.offsets[c])];
      for (int32_t i = s.offsets[c] + 1; i < s.offsets[c + 1]; i++) {
        length += double(glm::length(s.positions[size_t(i)] - s.positions[size_t(i - 1)]));
      }
    }
    const float curves = float(s.offsets.size() - 1);
    s.head_centre = root_sum / curves - vec3(0.0f, 0.0f, 0.05f);
    s.mean_length = float(length / double(curves));
    s.loaded = true;
    return s;
  }();
  return scene;
}

WindParams wind()
{
  WindParams w;
  w.speed = 3.0f;
  w.turbulence = 0.5f;
  return w;
}

LodParams lod_params()
{
  LodParams params;
  params.strips_num = 110; /* Ward's scene: 110 strips for 9,350 strands. */
  params.strip_splits = 1;
  params.cluster_min_radius = 0.01f;
  params.min_group_strands = 3;
  params.skeleton_points = 8; /* Ward's skeletons have 6 control points on average. */
  params.distance_near = 0.5f;
  params.distance_far = 6.0f;
  return params;
}

/* Camera for frame f: close to the face, or zooming out to 8 m. */
mat4 camera(const SintelScene &s, const int frame, const bool zoom_out)
{
  const float distance = zoom_out ? glm::mix(0.45f, 8.0f, float(frame) / float(frames_num - 1)) :
                                    0.45f;
  return camera_view_projection(s.head_centre + vec3(0.0f, -distance, 0.05f), s.head_centre);
}

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
  return StrandSolver(offsets, rest, mat4(1.0f), normals, StrandParams(), wind());
}

/* Processor time of the whole process (all threads), in ms: on a shared machine the wall
 * clock measures the other jobs too. Run with OMP_NUM_THREADS=1 for single-core figures. */
double milliseconds_since(const std::clock_t start)
{
  return 1000.0 * double(std::clock() - start) / double(CLOCKS_PER_SEC);
}

enum class Config { FineStrands, FinestSkeletons, CoarseStrips, LodClose, LodZoomOut };

/* ms per frame of `frames_num` frames, with and without collision. */
void run(benchmark::State &state, const Config config)
{
  const SintelScene &s = sintel();
  if (!s.loaded) {
    state.SkipWithError("the Sintel assets are missing (HAIRDYN_SHARED_DATA/sintel)");
    return;
  }
  for (auto _ : state) {
    double ms[2] = {0.0, 0.0};
    double error_sum = 0.0, visible_error_sum = 0.0;
    double skeletons_sum = 0.0;
    int64_t switches = 0;
    for (const bool collide : {true, false}) {
      const ColliderSet *colliders = collide ? s.colliders.get() : nullptr;
      const bool lod = config == Config::LodClose || config == Config::LodZoomOut;
      if (lod) {
        LodSolver solver(s.offsets, s.positions, {}, {}, mat4(1.0f), StrandParams(), wind(),
                         lod_params());
        solver.set_colliders(colliders, CollisionParams());
        /* The fine simulation of the same frames: the finest level everywhere. */
        LodParams fine_params = lod_params();
        fine_params.enabled = false;
        LodSolver fine(s.offsets, s.positions, {}, {}, mat4(1.0f), StrandParams(), wind(),
                       fine_params);
        fine.set_colliders(colliders, CollisionParams());
        for (int frame = 0; frame < frames_num; frame++) {
          const std::clock_t start = std::clock();
          solver.step(frame_dt, mat4(1.0f), camera(s, frame, config == Config::LodZoomOut));
          ms[collide] += milliseconds_since(start);
          if (collide) {
            fine.step(frame_dt, mat4(1.0f), mat4(1.0f));
            error_sum += mean_distance(solver.positions(), fine.positions());
            /* The same over the strands whose skeleton the camera sees. */
            double visible_sum = 0.0;
            int64_t visible_points = 0;
            for (int64_t c = 0; c + 1 < int64_t(s.offsets.size()); c++) {
              if (!solver.visible()[solver.strand_nodes()[c]]) {
                continue;
              }
              for (int32_t i = s.offsets[size_t(c)]; i < s.offsets[size_t(c) + 1]; i++) {
                visible_sum += double(glm::length(solver.positions()[i] - fine.positions()[i]));
                visible_points++;
              }
            }
            visible_error_sum += visible_points > 0 ? visible_sum / double(visible_points) : 0.0;
            skeletons_sum += double(solver.active_num());
            switches += solver.splits_num() + solver.merges_num() + solver.collapses_num();
          }
        }
        continue;
      }
      const LodHierarchy hierarchy(s.offsets, s.positions, {}, {}, lod_params());
      std::vector<int32_t> nodes;
      if (config == Config::FinestSkeletons) {
        nodes = hierarchy.level_nodes(hierarchy.max_depth());
      }
      else if (config == Config::CoarseStrips) {
        nodes = hierarchy.level_nodes(0);
      }
      StrandSolver solver = config == Config::FineStrands ?
                                StrandSolver(s.offsets, s.positions, mat4(1.0f), {},
                                             StrandParams(), wind()) :
                                skeleton_solver(hierarchy, nodes);
      solver.set_colliders(colliders, CollisionParams());
      skeletons_sum = double(solver.curves_num()) * frames_num;
      for (int frame = 0; frame < frames_num; frame++) {
        const std::clock_t start = std::clock();
        solver.step(frame_dt, mat4(1.0f));
        ms[collide] += milliseconds_since(start);
      }
    }
    state.counters["total_ms"] = ms[1] / frames_num;
    state.counters["dynamics_ms"] = ms[0] / frames_num;
    state.counters["collision_ms"] = (ms[1] - ms[0]) / frames_num;
    state.counters["skeletons"] = skeletons_sum / frames_num;
    if (config == Config::LodClose || config == Config::LodZoomOut) {
      state.counters["lod_error_mm"] = 1000.0 * error_sum / frames_num;
      state.counters["lod_error_pct"] = 100.0 * error_sum / frames_num / s.mean_length;
      state.counters["visible_error_pct"] = 100.0 * visible_error_sum / frames_num /
                                            s.mean_length;
      state.counters["lod_switches"] = double(switches);
    }
    state.counters["strands"] = double(s.offsets.size() - 1);
  }
}

}  // namespace

static void BM_LodSintel_FineStrands(benchmark::State &state) { run(state, Config::FineStrands); }
static void BM_LodSintel_FinestSkeletons(benchmark::State &state)
{
  run(state, Config::FinestSkeletons);
}
static void BM_LodSintel_CoarseStrips(benchmark::State &state) { run(state, Config::CoarseStrips); }
static void BM_LodSintel_Lod_CameraClose(benchmark::State &state) { run(state, Config::LodClose); }
static void BM_LodSintel_Lod_ZoomOut(benchmark::State &state) { run(state, Config::LodZoomOut); }

BENCHMARK(BM_LodSintel_FineStrands)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LodSintel_FinestSkeletons)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LodSintel_CoarseStrips)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LodSintel_Lod_CameraClose)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LodSintel_Lod_ZoomOut)->Iterations(1)->Unit(benchmark::kMillisecond);
