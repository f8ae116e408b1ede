#include "lcp/interactions_bando2003.hh"

#include <algorithm>
#include <cmath>

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
      const float support_sq = 4.0f * h * h;
      for (const int32_t j : neighbors.neighbors_of(i)) {
        const vec3 d = positions[j] - positions[i];
        const float r_sq = glm::dot(d, d);
        if (r_sq < support_sq) { /* The list may hold particles beyond the support. */
          rho += masses[j] * sph_kernel(std::sqrt(r_sq), h);
        }
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
        const float r_sq = glm::dot(x_ij, x_ij);
        if (!(r_sq > 0.0f && r_sq < 4.0f * h * h)) { /* The list may hold particles beyond 2h. */
          continue;
        }
        const float r = std::sqrt(r_sq);
        if (settings.attraction_repulsion) {
          /* Bando 2003, eq. 16 with P = k_a (ρ − ρ₀); ∇_i W = −W'(r) x_ij / r. */
          const float pressure_j =
              settings.pressure_stiffness * (density[j] - settings.rest_density);
          force +=
              masses[i] * masses[j] *
              (pressure_i / (density[i] * density[i]) + pressure_j / (density[j] * density[j])) *
              (sph_kernel_derivative(r, h) / r) * x_ij;
        }
        if (!settings.collision && !settings.friction) {
          continue;
        }
        const float w = sph_kernel(r, h);
        /* d_c, d_f act per unit SPH volume: m_i V_j with V_j = 2 m_j / (ρ_i + ρ_j), so the
         * response does not depend on the particle count (symmetric in i, j). */
        const float weight = w * masses[i] * 2.0f * masses[j] / (density[i] + density[j]);
        const vec3 v_ij = velocities[j] - velocities[i];
        /* Collision direction d_n = t_i × t_j, or for nearly collinear hair (|t_i × t_j| <
         * 0.1) the part of x_ij normal to t_i (§3.4). */
        vec3 d_n = glm::cross(directions[i], directions[j]);
        float d_n_sq = glm::dot(d_n, d_n);
        if (d_n_sq < 0.01f) {
          d_n = x_ij - glm::dot(x_ij, directions[i]) * directions[i];
          d_n_sq = glm::dot(d_n, d_n);
        }
        if (d_n_sq < 1e-24f) {
          continue;
        }
        d_n /= std::sqrt(d_n_sq);
        const float v_n = glm::dot(v_ij, d_n);
        if (settings.collision && glm::dot(x_ij, d_n) * v_n < 0.0f) {
          /* Bando 2003, eq. 17: approaching hair loses its normal relative velocity. */
          damped_force += settings.collision_damping * weight * v_n * d_n;
          damping += settings.collision_damping * weight;
        }
        if (settings.friction) {
          /* Bando 2003, eq. 18: (v_ij · d_t) d_t with d_t the unit tangential relative
           * velocity, which is that velocity itself. */
          const vec3 v_t = v_ij - v_n * d_n;
          if (glm::dot(v_t, v_t) > 1e-24f) {
            damped_force += settings.friction_damping * weight * v_t;
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

void compute_density_jacobian(const Span<vec3> positions, const Span<float> masses,
                              const Span<float> density, const NeighborList &neighbors,
                              const float h, const float pressure_stiffness,
                              const float rest_density, DensityJacobian &r_jacobian)
{
  const int64_t n = positions.size();
  const float support_sq = 4.0f * h * h;
  const auto in_support = [&](const int64_t i, const int32_t j) {
    const vec3 d = positions[j] - positions[i];
    const float r_sq = glm::dot(d, d);
    return r_sq < support_sq && r_sq > 0.0f;
  };
  r_jacobian.offsets.assign(size_t(n) + 1, 0);
  r_jacobian.kappa.resize(size_t(n));
  parallel_for(n, 1024, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      int32_t count = 0;
      for (const int32_t j : neighbors.neighbors_of(i)) {
        count += in_support(i, j) ? 1 : 0;
      }
      r_jacobian.offsets[size_t(i) + 1] = count;
      r_jacobian.kappa[size_t(i)] =
          masses[i] * pressure_stiffness / std::max(density[i] * density[i], 1e-30f);
    }
  });
  for (int64_t i = 0; i < n; i++) {
    r_jacobian.offsets[size_t(i) + 1] += r_jacobian.offsets[size_t(i)];
  }
  r_jacobian.entries.resize(size_t(r_jacobian.offsets[size_t(n)]));
  const std::vector<float> &kappa = r_jacobian.kappa;
  parallel_for(n, 1024, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      int32_t e = r_jacobian.offsets[size_t(i)];
      for (const int32_t j : neighbors.neighbors_of(i)) {
        if (!in_support(i, j)) {
          continue;
        }
        const vec3 x_ij = positions[j] - positions[i];
        const float r = glm::length(x_ij);
        const vec3 g = masses[j] * sph_kernel_gradient_i(x_ij, h);
        /* c_ij = κ_i C_i m_j + κ_j C_j m_i, times W'' along x̂ and W'/r across. */
        const float c = kappa[size_t(i)] * (density[i] - rest_density) * masses[j] +
                        kappa[size_t(j)] * (density[j] - rest_density) * masses[i];
        const float g_sq = glm::dot(g, g);
        const float along =
            g_sq > 0.0f ? std::max(0.0f, c * sph_kernel_second_derivative(r, h)) / g_sq : 0.0f;
        const float across = std::max(0.0f, c * sph_kernel_derivative(r, h) / r);
        r_jacobian.entries[size_t(e)] = { j, along, across, g };
        e++;
      }
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
