/* Hair–object collision of Ward & Lin 2003 §5.4 on fixed states: the BVH of swept spheres
 * returns exactly the triangles a brute-force search returns, and the pass pushes segments out
 * of bodies (even a segment through a thin blade whose nodes are both outside), keeps their
 * lengths, stops the velocity into the body and applies friction. */
#include <gtest/gtest.h>

#include <array>
#include <memory>
#include <random>
#include <set>

#include "collision/ssv_object_ward2003.hh"
#include "collision_test_shapes.hh"

using namespace hairdyn;

namespace {

std::shared_ptr<Collider> make_collider(const test::TestMesh &shape, const mat4 &object_to_world)
{
  const ColliderMesh mesh(shape.vertices, shape.triangles);
  auto collider = std::make_shared<Collider>(mesh, Span<int32_t>(), Span<int32_t>(),
                                             CollisionParams());
  collider->set_transform(object_to_world);
  return collider;
}

/* Smallest core distance of segment a–b to any triangle of the collider (world space). */
float segment_mesh_distance(const Collider &collider, const vec3 &a, const vec3 &b)
{
  float best = INFINITY;
  const mat4 &m = collider.object_to_world();
  for (const ivec3 &t : collider.triangles()) {
    const vec3 t0 = transform_point(m, collider.vertices()[t.x]);
    const vec3 t1 = transform_point(m, collider.vertices()[t.y]);
    const vec3 t2 = transform_point(m, collider.vertices()[t.z]);
    best = std::min(best, segment_triangle_distance(a, b, t0, t1, t2).distance);
  }
  return best;
}

struct Strand {
  std::vector<int32_t> offsets{0};
  std::vector<vec3> positions, velocities;
  SubstepState state(const float h)
  {
    SubstepState s;
    s.h = h;
    s.curve_offsets = offsets;
    s.positions_wo = positions;
    s.velocities_wo = velocities;
    return s;
  }
};

}  // namespace

TEST(SsvObject, HierarchyReturnsTheBruteForceTriangles)
{
  const test::TestMesh sphere = test::uv_sphere(0.1f, 32, 16);
  const SsvBVH bvh(sphere.vertices, sphere.triangles);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-0.15f, 0.15f);
  int64_t found_total = 0, strip_found_total = 0;
  for (int q = 0; q < 900; q++) {
    const vec3 a(u(rng), u(rng), u(rng));
    const vec3 b = a + 0.2f * vec3(u(rng), u(rng), u(rng));
    const float reach = std::array<float, 3>{0.0005f, 0.01f, 0.05f}[size_t(q % 3)];
    /* Every other query a strip's rectangle: the segment widened by a side across it. */
    const vec3 across = glm::cross(b - a, vec3(u(rng), u(rng), u(rng)));
    const vec3 side = q % 2 && glm::length(across) > 0.0f ?
                          0.03f * glm::normalize(across) :
                          vec3(0.0f);
    std::vector<TriangleContact> contacts;
    bvh.segment_contacts(a, b, reach, contacts, side);
    std::set<int32_t> found, reference;
    for (const TriangleContact &c : contacts) {
      found.insert(c.triangle);
    }
    for (size_t t = 0; t < sphere.triangles.size(); t++) {
      const ivec3 tri = sphere.triangles[t];
      const vec3 &c0 = sphere.vertices[tri.x], &c1 = sphere.vertices[tri.y],
                 &c2 = sphere.vertices[tri.z];
      const float distance =
          side != vec3(0.0f) ?
              rectangle_triangle_distance({a - side, b - a, 2.0f * side, 0.0f}, c0, c1, c2)
                  .distance :
              segment_triangle_distance(a, b, c0, c1, c2).distance;
      if (distance <= reach) {
        reference.insert(int32_t(t));
      }
    }
    EXPECT_EQ(found, reference) << "query " << q;
    (side != vec3(0.0f) ? strip_found_total : found_total) += int64_t(found.size());
  }
  EXPECT_GT(found_total, 300);
  EXPECT_GT(strip_found_total, 300);
}

TEST(SsvObject, SegmentThroughAThinBladeIsLiftedOutWholeKeepingItsLength)
{
  /* A blade 2 mm thick (z), 10 cm wide; a strand whose second segment dips through it: both
   * of that segment's nodes are outside (one above, one below), and it came from above. */
  ColliderSet colliders;
  colliders.add(make_collider(test::box(vec3(0.05f, 0.05f, 0.001f)), mat4(1.0f)));
  Strand strand;
  strand.positions = {vec3(-0.03f, 0, 0.01f), vec3(-0.01f, 0, 0.004f), vec3(0.01f, 0, -0.004f)};
  strand.offsets.push_back(3);
  strand.velocities = {vec3(0.0f), vec3(0, 0, -0.5f), vec3(0, 0, -0.5f)};
  const float l0 = glm::length(strand.positions[1] - strand.positions[0]);
  const float l1 = glm::length(strand.positions[2] - strand.positions[1]);
  ASSERT_EQ(segment_mesh_distance(colliders.collider(0), strand.positions[1], strand.positions[2]), 0.0f);

  SweptSphereParams params;
  params.body_collision = BodyCollision::SweptSpheres;
  params.thickness = 2e-4f;
  SsvObjectPass pass(&colliders, params);
  pass.apply(strand.state(0.02f));
  const std::vector<vec3> &x = strand.positions;
  EXPECT_GE(segment_mesh_distance(colliders.collider(0), x[1], x[2]), params.thickness * 0.999f);
  EXPECT_GE(segment_mesh_distance(colliders.collider(0), x[0], x[1]), params.thickness * 0.999f);
  EXPECT_GT(x[2].z, 0.001f) << "lifted to the side it came from";
  EXPECT_NEAR(glm::length(x[1] - x[0]), l0, 1e-6f);
  EXPECT_NEAR(glm::length(x[2] - x[1]), l1, 1e-6f);
  EXPECT_EQ(pass.stats().pushed_num, 1);
  EXPECT_EQ(pass.stats().unresolved_num, 0);
  /* Resting on the blade: no velocity into it. */
  EXPECT_GE(strand.velocities[2].z, 0.0f);

  /* "Maps" mode leaves the state alone. */
  params.body_collision = BodyCollision::Maps;
  SsvObjectPass off(&colliders, params);
  Strand again = strand;
  again.positions[2] = vec3(0.01f, 0, -0.004f);
  const std::vector<vec3> before = again.positions;
  off.apply(again.state(0.02f));
  EXPECT_EQ(again.positions, before);
}

TEST(SsvObject, PenetratingSegmentsOfARotatedSphereArePushedOutAlongTheNormal)
{
  /* A sphere of radius 0.1 moved and turned, and a strand that dips 5 mm into it. */
  const mat4 m = glm::rotate(glm::translate(mat4(1.0f), vec3(0.3f, -0.2f, 0.1f)), 0.7f,
                             glm::normalize(vec3(1, 2, 3)));
  ColliderSet colliders;
  colliders.add(make_collider(test::uv_sphere(0.1f, 64, 32), m));
  const vec3 center = transform_point(m, vec3(0.0f));
  Strand strand;
  const vec3 up(0, 0, 1);
  for (int i = 0; i < 6; i++) {
    /* From 2 cm above the top across it, 5 mm deep in the middle. */
    const float t = float(i) / 5.0f;
    const vec3 p = center + vec3(-0.04f + 0.08f * t, 0.0f, 0.0f) +
                   up * (i == 0 ? 0.12f : 0.095f + 0.0f * t);
    strand.positions.push_back(p);
    strand.velocities.push_back(vec3(0.0f));
  }
  strand.offsets.push_back(6);
  SweptSphereParams params;
  params.body_collision = BodyCollision::SweptSpheres;
  params.thickness = 1e-4f;
  SsvObjectPass pass(&colliders, params);
  pass.apply(strand.state(0.01f));
  for (int k = 0; k + 1 < 6; k++) {
    EXPECT_GE(segment_mesh_distance(colliders.collider(0), strand.positions[k], strand.positions[k + 1]),
              0.999f * params.thickness)
        << "segment " << k;
  }
  EXPECT_EQ(pass.stats().unresolved_num, 0);
}

TEST(SsvObject, FrictionSlowsTheTangentialMotionWithoutReversingIt)
{
  ColliderSet colliders;
  colliders.add(make_collider(test::box(vec3(0.05f, 0.05f, 0.01f)), mat4(1.0f)));
  /* A strand lying 0.5 mm above the top face (threshold 1 mm), sliding along x and pressed
   * down; over the substep it accelerated by 2 m/s² along x. */
  const auto run = [&](const float mu) {
    Strand strand;
    strand.positions = {vec3(-0.02f, 0, 0.0107f), vec3(0.0f, 0, 0.0107f), vec3(0.02f, 0, 0.0107f)};
    strand.offsets.push_back(3);
    SweptSphereParams params;
    params.body_collision = BodyCollision::SweptSpheres;
    params.thickness = 2e-4f;
    params.friction = mu;
    SsvObjectPass pass(&colliders, params);
    const float h = 0.01f;
    strand.velocities.assign(3, vec3(0.1f, 0, -0.05f));
    pass.apply(strand.state(h)); /* records the velocities */
    strand.velocities.assign(3, vec3(0.1f + 2.0f * h, 0, -0.05f));
    pass.apply(strand.state(h));
    return strand.velocities[2];
  };
  const vec3 free = run(0.0f), rough = run(0.5f);
  EXPECT_FLOAT_EQ(free.z, 0.0f) << "no velocity into the body within the threshold";
  EXPECT_FLOAT_EQ(free.x, 0.12f);
  /* μ_f |a_t| h = 0.5 · 2 · 0.01 = 0.01 m/s less. */
  EXPECT_NEAR(rough.x, 0.11f, 1e-6f);
  EXPECT_FLOAT_EQ(rough.z, 0.0f);
}

TEST(SsvObject, SegmentPenetrationShareCountsSegmentsThatCutABody)
{
  ColliderSet colliders;
  colliders.add(make_collider(test::box(vec3(0.05f, 0.05f, 0.001f)), mat4(1.0f)));
  /* Two strands of 2 segments: one crosses the blade in its second segment (both nodes
   * outside), the other stays above. */
  const std::vector<int32_t> offsets{0, 3, 6};
  const std::vector<vec3> x{vec3(-0.03f, 0, 0.01f), vec3(-0.01f, 0, 0.004f), vec3(0.01f, 0, -0.004f),
                            vec3(-0.03f, 0.01f, 0.01f), vec3(-0.01f, 0.01f, 0.01f), vec3(0.01f, 0.01f, 0.01f)};
  EXPECT_FLOAT_EQ(segment_penetration_share(offsets, x, colliders, 2e-4f), 0.25f);
  /* A zero tolerance counts any depth (max_segment_samples along the segment). */
  EXPECT_FLOAT_EQ(segment_penetration_share(offsets, x, colliders, 0.0f), 0.25f);
  /* A tolerance deeper than half the blade counts nothing. */
  EXPECT_FLOAT_EQ(segment_penetration_share(offsets, x, colliders, 0.0011f), 0.0f);
}

namespace {

/* The blade of SsvDynamics (2 mm thick, 10 cm square, centred 20 cm below the origin at
 * x = 8 cm: its edge runs along y at x = 3 cm) and one segment a–b moving at va, vb: what the
 * pass makes of it over a substep of 1/96 s. */
struct EdgeResult {
  vec3 tip;
  int64_t pushed = 0, unresolved = 0;
  float distance = 0.0f; /* from the segment's core to the blade */
  float stretch = 0.0f;  /* change of the segment's length */
};

EdgeResult push_at_blade_edge(const vec3 &a, const vec3 &b, const vec3 &va, const vec3 &vb)
{
  ColliderSet colliders;
  colliders.add(make_collider(test::box(vec3(0.05f, 0.05f, 0.001f)),
                              glm::translate(mat4(1.0f), vec3(0.08f, 0.0f, -0.2f))));
  SweptSphereParams params;
  params.body_collision = BodyCollision::SweptSpheres;
  params.thickness = 2e-4f;
  SsvObjectPass pass(&colliders, params);
  Strand strand;
  strand.positions = { a, b };
  strand.velocities = { va, vb };
  strand.offsets.push_back(2);
  pass.apply(strand.state(1.0f / 96.0f));
  const std::vector<vec3> &x = strand.positions;
  EdgeResult result;
  result.tip = x[1];
  result.pushed = pass.stats().pushed_num;
  result.unresolved = pass.stats().unresolved_num;
  result.distance = segment_mesh_distance(colliders.collider(0), x[0], x[1]);
  result.stretch = std::abs(glm::length(x[1] - x[0]) - glm::length(b - a));
  return result;
}

}  // namespace

TEST(SsvObject, ASegmentHangingJustPastABladesEdgeIsLeftAlone)
{
  /* Dragged along +x, the segment's base has passed over the blade's edge and its tip hangs
   * below the blade, just outside the edge (0.3 mm clear): nothing to push. Its part above
   * the bottom face lies over the top face, farther behind the bottom face than the blade
   * is thick; counted as met from the front (its closest point is level with the bottom
   * face, beside the edge), the bottom face asked to push the base down through the blade
   * and the tip was turned into it. */
  const EdgeResult r =
      push_at_blade_edge(vec3(0.0310f, 0.0f, -0.1868f), vec3(0.0290f, 0.0f, -0.2055f),
                         vec3(0.112f, 0.0f, -0.001f), vec3(0.113f, 0.0f, -0.001f));
  EXPECT_EQ(r.pushed, 0);
  EXPECT_EQ(r.unresolved, 0);
  EXPECT_EQ(r.tip, vec3(0.0290f, 0.0f, -0.2055f));
}

TEST(SsvObject, ASegmentGrazingABladesEdgeTurnsALittleAndStaysBelow)
{
  /* The tip has come 0.3 mm past the edge below the blade: the segment cuts the edge by a
   * fraction of a millimetre. It turns back a little and stays below; it is not mirrored
   * in the top face's plane (which flips it over onto the blade). */
  const EdgeResult r =
      push_at_blade_edge(vec3(0.0324f, 0.0f, -0.1867f), vec3(0.0303f, 0.0f, -0.2054f),
                         vec3(0.051f, 0.0f, 0.005f), vec3(0.156f, 0.0f, -0.009f));
  EXPECT_EQ(r.pushed, 1);
  EXPECT_EQ(r.unresolved, 0);
  EXPECT_GE(r.distance, 0.999f * 2e-4f);
  EXPECT_LT(r.tip.z, -0.201f) << "flipped over the edge";
  EXPECT_LT(r.stretch, 1e-6f);
}

TEST(SsvObject, ASegmentThatCrossedABladesEdgeWithinASubstepLeavesAcrossIt)
{
  /* The tip, pressed at 0.2 m/s against the edge from below-outside, crossed 2 mm into the
   * blade within the substep, farther than the threshold from the edge face. The face it
   * came through is within the distance it moved: it leaves across the edge, below, instead
   * of being taken for a segment that pierced the top face and flipped over onto the blade. */
  const EdgeResult r =
      push_at_blade_edge(vec3(0.0363f, 0.0f, -0.1828f), vec3(0.0312f, 0.0f, -0.2008f),
                         vec3(0.031f, 0.0f, 0.019f), vec3(0.196f, 0.0f, -0.035f));
  EXPECT_EQ(r.pushed, 1);
  EXPECT_EQ(r.unresolved, 0);
  EXPECT_GE(r.distance, 0.999f * 2e-4f);
  EXPECT_LT(r.tip.x, 0.03f) << "left across the edge";
  EXPECT_LT(r.tip.z, -0.199f) << "flipped over the edge";
  EXPECT_LT(r.stretch, 1e-6f);
}

TEST(SsvObject, ASegmentDrapedOffABladeFromABaseRestingOnItIsResolved)
{
  /* The base rests on the blade (at the strand's radius above the top face); the segment
   * runs over the side edge and down. Its real penetration is at the edge; the base's own
   * contact is no penetration a turn could remove, and chosen as the shallowest it used up
   * the iterations. */
  const EdgeResult r =
      push_at_blade_edge(vec3(0.1193f, 0.0389f, -0.1988f), vec3(0.1215f, 0.0573f, -0.2013f),
                         vec3(-0.012f, -0.090f, 0.0f), vec3(0.011f, -0.096f, -0.244f));
  EXPECT_EQ(r.pushed, 1);
  EXPECT_EQ(r.unresolved, 0);
  EXPECT_GE(r.distance, 0.99f * 2e-4f);
  EXPECT_LT(r.stretch, 1e-6f);
}

namespace {

/* Smallest core distance of a strip segment's rectangle (segment a–b widened by its half width
 * made orthogonal to it, as the pass builds it) to any triangle of the collider. */
float strip_mesh_distance(const Collider &collider, const vec3 &a, const vec3 &b,
                          const vec3 &half_width)
{
  const RectSS rect =
      RectSS::from_segment(a, b, half_width, 2.0f * glm::length(half_width), 0.0f);
  float best = INFINITY;
  for (const ivec3 &t : collider.triangles()) {
    best = std::min(best, rectangle_triangle_distance(rect, collider.vertices()[t.x],
                                                      collider.vertices()[t.y],
                                                      collider.vertices()[t.z])
                              .distance);
  }
  return best;
}

}  // namespace

TEST(SsvObject, AStripSegmentIsItsRectangleSweptSphere)
{
  /* A strip segment (level of detail) sloping down over the 2 mm blade, its width tilted so
   * that one long edge dips 1.7 mm into the blade while its core segment stays 3 mm above it.
   * The rectangle is tested exactly: it is lifted just clear (its corner to the strip's
   * radius above the top face), not as far as the line swept sphere around it (radius plus
   * half width, 11.4 mm) would ask. */
  ColliderSet colliders;
  colliders.add(make_collider(test::box(vec3(0.05f, 0.05f, 0.001f)), mat4(1.0f)));
  const Collider &blade = colliders.collider(0);
  const vec3 half_width(0.0f, 0.01f, -0.005f);
  Strand strand;
  strand.positions = {vec3(0.0f, 0.0f, 0.012f), vec3(0.03f, 0.0f, 0.004f)};
  strand.velocities = {vec3(0.0f), vec3(0.0f, 0.0f, -0.5f)};
  strand.offsets.push_back(2);
  const std::vector<vec3> half_widths{half_width, half_width};
  const float length = glm::length(strand.positions[1] - strand.positions[0]);
  ASSERT_GT(segment_mesh_distance(blade, strand.positions[0], strand.positions[1]), 0.0025f);
  ASSERT_EQ(strip_mesh_distance(blade, strand.positions[0], strand.positions[1], half_width),
            0.0f);

  SweptSphereParams params;
  params.body_collision = BodyCollision::SweptSpheres;
  params.thickness = 2e-4f;
  SsvObjectPass pass(&colliders, params);
  SubstepState state = strand.state(0.02f);
  state.strip_half_widths_hs = half_widths;
  pass.apply(state);
  const std::vector<vec3> &x = strand.positions;
  EXPECT_GE(strip_mesh_distance(blade, x[0], x[1], half_width), 0.999f * params.thickness);
  EXPECT_LT(strip_mesh_distance(blade, x[0], x[1], half_width), 2.0f * params.thickness)
      << "lifted just clear";
  EXPECT_LT(segment_mesh_distance(blade, x[0], x[1]), glm::length(half_width))
      << "lifted as far as the bounding line swept sphere";
  EXPECT_NEAR(glm::length(x[1] - x[0]), length, 1e-6f);
  EXPECT_EQ(pass.stats().pushed_num, 1);
  EXPECT_EQ(pass.stats().unresolved_num, 0);
  EXPECT_GE(strand.velocities[1].z, 0.0f) << "no velocity into the blade";

  /* The same strip flat, 3 mm over the blade: its rectangle is clear of it by more than the
   * radius and the threshold, so it is left alone (the bounding line swept sphere reaches
   * 10 mm down). Turned with the head by a quarter turn about z, its width still lies flat. */
  Strand flat;
  flat.positions = {vec3(0.0f, 0.0f, 0.004f), vec3(0.03f, 0.0f, 0.004f)};
  flat.velocities = {vec3(0.0f), vec3(0.0f)};
  flat.offsets.push_back(2);
  const std::vector<vec3> flat_widths(2, vec3(0.0f, 0.01f, 0.0f));
  for (const float turn : {0.0f, 1.5707963f}) {
    SsvObjectPass flat_pass(&colliders, params);
    const std::vector<vec3> before = flat.positions;
    SubstepState flat_state = flat.state(0.02f);
    flat_state.strip_half_widths_hs = flat_widths;
    flat_state.head_to_world = glm::rotate(mat4(1.0f), turn, vec3(0.0f, 0.0f, 1.0f));
    flat_pass.apply(flat_state);
    EXPECT_EQ(flat.positions, before);
    EXPECT_EQ(flat_pass.stats().pushed_num, 0);
    EXPECT_EQ(flat_pass.stats().near_num, 0);
  }
}
