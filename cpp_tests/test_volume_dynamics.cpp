/* Petrovic 2006's volume pass inside the strand solver's substeps: velocity smoothing keeps two
 * sheets of strands from passing through each other (§5.1, Fig. 4), and the density force
 * directs a groom toward a target shape (§5.2, Fig. 5 set-up). */
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "strand_scenes.hh"
#include "strands/strand_solver.hh"
#include "volume/volume_pass.hh"

using namespace hairdyn;

namespace {

using strand_scenes::Groom;

/* Fig. 4's two sheets (strand_scenes::run_crossing_sheets) with velocity smoothing of strength
 * s (0: no pass): the crossings over the frames and how far sheet A's tips fell. */
int64_t sheets_crossings(const StrandModel model, const float smoothing, const int frames,
                         float &r_tip_drop)
{
  VolumeParams volume_params;
  volume_params.smoothing = smoothing;
  volume_params.cell_size = 0.015f;
  VolumePass volume(volume_params);
  strand_scenes::CrossingSheets scene;
  scene.frames = frames;
  const strand_scenes::SheetsResult result = strand_scenes::run_crossing_sheets(
      model, smoothing > 0.0f ? &volume : nullptr, scene);
  EXPECT_EQ(result.diverged, 0);
  r_tip_drop = result.tip_drop;
  return result.crossings;
}

}  // namespace

/* §5.1, Fig. 4: with velocity smoothing the sheets cross at least 3× less often than without,
 * over the same frames. */
TEST(VolumeDynamics, SmoothingKeepsSheetsFromCrossing)
{
  const int frames = 40;
  for (const StrandModel model : { StrandModel::Kurihara1993, StrandModel::Articulated }) {
    float drop_without, drop_with;
    const int64_t without = sheets_crossings(model, 0.0f, frames, drop_without);
    const int64_t with = sheets_crossings(model, 0.9f, frames, drop_with);
    std::printf("model %d: crossing segment pairs over %d frames: %lld without smoothing, %lld "
                "with s = 0.9; sheet A's tips fell %.3f m and %.3f m\n",
                int(model), frames, (long long)without, (long long)with, drop_without,
                drop_with);
    EXPECT_GT(without, 30) << "model " << int(model) << ": the sheets must sweep through";
    EXPECT_LE(3 * with, without) << "model " << int(model);
    /* Smoothing does not hold the sheet up: it still falls most of the way (it drags sheet B
     * along instead of passing through it). */
    EXPECT_GT(drop_with, 0.5f * drop_without) << "model " << int(model);
  }
}

namespace {

/* A 5 × 6 block of strands 15 cm long hanging from a 1 cm lattice; `bend` (rad) curves each
 * strand in a circular arc toward +x. */
Groom hanging_block(const float bend)
{
  Groom groom;
  const int segments = 12;
  const float length = 0.15f;
  for (int a = 0; a < 5; a++) {
    for (int b = 0; b < 6; b++) {
      vec3 p(0.01f * float(a), 0.01f * float(b), 0.0f);
      for (int i = 0; i <= segments; i++) {
        groom.positions.push_back(p);
        const float angle = bend * (float(i) + 0.5f) / float(segments);
        p += (length / float(segments)) * vec3(std::sin(angle), 0.0f, -std::cos(angle));
      }
      groom.offsets.push_back(int32_t(groom.positions.size()));
    }
  }
  return groom;
}

float mean_distance(Span<vec3> a, const std::vector<vec3> &b)
{
  double sum = 0.0;
  for (size_t i = 0; i < b.size(); i++) {
    sum += double(glm::length(a[int64_t(i)] - b[i]));
  }
  return float(sum / double(b.size()));
}

}  // namespace

/* E of eq. 3 between `positions` and `target` on the lattice of spacing h (head at rest). */
double error_of(Span<vec3> positions, DensityTarget &target, const float h)
{
  HeadBox box = head_box(positions, mat4(1.0f));
  box.include(target.box());
  const GridFrame grid = grid_around(box, h, 1, mat4(1.0f));
  PointBins bins;
  bin_points(grid, positions, bins);
  TargetGrids grids;
  return target_error(grid, bins, target, grids);
}

/* §5.2 with the Fig. 5 set-up: from the rest groom, no gravity, no head motion (no inertia), no
 * collision, the density force directs damped, soft strands (the hinge springs resist the
 * target, as the paper notes) toward a copy bent by 1 rad, with the default volume settings
 * (velocity smoothing s = 0.2 keeps neighbours together). The error of eq. 3 on the finest
 * grid falls by at least 80% and the nodes end closer to the target, in both strand models.
 *
 * Articulated: a tenth of human hair's Young's modulus, bending damping τ = 0.4 s (the ratio
 * γ / k of the Kurihara hinges). The coarse levels' kicks reach 10 m/s per substep; lightly
 * damped strands (the default τ = 2 ms) flail under them and a few run away. */
TEST(VolumeDynamics, TargetingDirectsTheGroomTowardABentCopy)
{
  const Groom rest = hanging_block(0.0f);
  const Groom target = hanging_block(1.0f);
  for (const StrandModel model : { StrandModel::Kurihara1993, StrandModel::Articulated }) {
    SCOPED_TRACE(model == StrandModel::Articulated ? "articulated" : "kurihara1993");
    StrandParams params;
    params.model = model;
    params.gravity = vec3(0.0f);
    params.k_theta = params.k_phi = 1e-8f;
    params.damping = 4e-9f;
    params.youngs_modulus = 0.1f * StrandParams().youngs_modulus;
    params.bending_damping = 0.4f;
    StrandSolver solver(rest.offsets, rest.positions, mat4(1.0f), {}, params);
    VolumeParams volume_params;
    volume_params.cell_size = 0.0125f;
    VolumePass volume(volume_params);
    volume.set_target(target.positions, mat4(1.0f));
    solver.add_pass(&volume);

    DensityTarget reference(target.positions, mat4(1.0f));
    const double start_error = error_of(solver.positions(), reference, volume_params.cell_size);
    const float start_distance = mean_distance(solver.positions(), target.positions);
    for (int frame = 0; frame < 96; frame++) {
      solver.step(1.0f / 24.0f, mat4(1.0f));
      ASSERT_EQ(solver.diverged_num(), 0);
    }
    const double end_error = error_of(solver.positions(), reference, volume_params.cell_size);
    const float end_distance = mean_distance(solver.positions(), target.positions);
    std::printf("model %d: eq. 3 error %.1f -> %.1f (%.0f%% lower), mean distance to target "
                "%.4f -> %.4f m, level %d\n",
                int(model), start_error, end_error, 100.0 * (1.0 - end_error / start_error),
                start_distance, end_distance, volume.target_level());
    EXPECT_EQ(volume.target_level(), 0);
    EXPECT_LE(end_error, 0.2 * start_error);
    EXPECT_LT(end_distance, start_distance);
    /* The pass reports the same error on its finest grid. */
    EXPECT_GT(volume.target_error(), 0.0);
    EXPECT_LE(volume.target_error(), 0.3 * start_error);
  }
}
