/* Pinned points (groom/pins.hh): reach_pin brings a pin onto its target with every length kept, and the strand
 * solver holds pinned points on their rest positions carried by the head, like the roots, in
 * both strand models, with and without substep passes. */
#include <gtest/gtest.h>

#include <cmath>

#include "groom/groom.hh"
#include "groom/metrics.hh"
#include "groom/pins.hh"
#include "strand_scenes.hh"
#include "strands/strand_solver.hh"

using namespace hairdyn;

namespace {

using strand_scenes::Groom;

/* 16 segments of 1.5 cm; a hard shake (yaw at 8 rad/s, sliding at 10 rad/s). */
Groom wavy_groom(const int strands_num)
{
  return strand_scenes::wavy_groom(strands_num, 16, 0.015f);
}

mat4 shaking_head(const int frame)
{
  return strand_scenes::swaying_head(frame, 8.0f, 10.0f);
}

/* Pins the points `index_in_strand` (negative: from the tip) of every strand. */
std::vector<uint8_t> pin_points(const Groom &groom, const std::vector<int> &index_in_strand)
{
  std::vector<uint8_t> pinned(groom.positions.size(), 0);
  for (size_t c = 0; c + 1 < groom.offsets.size(); c++) {
    const int size = groom.offsets[c + 1] - groom.offsets[c];
    for (const int k : index_in_strand) {
      pinned[size_t(groom.offsets[c] + (k < 0 ? size + k : k))] = 1;
    }
  }
  return pinned;
}

/* m, the farthest a pinned point gets from its rest position carried by the head. */
float pin_drift(const Groom &groom, const std::vector<uint8_t> &pinned, Span<vec3> positions,
                const mat4 &head)
{
  float drift = 0.0f;
  for (size_t i = 0; i < pinned.size(); i++) {
    if (pinned[i]) {
      const vec3 carried = vec3(head * vec4(groom.positions[i], 1.0f));
      drift = std::max(drift, glm::length(positions[int64_t(i)] - carried));
    }
  }
  return drift;
}

/* A uniform push of every node, about half a g: a substep pass (volume, swept spheres) that
 * pins must survive. */
class PushPass : public SubstepPass {
 public:
  const char *name() const override { return "push"; }
  void apply(const SubstepState &state) override
  {
    for (int64_t i = 0; i < state.positions_wo.size(); i++) {
      state.positions_wo[i].y += 0.0002f;
      state.velocities_wo[i].y += 0.05f;
    }
  }
};

struct PinCase {
  StrandModel model;
  bool with_pass;
};

class StrandPins : public testing::TestWithParam<PinCase> {};

/* 96 frames of the shaking head with the points `pinned_indices` of every strand pinned: the
 * pins stay within 0.1 mm of their head-carried rest positions (where the same points of an
 * unpinned groom move by centimetres), no segment stretches, and the other points still move. */
void run_pinned(const PinCase c, const std::vector<int> &pinned_indices)
{
  const Groom groom = wavy_groom(12);
  StrandParams params;
  params.model = c.model;
  params.substeps = 4;
  StrandSolver free(groom.offsets, groom.positions, mat4(1.0f), {}, params);
  StrandSolver held(groom.offsets, groom.positions, mat4(1.0f), {}, params);
  const std::vector<uint8_t> pinned = pin_points(groom, pinned_indices);
  held.set_pinned(pinned);
  EXPECT_EQ(held.pins_num(), int64_t(12 * pinned_indices.size()));
  PushPass push_free, push_held;
  if (c.with_pass) {
    free.add_pass(&push_free);
    held.add_pass(&push_held);
  }
  float drift = 0.0f, free_drift = 0.0f, stretch = 0.0f;
  int64_t diverged = 0;
  for (int frame = 1; frame <= 96; frame++) {
    const mat4 head = shaking_head(frame);
    free.step(1.0f / 24.0f, head);
    held.step(1.0f / 24.0f, head);
    diverged += held.diverged_num();
    drift = std::max(drift, pin_drift(groom, pinned, held.positions(), head));
    free_drift = std::max(free_drift, pin_drift(groom, pinned, free.positions(), head));
    stretch =
        std::max(stretch, max_relative_stretch(groom.offsets, groom.positions, held.positions()));
  }
  EXPECT_EQ(diverged, 0);
  EXPECT_GT(free_drift, 0.005f) << "the shake does not move unpinned points: a vacuous test";
  EXPECT_LE(drift, 1e-4f) << "pinned points left their head-carried rest positions";
  EXPECT_LE(stretch, 1e-5f);
  /* The points beyond a pin still move: only the pins are kinematic. */
  const Span<vec3> x = held.positions();
  bool moved = false;
  for (size_t i = 0; i < pinned.size(); i++) {
    const vec3 carried = vec3(shaking_head(96) * vec4(groom.positions[i], 1.0f));
    moved = moved || (!pinned[i] && glm::length(x[int64_t(i)] - carried) > 1e-3f);
  }
  EXPECT_TRUE(moved);
}

}  // namespace

TEST(Pins, ReachPinReachesTheTargetWithLengthsKept)
{
  std::vector<vec3> chain;
  std::vector<float> lengths{ 0.0f };
  for (int i = 0; i <= 10; i++) {
    chain.emplace_back(0.1f * float(i), 0.02f * std::sin(float(i)), 0.0f);
    if (i > 0) {
      lengths.push_back(glm::length(chain[size_t(i)] - chain[size_t(i - 1)]));
    }
  }
  const vec3 target = chain.back() + vec3(-0.05f, 0.1f, 0.03f);
  const float error = reach_pin(MutableSpan<vec3>(chain), Span<float>(lengths), target, 1e-6f);
  EXPECT_LE(error, 1e-6f);
  EXPECT_LE(glm::length(chain.back() - target), 1e-6f);
  EXPECT_EQ(chain.front(), vec3(0.0f));
  for (size_t i = 1; i < chain.size(); i++) {
    EXPECT_NEAR(glm::length(chain[i] - chain[i - 1]), lengths[i], 1e-6f);
  }
  /* Out of reach: straight toward it, lengths kept. */
  const float error_far =
      reach_pin(MutableSpan<vec3>(chain), Span<float>(lengths), vec3(0.0f, 5.0f, 0.0f), 1e-6f);
  EXPECT_GT(error_far, 3.0f);
  for (size_t i = 1; i < chain.size(); i++) {
    EXPECT_NEAR(chain[i].x, 0.0f, 1e-6f);
    EXPECT_NEAR(glm::length(chain[i] - chain[i - 1]), lengths[i], 1e-6f);
  }
}

TEST_P(StrandPins, PinnedTipsStayOnTheHead)
{
  run_pinned(GetParam(), { -1 });
}

TEST_P(StrandPins, PinnedMiddleAndTipStayOnTheHead)
{
  run_pinned(GetParam(), { 8, -1 });
}

TEST_P(StrandPins, PinnedMiddleStaysOnTheHeadAndTheTipSwings)
{
  run_pinned(GetParam(), { 6 });
}

INSTANTIATE_TEST_SUITE_P(Models, StrandPins,
                         testing::Values(PinCase{ StrandModel::Kurihara1993, false },
                                         PinCase{ StrandModel::Articulated, false },
                                         PinCase{ StrandModel::Kurihara1993, true },
                                         PinCase{ StrandModel::Articulated, true }),
                         [](const testing::TestParamInfo<PinCase> &param_info) {
                           return std::string(param_info.param.model == StrandModel::Kurihara1993
                                                  ? "Kurihara1993"
                                                  : "Articulated") +
                                  (param_info.param.with_pass ? "WithPass" : "");
                         });

TEST(StrandPinsReset, NoPinsChangeNoBit)
{
  /* An empty mask (and a mask of roots only) leaves the solver as it was, bit for bit. */
  const Groom groom = wavy_groom(6);
  StrandParams params;
  StrandSolver plain(groom.offsets, groom.positions, mat4(1.0f), {}, params);
  StrandSolver roots(groom.offsets, groom.positions, mat4(1.0f), {}, params);
  roots.set_pinned(pin_points(groom, { 0 }));
  EXPECT_EQ(roots.pins_num(), 0);
  for (int frame = 1; frame <= 12; frame++) {
    plain.step(1.0f / 24.0f, shaking_head(frame));
    roots.step(1.0f / 24.0f, shaking_head(frame));
  }
  for (int64_t i = 0; i < plain.positions().size(); i++) {
    EXPECT_EQ(plain.positions()[i], roots.positions()[i]);
  }
}
