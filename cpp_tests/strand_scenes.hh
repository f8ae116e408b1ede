#pragma once
/* Scenes shared by the strand tests: a wavy groom hanging from the top of a 0.1 m head, and a
 * head that sways about the vertical while it slides sideways. */
#include <algorithm>
#include <cmath>
#include <vector>

#include "core/math.hh"
#include "strands/strand_solver.hh"
#include "strands/substep_pass.hh"

namespace hairdyn::strand_scenes {

struct Groom {
  std::vector<int32_t> offsets{ 0 };
  std::vector<vec3> positions;

  void add_straight(const vec3 &root, const vec3 &direction, const float length,
                    const int segments)
  {
    for (int i = 0; i <= segments; i++) {
      positions.push_back(root +
                          glm::normalize(direction) * (length * float(i) / float(segments)));
    }
    offsets.push_back(int32_t(positions.size()));
  }
};

/* `strands_num` wavy strands of `segments_num` segments of `segment_length` m, rooted on a
 * 3 cm circle on the top of a 0.1 m head. */
inline Groom wavy_groom(const int strands_num, const int segments_num, const float segment_length)
{
  Groom groom;
  for (int s = 0; s < strands_num; s++) {
    const float angle = 6.2831853f * float(s) / float(strands_num);
    const vec3 out(std::cos(angle), std::sin(angle), 0.0f);
    vec3 p = vec3(0.0f, 0.0f, 0.101f) + 0.03f * out;
    for (int i = 0; i <= segments_num; i++) {
      groom.positions.push_back(p);
      p += segment_length * glm::normalize(out + vec3(0.0f, 0.3f * std::sin(float(i)), -0.5f));
    }
    groom.offsets.push_back(int32_t(groom.positions.size()));
  }
  return groom;
}

/* The head at `frame` (24 fps): ±0.6 rad about the vertical at `yaw_rate` rad/s and ±5 cm
 * along x at `slide_rate` rad/s. */
inline mat4 swaying_head(const int frame, const float yaw_rate, const float slide_rate)
{
  const float t = float(frame) / 24.0f;
  return glm::rotate(
      glm::translate(mat4(1.0f), vec3(0.05f * std::sin(slide_rate * t), 0.0f, 0.0f)),
      0.6f * std::sin(yaw_rate * t), vec3(0.0f, 0.0f, 1.0f));
}

/* Closest points of segments [a0, a1] and [b0, b1]: parameters s, u in [0, 1]. */
inline void closest_parameters(const vec3 &a0, const vec3 &a1, const vec3 &b0, const vec3 &b1,
                               float &r_s, float &r_u)
{
  const vec3 da = a1 - a0, db = b1 - b0, r = a0 - b0;
  const float aa = glm::dot(da, da), bb = glm::dot(db, db), ab = glm::dot(da, db);
  const float ar = glm::dot(da, r), br = glm::dot(db, r);
  const float denominator = aa * bb - ab * ab;
  float s =
      denominator > 1e-12f ? glm::clamp((ab * br - bb * ar) / denominator, 0.0f, 1.0f) : 0.0f;
  float u = glm::clamp((ab * s + br) / bb, 0.0f, 1.0f);
  s = glm::clamp((ab * u - ar) / aa, 0.0f, 1.0f);
  r_s = s;
  r_u = u;
}

/* Pairs of segments, one of sheet A (strands [0, split)) and one of sheet B (the rest), that
 * pass through each other between two states: at both states their closest points lie inside
 * both segments, less than `reach` apart, and the side of segment b on which segment a lies
 * (the sign of (a − b) · (da × db) at the closest points) flips. A geometric count, independent
 * of the solver and of any collision pass. */
inline int64_t count_sheet_crossings(const Groom &groom, const int64_t split,
                                     const std::vector<vec3> &before,
                                     const std::vector<vec3> &after, const float reach)
{
  const auto side = [&](const std::vector<vec3> &x, const int64_t a, const int64_t b,
                        float &r_side) {
    float s, u;
    closest_parameters(x[a], x[a + 1], x[b], x[b + 1], s, u);
    if (s <= 0.0f || s >= 1.0f || u <= 0.0f || u >= 1.0f) {
      return false;
    }
    const vec3 gap = glm::mix(x[a], x[a + 1], s) - glm::mix(x[b], x[b + 1], u);
    if (glm::length(gap) > reach) {
      return false;
    }
    r_side = glm::dot(gap, glm::cross(x[a + 1] - x[a], x[b + 1] - x[b]));
    return true;
  };
  int64_t crossings = 0;
  const int64_t curves_num = int64_t(groom.offsets.size()) - 1;
  for (int64_t ca = 0; ca < split; ca++) {
    for (int64_t a = groom.offsets[ca]; a < groom.offsets[ca + 1] - 1; a++) {
      for (int64_t cb = split; cb < curves_num; cb++) {
        for (int64_t b = groom.offsets[cb]; b < groom.offsets[cb + 1] - 1; b++) {
          float side_before, side_after;
          if (side(before, a, b, side_before) && side(after, a, b, side_after) &&
              (side_before > 0.0f) != (side_after > 0.0f))
          {
            crossings++;
          }
        }
      }
    }
  }
  return crossings;
}

/* Petrovic 2006 Fig. 4's situation: two sheets of strands pass through each other. Sheet A,
 * `strands_per_sheet` horizontal strands `spacing` apart along +x, falls under gravity through
 * sheet B, strands at 45° in the plane x = `plane_x` (the farther out, the faster A's segments
 * meet it). Both sheets are limp: in Kurihara's model near-zero hinge springs, in the
 * articulated model human hair (the default material; Γ ≈ 70 for these 20 cm strands). In
 * Kurihara's model B hangs from its upper end and A sweeps through it; two articulated sheets
 * hanging from above sag together and hardly pass through each other, so there B stands from
 * roots 14 cm lower and falls over through A. */
struct CrossingSheets {
  int strands_per_sheet = 12;
  float spacing = 0.01f; /* m, between neighbouring strands of a sheet */
  float plane_x = 0.06f; /* m, sheet B's plane */
  int frames = 40;       /* at 100 fps, 4 substeps each */
};

struct SheetsResult {
  int64_t crossings = 0;      /* count_sheet_crossings summed over the frames */
  float tip_drop = 0.0f;      /* m, how far sheet A's tips fell on average */
  int64_t diverged = 0;       /* strands the solver reported diverged, over the frames */
  float worst_stretch = 0.0f; /* the largest |length − rest length| / rest length of a segment */
  float fastest = 0.0f;       /* m/s, the fastest node at the end of any frame */
};

inline Groom crossing_sheets_groom(const StrandModel model, const CrossingSheets &scene)
{
  Groom groom;
  const int n = scene.strands_per_sheet;
  const float half = 0.5f * scene.spacing * float(n - 1);
  for (int i = 0; i < n; i++) {
    groom.add_straight(vec3(0.0f, -half + scene.spacing * float(i), 0.0f), vec3(1, 0, 0), 0.2f,
                       10);
  }
  /* Lines from (plane_x, -half - 0.045 + spacing i, 0.03) along (0, 1, -1), rooted at their
   * upper end (Kurihara) or their lower end (articulated). */
  const vec3 down = 0.2f * glm::normalize(vec3(0, 1, -1));
  const bool from_below = model == StrandModel::Articulated;
  for (int i = 0; i < n; i++) {
    const vec3 top(scene.plane_x, -half - 0.045f + scene.spacing * float(i), 0.03f);
    groom.add_straight(from_below ? top + down : top, from_below ? -down : down, 0.2f, 10);
  }
  return groom;
}

/* Runs the scene with `pass` (nullptr: none) in the solver's substeps. */
inline SheetsResult run_crossing_sheets(const StrandModel model, SubstepPass *pass,
                                        const CrossingSheets &scene = CrossingSheets())
{
  const Groom groom = crossing_sheets_groom(model, scene);
  StrandParams params;
  params.model = model;
  params.k_theta = params.k_phi = 1e-9f; /* Kurihara: limp */
  params.damping = 1e-11f;
  params.substeps = 4;
  StrandSolver solver(groom.offsets, groom.positions, mat4(1.0f), {}, params);
  if (pass != nullptr) {
    solver.add_pass(pass);
  }
  SheetsResult result;
  std::vector<vec3> before(solver.positions().begin(), solver.positions().end());
  for (int frame = 0; frame < scene.frames; frame++) {
    solver.step(1.0f / 100.0f, mat4(1.0f));
    result.diverged += solver.diverged_num();
    const std::vector<vec3> after(solver.positions().begin(), solver.positions().end());
    result.crossings +=
        count_sheet_crossings(groom, scene.strands_per_sheet, before, after, 0.02f);
    for (const vec3 &v : solver.velocities()) {
      result.fastest = std::max(result.fastest, glm::length(v));
    }
    for (size_t c = 0; c + 1 < groom.offsets.size(); c++) {
      for (int32_t p = groom.offsets[c] + 1; p < groom.offsets[c + 1]; p++) {
        const float rest =
            glm::length(groom.positions[size_t(p)] - groom.positions[size_t(p - 1)]);
        const float length = glm::length(after[size_t(p)] - after[size_t(p - 1)]);
        result.worst_stretch = std::max(result.worst_stretch, std::abs(length - rest) / rest);
      }
    }
    before = after;
  }
  for (int i = 0; i < scene.strands_per_sheet; i++) {
    result.tip_drop -= before[size_t(groom.offsets[i + 1] - 1)].z / float(scene.strands_per_sheet);
  }
  return result;
}

}  // namespace hairdyn::strand_scenes
