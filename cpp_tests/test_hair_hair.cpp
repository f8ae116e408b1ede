/* Hair–hair collision of Ward & Lin 2003 §5.3 on fixed states: the grid finds exactly the
 * intersecting pairs a brute-force search finds, the response does what §5.3 says, and the
 * result does not depend on the thread count. */
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <random>
#include <set>

#include "collision/collider.hh"
#include "collision/hair_hair_ward2003.hh"
#include "core/parallel.hh"

using namespace hairdyn;

namespace {

struct Strands {
  std::vector<int32_t> offsets{0};
  std::vector<vec3> positions;
  std::vector<vec3> velocities;

  void add(const std::vector<vec3> &points, const vec3 &velocity = vec3(0.0f))
  {
    positions.insert(positions.end(), points.begin(), points.end());
    velocities.insert(velocities.end(), points.size(), velocity);
    offsets.push_back(int32_t(positions.size()));
  }
  SubstepState state(const float h = 1e-3f)
  {
    SubstepState s;
    s.h = h;
    s.curve_offsets = offsets;
    s.positions_wo = positions;
    s.velocities_wo = velocities;
    return s;
  }
};

/* Random-walk strands in a 6 cm box: many crossings, segments of 5–15 mm. */
Strands random_strands(const int strands_num, const int points_num, const uint32_t seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  Strands strands;
  for (int s = 0; s < strands_num; s++) {
    std::vector<vec3> points{0.03f * vec3(u(rng), u(rng), u(rng))};
    for (int i = 1; i < points_num; i++) {
      const vec3 step = glm::normalize(vec3(u(rng), u(rng), u(rng)) + vec3(1e-3f));
      points.push_back(points.back() + (0.01f + 0.005f * u(rng)) * step);
    }
    strands.add(points, vec3(u(rng), u(rng), u(rng)));
  }
  return strands;
}

/* Index pairs of the brute-force O(S²) search. */
std::set<std::pair<int32_t, int32_t>> brute_force(const Strands &strands, const float radius,
                                                  const bool different_strands_only)
{
  std::vector<std::pair<int32_t, int32_t>> segments; /* (first point, strand) */
  for (size_t c = 0; c + 1 < strands.offsets.size(); c++) {
    for (int32_t p = strands.offsets[c]; p + 1 < strands.offsets[c + 1]; p++) {
      segments.push_back({p, int32_t(c)});
    }
  }
  std::set<std::pair<int32_t, int32_t>> pairs;
  const std::vector<vec3> &x = strands.positions;
  for (size_t i = 0; i < segments.size(); i++) {
    for (size_t j = i + 1; j < segments.size(); j++) {
      const auto [pi, ci] = segments[i];
      const auto [pj, cj] = segments[j];
      if (ci == cj && (different_strands_only || pj - pi <= 1)) {
        continue;
      }
      if (segment_segment_distance(x[pi], x[pi + 1], x[pj], x[pj + 1]).distance < 2.0f * radius) {
        pairs.insert({pi, pj});
      }
    }
  }
  return pairs;
}

}  // namespace

TEST(HairHair, GridFindsExactlyTheBruteForcePairs)
{
  const Strands strands = random_strands(150, 10, 7);
  const float radius = 0.002f;
  for (const bool different_only : {false, true}) {
    SegmentGridScratch scratch;
    std::vector<SegmentContact> contacts;
    find_segment_contacts(strands.offsets, strands.positions, {}, radius, different_only, scratch,
                          contacts);
    std::set<std::pair<int32_t, int32_t>> found;
    for (const SegmentContact &c : contacts) {
      found.insert({c.first, c.second});
      EXPECT_LT(c.overlap, 0.0f);
    }
    EXPECT_EQ(found.size(), contacts.size()) << "a pair was reported twice";
    EXPECT_TRUE(std::is_sorted(contacts.begin(), contacts.end(),
                               [](const SegmentContact &a, const SegmentContact &b) {
                                 return a.first != b.first ? a.first < b.first :
                                                             a.second < b.second;
                               }))
        << "contacts come in the order of their pairs";
    const auto reference = brute_force(strands, radius, different_only);
    EXPECT_GT(reference.size(), 100u);
    EXPECT_EQ(found, reference);
    EXPECT_LT(scratch.candidate_pairs_num, 1350 * 1349 / 2) << "the grid prunes nothing";
    if (different_only) {
      EXPECT_EQ(count_crossings(strands.offsets, strands.positions, {}, radius),
                int64_t(reference.size()));
    }
  }
}

TEST(HairHair, BigSegmentsFindTheBruteForcePairsToo)
{
  /* Short random-walk strands and a few long ones whose segments (10 cm) outgrow the grid's
   * cells, which are listed apart and tested against every cell they cover and each other;
   * then so many long ones that the cells grow instead. */
  for (const int long_num : {12, 1100}) {
    Strands strands = random_strands(long_num == 12 ? 150 : 40, 10, 11);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (int s = 0; s < long_num; s++) {
      const vec3 a = 0.04f * vec3(u(rng), u(rng), u(rng));
      const vec3 dir = glm::normalize(vec3(u(rng), u(rng), u(rng)) + vec3(1e-3f));
      strands.add({a, a + 0.1f * dir, a + 0.1f * dir + 0.005f * vec3(0, 0, 1)});
    }
    const float radius = 0.001f;
    SegmentGridScratch scratch;
    std::vector<SegmentContact> contacts;
    find_segment_contacts(strands.offsets, strands.positions, {}, radius, false, scratch,
                          contacts);
    std::set<std::pair<int32_t, int32_t>> found;
    for (const SegmentContact &c : contacts) {
      found.insert({c.first, c.second});
    }
    EXPECT_EQ(found.size(), contacts.size()) << "a pair was reported twice";
    const auto reference = brute_force(strands, radius, false);
    EXPECT_GT(reference.size(), 50u);
    EXPECT_EQ(found, reference) << long_num << " long strands";
    EXPECT_GT(scratch.big_segments.size(), 0u);
    EXPECT_LE(scratch.big_segments.size(), 1024u);
  }
}

TEST(HairHair, MovingStrandsFindTheContactsOfTheirPairsAlone)
{
  /* With continuous detection (each segment swept from x − h v), the grid over all strands
   * finds exactly the contacts it finds over each pair of strands alone (and each strand alone
   * for its own), field for field. */
  const Strands strands = random_strands(40, 7, 13);
  SweptSphereParams params;
  params.thickness = 0.0015f;
  const float h = 0.02f;
  const auto find = [&](const std::vector<int> &curves) {
    Strands subset;
    std::vector<int32_t> first_point;
    for (const int c : curves) {
      const auto begin = strands.positions.begin() + strands.offsets[size_t(c)];
      const auto end = strands.positions.begin() + strands.offsets[size_t(c) + 1];
      first_point.push_back(strands.offsets[size_t(c)] - int32_t(subset.positions.size()));
      subset.add(std::vector<vec3>(begin, end), strands.velocities[size_t(strands.offsets[size_t(c)])]);
    }
    SegmentGridScratch scratch;
    std::vector<SegmentContact> contacts;
    find_segment_contacts(subset.offsets, subset.positions, {}, params.thickness, false, scratch,
                          contacts, {}, subset.velocities, &params, h);
    /* Back to the indices of all strands. */
    const auto global = [&](const int32_t p) {
      return p + first_point[size_t(std::upper_bound(subset.offsets.begin(), subset.offsets.end(), p) -
                                    subset.offsets.begin() - 1)];
    };
    for (SegmentContact &c : contacts) {
      c.first = global(c.first);
      c.second = global(c.second);
    }
    return contacts;
  };
  std::vector<int> all(40);
  for (int c = 0; c < 40; c++) {
    all[size_t(c)] = c;
  }
  const std::vector<SegmentContact> together = find(all);
  std::vector<SegmentContact> alone;
  for (int a = 0; a < 40; a++) {
    for (int b = a; b < 40; b++) {
      for (const SegmentContact &c : find(a == b ? std::vector<int>{a} : std::vector<int>{a, b})) {
        const bool own = a == b, pair_of_both = c.first < strands.offsets[size_t(a) + 1] &&
                                               c.second >= strands.offsets[size_t(b)];
        if (own || pair_of_both) {
          alone.push_back(c);
        }
      }
    }
  }
  std::sort(alone.begin(), alone.end(), [](const SegmentContact &p, const SegmentContact &q) {
    return p.first != q.first ? p.first < q.first : p.second < q.second;
  });
  int64_t crossed = 0;
  ASSERT_EQ(together.size(), alone.size());
  for (size_t i = 0; i < together.size(); i++) {
    const SegmentContact &p = together[i], &q = alone[i];
    EXPECT_EQ(p.first, q.first);
    EXPECT_EQ(p.second, q.second);
    EXPECT_EQ(p.crossed, q.crossed);
    EXPECT_EQ(p.parallel, q.parallel);
    EXPECT_EQ(std::memcmp(&p.overlap, &q.overlap, sizeof(float)), 0);
    EXPECT_EQ(std::memcmp(&p.move, &q.move, sizeof(vec3)), 0);
    crossed += p.crossed ? 1 : 0;
  }
  EXPECT_GT(together.size(), 50u);
  EXPECT_GT(crossed, 5);
}

/* Strands that move together (a character walking: here 4 cm in the substep, four
 * segments' length) sweep their boxes in the frame of that common move, so they meet as many
 * candidate pairs as at rest and find the same contacts; swept in the world, every box would
 * stretch over the whole move. */
TEST(HairHair, StrandsMovingTogetherMeetTheCandidatesOfStrandsAtRest)
{
  Strands strands = random_strands(40, 7, 13);
  SweptSphereParams params;
  params.thickness = 0.0015f;
  const float h = 0.02f;
  const auto find = [&](const vec3 &velocity, int64_t &r_candidates) {
    std::fill(strands.velocities.begin(), strands.velocities.end(), velocity);
    SegmentGridScratch scratch;
    std::vector<SegmentContact> contacts;
    find_segment_contacts(strands.offsets, strands.positions, {}, params.thickness, false, scratch,
                          contacts, {}, strands.velocities, &params, h);
    r_candidates = scratch.candidate_pairs_num;
    return contacts;
  };
  int64_t at_rest = 0, moving = 0;
  const std::vector<SegmentContact> still = find(vec3(0.0f), at_rest);
  const std::vector<SegmentContact> walking = find(vec3(1.2f, -1.0f, 1.0f), moving);
  std::printf("candidate pairs: %lld at rest, %lld moving together\n", (long long)at_rest,
              (long long)moving);
  EXPECT_LE(double(moving), 1.02 * double(at_rest));
  ASSERT_EQ(walking.size(), still.size());
  for (size_t i = 0; i < still.size(); i++) {
    EXPECT_EQ(walking[i].first, still[i].first);
    EXPECT_EQ(walking[i].second, still[i].second);
    EXPECT_FALSE(walking[i].crossed);
  }
  EXPECT_GT(still.size(), 50u);
}

TEST(HairHair, PerPointRadiiSetEachSegmentsSweptSphere)
{
  /* Two parallel strands 3 mm apart: they touch with radii 2 mm, not with 1 mm. */
  Strands strands;
  strands.add({vec3(0, 0, 0), vec3(0.01f, 0, 0.0f), vec3(0.02f, 0, 0)});
  strands.add({vec3(0, 0.003f, 0), vec3(0.01f, 0.003f, 0), vec3(0.02f, 0.003f, 0)});
  const std::vector<float> thin(6, 0.001f), thick(6, 0.002f);
  EXPECT_EQ(count_crossings(strands.offsets, strands.positions, thin, 0.0f), 0);
  EXPECT_EQ(count_crossings(strands.offsets, strands.positions, thick, 0.0f), 4);
}

TEST(HairHair, CrossingSegmentsArePushedApartByHalfTheOverlapEach)
{
  /* Two strands whose second segments cross at right angles, 1 mm apart; radii 1 mm. */
  const float r = 0.001f;
  Strands strands;
  strands.add({vec3(-0.02f, 0, 0), vec3(-0.005f, 0, 0), vec3(0.005f, 0, 0)}, vec3(0, 0, 0.1f));
  strands.add({vec3(0, -0.02f, 0.001f), vec3(0, -0.005f, 0.001f), vec3(0, 0.005f, 0.001f)},
              vec3(0, 0, -0.1f));
  SweptSphereParams params;
  params.thickness = r;
  SegmentGridScratch scratch;
  std::vector<SegmentContact> contacts;
  const std::vector<vec3> before = strands.positions;
  const HairHairStats stats = resolve_hair_hair(params, strands.state(), scratch, contacts);
  EXPECT_EQ(stats.pairs_num, 1);
  EXPECT_EQ(stats.pushed_num, 1);
  const std::vector<vec3> &x = strands.positions;
  /* Overlap 1 mm: each contact point moves 0.5 mm along the closest-point vector (z). */
  EXPECT_NEAR(segment_segment_distance(x[1], x[2], x[4], x[5]).distance, 2.0f * r, 1e-7f);
  const vec3 moved_a = glm::mix(x[1], x[2], 0.5f) - glm::mix(before[1], before[2], 0.5f);
  EXPECT_NEAR(moved_a.z, -0.0005f, 1e-8f);
  EXPECT_NEAR(glm::length(vec3(moved_a.x, moved_a.y, 0.0f)), 0.0f, 1e-9f);
  EXPECT_EQ(x[0], before[0]) << "roots stay";
  EXPECT_EQ(x[3], before[3]);
  /* They were approaching at 0.2 m/s along z: no longer. */
  const vec3 va = glm::mix(strands.velocities[1], strands.velocities[2], 0.5f);
  const vec3 vb = glm::mix(strands.velocities[4], strands.velocities[5], 0.5f);
  EXPECT_NEAR(vb.z - va.z, 0.0f, 1e-6f);
}

TEST(HairHair, NearParallelSegmentsShareTheirAverageVelocity)
{
  /* Second segments 4 cm long, 10° apart, crossing at their middles 0.5 mm apart (radii
   * 1 mm; their ends are 3.5 mm apart); the root segments come from below and above. */
  const float r = 0.001f;
  const vec3 dir(std::cos(0.1745f), std::sin(0.1745f), 0.0f);
  const vec3 lift(0.0f, 0.0f, 0.0005f);
  Strands strands;
  strands.add({vec3(-0.02f, 0, -0.02f), vec3(-0.02f, 0, 0), vec3(0.02f, 0, 0)}, vec3(0.2f, 0, 0));
  strands.add({vec3(0, 0, 0.02f) - 0.02f * dir + lift, -0.02f * dir + lift, 0.02f * dir + lift},
              vec3(0.0f, 0.1f, 0));
  SweptSphereParams params;
  params.thickness = r;
  params.near_parallel_angle = 0.2618f; /* 15° */
  SegmentGridScratch scratch;
  std::vector<SegmentContact> contacts;
  const std::vector<vec3> before = strands.positions;
  const HairHairStats stats = resolve_hair_hair(params, strands.state(), scratch, contacts);
  EXPECT_EQ(stats.pairs_num, 1);
  EXPECT_EQ(stats.averaged_num, 1);
  EXPECT_EQ(strands.positions, before) << "near-parallel pairs are not pushed";
  /* Both segments now move at the average (0.1, 0.05, 0); the roots keep theirs. */
  for (const int p : {1, 2, 4, 5}) {
    EXPECT_NEAR(strands.velocities[size_t(p)].x, 0.1f, 1e-6f) << p;
    EXPECT_NEAR(strands.velocities[size_t(p)].y, 0.05f, 1e-6f) << p;
  }
  EXPECT_EQ(strands.velocities[0], vec3(0.2f, 0, 0));
  params.near_parallel_angle = 0.1f; /* now 10° is not near parallel: pushed */
  strands.velocities.assign(6, vec3(0.0f));
  EXPECT_EQ(resolve_hair_hair(params, strands.state(), scratch, contacts).pushed_num, 1);
}

TEST(HairHair, NeighbouringSegmentsOfAStrandAreSkipped)
{
  /* A strand folded back on itself: segments 0 and 1 meet at a node (skipped), segments 0 and
   * 2 lie on each other (a real self-contact). */
  Strands strands;
  strands.add({vec3(0, 0, 0), vec3(0.01f, 0, 0), vec3(0.0f, 0.0005f, 0), vec3(0.01f, 0.001f, 0)});
  SegmentGridScratch scratch;
  std::vector<SegmentContact> contacts;
  find_segment_contacts(strands.offsets, strands.positions, {}, 0.001f, false, scratch, contacts);
  ASSERT_EQ(contacts.size(), 1u);
  EXPECT_EQ(contacts[0].first, 0);
  EXPECT_EQ(contacts[0].second, 2);
  EXPECT_EQ(count_crossings(strands.offsets, strands.positions, {}, 0.001f), 0);
}

TEST(HairHair, SegmentsThatCrossedDuringTheSubstepGoBackToTheirSides)
{
  /* Segment b came down through segment a in this substep (it was 2 mm above it at the start,
   * x − h v) and is now 0.4 mm below it: it goes back above. */
  const float r = 0.0005f, h = 0.01f;
  Strands strands;
  strands.add({vec3(-0.02f, 0, 0), vec3(-0.005f, 0, 0), vec3(0.005f, 0, 0)});
  strands.add({vec3(0, -0.02f, -0.0004f), vec3(0, -0.005f, -0.0004f), vec3(0, 0.005f, -0.0004f)},
              vec3(0, 0, -0.24f));
  SweptSphereParams params;
  params.thickness = r;
  SegmentGridScratch scratch;
  std::vector<SegmentContact> contacts;
  resolve_hair_hair(params, strands.state(h), scratch, contacts);
  const std::vector<vec3> &x = strands.positions;
  const CoreDistance after = segment_segment_distance(x[1], x[2], x[4], x[5]);
  EXPECT_GT(after.point_b.z, after.point_a.z) << "b is above a again";
  EXPECT_NEAR(after.distance, 2.0f * r, 1e-6f);
}

/* The same crossing between two groups' volumes (level of detail: GroupVolumes). Apart at rest,
 * b goes back above a, as two strands do. Overlapping at rest (their strands interleave, the
 * cores 1.2 mm apart within the radii's 2 mm), b stays below, where its core went, and the pair
 * is kept as far apart as at rest: interleaved wisps may pass each other. */
TEST(HairHair, GroupsThatInterleaveAtRestMayPassEachOther)
{
  const float r = 0.001f, h = 0.01f;
  for (const float rest_gap : { 0.005f, 0.0012f }) {
    SCOPED_TRACE("b " + std::to_string(rest_gap) + " m above a at rest");
    Strands strands;
    strands.add({ vec3(-0.02f, 0, 0), vec3(-0.005f, 0, 0), vec3(0.005f, 0, 0) });
    strands.add(
        { vec3(0, -0.02f, -0.0004f), vec3(0, -0.005f, -0.0004f), vec3(0, 0.005f, -0.0004f) },
        vec3(0, 0, -0.24f));
    std::vector<vec3> rest = strands.positions;
    for (size_t p = 3; p < rest.size(); p++) {
      rest[p].z = rest_gap;
    }
    SweptSphereParams params;
    params.thickness = r;
    SubstepState state = strands.state(h);
    state.rest_positions_hs = rest;
    SegmentGridScratch scratch;
    std::vector<SegmentContact> contacts;
    const HairHairStats stats = resolve_hair_hair(params, state, scratch, contacts);
    const std::vector<vec3> &x = strands.positions;
    const CoreDistance after = segment_segment_distance(x[1], x[2], x[4], x[5]);
    const bool apart_at_rest = rest_gap >= 2.0f * r;
    EXPECT_EQ(stats.crossed_num, apart_at_rest ? 1 : 0);
    EXPECT_EQ(after.point_b.z > after.point_a.z, apart_at_rest) << "b above a";
    EXPECT_NEAR(after.distance, apart_at_rest ? 2.0f * r : rest_gap, 1e-6f);
  }
}

/* Three passes over 400 random strands (the seed's), each swept from x − h v; the last
 * pass's statistics in r_stats. */
Strands three_passes(const uint32_t seed, const float h, HairHairStats *r_stats = nullptr)
{
  Strands strands = random_strands(400, 12, seed);
  SweptSphereParams params;
  params.thickness = 0.0015f;
  SegmentGridScratch scratch;
  std::vector<SegmentContact> contacts;
  for (int i = 0; i < 3; i++) {
    const HairHairStats stats = resolve_hair_hair(params, strands.state(h), scratch, contacts);
    if (r_stats != nullptr) {
      *r_stats = stats;
    }
  }
  return strands;
}

bool same_bits(const Strands &a, const Strands &b)
{
  return a.positions.size() == b.positions.size() &&
         std::memcmp(a.positions.data(), b.positions.data(), a.positions.size() * sizeof(vec3)) ==
             0 &&
         std::memcmp(a.velocities.data(), b.velocities.data(),
                     a.velocities.size() * sizeof(vec3)) == 0;
}

TEST(HairHair, SameBitsOnOneAndTwoThreads)
{
  const auto run = [](const int threads) {
    set_thread_num(threads);
    const Strands strands = three_passes(3, 1e-3f);
    set_thread_num(0);
    return strands;
  };
  EXPECT_TRUE(same_bits(run(1), run(2)));
}

TEST(HairHair, SameBitsWithAndWithoutAvx2)
{
  /* The sweep and cannot_touch eight entries at a time (AVX2) against four (the baseline):
   * the same candidates, contacts and bits, on strands that move (continuous detection) and
   * at rest. */
  if (!collision_avx2_available()) {
    GTEST_SKIP() << "no AVX2 on this CPU";
  }
  const bool was_used = collision_avx2_used();
  for (const float h : { 0.0f, 0.02f }) {
    SCOPED_TRACE("h " + std::to_string(h));
    HairHairStats baseline_stats, avx2_stats;
    set_collision_avx2(false);
    const Strands baseline = three_passes(5, h, &baseline_stats);
    set_collision_avx2(true);
    const Strands avx2 = three_passes(5, h, &avx2_stats);
    EXPECT_EQ(avx2_stats.candidates_num, baseline_stats.candidates_num);
    EXPECT_EQ(avx2_stats.pairs_num, baseline_stats.pairs_num);
    EXPECT_GT(baseline_stats.pairs_num, 100);
    EXPECT_TRUE(same_bits(baseline, avx2));
  }
  set_collision_avx2(was_used);
}

TEST(HairHair, RepeatedPassesSeparateTwoInterpenetratingLayers)
{
  /* A layer of 20 straight strands along x at z = 0 and one along y at z = 0.5 mm, strands
   * 2 mm apart, radius 0.5 mm: every strand crosses every strand of the other layer. Each pass
   * pushes the crossing pairs apart by half their overlap each. */
  Strands strands;
  for (int i = 0; i < 20; i++) {
    const float offset = -0.02f + 0.002f * float(i);
    std::vector<vec3> along_x, along_y;
    for (int k = 0; k <= 8; k++) {
      const float t = -0.025f + 0.00625f * float(k);
      along_x.push_back(vec3(t, offset, 0.0f));
      along_y.push_back(vec3(offset, t, 0.0005f));
    }
    strands.add(along_x);
    strands.add(along_y);
  }
  SweptSphereParams params;
  params.thickness = 0.0005f;
  const int64_t before = count_crossings(strands.offsets, strands.positions, {}, params.thickness);
  EXPECT_GE(before, 400);
  SegmentGridScratch scratch;
  std::vector<SegmentContact> contacts;
  for (int i = 0; i < 4; i++) {
    resolve_hair_hair(params, strands.state(), scratch, contacts);
  }
  EXPECT_EQ(count_crossings(strands.offsets, strands.positions, {}, params.thickness * 0.999f), 0);
}
