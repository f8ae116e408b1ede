/* Swept spheres under level of detail (Ward & Lin 2003 §5.2 with §4, §6): a strip's segment
 * is a rectangle swept sphere as wide as the strip, a cluster's or strand group's a line swept
 * sphere as thick as the group, and the hair–hair pass (§5.3) runs over the active skeletons
 * of every level together. */
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "collision/hair_hair_ward2003.hh"
#include "collision/ssv_object_ward2003.hh"
#include "lod/hierarchy_ward2003.hh"
#include "lod/lod_solver_ward2003.hh"
#include "lod_scenes.hh"
#include "strand_scenes.hh"

using namespace hairdyn;
using namespace hairdyn::test;

namespace {

/* Two sheets of `per_sheet` straight strands (10 segments of 2 cm), each sheet a top strip
 * (their roots' u apart): sheet A horizontal along +X from roots spaced `spacing` along Y at
 * z = 0, sheet B below it in the plane x = 0.06, its strands along (0, 1, −1), rooted at
 * their lower ends, its upper ends at z = −0.02 (apart from A at the start). Limp strands
 * under gravity: A falls onto B. */
struct Sheets {
  strand_scenes::Groom groom;
  std::vector<vec2> uvs;
  int per_sheet = 12;

  explicit Sheets(const float spacing = 0.01f)
  {
    const float half = 0.5f * spacing * float(per_sheet - 1);
    for (int i = 0; i < per_sheet; i++) {
      groom.add_straight(vec3(0.0f, -half + spacing * float(i), 0.0f), vec3(1, 0, 0), 0.2f, 10);
      uvs.emplace_back(0.25f, float(i) / float(per_sheet));
    }
    const vec3 down = 0.2f * glm::normalize(vec3(0, 1, -1));
    for (int i = 0; i < per_sheet; i++) {
      const vec3 top(0.06f, -half - 0.045f + spacing * float(i), -0.02f);
      groom.add_straight(top + down, -down, 0.2f, 10);
      uvs.emplace_back(0.75f, float(i) / float(per_sheet));
    }
  }
};

LodParams sheet_params(const int32_t level)
{
  LodParams params;
  params.strips_num = 2;
  params.strip_splits = 0;
  params.cluster_min_radius = 0.02f;
  params.use_occlusion = false;
  params.coarsest_level = params.finest_level = level; /* held at one level */
  return params;
}

struct SheetsRun {
  int64_t crossings = 0; /* sheet A's output segments through sheet B's, over the frames */
  float tip_drop = 0.0f; /* m, how far sheet A's tips fell on average */
  float tip_x = 0.0f;    /* m, where they are along X on average (sheet B: at 0.06) */
  bool finite = true;
  int64_t pairs = 0; /* the pass's intersecting pairs, over the frames */
  float late_x = 0.0f; /* m, tip_x averaged over the last half of the frames */
};

/* 40 frames at 100 fps, 4 substeps each, the level of detail held at `level`, with the
 * hair–hair pass or without. */
SheetsRun run_sheets(const int32_t level, const bool hair_hair,
                     const std::vector<float> &radii = {})
{
  const Sheets sheets;
  StrandParams strand_params;
  strand_params.k_theta = strand_params.k_phi = 1e-9f;
  strand_params.damping = 1e-11f;
  strand_params.substeps = 4;
  LodSolver solver(sheets.groom.offsets, sheets.groom.positions, sheets.uvs, {}, mat4(1.0f),
                   strand_params, WindParams(), sheet_params(level));
  SweptSphereParams params;
  params.hair_hair = true;
  HairHairPass pass(params);
  solver.set_radii(radii);
  if (hair_hair) {
    solver.add_pass(&pass, params.thickness);
  }
  const mat4 camera = camera_view_projection(vec3(0.0f, -3.0f, 0.0f));
  SheetsRun run;
  std::vector<vec3> before(solver.positions().begin(), solver.positions().end());
  const int frames = 40;
  for (int frame = 0; frame < frames; frame++) {
    solver.step(0.01f, mat4(1.0f), camera);
    const std::vector<vec3> after(solver.positions().begin(), solver.positions().end());
    run.crossings += strand_scenes::count_sheet_crossings(sheets.groom, sheets.per_sheet, before,
                                                          after, 0.02f);
    for (const vec3 &p : after) {
      run.finite = run.finite && std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
    }
    before = after;
    if (2 * frame >= frames) {
      for (int i = 0; i < sheets.per_sheet; i++) {
        run.late_x += after[size_t(sheets.groom.offsets[size_t(i) + 1] - 1)].x /
                      float(sheets.per_sheet * (frames - frames / 2));
      }
    }
    run.pairs += pass.stats().pairs_num;
    pass.reset_stats();
  }
  for (int i = 0; i < sheets.per_sheet; i++) {
    const vec3 tip = before[size_t(sheets.groom.offsets[size_t(i) + 1] - 1)];
    run.tip_drop -= tip.z / float(sheets.per_sheet);
    run.tip_x += tip.x / float(sheets.per_sheet);
  }
  return run;
}

}  // namespace

/* A top strip of one row of N evenly spaced straight strands: its half width is half the
 * row's width as a band gives it, √3 times the root mean square offset, (d/2)·√(N² − 1) for
 * spacing d, along the row, at every control point; it has no thickness across the row. Its
 * clusters have no width, and their spread is their strands' root mean square distance from
 * the skeleton (sheet A's: its strands lie across their skeleton, so the distance is all
 * across it). */
TEST(LodHierarchy, StripsKnowTheirWidthAndGroupsTheirSpread)
{
  const Sheets sheets;
  LodParams params = sheet_params(0);
  const LodHierarchy hierarchy(sheets.groom.offsets, sheets.groom.positions, sheets.uvs, {},
                               params);
  ASSERT_EQ(hierarchy.top_nodes_num(), 2);
  ASSERT_EQ(hierarchy.kind(0), LodKind::Strip);
  const int32_t n = hierarchy.skeleton_points_num();
  ASSERT_EQ(n, 11) << "the skeletons sample the strands at their own points";
  const float d = 0.01f, N = float(sheets.per_sheet);
  const float expected = 0.5f * d * std::sqrt(N * N - 1.0f);
  for (int32_t k = 0; k < n; k++) {
    const vec3 half = hierarchy.half_width(0)[k];
    EXPECT_NEAR(glm::length(half), expected, 1e-4f * expected) << "control point " << k;
    EXPECT_GT(std::abs(half.y), 0.9999f * glm::length(half)) << "across the row";
    EXPECT_LT(hierarchy.spread(0)[k], 1e-5f) << "a flat row has no thickness";
  }
  int64_t clusters = 0;
  for (int64_t node = 0; node < hierarchy.nodes_num(); node++) {
    if (hierarchy.kind(node) == LodKind::Strip || hierarchy.top_node(node) != 0) {
      continue;
    }
    clusters++;
    const Span<vec3> skeleton = hierarchy.rest_skeleton(node);
    for (int32_t k = 0; k < n; k++) {
      EXPECT_EQ(hierarchy.half_width(node)[k], vec3(0.0f));
      double sum2 = 0.0;
      for (const int32_t strand : hierarchy.strands(node)) {
        const vec3 d_k = sheets.groom.positions[size_t(sheets.groom.offsets[size_t(strand)] + k)] -
                         skeleton[k];
        sum2 += double(glm::dot(d_k, d_k));
      }
      const float rms = float(std::sqrt(sum2 / double(hierarchy.strands(node).size())));
      EXPECT_NEAR(hierarchy.spread(node)[k], rms, 1e-5f + 1e-3f * rms);
    }
  }
  EXPECT_GT(clusters, 0);
}

/* A strip's segment is a rectangle swept sphere: a strand segment lying 0.8 mm above the
 * strip's plane, 3 cm to the side of its skeleton but over the strip, touches it (radii
 * 0.5 mm each) and is pushed up; as a line swept sphere (no width) the strip misses it. */
TEST(LodSweptSpheres, AStripSegmentIsARectangle)
{
  const std::vector<int32_t> offsets{0, 2, 4};
  const std::vector<vec3> positions{vec3(0.0f), vec3(0.02f, 0.0f, 0.0f),
                                    vec3(0.01f, 0.03f, 0.0008f), vec3(0.01f, 0.04f, 0.0008f)};
  const std::vector<vec3> velocities(4, vec3(0.0f));
  const std::vector<vec3> half_widths{vec3(0.0f, 0.05f, 0.0f), vec3(0.0f, 0.05f, 0.0f),
                                      vec3(0.0f), vec3(0.0f)};
  SweptSphereParams params;
  SegmentGridScratch scratch;
  std::vector<SegmentContact> contacts;
  find_segment_contacts(offsets, positions, {}, 5e-4f, true, scratch, contacts, {}, velocities,
                        &params, 0.01f, GroupVolumes{half_widths, {}});
  ASSERT_EQ(contacts.size(), 1u);
  EXPECT_NEAR(contacts[0].overlap, -2e-4f, 1e-6f);
  EXPECT_NEAR(contacts[0].core.point_b.z - contacts[0].core.point_a.z, 8e-4f, 1e-6f);
  EXPECT_GT(contacts[0].move.z, 0.0f) << "the strand segment is pushed up, off the strip";
  EXPECT_NEAR(glm::length(contacts[0].move), 1e-4f, 1e-6f) << "half the overlap each";
  find_segment_contacts(offsets, positions, {}, 5e-4f, true, scratch, contacts, {}, velocities,
                        &params, 0.01f);
  EXPECT_TRUE(contacts.empty());
}

/* Sheet A falls onto sheet B under level of detail held at the strips (rectangle swept
 * spheres), at their clusters and at the finest level (line swept spheres as thick as each
 * group): with hair–hair on, A's strands go through B's at least 5× less often than without,
 * and A still falls onto B. */
TEST(LodSweptSpheres, HairHairKeepsSheetsApartAtEveryLevel)
{
  for (const int32_t level : {0, 1, 3}) {
    SCOPED_TRACE("level " + std::to_string(level));
    const SheetsRun off = run_sheets(level, false);
    const SheetsRun on = run_sheets(level, true);
    std::printf("level %d: %lld crossings off, %lld on (%lld pairs); A's tips fell %.3f m off, "
                "%.3f m on, and are at x = %.3f m off, %.3f m on\n",
                level, (long long)off.crossings, (long long)on.crossings, (long long)on.pairs,
                off.tip_drop, on.tip_drop, off.tip_x, on.tip_x);
    EXPECT_TRUE(off.finite && on.finite);
    EXPECT_GE(off.crossings, 20) << "the sheets must fall through each other";
    EXPECT_LE(5 * on.crossings, off.crossings);
    EXPECT_GT(on.pairs, 0);
    EXPECT_GT(on.tip_drop, 0.02f) << "A falls onto B, it does not hang still";
    /* Without, A swings through B and hangs on the near side; with, it drapes over B. */
    EXPECT_LT(off.tip_x, 0.06f);
    EXPECT_GT(on.tip_x, 0.06f);
  }
}

/* The strands' own radii (a Curves radius attribute) size the groups' volumes: radii equal to
 * the pass's thickness everywhere give the thickness's run bit for bit, and four times it keep
 * the sheets farther apart than a quarter of it. (Sheet A still swings at the end: where its
 * tips are is taken over the last half of the run. Against the thickness itself the order of
 * either is within the swing's chaos where the groups' spread outweighs the radius, as at
 * level 2.) */
TEST(LodSweptSpheres, TheStrandsRadiiSizeTheGroupVolumes)
{
  const size_t points = Sheets().groom.positions.size();
  const float thickness = SweptSphereParams().thickness;
  for (const int32_t level : {0, 2}) {
    SCOPED_TRACE("level " + std::to_string(level));
    const SheetsRun plain = run_sheets(level, true);
    const SheetsRun same = run_sheets(level, true, std::vector<float>(points, thickness));
    EXPECT_EQ(same.pairs, plain.pairs);
    EXPECT_EQ(same.crossings, plain.crossings);
    EXPECT_EQ(same.tip_x, plain.tip_x);
    const SheetsRun thin = run_sheets(level, true, std::vector<float>(points, 0.25f * thickness));
    const SheetsRun thick = run_sheets(level, true, std::vector<float>(points, 4.0f * thickness));
    /* Sheet A drapes over B (at x = 0.06 m) the farther out, the thicker the volumes. */
    EXPECT_LT(thin.late_x, thick.late_x);
  }
}

/* A skeleton may stay as near the body as it was at rest (SubstepState::rest_clearances): a
 * strand draped over a sphere 1 mm above it, its swept spheres 5 mm thick (a group's), stays
 * about 1 mm above it under swept-sphere body collision; without the clearances the pass
 * lifts it to 5 mm. */
TEST(LodSweptSpheres, ASkeletonStaysAsNearTheBodyAsAtRest)
{
  const auto colliders = head_colliders(0.1f);
  strand_scenes::Groom groom;
  for (int i = 0; i <= 10; i++) {
    const float angle = 0.1f * float(i); /* 1 cm segments along a great circle */
    groom.positions.push_back(0.101f * vec3(std::sin(angle), 0.0f, std::cos(angle)));
  }
  groom.offsets.push_back(int32_t(groom.positions.size()));
  const auto height = [&](const Span<vec3> positions) {
    float sum = 0.0f;
    for (int i = 1; i <= 10; i++) {
      sum += (glm::length(positions[i]) - 0.1f) / 10.0f;
    }
    return sum;
  };
  float heights[2];
  for (const bool with_clearances : {false, true}) {
    StrandSolver solver(groom.offsets, groom.positions, mat4(1.0f), {}, StrandParams());
    SweptSphereParams params;
    params.body_collision = BodyCollision::SweptSpheres;
    SsvObjectPass pass(colliders.get(), params);
    PassVolumes volumes;
    volumes.radii.assign(groom.positions.size(), 0.005f);
    if (with_clearances) {
      for (const vec3 &p : groom.positions) {
        volumes.rest_clearances.push_back(
            std::max(colliders->collider(0).exact().signed_distance(p), 0.0f));
      }
    }
    solver.set_pass_volumes(volumes);
    solver.add_pass(&pass);
    for (int frame = 0; frame < 24; frame++) {
      solver.step(1.0f / 24.0f, mat4(1.0f));
    }
    heights[with_clearances] = height(solver.positions());
  }
  std::printf("mean height over the sphere: %.2f mm with rest clearances, %.2f mm without\n",
              1e3f * heights[1], 1e3f * heights[0]);
  EXPECT_LT(heights[1], 0.002f);
  EXPECT_GT(heights[0], 0.004f);
}

/* With the body collided by swept spheres only, the maps are off (set_colliders(nullptr)) and
 * the colliders still hide hair (set_occluders, §6.1): about as many strands come out at the
 * coarsest level as with the colliders set (the hair, no longer held off the head by the
 * maps, hangs a little differently), none without them, and the skeletons make no map
 * contacts. */
TEST(LodSweptSpheres, OccludersWithoutMapsStillHideHair)
{
  LodParams params;
  params.strips_num = 48;
  params.strip_splits = 1;
  params.cluster_min_radius = 0.02f;
  params.distance_near = 2.0f; /* by distance everything wants the finest level */
  params.distance_far = 3.0f;
  params.velocity_slow = 50.0f;
  params.velocity_fast = 100.0f;
  const CapGroom groom(300, 10);
  const auto colliders = head_colliders();
  const mat4 camera = camera_view_projection(vec3(0.0f, -0.35f, 0.05f));
  enum { Maps, Occluders, Neither };
  int64_t coarsest[3] = {0, 0, 0}, contacts[3] = {0, 0, 0};
  for (const int setup : {Maps, Occluders, Neither}) {
    LodSolver solver(groom.offsets, groom.positions, {}, groom.normals, mat4(1.0f),
                     StrandParams(), WindParams(), params);
    solver.set_colliders(setup == Maps ? colliders.get() : nullptr, CollisionParams());
    if (setup == Occluders) {
      solver.set_occluders(colliders.get());
    }
    for (int frame = 0; frame < solver.hierarchy().max_depth() + 3; frame++) {
      solver.step(1.0f / 24.0f, mat4(1.0f), camera);
      contacts[setup] += solver.contacts_num();
    }
    for (const int32_t node : solver.strand_nodes()) {
      coarsest[setup] += solver.hierarchy().depth(node) == 0;
    }
  }
  std::printf("strands at the coarsest level: %lld with the colliders, %lld with occluders only, "
              "%lld with neither\n",
              (long long)coarsest[Maps], (long long)coarsest[Occluders],
              (long long)coarsest[Neither]);
  EXPECT_GT(coarsest[Maps], 30) << "some strands must be hidden behind the head";
  EXPECT_NEAR(double(coarsest[Occluders]), double(coarsest[Maps]), 0.1 * double(coarsest[Maps]));
  EXPECT_EQ(coarsest[Neither], 0);
  EXPECT_GT(contacts[Maps], 0);
  EXPECT_EQ(contacts[Occluders], 0);
}
