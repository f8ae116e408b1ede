#include "lcp/sampling_bando2003.hh"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <unordered_map>

#include "core/parallel.hh"
#include "core/spatial_grid.hh"
#include "groom/groom.hh"
#include "groom/metrics.hh"
#include "lcp/interactions_bando2003.hh"

namespace hairdyn {

float LengthMap::sample(const ScalpPoint &point, const vec2 &uv) const
{
  if (image.is_empty()) {
    return std::clamp(point.weight, 0.0f, 1.0f);
  }
  const float x = std::clamp(uv.x, 0.0f, 1.0f) * float(image_width - 1);
  const float y = std::clamp(uv.y, 0.0f, 1.0f) * float(image_height - 1);
  const int64_t x0 = std::min(int64_t(x), image_width - 1), y0 = std::min(int64_t(y), image_height - 1);
  const int64_t x1 = std::min(x0 + 1, image_width - 1), y1 = std::min(y0 + 1, image_height - 1);
  const float fx = x - float(x0), fy = y - float(y0);
  const auto at = [&](const int64_t col, const int64_t row) { return image[row * image_width + col]; };
  const float value = (1.0f - fy) * ((1.0f - fx) * at(x0, y0) + fx * at(x1, y0)) +
                      fy * ((1.0f - fx) * at(x0, y1) + fx * at(x1, y1));
  return std::clamp(value, 0.0f, 1.0f);
}

std::string find_length_map_error(const ScalpMap &scalp, const LengthMap &length)
{
  if (!length.image.is_empty()) {
    if (length.image_width < 1 || length.image_height < 1 ||
        length.image_width * length.image_height != length.image.size())
    {
      return "the length map image has the wrong size";
    }
    for (const float value : length.image) {
      if (value > 0.0f) {
        return {};
      }
    }
    return "the length map is empty (all zero): no hair would grow";
  }
  const Span<ivec3> triangles = scalp.triangles();
  for (int64_t t = 0; t < triangles.size(); t++) {
    vec2 uv;
    const ScalpPoint p = scalp.point_in_triangle(t, vec3(1.0f / 3.0f), uv);
    if (p.weight > 0.0f && scalp.triangle_areas()[t] > 0.0f) {
      return {};
    }
  }
  return "the length map is empty (all weights are zero): no hair would grow";
}

vec3 root_direction(const vec3 &normal, const vec3 &whorl_normal, const float w_t,
                    const float w_n)
{
  /* Bando 2003, eq. 4: t_r = −w_t {n_w − (n_w·n) n} + w_n n, then normalised. */
  const vec3 t = -w_t * (whorl_normal - glm::dot(whorl_normal, normal) * normal) + w_n * normal;
  const float len = glm::length(t);
  return len > 1e-8f ? t / len : normal;
}

void cantilever_beam(const vec3 &root, const vec3 &root_dir, const vec3 &gravity_dir,
                     const float length, const float s, const float bending_length,
                     vec3 &r_position, vec3 &r_direction)
{
  /* Anjyo et al. 1992: the hair is a cantilever beam clamped at the root. At arc length σ the
   * bending moment is the weight of the remaining hair (length ℓ = L − σ, taken straight
   * along the current direction) times its lever arm, M = λ g ℓ² sin φ / 2, where φ is the
   * angle between the hair and gravity. The curvature M / EI = ℓ² sin φ / (2 b³) turns the
   * direction toward gravity; integrate from the root to s. */
  vec3 x = root;
  vec3 t = root_dir;
  const float b3 = bending_length * bending_length * bending_length;
  const int steps = std::max(1, int(std::ceil(s / std::max(length, 1e-6f) * 64.0f)));
  const float ds = s / float(steps);
  for (int k = 0; k < steps; k++) {
    const float sigma = (float(k) + 0.5f) * ds;
    const float remaining = std::max(length - sigma, 0.0f);
    const vec3 g_perp = gravity_dir - glm::dot(gravity_dir, t) * t;
    const float sin_phi = glm::length(g_perp);
    const float turn = remaining * remaining * sin_phi / (2.0f * b3) * ds;
    const float half_turn = 0.5f * std::min(turn, std::asin(std::min(sin_phi, 1.0f)));
    /* Midpoint rule: advance along the direction half-way through the turn. */
    vec3 t_mid = t;
    if (sin_phi > 1e-7f) {
      const vec3 axis_dir = g_perp / sin_phi;
      t_mid = glm::normalize(std::cos(half_turn) * t + std::sin(half_turn) * axis_dir);
      t = glm::normalize(std::cos(2.0f * half_turn) * t + std::sin(2.0f * half_turn) * axis_dir);
    }
    x += t_mid * ds;
  }
  r_position = x;
  r_direction = t;
}

namespace {

/* Poisson-disc acceptance in the 4D space (x, y, z, s) whose Euclidean distance is eq. 3:
 * d(P1, P2)² = ‖φ⁻¹(u1, v1) − φ⁻¹(u2, v2)‖² + (s1 − s2)². Hashed cells of edge r. */
class PoissonDiscSet {
 public:
  explicit PoissonDiscSet(const float radius) : radius_(radius) {}

  bool try_insert(const vec3 &scalp_point, const float s)
  {
    const glm::ivec4 c = cell(scalp_point, s);
    for (int dw = -1; dw <= 1; dw++) {
      for (int dz = -1; dz <= 1; dz++) {
        for (int dy = -1; dy <= 1; dy++) {
          for (int dx = -1; dx <= 1; dx++) {
            const auto it = cells_.find(key(c + glm::ivec4(dx, dy, dz, dw)));
            if (it == cells_.end()) {
              continue;
            }
            for (const int32_t k : it->second) {
              const vec3 d = points_[size_t(k)] - scalp_point;
              const float ds = s_[size_t(k)] - s;
              /* Bando 2003, eq. 3. */
              if (glm::dot(d, d) + ds * ds < radius_ * radius_) {
                return false;
              }
            }
          }
        }
      }
    }
    cells_[key(c)].push_back(int32_t(points_.size()));
    points_.push_back(scalp_point);
    s_.push_back(s);
    return true;
  }
  int64_t size() const { return int64_t(points_.size()); }

 private:
  glm::ivec4 cell(const vec3 &p, const float s) const
  {
    return glm::ivec4(int(std::floor(p.x / radius_)), int(std::floor(p.y / radius_)),
                      int(std::floor(p.z / radius_)), int(std::floor(s / radius_)));
  }
  static uint64_t key(const glm::ivec4 &c)
  {
    const auto part = [](const int v) { return uint64_t(uint16_t(int16_t(v))); };
    return part(c.x) | (part(c.y) << 16) | (part(c.z) << 32) | (part(c.w) << 48);
  }

  float radius_;
  std::unordered_map<uint64_t, std::vector<int32_t>> cells_;
  std::vector<vec3> points_;
  std::vector<float> s_;
};

/* Fraction of space a maximal random Poisson-disc set of radius r leaves per sample is about
 * 1.745 r³ (random sequential adsorption in 3D jams at a sphere packing of ~0.38): radius
 * for a target count, with margin so that the target is reached before jamming. */
float radius_for_count(const double volume, const int64_t count)
{
  return float(std::cbrt(0.573 * volume / double(std::max<int64_t>(count, 1))));
}

/* Candidates uniformly distributed in the (u, v, s) volume, measured with eq. 3: area-uniform
 * on the scalp, s uniform in [−s_r, L_max], rejected above L(u, v). The first volume_probes
 * of them estimate the volume V = ∫ (L + s_r) dA by Monte Carlo (the plan); the sampler then
 * draws on from the same stream. */
class ScalpDarts {
 public:
  struct Candidate {
    ScalpPoint point;
    vec2 uv;
    float s, length;
  };

  ScalpDarts(const ScalpMap &scalp, const LengthMap &length, const LcpParams &params)
      : scalp_(scalp), length_(length), s_r_(params.root_depth), l_max_(params.max_length),
        rng_(uint64_t(params.seed))
  {
    assert(find_length_map_error(scalp, length).empty());
    const Span<float> areas = scalp.triangle_areas();
    cumulative_.assign(size_t(areas.size()) + 1, 0.0);
    for (int64_t t = 0; t < areas.size(); t++) {
      cumulative_[size_t(t) + 1] = cumulative_[size_t(t)] + double(areas[t]);
    }
    int64_t inside_num = 0;
    const int64_t volume_probes = 20000;
    Candidate c;
    for (int64_t k = 0; k < volume_probes; k++) {
      inside_num += draw(c) ? 1 : 0;
    }
    volume_ = cumulative_.back() * double(s_r_ + l_max_) * double(inside_num) /
              double(volume_probes);
  }

  /* One candidate; false when it lies above the length map. */
  bool draw(Candidate &r_c)
  {
    const double a = unit_(rng_) * cumulative_.back();
    const int64_t t = std::clamp<int64_t>(
        int64_t(std::upper_bound(cumulative_.begin(), cumulative_.end(), a) -
                cumulative_.begin()) - 1,
        0, int64_t(cumulative_.size()) - 2);
    double b1 = unit_(rng_), b2 = unit_(rng_);
    if (b1 + b2 > 1.0) {
      b1 = 1.0 - b1;
      b2 = 1.0 - b2;
    }
    r_c.point = scalp_.point_in_triangle(t, vec3(float(1.0 - b1 - b2), float(b1), float(b2)),
                                         r_c.uv);
    r_c.s = float(-double(s_r_) + unit_(rng_) * double(s_r_ + l_max_));
    r_c.length = l_max_ * length_.sample(r_c.point, r_c.uv);
    return r_c.s <= r_c.length;
  }

  double volume() const { return volume_; }

 private:
  const ScalpMap &scalp_;
  const LengthMap &length_;
  float s_r_, l_max_;
  std::vector<double> cumulative_;
  std::mt19937_64 rng_;
  std::uniform_real_distribution<double> unit_{0.0, 1.0};
  double volume_ = 0.0;
};

/* x as a count, at most 2⁶² (a request far beyond any limit stays beyond it, defined). */
int64_t saturated(const double x)
{
  return x < 4.6e18 ? int64_t(x) : int64_t(4.6e18);
}

ScalpSampling plan_from(const double volume, const LcpParams &params)
{
  ScalpSampling plan;
  plan.volume = volume;
  plan.radius = params.particle_num > 0 ? radius_for_count(volume, params.particle_num) :
                                          params.particle_spacing;
  plan.count = params.particle_num > 0 ?
                   int64_t(params.particle_num) :
                   saturated(volume / (1.745 * double(plan.radius) * plan.radius * plan.radius)) +
                       1;
  return plan;
}

/* The bits of x (below 2²¹) spread to every third bit: one axis of a Morton code. */
uint64_t spread_bits(uint64_t x)
{
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffull;
  x = (x | x << 16) & 0x1f0000ff0000ffull;
  x = (x | x << 8) & 0x100f00f00f00f00full;
  x = (x | x << 4) & 0x10c30c30c30c30c3ull;
  x = (x | x << 2) & 0x1249249249249249ull;
  return x;
}

/* The particles in Morton (Z) order of cells of `cell` m: particles near each other in space
 * lie near each other in memory, so the neighbours every interaction and matrix product
 * gathers are mostly in cache. Samplers hand them out in a random order; in this order
 * BM_LcpFrame/20000 takes 15% less with explicit pressure, 8% less with implicit. Ties keep
 * their order (the same particles give the same order). */
LcpParticles in_space_order(const LcpParticles &particles, const float cell)
{
  const int64_t n = particles.size();
  vec3 low, high;
  point_bounds(particles.positions, low, high);
  std::vector<std::pair<uint64_t, int64_t>> keys(static_cast<size_t>(n));
  for (int64_t i = 0; i < n; i++) {
    vec3 q = glm::clamp((particles.positions[size_t(i)] - low) / cell, vec3(0.0f),
                        vec3(float(0x1fffff)));
    q = is_finite(q) ? q : vec3(0.0f); /* never a NaN cast to an integer */
    keys[size_t(i)] = {spread_bits(uint64_t(q.x)) | spread_bits(uint64_t(q.y)) << 1 |
                           spread_bits(uint64_t(q.z)) << 2,
                       i};
  }
  std::sort(keys.begin(), keys.end());
  LcpParticles ordered;
  for (const auto &[key, i] : keys) {
    ordered.positions.push_back(particles.positions[size_t(i)]);
    ordered.directions.push_back(particles.directions[size_t(i)]);
    ordered.u.push_back(particles.u[size_t(i)]);
    ordered.v.push_back(particles.v[size_t(i)]);
    ordered.s.push_back(particles.s[size_t(i)]);
    if (!particles.fixed.empty()) {
      ordered.fixed.push_back(particles.fixed[size_t(i)]);
    }
  }
  return ordered;
}

}  // namespace

ScalpSampling plan_scalp_sampling(const ScalpMap &scalp, const LengthMap &length,
                                  const LcpParams &params)
{
  return plan_from(ScalpDarts(scalp, length, params).volume(), params);
}

std::string find_sampling_size_error(const ScalpSampling &plan, const LcpParams &params)
{
  if (plan.count > max_lcp_particles) {
    return "the particle " + std::string(params.particle_num > 0 ? "count" : "spacing") +
           " asks for about " + std::to_string(plan.count) + " particles, more than the " +
           std::to_string(max_lcp_particles) + " an LCP simulation may hold: " +
           (params.particle_num > 0 ? "lower the count" : "raise the spacing");
  }
  /* Neighbours of a particle within 2h (h the larger of h₁ and h₂) at the plan's density. */
  const double reach = 2.0 * double(std::max(params.h1, params.h2));
  const double neighbors = double(plan.count) / std::max(plan.volume, 1e-30) * 4.0 / 3.0 *
                           glm::pi<double>() * reach * reach * reach;
  if (double(plan.count) * neighbors > double(max_lcp_neighbor_entries)) {
    const int64_t entries = saturated(double(plan.count) * neighbors);
    return "with h₁ = " + std::to_string(params.h1) + " m and h₂ = " +
           std::to_string(params.h2) + " m each of about " + std::to_string(plan.count) +
           " particles would have about " + std::to_string(saturated(neighbors)) +
           " neighbours within 2 max(h₁, h₂), " + std::to_string(entries) +
           " in all, more than the " + std::to_string(max_lcp_neighbor_entries) +
           " the lists may hold: lower h₁ and h₂ with the particle spacing (Bando 2003 has "
           "each particle reach a few tens)";
  }
  return {};
}

LcpParticles sample_scalp_particles(const ScalpMap &scalp, const LengthMap &length,
                                    const LcpParams &params, const vec3 &gravity_dir)
{
  ScalpDarts darts(scalp, length, params);
  using Candidate = ScalpDarts::Candidate;
  const ScalpSampling plan = plan_from(darts.volume(), params);
  float radius = plan.radius;
  const int64_t expected_num = plan.count;
  Candidate c;
  std::vector<Candidate> accepted;
  PoissonDiscSet disc(radius);
  int64_t failures = 0;
  while (params.particle_num == 0 || int64_t(accepted.size()) < params.particle_num) {
    if (failures > 30 * expected_num + 1000) {
      if (params.particle_num == 0) {
        break; /* Maximal for this radius. */
      }
      /* Jammed before the target count: continue with a smaller disc (the samples kept so
       * far are farther apart than it, so they stay valid). */
      radius *= 0.9f;
      PoissonDiscSet smaller(radius);
      for (const Candidate &a : accepted) {
        smaller.try_insert(a.point.position, a.s);
      }
      disc = std::move(smaller);
      failures = 0;
    }
    if (!darts.draw(c) || !disc.try_insert(c.point.position, c.s)) {
      failures++;
      continue;
    }
    failures = 0;
    accepted.push_back(c);
  }

  const ScalpPoint whorl = scalp.locate(vec2(params.whorl_u, params.whorl_v));
  LcpParticles particles;
  for (const Candidate &a : accepted) {
    const vec3 t_r = root_direction(a.point.normal, whorl.normal, params.root_tangent_weight,
                                    params.root_normal_weight);
    vec3 x, t;
    if (a.s < 0.0f) {
      /* §3.2: root particles inside the scalp, x = φ⁻¹(u, v) + s t_r(u, v). */
      x = a.point.position + a.s * t_r;
      t = t_r;
    }
    else {
      cantilever_beam(a.point.position, t_r, gravity_dir, a.length, a.s, params.beam_length, x, t);
    }
    particles.positions.push_back(x);
    particles.directions.push_back(t);
    particles.u.push_back(a.uv.x);
    particles.v.push_back(a.uv.y);
    particles.s.push_back(a.s);
  }
  return in_space_order(particles, params.h2);
}

int64_t groom_candidates_num(const Span<int32_t> curve_offsets, const Span<vec3> positions,
                             const LcpParams &params)
{
  const double step = 0.25 * double(params.particle_spacing);
  double count = 0.0;
  for (int64_t c = 0; c + 1 < curve_offsets.size(); c++) {
    double length = 0.0;
    for (int64_t k = curve_offsets[c]; k + 1 < curve_offsets[c + 1]; k++) {
      length += double(glm::length(positions[k + 1] - positions[k]));
    }
    count += std::ceil(double(params.root_depth) / step) + std::floor(length / step) + 1.0;
  }
  return saturated(count);
}

LcpParticles sample_groom_particles(const Span<int32_t> curve_offsets, const Span<vec3> positions,
                                    const Span<vec2> root_uv, const LcpParams &params,
                                    const Span<uint8_t> pinned)
{
  assert(find_groom_error(curve_offsets, positions).empty());
  const int64_t curves_num = curve_offsets.size() - 1;
  /* (u, v) per strand. */
  std::vector<vec2> strand_uv(static_cast<size_t>(curves_num));
  if (!root_uv.is_empty()) {
    std::copy(root_uv.begin(), root_uv.end(), strand_uv.begin());
  }
  else {
    vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
    for (int64_t c = 0; c < curves_num; c++) {
      lo = glm::min(lo, positions[curve_offsets[c]]);
      hi = glm::max(hi, positions[curve_offsets[c]]);
    }
    const vec3 extent = hi - lo;
    int axes[3] = {0, 1, 2};
    std::sort(axes, axes + 3, [&](const int a, const int b) { return extent[a] > extent[b]; });
    for (int64_t c = 0; c < curves_num; c++) {
      const vec3 p = positions[curve_offsets[c]] - lo;
      strand_uv[size_t(c)] = vec2(p[axes[0]] / std::max(extent[axes[0]], 1e-12f),
                                  p[axes[1]] / std::max(extent[axes[1]], 1e-12f));
    }
  }

  /* Candidates every r/4 along each strand, its root continued s_r beneath the scalp. */
  struct Candidate {
    int32_t curve;
    float s;
    vec3 position, direction;
    uint8_t fixed = 0;
  };
  const float step = params.particle_spacing * 0.25f;
  std::vector<Candidate> candidates;
  for (int64_t c = 0; c < curves_num; c++) {
    const IndexRange points = curve_points(curve_offsets, c);
    const vec3 root = positions[points.start];
    const vec3 root_dir = glm::normalize(positions[points.start + 1] - root);
    for (float s = -params.root_depth; s < 0.0f; s += step) {
      candidates.push_back({int32_t(c), s, root + s * root_dir, root_dir, 0});
    }
    float arc = 0.0f, next = 0.0f;
    for (int64_t k = points.start; k + 1 < points.one_after_last(); k++) {
      const vec3 seg = positions[k + 1] - positions[k];
      const float len = glm::length(seg);
      while (next <= arc + len) {
        const float f = (next - arc) / len;
        const int64_t nearest = f <= 0.5f ? k : k + 1;
        const uint8_t fixed = !pinned.is_empty() && nearest != points.start && pinned[nearest];
        candidates.push_back({int32_t(c), next, positions[k] + f * seg, seg / len, fixed});
        next += step;
      }
      arc += len;
    }
  }
  std::mt19937_64 rng(uint64_t(params.seed));
  std::shuffle(candidates.begin(), candidates.end(), rng);

  /* Poisson-disc selection with eq. 3, where φ⁻¹(u, v) is the strand's root. */
  const auto select = [&](const float radius, const int64_t limit, std::vector<int32_t> &r_chosen) {
    r_chosen.clear();
    PoissonDiscSet disc(radius);
    for (size_t k = 0; k < candidates.size() && int64_t(r_chosen.size()) < limit; k++) {
      const Candidate &cand = candidates[k];
      if (disc.try_insert(positions[curve_offsets[cand.curve]], cand.s)) {
        r_chosen.push_back(int32_t(k));
      }
    }
  };
  std::vector<int32_t> chosen;
  const int64_t unlimited = std::numeric_limits<int64_t>::max();
  float radius = params.particle_spacing;
  select(radius, unlimited, chosen);
  if (params.particle_num > 0) {
    /* Adjust the radius toward the target count, then stop at the target. */
    for (int iter = 0; iter < 6 && int64_t(chosen.size()) != params.particle_num; iter++) {
      radius *= float(std::cbrt(double(chosen.size()) / double(params.particle_num)));
      select(radius, unlimited, chosen);
    }
    for (int iter = 0; iter < 20 && int64_t(chosen.size()) < params.particle_num; iter++) {
      radius *= 0.8f;
      select(radius, unlimited, chosen);
    }
    select(radius, params.particle_num, chosen);
  }

  LcpParticles particles;
  for (const int32_t k : chosen) {
    const Candidate &cand = candidates[size_t(k)];
    particles.positions.push_back(cand.position);
    particles.directions.push_back(cand.direction);
    particles.u.push_back(strand_uv[size_t(cand.curve)].x);
    particles.v.push_back(strand_uv[size_t(cand.curve)].y);
    particles.s.push_back(cand.s);
    if (!pinned.is_empty()) {
      particles.fixed.push_back(cand.fixed);
    }
  }
  return in_space_order(particles, params.h2);
}

int64_t separate_close_particles(const MutableSpan<vec3> positions, const Span<uint8_t> is_fixed,
                                 const float min_distance, const int iterations,
                                 const std::function<void(vec3 &)> &constrain)
{
  const int64_t n = positions.size();
  std::vector<vec3> pushes(static_cast<size_t>(n));
  SpatialGrid grid;
  NeighborList neighbors;
  const auto count_close = [&]() {
    grid.build(positions, min_distance);
    find_neighbors(grid, positions, 0.99f * min_distance, true, neighbors);
    return count_close_pairs(positions, is_fixed, neighbors, 0.99f * min_distance);
  };
  int64_t close_num = count_close();
  for (int iteration = 0; iteration < iterations && close_num > 0; iteration++) {
    parallel_for(n, 1024, [&](const IndexRange range) {
      for (int64_t i = range.start; i < range.one_after_last(); i++) {
        vec3 push(0.0f);
        if (!is_fixed[i]) {
          for (const int32_t j : neighbors.neighbors_of(i)) {
            const vec3 d = positions[i] - positions[j];
            const float dist = glm::length(d);
            if (dist > 0.0f) {
              push += (is_fixed[j] ? 1.0f : 0.5f) * (min_distance - dist) / dist * d;
            }
          }
        }
        pushes[size_t(i)] = push;
      }
    });
    parallel_for(n, 1024, [&](const IndexRange range) {
      for (int64_t i = range.start; i < range.one_after_last(); i++) {
        if (pushes[size_t(i)] != vec3(0.0f)) {
          positions[i] += pushes[size_t(i)];
          constrain(positions[i]);
        }
      }
    });
    close_num = count_close();
  }
  return close_num;
}

}  // namespace hairdyn
