#include "lcp/springs_bando2003.hh"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/parallel.hh"
#include "core/spatial_grid.hh"
#include "core/sph_kernels.hh"

namespace hairdyn {

float alignment(const vec3 &t_i, const vec3 &t_j, const vec3 &x_ij)
{
  const vec3 d = glm::normalize(x_ij);
  const float cos_ij = glm::dot(t_i, d);  /* θ_ij: t_i to x_ij. */
  const float cos_ji = glm::dot(t_j, -d); /* θ_ji: t_j to x_ji. */
  /* Bando 2003, eq. 6. */
  return cos_ij * cos_ji < 0.0f ? std::abs(cos_ij - cos_ji) * 0.5f : 0.0f;
}

LcpConnections build_connections(const Span<vec3> positions, const Span<vec3> directions,
                                 const Span<uint8_t> is_root, const float h1, const float a0,
                                 const int32_t neighbor_num)
{
  const int64_t n = positions.size();
  SpatialGrid grid;
  grid.build(positions, 2.0f * h1);
  NeighborList neighbors;
  find_neighbors(grid, positions, 2.0f * h1, true, neighbors);

  struct Candidate {
    int32_t root, tip;
    float weight; /* c_ij W(l_ij, h₁): the initial spring coefficient (eq. 7). */
  };
  std::vector<Candidate> candidates;
  for (int64_t i = 0; i < n; i++) {
    for (const int32_t j : neighbors.neighbors_of(i)) {
      if (j <= i || (is_root[i] && is_root[j])) {
        continue;
      }
      const vec3 x_ij = positions[j] - positions[i];
      const float l = glm::length(x_ij);
      if (l <= 0.0f) {
        continue;
      }
      const float a = alignment(directions[i], directions[j], x_ij);
      if (a < a0 || a <= 0.0f) {
        continue; /* §3.2: omit pairs with a_ij < a₀. */
      }
      /* Bando 2003, eq. 5: c_ij = a_ij l_ij. */
      const float c = a * l;
      /* j ∈ N_t(i) when x_ij points along t_i (then i ∈ N_r(j)). */
      const bool j_is_tipward = glm::dot(directions[i], x_ij) > 0.0f;
      candidates.push_back({j_is_tipward ? int32_t(i) : j, j_is_tipward ? j : int32_t(i),
                            c * sph_kernel(l, h1)});
    }
  }
  /* A free particle whose rootward neighbours all fail a_ij ≥ a₀ (near the tips, where the
   * hair curls) would hang from nothing and fall away: it keeps its best-aligned rootward
   * neighbour within 2h₁ whatever a₀ says. */
  std::vector<uint8_t> held(size_t(n), 0);
  for (const Candidate &c : candidates) {
    held[size_t(c.tip)] = 1;
  }
  for (int64_t i = 0; i < n; i++) {
    if (is_root[i] || held[size_t(i)]) {
      continue;
    }
    Candidate best{-1, int32_t(i), 0.0f};
    for (const int32_t j : neighbors.neighbors_of(i)) {
      const vec3 x_ji = positions[i] - positions[j];
      const float l = glm::length(x_ji);
      if (l <= 0.0f || glm::dot(directions[i], x_ji) <= 0.0f) {
        continue; /* j must lie rootward of i. */
      }
      const float weight = std::max(alignment(directions[j], directions[i], x_ji), 1e-3f) * l *
                           sph_kernel(l, h1);
      if (weight > best.weight) {
        best = {j, int32_t(i), weight};
      }
    }
    if (best.root >= 0) {
      candidates.push_back(best);
    }
  }
  /* §3.2: omit the weakest pairs first while both ends keep more than N_n connections, and
   * never a particle's last pair toward the root (what holds it up) or toward the tip: a
   * particle left without either would hang from nothing or hold nothing. */
  std::vector<int32_t> degree(size_t(n), 0);
  std::vector<int32_t> rootward_num(size_t(n), 0), tipward_num(size_t(n), 0);
  for (const Candidate &c : candidates) {
    degree[size_t(c.root)]++;
    degree[size_t(c.tip)]++;
    rootward_num[size_t(c.tip)]++;
    tipward_num[size_t(c.root)]++;
  }
  std::vector<int32_t> order(candidates.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](const int32_t a, const int32_t b) {
    return candidates[size_t(a)].weight < candidates[size_t(b)].weight;
  });
  std::vector<bool> kept(candidates.size(), true);
  for (const int32_t k : order) {
    const Candidate &c = candidates[size_t(k)];
    if (degree[size_t(c.root)] > neighbor_num && degree[size_t(c.tip)] > neighbor_num &&
        rootward_num[size_t(c.tip)] > 1 && tipward_num[size_t(c.root)] > 1)
    {
      kept[size_t(k)] = false;
      degree[size_t(c.root)]--;
      degree[size_t(c.tip)]--;
      rootward_num[size_t(c.tip)]--;
      tipward_num[size_t(c.root)]--;
    }
  }

  LcpConnections result;
  for (size_t k = 0; k < candidates.size(); k++) {
    if (!kept[k]) {
      continue;
    }
    const Candidate &c = candidates[k];
    const vec3 x = positions[c.tip] - positions[c.root];
    const float l = glm::length(x);
    result.root.push_back(c.root);
    result.tip.push_back(c.tip);
    result.rest_length.push_back(l);
    result.cos_theta_root.push_back(glm::dot(directions[c.root], x / l));
    result.cos_theta_tip.push_back(glm::dot(directions[c.tip], -x / l));
    /* Eq. 5, c_ij = a_ij l_ij (a rescued pair of a poorly aligned particle keeps a floor). */
    result.strength.push_back(std::max(alignment(directions[c.root], directions[c.tip], x), 1e-3f) *
                              l);
  }
  result.particle_offsets.assign(size_t(n) + 1, 0);
  for (int64_t p = 0; p < result.size(); p++) {
    result.particle_offsets[size_t(result.root[size_t(p)]) + 1]++;
    result.particle_offsets[size_t(result.tip[size_t(p)]) + 1]++;
  }
  for (int64_t i = 0; i < n; i++) {
    result.particle_offsets[size_t(i) + 1] += result.particle_offsets[size_t(i)];
  }
  result.particle_pairs.resize(size_t(result.particle_offsets.back()));
  std::vector<int32_t> cursor(result.particle_offsets.begin(), result.particle_offsets.end() - 1);
  for (int64_t p = 0; p < result.size(); p++) {
    result.particle_pairs[size_t(cursor[size_t(result.root[size_t(p)])]++)] = int32_t(2 * p);
    result.particle_pairs[size_t(cursor[size_t(result.tip[size_t(p)])]++)] = int32_t(2 * p + 1);
  }
  return result;
}

void compute_spring_coefficients(const LcpConnections &connections, const Span<vec3> positions,
                                 const Span<float> cross_sections, const float h1,
                                 const float young_modulus, const MutableSpan<float> r_k,
                                 const MutableSpan<float> r_alpha_k,
                                 const MutableSpan<float> r_side_sums)
{
  const int64_t pairs_num = connections.size();
  parallel_for(pairs_num, 2048, [&](const IndexRange range) {
    for (int64_t p = range.start; p < range.one_after_last(); p++) {
      const float dist = glm::length(positions[connections.tip[size_t(p)]] -
                                     positions[connections.root[size_t(p)]]);
      /* Bando 2003, eq. 7: k_ij = c_ij W(‖x_ij‖, h₁). */
      r_k[p] = connections.strength[size_t(p)] * sph_kernel(dist, h1);
    }
  });
  /* Σ_{j ∈ N_r(i)} l_ij k_ij and Σ_{j ∈ N_t(i)} l_ij k_ij, gathered per particle. */
  const int64_t n = positions.size();
  parallel_for(n, 1024, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      float root_side = 0.0f, tip_side = 0.0f;
      for (int32_t k = connections.particle_offsets[size_t(i)];
           k < connections.particle_offsets[size_t(i) + 1]; k++)
      {
        const int32_t code = connections.particle_pairs[size_t(k)];
        const int32_t p = code >> 1;
        const float lk = connections.rest_length[size_t(p)] * r_k[p];
        /* i is the tip end of pair p: its partner is on i's root side, N_r(i). */
        ((code & 1) ? root_side : tip_side) += lk;
      }
      r_side_sums[2 * i] = root_side;
      r_side_sums[2 * i + 1] = tip_side;
    }
  });
  parallel_for(pairs_num, 2048, [&](const IndexRange range) {
    for (int64_t p = range.start; p < range.one_after_last(); p++) {
      const int32_t a = connections.root[size_t(p)], b = connections.tip[size_t(p)];
      /* Bando 2003, eq. 13: α_t,a = E A_a / Σ_{N_t(a)} l k, α_r,b = E A_b / Σ_{N_r(b)} l k. */
      const float sum_t_a = r_side_sums[2 * a + 1], sum_r_b = r_side_sums[2 * b];
      const float alpha_t_a = sum_t_a > 0.0f ? young_modulus * cross_sections[a] / sum_t_a : 0.0f;
      const float alpha_r_b = sum_r_b > 0.0f ? young_modulus * cross_sections[b] / sum_r_b : 0.0f;
      /* Eq. 14: b ∈ N_t(a) ∧ a ∈ N_r(b) → α_ab = (α_r,b + α_t,a) / 2. */
      r_alpha_k[p] = 0.5f * (alpha_t_a + alpha_r_b) * r_k[p];
    }
  });
}

void compute_tensile_moduli(const LcpConnections &connections, const Span<float> alpha_k,
                            const Span<float> cross_sections,
                            const MutableSpan<float> r_modulus_root_side,
                            const MutableSpan<float> r_modulus_tip_side)
{
  const int64_t n = cross_sections.size();
  for (int64_t i = 0; i < n; i++) {
    float root_side = 0.0f, tip_side = 0.0f;
    bool has_root_side = false, has_tip_side = false;
    for (int32_t k = connections.particle_offsets[size_t(i)];
         k < connections.particle_offsets[size_t(i) + 1]; k++)
    {
      const int32_t code = connections.particle_pairs[size_t(k)];
      const int32_t p = code >> 1;
      const float lak = connections.rest_length[size_t(p)] * alpha_k[p];
      if (code & 1) {
        root_side += lak;
        has_root_side = true;
      }
      else {
        tip_side += lak;
        has_tip_side = true;
      }
    }
    /* Bando 2003, eq. 10 and 11. */
    r_modulus_root_side[i] = has_root_side ? root_side / cross_sections[i] : NAN;
    r_modulus_tip_side[i] = has_tip_side ? tip_side / cross_sections[i] : NAN;
  }
}

void accumulate_spring_forces(const LcpConnections &connections, const Span<vec3> positions,
                              const Span<vec3> velocities, const Span<float> alpha_k,
                              const float damping_time,
                              const MutableSpan<vec3> r_elastic_forces,
                              const MutableSpan<vec3> r_damped_forces,
                              const MutableSpan<float> r_damping)
{
  parallel_for(positions.size(), 1024, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      vec3 elastic(0.0f), damped(0.0f);
      float stiffness = 0.0f;
      for (int32_t k = connections.particle_offsets[size_t(i)];
           k < connections.particle_offsets[size_t(i) + 1]; k++)
      {
        const int32_t code = connections.particle_pairs[size_t(k)];
        const int32_t p = code >> 1;
        const float ak = alpha_k[p];
        if (ak <= 0.0f) {
          continue;
        }
        const int32_t j = connections.partner(code);
        const vec3 x_ij = positions[j] - positions[i];
        const float dist = glm::length(x_ij);
        if (dist <= 0.0f) {
          continue;
        }
        const vec3 dir = x_ij / dist;
        /* Damped spring with coefficient α_ij k_ij (§3.3). */
        const float stretch = dist - connections.rest_length[size_t(p)];
        const float closing = glm::dot(velocities[j] - velocities[i], dir);
        elastic += ak * stretch * dir;
        damped += ak * damping_time * closing * dir;
        stiffness += ak;
      }
      r_elastic_forces[i] += elastic;
      r_damped_forces[i] += damped;
      r_damping[i] += damping_time * stiffness;
    }
  });
}

float max_particle_stiffness(const LcpConnections &connections, const Span<float> alpha_k,
                             const Span<uint8_t> is_fixed)
{
  float result = 0.0f;
  for (int64_t i = 0; i < is_fixed.size(); i++) {
    if (is_fixed[i]) {
      continue;
    }
    float sum = 0.0f;
    for (int32_t k = connections.particle_offsets[size_t(i)];
         k < connections.particle_offsets[size_t(i) + 1]; k++)
    {
      sum += alpha_k[connections.particle_pairs[size_t(k)] >> 1];
    }
    result = std::max(result, sum);
  }
  return result;
}

void update_directions(const LcpConnections &connections, const Span<vec3> positions,
                       const Span<float> alpha_k, const Span<uint8_t> is_fixed,
                       const MutableSpan<vec3> r_directions)
{
  parallel_for(positions.size(), 1024, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      if (is_fixed[i]) {
        continue;
      }
      const vec3 t_i = r_directions[i];
      vec3 sum(0.0f);
      for (int32_t k = connections.particle_offsets[size_t(i)];
           k < connections.particle_offsets[size_t(i) + 1]; k++)
      {
        const int32_t code = connections.particle_pairs[size_t(k)];
        const int32_t p = code >> 1;
        const bool i_is_tip = code & 1;
        const int32_t j = connections.partner(code);
        const vec3 x_ij = positions[j] - positions[i];
        const float dist = glm::length(x_ij);
        if (dist <= 0.0f || alpha_k[p] <= 0.0f) {
          continue;
        }
        const vec3 d = x_ij / dist;
        /* θ_ij of i's end of the pair (Figure 3b). */
        const float cos_theta = i_is_tip ? connections.cos_theta_tip[size_t(p)] :
                                           connections.cos_theta_root[size_t(p)];
        const float sin_theta = std::sqrt(std::max(0.0f, 1.0f - cos_theta * cos_theta));
        /* Turn x̂_ij by θ_ij about the axis normal to t_i and x_ij, toward t_i (Figure 3c). */
        vec3 w = t_i - glm::dot(t_i, d) * d;
        const float w_len = glm::length(w);
        w = w_len > 1e-6f ? w / w_len : vec3(0.0f);
        const vec3 t_ij = cos_theta * d + sin_theta * w;
        /* Bando 2003, eq. 15. */
        sum += alpha_k[p] * t_ij;
      }
      const float len = glm::length(sum);
      if (len > 1e-12f) {
        r_directions[i] = sum / len;
      }
    }
  });
}

}  // namespace hairdyn
