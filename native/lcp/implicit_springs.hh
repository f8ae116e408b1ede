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
 * gradients with a block-Jacobi (3 × 3) preconditioner, plus a coarse correction over groups
 * of particles (group_cell), either in every iteration (two-level additive) or as a check of
 * the error the particles share once the iterations pass the tolerance
 * (coarse_in_preconditioner), warm-started from the previous steps' solutions (their
 * Galerkin projection, guess_history). The step is stable for any Δt: the
 * springs' stiffness no longer sets the number of substeps.
 *
 * The attraction/repulsion of eq. 16 may join the same step: its force is applied
 * explicitly by the caller before (in the velocities given), and its stiffness K_p = Jᵀ κ J
 * (lcp/interactions_bando2003.hh's DensityJacobian) goes into the matrix and, as −Δt² K_p v,
 * into the right-hand side. That is backward Euler for the pressure too: with a = Δt M⁻¹ f_p
 * already in v, (M + Δt² K_p)(a + Δv) = Δt f_p − Δt² K_p v₀ is (M + Δt² K_p) Δv =
 * −Δt² K_p (v₀ + a). A state where all forces balance is then a fixed point whatever Δt (a
 * pressure solved apart from the springs would bias the balance by M (M + Δt² K)⁻¹), and
 * the pressure's sound speed no longer sets the substeps. */
#include <vector>

#include "core/math.hh"
#include "core/span.hh"
#include "lcp/interactions_bando2003.hh"
#include "lcp/springs_bando2003.hh"

namespace hairdyn {

class ImplicitSprings {
 public:
  struct Result {
    int iterations = 0;
    /* Matrix products, the iterations' and the first guess's (one per vector of its basis). */
    int products = 0;
    /* m/s: the largest velocity correction P_i⁻¹ r_i left at the end. */
    float max_correction = 0.0f;
  };

  /* Adds to r_velocities the velocity change of one backward-Euler step of `dt` under the
   * damped springs (coefficients α_ij k_ij, damping time γ), and the pressure's stiffness
   * when `pressure` is given. Particles flagged in `is_fixed` keep their velocity (zero in the
   * head's frame) and hold their partners' springs. */
  Result step(const LcpConnections &connections, Span<vec3> positions, Span<float> alpha_k,
              float damping_time, Span<float> masses, Span<uint8_t> is_fixed, float dt,
              const DensityJacobian *pressure, MutableSpan<vec3> r_velocities);

  /* Forgets the previous steps' solutions, the next solve's first guess. */
  void reset()
  {
    history_.clear();
    group_.clear();
    coarse_.clear();
  }

  /* m/s: the conjugate gradients stop when no particle's velocity correction is larger (the
   * LCP solver sets it from h₂ and the step); and their iteration cap. */
  float velocity_tolerance = 1e-5f;
  int max_iterations = 200;
  /* m: the smallest cell of the grid that groups the particles for the coarse correction
   * (two-level preconditioner, below); 0 leaves it out. The cell grows until at most
   * max_groups cells hold particles. */
  float group_cell = 0.0f;
  int max_groups = 160;
  /* Whether the coarse correction joins every iteration's preconditioner (two-level
   * additive: where block-Jacobi converges slowly, as with the pressure's stiffness); else
   * the iterations are block-Jacobi's alone, and once they pass the tolerance the error the
   * particles share is checked with one coarse solve and, past it, corrected (at most
   * max_coarse_checks times a step). Either way the stop sees that shared error, which a
   * particle's block-Jacobi correction alone hides. */
  bool coarse_in_preconditioner = true;
  /* Whether this step rebuilds the coarse matrix; otherwise the last one's serves (any
   * symmetric positive definite A_c gives a valid preconditioner, and within a frame the
   * blocks change little). */
  bool refactor_coarse = true;
  /* How many of the last steps' solutions span the first guess (0: start from zero). */
  int guess_history = 2;

 private:
  /* r_product = (M + Δt C + Δt² K) d for the pair blocks of the last step(). */
  double multiply_dot(Span<vec3> d, MutableSpan<vec3> r_product);
  /* pressure_rates_ = κ J d / m, the first half of K_p d. */
  void pressure_rates(Span<vec3> d);
  /* Row i of Δt² K_p d (Jᵀ pressure_rates_ and the pair springs), the pressure's part of the
   * product; pressure_rates(d) first. */
  vec3 pressure_row(Span<vec3> d, int64_t i) const;

  /* The coarse correction of the two-level additive preconditioner P⁻¹ = D⁻¹ + Q A_c⁻¹ Qᵀ:
   * D the 3 × 3 diagonal blocks; Q the aggregation of the free particles into groups, the
   * cells of a grid (smoothed-out, low-frequency errors are what block-Jacobi leaves to CG:
   * the pressure of eq. 16 and the springs couple particles across the whole hair volume);
   * A_c = Qᵀ A Q, Galerkin's coarse matrix, assembled from the same blocks as the product
   * and factored densely (Cholesky). Symmetric positive definite, so CG stays CG.
   * factor_coarse() assembles and factors A_c from the step's blocks, when refactor_coarse
   * asks, over the groups of build_groups() (kept for regroup_steps steps). */
  void build_groups(Span<vec3> positions);
  void factor_coarse();
  /* coarse_correction_ = A_c⁻¹ Qᵀ r, per group; returns rᵀ Q A_c⁻¹ Qᵀ r, the coarse part of
   * rᵀ P⁻¹ r. */
  double solve_coarse(Span<vec3> residual);
  /* dv_ = the first guess and product_ = A dv_ (see history_); returns the products it took. */
  int first_guess();

  const LcpConnections *connections_ = nullptr;
  const DensityJacobian *pressure_ = nullptr;
  float dt_ = 0.0f;
  std::vector<float> pressure_rates_;
  Span<float> masses_;
  Span<uint8_t> is_fixed_;
  /* Per pair, what the rows of both its particles read, side by side (one cache line: the
   * rows gather them by pair): the block Δt C_ij + Δt² K_ij = along x̂x̂ᵀ + across I, the
   * elastic force α_ij k_ij (‖x_ij‖ − l_ij), α_ij k_ij, and max(0, 1 − l/r) of K's lateral
   * term. */
  struct alignas(32) PairTerms {
    vec3 axis;
    float along, across, stretch_force, alpha_k, lateral;
  };
  std::vector<PairTerms> pair_terms_;
  /* The pair blocks again, in each particle's row (LcpConnections::particle_pairs order), so
   * that the product streams through memory. */
  struct Entry {
    int32_t partner;
    float along, across;
    vec3 axis;
    /* The pair's block Δt C + Δt² K: along x̂x̂ᵀ + across I. */
    mat3 block() const { return along * glm::outerProduct(axis, axis) + mat3(across); }
  };
  std::vector<Entry> entries_;
  std::vector<mat3> inverse_diagonal_;
  std::vector<vec3> rhs_, dv_, residual_, preconditioned_, direction_, product_;
  /* The last steps' solutions, the newest first, and the first guess's basis p_k with A p_k:
   * the first guess is the solution's Galerkin projection onto their span, Δv₀ = Σ_k c_k Δv₋ₖ
   * with c minimising the A-norm of the error Δv − Δv₀ (the basis A-orthogonalised, so
   * c_k = p_kᵀ b / p_kᵀ A p_k). Of that span's vectors it is the closest to the solution,
   * whatever the motion: about the last Δv where the impulse changes slowly, a line through
   * the last two where it grows steadily, a turned Δv where the springs ring. It costs one
   * product per vector; the step's matrix is new, so the last steps' products do not serve
   * (coefficients from them took more iterations than the last Δv alone). */
  std::vector<std::vector<vec3>> history_, basis_, basis_products_;
  /* Per particle its group (−1: fixed); the coarse matrix, then its Cholesky factor (3g × 3g,
   * column-major, double), the factor again in single precision for the solves; the coarse
   * right-hand side Qᵀ r, A_c⁻¹ Qᵀ r and, per group, that correction. */
  std::vector<int32_t> group_;
  int64_t groups_num_ = 0;
  std::vector<double> coarse_;
  std::vector<float> coarse_factor_, coarse_rhs_, coarse_solution_;
  std::vector<vec3> coarse_correction_;
  std::vector<uint64_t> group_keys_;
  /* The groups are kept for regroup_steps steps: the particles drift little meanwhile, and
   * any grouping gives a valid preconditioner. */
  static constexpr int regroup_steps = 24;
  static constexpr int max_coarse_checks = 4;
  int steps_since_groups_ = 0;
};

}  // namespace hairdyn
