#pragma once
/* The loose connections of Bando 2003, §3.2-3.3: a fixed set of particle pairs found at rest
 * with smoothing length h₁, spring coefficients k_ij = c_ij W(‖x_ij‖, h₁) (eq. 7) scaled by
 * α_ij so that each particle's tensile Young's modulus stays E (eq. 9-14), and the hair
 * direction update (eq. 15). Pairs are oriented: `root[p]` is nearer the hair root and
 * `tip[p]` nearer the tip, i.e. tip ∈ N_t(root) and root ∈ N_r(tip). */
#include <vector>

#include "core/math.hh"
#include "core/span.hh"

namespace hairdyn {

struct LcpConnections {
  std::vector<int32_t> root, tip;
  std::vector<float> rest_length;     /* l_ij. */
  std::vector<float> cos_theta_root;  /* cos θ of t_root to x_{root→tip} at rest (> 0). */
  std::vector<float> cos_theta_tip;   /* cos θ of t_tip to x_{tip→root} at rest (< 0). */
  std::vector<float> strength;        /* c_ij of eq. 5. */
  /* Pairs of each particle as compressed rows: pair index * 2 + (1 if the particle is the
   * pair's tip end, 0 if its root end). */
  std::vector<int32_t> particle_offsets;
  std::vector<int32_t> particle_pairs;

  int64_t size() const { return int64_t(root.size()); }
  /* The particle at the other end of a `particle_pairs` entry. */
  int32_t partner(const int32_t code) const
  {
    return (code & 1) ? root[size_t(code >> 1)] : tip[size_t(code >> 1)];
  }
};

/* a_ij of eq. 6 from the rest directions and x_ij = x_j − x_i. */
float alignment(const vec3 &t_i, const vec3 &t_j, const vec3 &x_ij);

/* §3.2: pairs within 2h₁ at rest, a_ij ≥ a₀, pruned weakest c_ij W(l_ij, h₁) first until each
 * particle keeps about N_n. Pairs of two root particles (both fixed) are left out. */
LcpConnections build_connections(Span<vec3> positions, Span<vec3> directions,
                                 Span<uint8_t> is_root, float h1, float a0, int32_t neighbor_num);

/* Cross-section A_i = (m_i / δ)^(2/3) of eq. 9. */
inline float cross_section(const float mass, const float material_density)
{
  return std::pow(mass / material_density, 2.0f / 3.0f);
}

/* Per step: r_k[p] = k_ij (eq. 7) and r_alpha_k[p] = α_ij k_ij with α from eq. 13-14 for the
 * modulus E. `r_side_sums` is scratch of 2 floats per particle (Σ l k over N_r, N_t). */
void compute_spring_coefficients(const LcpConnections &connections, Span<vec3> positions,
                                 Span<float> cross_sections, float h1, float young_modulus,
                                 MutableSpan<float> r_k, MutableSpan<float> r_alpha_k,
                                 MutableSpan<float> r_side_sums);

/* The tensile modulus of eq. 10 (root side) and eq. 11 (tip side) of every particle for the
 * given spring coefficients: (1/A_i) Σ l_ij α_ij k_ij. NaN for a side with no pairs. */
void compute_tensile_moduli(const LcpConnections &connections, Span<float> alpha_k,
                            Span<float> cross_sections, MutableSpan<float> r_modulus_root_side,
                            MutableSpan<float> r_modulus_tip_side);

/* Damped springs (§3.3): the elastic part Σ_j α_ij k_ij (‖x_ij‖ − l_ij) x̂_ij goes to
 * r_elastic_forces; the damping part Σ_j γ α_ij k_ij (v_ij · x̂_ij) x̂_ij to r_damped_forces,
 * with its diagonal coefficient Σ_j γ α_ij k_ij added to r_damping. */
void accumulate_spring_forces(const LcpConnections &connections, Span<vec3> positions,
                              Span<vec3> velocities, Span<float> alpha_k, float damping_time,
                              MutableSpan<vec3> r_elastic_forces,
                              MutableSpan<vec3> r_damped_forces, MutableSpan<float> r_damping);

/* max_i Σ_j α_ij k_ij over the free particles: with the particle mass it bounds the highest
 * spring frequency, ω² ≤ 2 max Σ α k / m (Gershgorin), which sets the explicit time step. */
float max_particle_stiffness(const LcpConnections &connections, Span<float> alpha_k,
                             Span<uint8_t> is_fixed);

/* Eq. 15: t_i* = Σ_j α_ij k_ij t_i^j, t_i^j = x̂_ij turned by θ_ij toward t_i, normalised.
 * Particles flagged in `is_fixed` keep their direction. */
void update_directions(const LcpConnections &connections, Span<vec3> positions,
                       Span<float> alpha_k, Span<uint8_t> is_fixed, MutableSpan<vec3> r_directions);

}  // namespace hairdyn
