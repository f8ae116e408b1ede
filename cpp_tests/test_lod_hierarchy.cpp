/* The hair hierarchy of Ward & Lin 2003, §4, and the skinning that hangs strands and children
 * on skeletons (§4.2, §6.2). */
#include <gtest/gtest.h>

#include <cmath>

#include "groom/groom.hh"
#include "lod/hierarchy_ward2003.hh"
#include "lod/skinning_ward2003.hh"
#include "lod_scenes.hh"

using namespace hairdyn;
using namespace hairdyn::test;

namespace {

LodHierarchy build(const CapGroom &groom, const LodParams &params)
{
  return LodHierarchy(groom.offsets, groom.positions, {}, groom.normals, params);
}

LodParams small_params()
{
  LodParams params;
  params.strips_num = 6;
  params.strip_splits = 1;
  params.cluster_min_radius = 0.02f;
  return params;
}

}  // namespace

TEST(LodHierarchy, EveryLevelCoversEachStrandOnce)
{
  const CapGroom groom(300, 10);
  const LodHierarchy hierarchy = build(groom, small_params());
  ASSERT_EQ(hierarchy.top_nodes_num(), 6);
  ASSERT_GE(hierarchy.max_depth(), 4);
  for (int32_t level = 0; level <= hierarchy.max_depth() + 1; level++) {
    std::vector<int> covered(300, 0);
    for (const int32_t node : hierarchy.level_nodes(level)) {
      EXPECT_TRUE(hierarchy.depth(node) == level ||
                  (hierarchy.is_leaf(node) && hierarchy.depth(node) < level));
      for (const int32_t strand : hierarchy.strands(node)) {
        covered[size_t(strand)]++;
      }
    }
    for (int s = 0; s < 300; s++) {
      ASSERT_EQ(covered[size_t(s)], 1) << "strand " << s << " at level " << level;
    }
  }
  /* Children partition their parent's strands. */
  for (int64_t node = 0; node < hierarchy.nodes_num(); node++) {
    int64_t children_strands = 0;
    const IndexRange kids = hierarchy.children(node);
    for (int64_t child = kids.start; child < kids.one_after_last(); child++) {
      EXPECT_EQ(hierarchy.parent(child), node);
      EXPECT_EQ(hierarchy.depth(child), hierarchy.depth(node) + 1);
      EXPECT_GT(hierarchy.strands(child).size(), 0);
      children_strands += hierarchy.strands(child).size();
    }
    if (!hierarchy.is_leaf(node)) {
      EXPECT_EQ(children_strands, hierarchy.strands(node).size());
    }
  }
}

TEST(LodHierarchy, StripsSplitInTwoThenQuadrantsDownToSingleStrands)
{
  const CapGroom groom(300, 10);
  LodParams params = small_params();
  params.strip_splits = 2;
  const LodHierarchy hierarchy = build(groom, params);
  bool saw_cluster = false, saw_group = false;
  for (int64_t node = 0; node < hierarchy.nodes_num(); node++) {
    const int64_t kids = hierarchy.children(node).size;
    const LodKind kind = hierarchy.kind(node);
    if (kind == LodKind::Strip) {
      EXPECT_LE(hierarchy.depth(node), 2);
      /* §4.1: a binary tree of strips, the finest strips turn into quadrant clusters. */
      EXPECT_LE(kids, hierarchy.depth(node) < 2 ? 2 : 4);
    }
    else {
      EXPECT_LE(kids, 4); /* §4.2: between zero and four children. */
      EXPECT_GT(hierarchy.depth(node), 2);
    }
    saw_cluster |= kind == LodKind::Cluster;
    saw_group |= kind == LodKind::StrandGroup;
    if (hierarchy.is_leaf(node)) {
      EXPECT_EQ(hierarchy.strands(node).size(), 1); /* Down to single strands. */
    }
    if (kind == LodKind::StrandGroup && hierarchy.parent(node) >= 0) {
      EXPECT_NE(hierarchy.kind(hierarchy.parent(node)), LodKind::Strip);
    }
  }
  EXPECT_TRUE(saw_cluster);
  EXPECT_TRUE(saw_group);
}

TEST(LodHierarchy, MinimumGroupSizeStopsTheSplits)
{
  const CapGroom groom(300, 10);
  LodParams params = small_params();
  params.min_group_strands = 5;
  const LodHierarchy hierarchy = build(groom, params);
  int64_t leaves = 0;
  for (int64_t node = 0; node < hierarchy.nodes_num(); node++) {
    if (hierarchy.is_leaf(node)) {
      leaves++;
      EXPECT_LE(hierarchy.strands(node).size(), 5);
    }
    else {
      EXPECT_GT(hierarchy.strands(node).size(), 5);
    }
  }
  EXPECT_LT(leaves, 300);
  EXPECT_GT(leaves, 300 / 5);
}

TEST(LodHierarchy, SkeletonsHaveTheirParentsPointCountAndStoredOffsets)
{
  const CapGroom groom(200, 12);
  for (const int32_t points : {0, 7, 1000}) {
    LodParams params = small_params();
    params.skeleton_points = points;
    const LodHierarchy hierarchy = build(groom, params);
    /* 0, or more than the strands' 12: theirs. */
    const int32_t n = points == 0 || points > 12 ? 12 : points;
    ASSERT_EQ(hierarchy.skeleton_points_num(), n);
    for (int64_t node = 0; node < hierarchy.nodes_num(); node++) {
      ASSERT_EQ(hierarchy.rest_skeleton(node).size(), n);
      ASSERT_EQ(hierarchy.rest_frames(node).size(), n);
      ASSERT_EQ(hierarchy.offsets(node).size(), n);
      const int32_t parent = hierarchy.parent(node);
      if (parent < 0) {
        continue;
      }
      /* §6.2: the child = parent + stored offset, in the parent's rest frames. */
      std::vector<vec3> placed(static_cast<size_t>(n));
      place_child(hierarchy.rest_skeleton(parent), hierarchy.rest_frames(parent),
                  hierarchy.offsets(node), placed);
      for (int32_t k = 0; k < n; k++) {
        EXPECT_LT(glm::length(placed[size_t(k)] - hierarchy.rest_skeleton(node)[k]), 1e-6f);
      }
    }
    /* A single strand's skeleton is the strand itself (evenly spaced points when n equals
     * the strand's count: the scene's segments are all equally long). */
    for (int64_t node = 0; node < hierarchy.nodes_num() && points == 0; node++) {
      if (hierarchy.strands(node).size() == 1) {
        const int32_t strand = hierarchy.strands(node)[0];
        for (int32_t k = 0; k < n; k++) {
          EXPECT_LT(glm::length(hierarchy.rest_skeleton(node)[k] -
                                groom.positions[size_t(strand * 12 + k)]),
                    1e-5f);
        }
      }
    }
  }
}

/* A value per strand point at the skeletons' control points: one that grows linearly along
 * each strand (the cap groom's segments are equal) comes out linear in the control point's
 * index, root and tip values at the ends, on any point count against the skeleton's. */
TEST(LodHierarchy, PointValuesAtTheControlPointsFollowTheArcLength)
{
  for (const int points_num : {4, 10, 23}) {
    SCOPED_TRACE(points_num);
    const CapGroom groom(40, points_num);
    const LodHierarchy hierarchy = build(groom, small_params());
    std::vector<float> values;
    for (int64_t s = 0; s < groom.strands_num(); s++) {
      for (int i = 0; i < points_num; i++) {
        values.push_back(float(s) + float(i) / float(points_num - 1)); /* s at the root */
      }
    }
    const int32_t n = hierarchy.skeleton_points_num();
    const std::vector<float> at = hierarchy.at_control_points(values);
    ASSERT_EQ(at.size(), size_t(groom.strands_num()) * size_t(n));
    for (int64_t s = 0; s < groom.strands_num(); s++) {
      for (int32_t k = 0; k < n; k++) {
        EXPECT_NEAR(at[size_t(s * n + k)], float(s) + float(k) / float(n - 1), 1e-4f)
            << "strand " << s << ", control point " << k;
      }
    }
  }
}

TEST(LodHierarchy, GivenUvsDecideTheStrips)
{
  /* Roots whose UVs put strands 0..99 left and 100..199 right of u = 0.5: two top strips of
   * one band split them there, whatever their 3D positions. */
  const CapGroom groom(200, 6);
  std::vector<vec2> uvs(200);
  for (int s = 0; s < 200; s++) {
    uvs[size_t(s)] = vec2(s < 100 ? 0.25f : 0.75f, 0.001f * float(s % 7));
  }
  LodParams params = small_params();
  params.strips_num = 2;
  params.strip_splits = 0;
  const LodHierarchy hierarchy(groom.offsets, groom.positions, uvs, {}, params);
  ASSERT_EQ(hierarchy.top_nodes_num(), 2);
  for (int64_t top = 0; top < 2; top++) {
    for (const int32_t strand : hierarchy.strands(top)) {
      EXPECT_EQ(strand < 100, top == 0);
    }
  }
}

TEST(LodSkinning, RestSkeletonGivesTheRestStrands)
{
  const CapGroom groom(150, 9);
  const LodHierarchy hierarchy = build(groom, small_params());
  std::vector<vec3> out(groom.positions.size());
  for (int64_t node = 0; node < hierarchy.nodes_num(); node++) {
    for (const int32_t strand : hierarchy.strands(node)) {
      const IndexRange points = curve_points(groom.offsets, strand);
      skin_strand(hierarchy, node, strand, hierarchy.rest_skeleton(node),
                  hierarchy.rest_frames(node), MutableSpan<vec3>(out).slice(points.start, points.size));
      for (int64_t i = points.start; i < points.one_after_last(); i++) {
        ASSERT_LT(glm::length(out[size_t(i)] - groom.positions[size_t(i)]), 1e-6f);
      }
    }
  }
}

TEST(LodSkinning, RigidMotionCarriesStrandsRigidly)
{
  /* Turn every skeleton rigidly about the head's centre: its strands (and the children
   * placed on it) turn with it exactly. */
  const CapGroom groom(150, 9);
  const LodHierarchy hierarchy = build(groom, small_params());
  const mat3 turn = mat3(glm::rotate(mat4(1.0f), 0.7f, glm::normalize(vec3(0.3f, -1.0f, 0.5f))));
  const vec3 shift(0.1f, -0.2f, 0.05f);
  const int32_t n = hierarchy.skeleton_points_num();
  std::vector<vec3> skeleton(static_cast<size_t>(n)), out(groom.positions.size());
  std::vector<mat3> frames(static_cast<size_t>(n));
  float worst = 0.0f;
  for (int64_t node = 0; node < hierarchy.nodes_num(); node++) {
    for (int32_t k = 0; k < n; k++) {
      skeleton[size_t(k)] = turn * hierarchy.rest_skeleton(node)[k] + shift;
    }
    current_skeleton_frames(skeleton, hierarchy.rest_frames(node), turn, frames);
    for (const int32_t strand : hierarchy.strands(node)) {
      const IndexRange points = curve_points(groom.offsets, strand);
      skin_strand(hierarchy, node, strand, skeleton, frames,
                  MutableSpan<vec3>(out).slice(points.start, points.size));
      for (int64_t i = points.start; i < points.one_after_last(); i++) {
        worst = std::max(worst, glm::length(out[size_t(i)] - (turn * groom.positions[size_t(i)] + shift)));
      }
    }
    const IndexRange kids = hierarchy.children(node);
    std::vector<vec3> child(static_cast<size_t>(n)), back(static_cast<size_t>(n));
    for (int64_t c = kids.start; c < kids.one_after_last(); c++) {
      place_child(skeleton, frames, hierarchy.offsets(c), child);
      std::vector<mat3> child_frames(static_cast<size_t>(n));
      current_skeleton_frames(child, hierarchy.rest_frames(c), turn, child_frames);
      parent_from_child(child, child_frames, hierarchy.rest_frames(c), hierarchy.rest_frames(node),
                        hierarchy.offsets(c), back);
      for (int32_t k = 0; k < n; k++) {
        worst = std::max(worst, glm::length(child[size_t(k)] - (turn * hierarchy.rest_skeleton(c)[k] + shift)));
        worst = std::max(worst, glm::length(back[size_t(k)] - skeleton[size_t(k)]));
      }
    }
  }
  EXPECT_LT(worst, 2e-6f);
}
