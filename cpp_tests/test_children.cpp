/* Child hairs (Kurihara 1993, §4 cluster model) and guide interpolation. */
#include <gtest/gtest.h>

#include <cmath>

#include "groom/children_kurihara1993.hh"
#include "groom/frames.hh"

using namespace hairdyn;

namespace {

/* Three wavy guides of different lengths hanging from a row of roots on the XY plane. */
struct Guides {
  std::vector<int32_t> offsets{0};
  std::vector<vec3> positions;
  std::vector<mat3> root_frames;

  Guides()
  {
    const int segments[3] = {8, 12, 5};
    for (int g = 0; g < 3; g++) {
      for (int i = 0; i <= segments[g]; i++) {
        const float s = 0.02f * float(i);
        positions.emplace_back(0.05f * float(g) + 0.01f * std::sin(30.0f * s), 0.3f * s, -s);
      }
      offsets.push_back(int32_t(positions.size()));
      root_frames.push_back(root_frame_from_normal(vec3(0.0f, 0.0f, 1.0f)));
    }
  }
};

/* The first guide of Guides (9 points) and a copy 4 cm along x, both with root frames from
 * `root_normal`. */
Guides two_guides_apart(const vec3 &root_normal)
{
  const Guides guides;
  Guides pair;
  pair.offsets = {0, 9, 18};
  pair.positions.assign(guides.positions.begin(), guides.positions.begin() + 9);
  for (int j = 0; j < 9; j++) {
    pair.positions.push_back(pair.positions[size_t(j)] + vec3(0.04f, 0.0f, 0.0f));
  }
  pair.root_frames.assign(2, root_frame_from_normal(root_normal));
  return pair;
}

float max_distance(const Span<vec3> a, const Span<vec3> b)
{
  float result = 0.0f;
  for (int64_t i = 0; i < a.size(); i++) {
    result = std::max(result, glm::length(a[i] - b[i]));
  }
  return result;
}

}  // namespace

TEST(Children, CountAndRootsWithinSpread)
{
  const Guides guides;
  const float spread = 0.01f;
  ChildHairs children = ChildHairs::around_guides(guides.offsets, 7, spread, 3);
  children.update(guides.positions, guides.root_frames);
  ASSERT_EQ(children.curves_num(), 21);
  float distance_max = 0.0f;
  for (int64_t c = 0; c < children.curves_num(); c++) {
    const int64_t guide = c / 7;
    const int32_t guide_root = guides.offsets[size_t(guide)];
    EXPECT_EQ(children.curve_offsets()[c + 1] - children.curve_offsets()[c],
              guides.offsets[size_t(guide) + 1] - guide_root);
    const vec3 offset = children.positions()[children.curve_offsets()[c]] -
                        guides.positions[size_t(guide_root)];
    EXPECT_LE(glm::length(offset), spread * 1.0001f);
    EXPECT_NEAR(offset.z, 0.0f, 1e-7f); /* On the scalp plane (normal +Z). */
    distance_max = std::max(distance_max, glm::length(offset));
  }
  EXPECT_GT(distance_max, 0.5f * spread);
}

TEST(Children, SameSeedSameChildren)
{
  const Guides guides;
  ChildHairs a = ChildHairs::around_guides(guides.offsets, 5, 0.02f, 11);
  ChildHairs b = ChildHairs::around_guides(guides.offsets, 5, 0.02f, 11);
  ChildHairs c = ChildHairs::around_guides(guides.offsets, 5, 0.02f, 12);
  for (ChildHairs *children : {&a, &b, &c}) {
    children->update(guides.positions, guides.root_frames);
  }
  EXPECT_EQ(max_distance(a.positions(), b.positions()), 0.0f);
  EXPECT_GT(max_distance(a.positions(), c.positions()), 1e-3f);
}

TEST(Children, FollowTheirGuideRigidly)
{
  /* Move and turn the guides rigidly (points and root frames): every child point moves the
   * same way. */
  const Guides guides;
  ChildHairs children = ChildHairs::around_guides(guides.offsets, 6, 0.015f, 5);
  children.update(guides.positions, guides.root_frames);
  const std::vector<vec3> before(children.positions().begin(), children.positions().end());

  const mat4 motion = glm::rotate(glm::translate(mat4(1.0f), vec3(0.4f, -0.2f, 1.0f)), 1.3f,
                                  glm::normalize(vec3(1.0f, -2.0f, 0.5f)));
  Guides moved = guides;
  for (vec3 &p : moved.positions) {
    p = transform_point(motion, p);
  }
  for (mat3 &frame : moved.root_frames) {
    frame = mat3(motion) * frame;
  }
  children.update(moved.positions, moved.root_frames);
  for (size_t i = 0; i < before.size(); i++) {
    EXPECT_LE(glm::length(children.positions()[int64_t(i)] - transform_point(motion, before[i])),
              1e-5f)
        << i;
  }
}

TEST(Children, FollowTheirGuideShape)
{
  /* Bend one guide (its tip half swings sideways): its children bend with it, other guides'
   * children do not move. */
  const Guides guides;
  ChildHairs children = ChildHairs::around_guides(guides.offsets, 4, 0.01f, 9);
  children.update(guides.positions, guides.root_frames);
  const std::vector<vec3> before(children.positions().begin(), children.positions().end());
  Guides bent = guides;
  for (int32_t i = bent.offsets[0] + 5; i < bent.offsets[1]; i++) {
    bent.positions[size_t(i)].x += 0.05f;
  }
  children.update(bent.positions, bent.root_frames);
  for (int64_t c = 0; c < children.curves_num(); c++) {
    const int64_t tip = children.curve_offsets()[c + 1] - 1;
    const float moved = glm::length(children.positions()[tip] - before[size_t(tip)]);
    if (c < 4) {
      EXPECT_NEAR(moved, 0.05f, 0.01f) << c;
    }
    else {
      EXPECT_EQ(moved, 0.0f) << c;
    }
  }
}

TEST(Children, InterpolationReproducesGuideAtItsRoot)
{
  Guides guides;
  std::vector<vec3> roots;
  for (size_t g = 0; g < 3; g++) {
    roots.push_back(guides.positions[size_t(guides.offsets[g])]);
  }
  ChildHairs children = ChildHairs::between_guides(guides.offsets, guides.positions,
                                                   guides.root_frames, roots, 3);
  /* A later shape of the guides: the blend must hold on it, not only at rest. */
  for (size_t i = 0; i < guides.positions.size(); i++) {
    guides.positions[i] += vec3(0.0f, 0.01f * float(i % 5), 0.0f);
  }
  children.update(guides.positions, guides.root_frames);
  ASSERT_EQ(children.curves_num(), 3);
  for (int64_t c = 0; c < 3; c++) {
    const Span<vec3> guide(guides.positions.data() + guides.offsets[size_t(c)],
                           guides.offsets[size_t(c) + 1] - guides.offsets[size_t(c)]);
    const Span<vec3> child = children.positions().slice(
        children.curve_offsets()[c], children.curve_offsets()[c + 1] - children.curve_offsets()[c]);
    ASSERT_EQ(child.size(), guide.size());
    EXPECT_LE(max_distance(child, guide), 1e-6f) << c;
  }
}

TEST(Children, InterpolationBlendsByInverseDistance)
{
  /* Two guides of the same bent shape 4 cm apart: a hair rooted a quarter of the way from the
   * first has weights 3/4 and 1/4 and, the offsets cancelling in the shared frames, lies at
   * 3/4 G0 + 1/4 G1 all along. */
  Guides pair = two_guides_apart(vec3(0.2f, 0.1f, 1.0f));
  const std::vector<vec3> roots{pair.positions[0] + vec3(0.01f, 0.0f, 0.0f)};
  ChildHairs children = ChildHairs::between_guides(pair.offsets, pair.positions,
                                                   pair.root_frames, roots, 3);
  for (size_t i = 0; i < pair.positions.size(); i++) {
    pair.positions[i] += vec3(0.0f, 0.0f, 0.005f * float((i % 9) * (i % 9)));
  }
  children.update(pair.positions, pair.root_frames);
  ASSERT_EQ(children.positions().size(), 9);
  for (int64_t j = 0; j < 9; j++) {
    const vec3 expected = 0.75f * pair.positions[size_t(j)] + 0.25f * pair.positions[size_t(9 + j)];
    EXPECT_LE(glm::length(children.positions()[j] - expected), 1e-6f) << j;
  }
}

TEST(Children, BlendCarriesGuideValuesAsThePositionsAre)
{
  /* Values per guide point (shading normals, say): a child beside one guide takes that guide's
   * value at its place along it; a child blending two takes the weighted blend. */
  Guides guides;
  std::vector<vec3> values(guides.positions.size());
  for (size_t i = 0; i < values.size(); i++) {
    values[i] = vec3(float(i), 1.0f - 0.1f * float(i), 0.5f);
  }
  ChildHairs around = ChildHairs::around_guides(guides.offsets, 3, 0.01f, 4);
  around.update(guides.positions, guides.root_frames);
  std::vector<vec3> carried(size_t(around.positions().size()));
  around.blend(values, carried);
  for (int64_t c = 0; c < around.curves_num(); c++) {
    const int64_t guide = c / 3; /* children come guide by guide */
    const int64_t n = around.curve_offsets()[c + 1] - around.curve_offsets()[c];
    ASSERT_EQ(n, guides.offsets[size_t(guide) + 1] - guides.offsets[size_t(guide)]);
    for (int64_t j = 0; j < n; j++) {
      EXPECT_EQ(carried[size_t(around.curve_offsets()[c] + j)],
                values[size_t(guides.offsets[size_t(guide)] + j)])
          << c << " " << j;
    }
  }
  Guides pair = two_guides_apart(vec3(0.0f, 0.0f, 1.0f));
  const std::vector<vec3> roots{pair.positions[0] + vec3(0.01f, 0.0f, 0.0f)};
  ChildHairs between = ChildHairs::between_guides(pair.offsets, pair.positions,
                                                  pair.root_frames, roots, 3);
  std::vector<vec3> blended(9);
  between.blend(Span<vec3>(values).slice(0, 18), blended);
  for (int64_t j = 0; j < 9; j++) {
    const vec3 expected = 0.75f * values[size_t(j)] + 0.25f * values[size_t(9 + j)];
    EXPECT_LE(glm::length(blended[size_t(j)] - expected), 1e-5f) << j;
  }
}
