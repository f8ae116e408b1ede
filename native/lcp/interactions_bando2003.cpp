#include "lcp/interactions_bando2003.hh"

#include "core/parallel.hh"
#include "core/sph_kernels.hh"

namespace hairdyn {

void compute_density(const Span<vec3> positions, const Span<float> masses,
                     const NeighborList &neighbors, const float h,
                     const MutableSpan<float> r_density)
{
  parallel_for(positions.size(), 1024, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      /* Bando 2003, eq. 1 (with j = i: W(0, h)). */
      float rho = masses[i] * sph_kernel(0.0f, h);
      for (const int32_t j : neighbors.neighbors_of(i)) {
        rho += masses[j] * sph_kernel(glm::length(positions[j] - positions[i]), h);
      }
      r_density[i] = rho;
    }
  });
}

void accumulate_hair_interactions(const Span<vec3> positions, const Span<vec3> velocities,
                                  const Span<vec3> directions, const Span<float> masses,
                                  const Span<float> density, const NeighborList &neighbors,
                                  const HairInteractionSettings &settings,
                                  const MutableSpan<vec3> r_forces,
                                  const MutableSpan<vec3> r_damped_forces,
                                  const MutableSpan<float> r_damping)
{
  const float h = settings.h2;
  parallel_for(positions.size(), 512, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      const float pressure_i = settings.pressure_stiffness * (density[i] - settings.rest_density);
      vec3 force(0.0f), damped_force(0.0f);
      float damping = 0.0f;
      for (const int32_t j : neighbors.neighbors_of(i)) {
        const vec3 x_ij = positions[j] - positions[i];
        const float r = glm::length(x_ij);
        if (r <= 0.0f) {
          continue;
        }
        if (settings.attraction_repulsion) {
          /* Bando 2003, eq. 16 with P = k_a (ρ − ρ₀). */
          const float pressure_j = settings.pressure_stiffness * (density[j] - settings.rest_density);
          force -= masses[i] * masses[j] *
                   (pressure_i / (density[i] * density[i]) + pressure_j / (density[j] * density[j])) *
                   sph_kernel_gradient_i(x_ij, h);
        }
        if (!settings.collision && !settings.friction) {
          continue;
        }
        const float w = sph_kernel(r, h);
        /* d_c, d_f act per unit SPH volume: m_i V_j with V_j = 2 m_j / (ρ_i + ρ_j), so the
         * response does not depend on the particle count (symmetric in i, j). */
        const float weight = w * masses[i] * 2.0f * masses[j] / (density[i] + density[j]);
        const vec3 v_ij = velocities[j] - velocities[i];
        /* Collision direction d_n = t_i × t_j, or for nearly collinear hair the part of x_ij
         * normal to t_i (§3.4). */
        vec3 d_n = glm::cross(directions[i], directions[j]);
        if (glm::length(d_n) < 0.1f) {
          d_n = x_ij - glm::dot(x_ij, directions[i]) * directions[i];
        }
        const float d_n_len = glm::length(d_n);
        if (d_n_len < 1e-12f) {
          continue;
        }
        d_n /= d_n_len;
        const float v_n = glm::dot(v_ij, d_n);
        if (settings.collision && glm::dot(x_ij, d_n) * v_n < 0.0f) {
          /* Bando 2003, eq. 17: approaching hair loses its normal relative velocity. */
          damped_force += settings.collision_damping * weight * v_n * d_n;
          damping += settings.collision_damping * weight;
        }
        if (settings.friction) {
          vec3 d_t = v_ij - v_n * d_n;
          const float d_t_len = glm::length(d_t);
          if (d_t_len > 1e-12f) {
            d_t /= d_t_len;
            /* Bando 2003, eq. 18. */
            damped_force += settings.friction_damping * weight * glm::dot(v_ij, d_t) * d_t;
            damping += settings.friction_damping * weight;
          }
        }
      }
      r_forces[i] += force;
      r_damped_forces[i] += damped_force;
      r_damping[i] += damping;
    }
  });
}

int64_t count_close_pairs(const Span<vec3> positions, const Span<uint8_t> is_fixed,
                          const NeighborList &neighbors, const float distance)
{
  int64_t count = 0;
  const float distance_sq = distance * distance;
  for (int64_t i = 0; i < positions.size(); i++) {
    for (const int32_t j : neighbors.neighbors_of(i)) {
      if (j <= i || (is_fixed[i] && is_fixed[j])) {
        continue;
      }
      const vec3 d = positions[j] - positions[i];
      count += glm::dot(d, d) < distance_sq ? 1 : 0;
    }
  }
  return count;
}

}  // namespace hairdyn
