#pragma once
/* Backward-Euler velocity update for the loose springs of Bando 2003 (§3.3), linearised as
 * Baraff & Witkin 1998 do for cloth:
 *
 *     (M + Δt C + Δt² K) Δv = Δt (f(x, v) − Δt K v),
 *
 * with K = −∂f/∂x and C = −∂f/∂v the springs' stiffness and damping matrices at the current
 * positions and α_ij k_ij (eq. 7, 13-14) held over the step. Per pair, with x̂ the unit
 * direction, r the length and l the rest length,
 *
 *     K_ij = α_ij k_ij [x̂x̂ᵀ + max(0, 1 − l/r)(I − x̂x̂ᵀ)],   C_ij = γ α_ij k_ij x̂x̂ᵀ,
 *
 * K keeping only its positive semi-definite part (a compressed spring's lateral term is
 * dropped). The matrix is then symmetric positive definite and is solved by conjugate
 * gradients with a block-Jacobi (3 × 3) preconditioner, warm-started from the previous
 * step's solution. The step is stable for any Δt: the springs' stiffness no longer sets the
 * number of substeps. */
#include <vector>

#include "core/math.hh"
#include "core/span.hh"
#include "lcp/springs_bando2003.hh"

namespace hairdyn {

class ImplicitSprings {
 public:
  struct Result {
    int iterations = 0;
    /* m/s: the largest velocity correction P_i⁻¹ r_i left at the end. */
    float max_correction = 0.0f;
  };

  /* Adds to r_velocities the velocity change of one backward-Euler step of `dt` under the
   * damped springs (coefficients α_ij k_ij, damping time γ). Particles flagged in `is_fixed`
   * keep their velocity (zero in the head's frame) and hold their partners' springs. */
  Result step(const LcpConnections &connections, Span<vec3> positions, Span<float> alpha_k,
              float damping_time, Span<float> masses, Span<uint8_t> is_fixed, float dt,
              MutableSpan<vec3> r_velocities);

  /* Forgets the previous step's solution, the next solve's first guess. */
  void reset() { guess_.clear(); }

  /* m/s: the conjugate gradients stop when no particle's velocity correction is larger;
   * and their iteration cap. */
  float velocity_tolerance = 1e-5f;
  int max_iterations = 200;

 private:
  /* r_product = (M + Δt C + Δt² K) d for the pair blocks of the last step(). */
  double multiply_dot(Span<vec3> d, MutableSpan<vec3> r_product) const;

  const LcpConnections *connections_ = nullptr;
  Span<float> masses_;
  Span<uint8_t> is_fixed_;
  /* Pair block Δt C_ij + Δt² K_ij = along x̂x̂ᵀ + across I. */
  std::vector<vec3> axis_;
  std::vector<float> along_, across_;
  /* α_ij k_ij (‖x_ij‖ − l_ij), and max(0, 1 − l/r) of K's lateral term. */
  std::vector<float> stretch_force_, lateral_;
  /* The pair blocks again, in each particle's row (LcpConnections::particle_pairs order), so
   * that the product streams through memory. */
  struct Entry {
    int32_t partner;
    float along, across;
    vec3 axis;
  };
  std::vector<Entry> entries_;
  std::vector<mat3> inverse_diagonal_;
  std::vector<vec3> rhs_, dv_, residual_, preconditioned_, direction_, product_, guess_;
};

}  // namespace hairdyn
