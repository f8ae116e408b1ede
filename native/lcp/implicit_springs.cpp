#include "lcp/implicit_springs.hh"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "core/parallel.hh"

namespace hairdyn {

static constexpr int64_t grain = 1024;

void ImplicitSprings::pressure_rates(const Span<vec3> d)
{
  const DensityJacobian &jacobian = *pressure_;
  pressure_rates_.resize(size_t(d.size()));
  parallel_for(d.size(), grain, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      float rate = 0.0f; /* (J d)_i = Σ_j g_ij · (d_i − d_j) */
      for (int32_t e = jacobian.offsets[size_t(i)]; e < jacobian.offsets[size_t(i) + 1]; e++) {
        const DensityJacobian::Entry &entry = jacobian.entries[size_t(e)];
        rate += glm::dot(entry.gradient, d[i] - d[entry.partner]);
      }
      pressure_rates_[size_t(i)] = jacobian.kappa[size_t(i)] / masses_[i] * rate;
    }
  });
}

vec3 ImplicitSprings::pressure_row(const Span<vec3> d, const int64_t i) const
{
  const DensityJacobian &jacobian = *pressure_;
  /* pressure_rates_ holds t / m: (Jᵀ t)_i = Σ_j g_ij m_i (t_i/m_i + t_j/m_j), and the pair
   * springs. */
  const float m_i = masses_[i], rate_i = pressure_rates_[size_t(i)];
  vec3 row(0.0f);
  for (int32_t e = jacobian.offsets[size_t(i)]; e < jacobian.offsets[size_t(i) + 1]; e++) {
    const DensityJacobian::Entry &entry = jacobian.entries[size_t(e)];
    const vec3 d_ij = d[i] - d[entry.partner];
    row += entry.gradient * (m_i * (rate_i + pressure_rates_[size_t(entry.partner)]) +
                             entry.along * glm::dot(entry.gradient, d_ij)) +
           entry.across * d_ij;
  }
  return dt_ * dt_ * row;
}

double ImplicitSprings::multiply_dot(const Span<vec3> d, const MutableSpan<vec3> r_product)
{
  if (pressure_ != nullptr) {
    pressure_rates(d);
  }
  const std::vector<int32_t> &offsets = connections_->particle_offsets;
  /* Returns dᵀ A d as well: one pass for the product and the dot product CG needs. */
  return parallel_sum(d.size(), grain, [&](const IndexRange range) {
    double dot = 0.0;
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      if (is_fixed_[i]) {
        r_product[i] = vec3(0.0f);
        continue;
      }
      const vec3 d_i = d[i];
      vec3 y = masses_[i] * d_i;
      for (int32_t k = offsets[size_t(i)]; k < offsets[size_t(i) + 1]; k++) {
        const Entry &e = entries_[size_t(k)];
        /* Fixed partners have no unknown: d_j = 0 there. */
        const vec3 d_ij = d_i - d[e.partner];
        y += e.along * glm::dot(e.axis, d_ij) * e.axis + e.across * d_ij;
      }
      if (pressure_ != nullptr) {
        y += pressure_row(d, i);
      }
      r_product[i] = y;
      dot += double(glm::dot(d_i, y));
    }
    return dot;
  });
}

void ImplicitSprings::build_groups(const Span<vec3> positions)
{
  const int64_t n = positions.size();
  group_.assign(size_t(n), -1);
  groups_num_ = 0;
  vec3 lo(std::numeric_limits<float>::max());
  for (int64_t i = 0; i < n; i++) {
    if (!is_fixed_[i]) {
      lo = glm::min(lo, positions[i]);
    }
  }
  if (group_cell <= 0.0f || lo.x == std::numeric_limits<float>::max()) {
    return;
  }
  /* The occupied cells of the grid, in the order of their keys; the cell grows until they
   * are few enough for a dense factorisation. */
  float cell = group_cell;
  const auto key_of = [&](const vec3 &p) {
    uint64_t key = 0;
    for (int a = 0; a < 3; a++) {
      const float c = (p[a] - lo[a]) / cell; /* not a number: cell 0 */
      key |= uint64_t(c >= 0.0f ? std::min(c, 2097151.0f) : 0.0f) << (21 * a);
    }
    return key;
  };
  for (;;) {
    group_keys_.clear();
    for (int64_t i = 0; i < n; i++) {
      if (!is_fixed_[i]) {
        group_keys_.push_back(key_of(positions[i]));
      }
    }
    std::sort(group_keys_.begin(), group_keys_.end());
    group_keys_.erase(std::unique(group_keys_.begin(), group_keys_.end()), group_keys_.end());
    if (int64_t(group_keys_.size()) <= std::max(max_groups, 1)) {
      break;
    }
    cell *= 1.25f;
  }
  groups_num_ = int64_t(group_keys_.size());
  for (int64_t i = 0; i < n; i++) {
    if (!is_fixed_[i]) {
      group_[size_t(i)] =
          int32_t(std::lower_bound(group_keys_.begin(), group_keys_.end(), key_of(positions[i])) -
                  group_keys_.begin());
    }
  }
}

void ImplicitSprings::factor_coarse()
{
  const int64_t size = 3 * groups_num_;
  coarse_.assign(size_t(size * size), 0.0);
  /* A_c[a][b] += B (3 × 3 blocks of the column-major matrix). */
  const auto add = [&](const int32_t a, const int32_t b, const mat3 &block) {
    for (int c = 0; c < 3; c++) {
      double *column = coarse_.data() + (3 * int64_t(b) + c) * size + 3 * int64_t(a);
      for (int r = 0; r < 3; r++) {
        column[r] += double(block[c][r]);
      }
    }
  };
  const int64_t n = int64_t(group_.size());
  const float dt2 = dt_ * dt_;
  const std::vector<int32_t> &offsets = connections_->particle_offsets;
  /* A pair block B in row i, B (d_i − d_j), gives Qᵀ A Q's blocks [a][a] += B and
   * [a][b] −= B (a, b the groups of i and j), which cancel within a group: only pairs across
   * groups are added (a group holds hundreds of particles). A fixed partner (b = −1) has no
   * unknown: the first only. */
  const auto add_pair = [&](const int32_t a, const int32_t b, const mat3 &block) {
    add(a, a, block);
    if (b >= 0) {
      add(a, b, -block);
    }
  };
  for (int64_t i = 0; i < n; i++) {
    const int32_t a = group_[size_t(i)];
    if (a < 0) {
      continue;
    }
    add(a, a, mat3(masses_[i]));
    for (int32_t k = offsets[size_t(i)]; k < offsets[size_t(i) + 1]; k++) {
      const Entry &e = entries_[size_t(k)];
      const int32_t b = group_[size_t(e.partner)];
      if (b != a) {
        add_pair(a, b, e.block());
      }
    }
    if (pressure_ != nullptr) {
      for (int32_t k = pressure_->offsets[size_t(i)]; k < pressure_->offsets[size_t(i) + 1]; k++) {
        const DensityJacobian::Entry &e = pressure_->entries[size_t(k)];
        const int32_t b = group_[size_t(e.partner)];
        if (b != a) {
          add_pair(a, b,
                   dt2 * (e.along * glm::outerProduct(e.gradient, e.gradient) + mat3(e.across)));
        }
      }
    }
  }
  if (pressure_ != nullptr) {
    /* Jᵀ κ J: Σ_k κ_k u_k u_kᵀ with u_k = (J Q)_k, row k of J summed over each group:
     * g_kj at k's group and −g_kj at j's, for each neighbour j in another group (within a
     * group the two cancel). */
    std::vector<std::pair<int32_t, vec3>> u;
    const auto push = [&](const int32_t group, const vec3 &value) {
      if (group < 0) {
        return;
      }
      for (std::pair<int32_t, vec3> &slot : u) {
        if (slot.first == group) {
          slot.second += value;
          return;
        }
      }
      u.emplace_back(group, value);
    };
    for (int64_t k = 0; k < n; k++) {
      u.clear();
      const int32_t a = group_[size_t(k)];
      for (int32_t e = pressure_->offsets[size_t(k)]; e < pressure_->offsets[size_t(k) + 1]; e++) {
        const DensityJacobian::Entry &entry = pressure_->entries[size_t(e)];
        const int32_t b = group_[size_t(entry.partner)];
        if (b != a) {
          push(a, entry.gradient);
          push(b, -entry.gradient);
        }
      }
      const float scale = dt2 * pressure_->kappa[size_t(k)];
      for (const std::pair<int32_t, vec3> &b : u) {
        for (const std::pair<int32_t, vec3> &c : u) {
          add(b.first, c.first, scale * glm::outerProduct(b.second, c.second));
        }
      }
    }
  }
  Eigen::Map<Eigen::MatrixXd> matrix(coarse_.data(), size, size);
  const Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>> cholesky(matrix);
  if (cholesky.info() != Eigen::Success) {
    groups_num_ = 0; /* not positive definite in double: block-Jacobi alone */
  }
  /* The factor in single precision for the solve of every iteration: half the bytes to read
   * (Sintel's groom at 2,000 particles: 102 groups, 22 → 16 µs a solve). */
  coarse_factor_.assign(coarse_.begin(), coarse_.end());
  coarse_rhs_.resize(size_t(size));
  coarse_solution_.resize(size_t(size));
  coarse_correction_.resize(size_t(groups_num_));
}

double ImplicitSprings::solve_coarse(const Span<vec3> residual)
{
  std::fill(coarse_rhs_.begin(), coarse_rhs_.end(), 0.0f);
  for (int64_t i = 0; i < residual.size(); i++) {
    const int32_t a = group_[size_t(i)];
    if (a >= 0) {
      for (int c = 0; c < 3; c++) {
        coarse_rhs_[size_t(3 * a + c)] += residual[i][c];
      }
    }
  }
  const int64_t size = 3 * groups_num_;
  const Eigen::Map<const Eigen::MatrixXf> factor(coarse_factor_.data(), size, size);
  const Eigen::Map<const Eigen::VectorXf> rhs(coarse_rhs_.data(), size);
  Eigen::Map<Eigen::VectorXf> x(coarse_solution_.data(), size);
  x = rhs;
  factor.triangularView<Eigen::Lower>().solveInPlace(x);
  factor.triangularView<Eigen::Lower>().adjoint().solveInPlace(x);
  double energy = 0.0;
  for (int64_t a = 0; a < groups_num_; a++) {
    coarse_correction_[size_t(a)] = vec3(x[3 * a], x[3 * a + 1], x[3 * a + 2]);
    energy += double(
        glm::dot(vec3(rhs[3 * a], rhs[3 * a + 1], rhs[3 * a + 2]), coarse_correction_[size_t(a)]));
  }
  return energy;
}

int ImplicitSprings::first_guess()
{
  const int64_t n = int64_t(dv_.size());
  std::fill(dv_.begin(), dv_.end(), vec3(0.0f));
  std::fill(product_.begin(), product_.end(), vec3(0.0f));
  const auto dot = [&](const std::vector<vec3> &a, const std::vector<vec3> &b) {
    return parallel_sum(n, grain, [&](const IndexRange range) {
      double sum = 0.0;
      for (int64_t i = range.start; i < range.one_after_last(); i++) {
        sum += double(glm::dot(a[size_t(i)], b[size_t(i)]));
      }
      return sum;
    });
  };
  /* p += s q and A p += s A q, over every particle. */
  const auto add_scaled = [&](std::vector<vec3> &p, std::vector<vec3> &product, const float s,
                              const std::vector<vec3> &q, const std::vector<vec3> &q_product) {
    parallel_for(n, grain, [&](const IndexRange range) {
      for (int64_t i = range.start; i < range.one_after_last(); i++) {
        p[size_t(i)] += s * q[size_t(i)];
        product[size_t(i)] += s * q_product[size_t(i)];
      }
    });
  };
  basis_.resize(history_.size());
  basis_products_.resize(history_.size());
  std::vector<double> energies;
  for (size_t k = 0; k < history_.size(); k++) {
    std::vector<vec3> &p = basis_[energies.size()], &product = basis_products_[energies.size()];
    /* A fixed particle has no unknown (the product takes its Δv as 0). */
    p.resize(size_t(n));
    product.resize(size_t(n));
    parallel_for(n, grain, [&](const IndexRange range) {
      for (int64_t i = range.start; i < range.one_after_last(); i++) {
        p[size_t(i)] = is_fixed_[i] ? vec3(0.0f) : history_[k][size_t(i)];
      }
    });
    const double energy = multiply_dot(p, product);
    /* A-orthogonal to the basis so far (Gram-Schmidt in the A inner product); dropped when
     * what is left of it is rounding. */
    for (size_t j = 0; j < energies.size(); j++) {
      const float beta = float(dot(basis_[j], product) / energies[j]);
      add_scaled(p, product, -beta, basis_[j], basis_products_[j]);
    }
    const double left = dot(p, product);
    if (!(left > 1e-8 * energy)) {
      continue;
    }
    energies.push_back(left);
    add_scaled(dv_, product_, float(dot(p, rhs_) / left), p, product);
  }
  return int(history_.size());
}

ImplicitSprings::Result ImplicitSprings::step(
    const LcpConnections &connections, const Span<vec3> positions, const Span<float> alpha_k,
    const float damping_time, const Span<float> masses, const Span<uint8_t> is_fixed,
    const float dt, const DensityJacobian *pressure, const MutableSpan<vec3> r_velocities)
{
  const int64_t n = positions.size();
  const int64_t pairs_num = connections.size();
  connections_ = &connections;
  masses_ = masses;
  is_fixed_ = is_fixed;
  pressure_ = pressure;
  dt_ = dt;
  if (pressure != nullptr) {
    pressure_rates(r_velocities); /* for −Δt² K_p v */
  }
  pair_terms_.resize(size_t(pairs_num));
  for (std::vector<vec3> *buffer :
       { &rhs_, &dv_, &residual_, &preconditioned_, &direction_, &product_ })
  {
    buffer->resize(size_t(n));
  }
  inverse_diagonal_.resize(size_t(n));
  entries_.resize(connections.particle_pairs.size());
  if (!history_.empty() && int64_t(history_.front().size()) != n) {
    history_.clear();
  }

  /* Pair blocks Δt C + Δt² K, and the spring forces of the step's start. */
  parallel_for(pairs_num, grain, [&](const IndexRange range) {
    for (int64_t p = range.start; p < range.one_after_last(); p++) {
      const int32_t a = connections.root[size_t(p)], b = connections.tip[size_t(p)];
      const vec3 x_ab = positions[b] - positions[a];
      const float r = glm::length(x_ab);
      const float ak = alpha_k[p];
      PairTerms &terms = pair_terms_[size_t(p)];
      if (r <= 0.0f || ak <= 0.0f) {
        terms = { vec3(0.0f), 0.0f, 0.0f, 0.0f, ak, 0.0f };
        continue;
      }
      const float l = connections.rest_length[size_t(p)];
      const float lateral = std::max(0.0f, 1.0f - l / r); /* PSD part of K's lateral term. */
      terms.axis = x_ab / r;
      terms.along = dt * damping_time * ak + dt * dt * ak * (1.0f - lateral);
      terms.across = dt * dt * ak * lateral;
      /* Elastic force on the root end, along x̂ (§3.3): α_ij k_ij (‖x_ij‖ − l_ij). */
      terms.stretch_force = ak * (r - l);
      terms.alpha_k = ak;
      terms.lateral = lateral;
    }
  });

  /* Right-hand side Δt (f − Δt K v) and the inverse 3 × 3 diagonal blocks. */
  parallel_for(n, grain, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      if (is_fixed[i]) {
        rhs_[size_t(i)] = vec3(0.0f);
        inverse_diagonal_[size_t(i)] = mat3(0.0f);
        continue;
      }
      const vec3 v_i = r_velocities[i];
      vec3 force(0.0f), stiff_v(0.0f);
      mat3 diagonal(masses[i]);
      for (int32_t k = connections.particle_offsets[size_t(i)];
           k < connections.particle_offsets[size_t(i) + 1]; k++)
      {
        const int32_t code = connections.particle_pairs[size_t(k)];
        const int32_t p = code >> 1;
        const PairTerms &terms = pair_terms_[size_t(p)];
        const vec3 &axis = terms.axis;
        /* x̂_ij points from i to its partner j. */
        const vec3 x_hat = (code & 1) ? -axis : axis;
        const int32_t j = connections.partner(code);
        const vec3 v_ij = r_velocities[j] - v_i;
        const float ak = terms.alpha_k, lateral = terms.lateral;
        /* Damped spring (§3.3): elastic α k (r − l) x̂ and damping γ α k (v_ij · x̂) x̂. */
        force += (terms.stretch_force + damping_time * ak * glm::dot(v_ij, x_hat)) * x_hat;
        /* K (v_i − v_j) of this pair. */
        stiff_v -= ak * ((1.0f - lateral) * glm::dot(axis, v_ij) * axis + lateral * v_ij);
        entries_[size_t(k)] = { j, terms.along, terms.across, axis };
        diagonal += entries_[size_t(k)].block();
      }
      rhs_[size_t(i)] = dt * (force - dt * stiff_v);
      if (pressure != nullptr) {
        rhs_[size_t(i)] -= pressure_row(r_velocities, i);
        /* K_p's diagonal block: κ_i G_i G_iᵀ + Σ_j κ_j (m_i/m_j)² g_ij g_ijᵀ, G_i = Σ_j g_ij. */
        vec3 own(0.0f);
        mat3 others(0.0f);
        for (int32_t e = pressure->offsets[size_t(i)]; e < pressure->offsets[size_t(i) + 1]; e++) {
          const DensityJacobian::Entry &entry = pressure->entries[size_t(e)];
          const vec3 &g = entry.gradient;
          own += g;
          const float scale = masses[i] / masses[entry.partner];
          others += (pressure->kappa[size_t(entry.partner)] * scale * scale + entry.along) *
                        glm::outerProduct(g, g) +
                    mat3(entry.across);
        }
        diagonal += dt * dt * (pressure->kappa[size_t(i)] * glm::outerProduct(own, own) + others);
      }
      inverse_diagonal_[size_t(i)] = glm::inverse(diagonal);
    }
  });

  /* Preconditioned conjugate gradients, starting from the projection of the last steps' Δv
   * (from one substep to the next the springs' impulse changes little), until no particle's
   * preconditioned residual z = P⁻¹ r, a velocity correction, exceeds the tolerance. */
  /* r_i −= alpha q_i, z_i = D_i⁻¹ r_i (the block-Jacobi part of P⁻¹ r); returns its part of
   * rᵀ z. */
  const auto update_residual = [&](const IndexRange range, const float alpha) {
    double rz = 0.0;
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      residual_[size_t(i)] -= alpha * product_[size_t(i)];
      preconditioned_[size_t(i)] = inverse_diagonal_[size_t(i)] * residual_[size_t(i)];
      rz += double(glm::dot(residual_[size_t(i)], preconditioned_[size_t(i)]));
    }
    return rz;
  };
  /* The groups (kept for regroup_steps steps) and the coarse factor (as refactor_coarse
   * asks). With coarse_in_preconditioner, in each iteration the coarse correction
   * Q A_c⁻¹ Qᵀ r, added to z as the direction is updated, and its part of rᵀ z:
   * rᵀ Q A_c⁻¹ Qᵀ r = b_cᵀ A_c⁻¹ b_c over the groups alone (no pass over the particles for
   * it); without, the check after the iterations below. */
  bool refactor = refactor_coarse || coarse_.empty();
  bool regroup = int64_t(group_.size()) != n || steps_since_groups_ >= regroup_steps;
  for (int64_t i = 0; i < (groups_num_ > 0 && !regroup ? n : 0); i++) {
    regroup |= (group_[size_t(i)] >= 0) == bool(is_fixed[i]); /* a particle fixed or freed */
  }
  if (regroup) {
    build_groups(positions);
    steps_since_groups_ = 0;
    refactor = true;
  }
  steps_since_groups_++;
  if (refactor) {
    factor_coarse();
  }
  const bool additive = coarse_in_preconditioner && groups_num_ > 0;
  const auto coarse_part = [&]() {
    return additive ? solve_coarse(residual_) : 0.0;
  };
  /* p = z + β p (p = z when β is 0: the first direction reads nothing of the last solve's),
   * z = D⁻¹ r plus, in the additive preconditioner, the coarse correction of the particle's
   * group; returns max_i ‖z_i‖, what the stop test reads. */
  const auto update_direction = [&](const float beta) {
    return parallel_reduce(
        n, grain, 0.0f,
        [&](const IndexRange range) {
          float largest = 0.0f;
          for (int64_t i = range.start; i < range.one_after_last(); i++) {
            const int32_t a = additive ? group_[size_t(i)] : -1;
            const vec3 z = a >= 0 ? preconditioned_[size_t(i)] + coarse_correction_[size_t(a)]
                                  : preconditioned_[size_t(i)];
            direction_[size_t(i)] = beta == 0.0f ? z : z + beta * direction_[size_t(i)];
            largest = std::max(largest, glm::length(z));
          }
          return largest;
        },
        [](const float a, const float b) {
          return std::max(a, b);
        });
  };
  /* Δv += direction_ (when `add_direction`) and r −= product_, z, rᵀ z, and the first
   * direction z: the start of the iterations, from the first guess or a coarse correction. */
  double rz = 0.0;
  const auto start_from = [&](const bool add_direction) {
    rz = parallel_sum(n, grain, [&](const IndexRange range) {
      for (int64_t i = range.start; add_direction && i < range.one_after_last(); i++) {
        dv_[size_t(i)] += direction_[size_t(i)];
      }
      return update_residual(range, 1.0f);
    });
    rz += coarse_part();
    return update_direction(0.0f);
  };
  Result result;
  result.products = first_guess(); /* r = b − A Δv₀ */
  residual_ = rhs_;
  float max_correction = start_from(false);
  for (int check = 0;; check++) {
    while (max_correction > velocity_tolerance && result.iterations < max_iterations) {
      const double pq = multiply_dot(direction_, product_);
      if (!(pq > 0.0)) {
        break;
      }
      const float alpha = float(rz / pq);
      double next_rz = parallel_sum(n, grain, [&](const IndexRange range) {
        for (int64_t i = range.start; i < range.one_after_last(); i++) {
          dv_[size_t(i)] += alpha * direction_[size_t(i)];
        }
        return update_residual(range, alpha);
      });
      next_rz += coarse_part();
      const float beta = float(next_rz / rz);
      rz = next_rz;
      max_correction = update_direction(beta);
      result.iterations++;
      result.products++;
    }
    /* Block-Jacobi alone passed the test: the error the particles share, A_c⁻¹ Qᵀ r per
     * group, is checked once; past half the tolerance (a group's mean understates its
     * particles' error: at the full tolerance a cap of hair lagged a turning head 4% short,
     * at half 0.6%) it is added to Δv and the conjugate gradients start again from there
     * (r −= A Q A_c⁻¹ Qᵀ r). */
    if (additive || groups_num_ == 0 || result.iterations >= max_iterations ||
        check == max_coarse_checks)
    {
      break;
    }
    solve_coarse(residual_);
    float shared = 0.0f;
    for (const vec3 &correction : coarse_correction_) {
      shared = std::max(shared, glm::length(correction));
    }
    if (!(shared > 0.5f * velocity_tolerance)) {
      break;
    }
    parallel_for(n, grain, [&](const IndexRange range) {
      for (int64_t i = range.start; i < range.one_after_last(); i++) {
        const int32_t a = group_[size_t(i)];
        direction_[size_t(i)] = a >= 0 ? coarse_correction_[size_t(a)] : vec3(0.0f);
      }
    });
    multiply_dot(direction_, product_);
    result.products++;
    max_correction = start_from(true);
  }
  result.max_correction = max_correction;

  parallel_for(n, grain, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      r_velocities[i] += dv_[size_t(i)];
    }
  });
  if (guess_history > 0) {
    /* The newest first; the oldest's storage takes the new one when the history is full. */
    history_.resize(std::min(history_.size(), size_t(guess_history)));
    if (int64_t(history_.size()) < guess_history) {
      history_.emplace_back();
    }
    std::rotate(history_.rbegin(), history_.rbegin() + 1, history_.rend());
    history_.front() = dv_;
  }
  return result;
}

}  // namespace hairdyn
