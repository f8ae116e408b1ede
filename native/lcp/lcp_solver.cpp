#include "lcp/lcp_solver.hh"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "core/parallel.hh"
#include "core/sph_kernels.hh"
#include "lcp/interactions_bando2003.hh"

namespace hairdyn {

/* v turned about `omega` by the angle |omega| · scale (right hand). */
static vec3 rotate_about(const vec3 &v, const vec3 &omega, const float scale)
{
  const float rate = glm::length(omega);
  if (!(rate > 0.0f)) {
    return v;
  }
  return rotate_about_axis(v, omega / rate, rate * scale);
}

vec3 LcpSolver::transport_head(const HeadState &head, const vec3 &x)
{
  return glm::transpose(head.rotation) *
         head.acceleration.transport(head.rotation * x + head.translation);
}

vec3 LcpSolver::fictitious_acceleration(const int64_t i) const
{
  const vec3 &x = x_head_[size_t(i)], &v = v_head_[size_t(i)];
  return -transport_head(last_head_, x) - 2.0f * glm::cross(last_head_.omega_head, v);
}

LcpSolver::LcpSolver(const LcpParams &params, const LcpParticles &particles_wo,
                     const mat4 &head_to_world_rest, const WindParams &wind) :
    params_(params),
    head_rest_(HeadPose::from_matrix(head_to_world_rest)), u_(particles_wo.u), v_(particles_wo.v),
    s_(particles_wo.s), wind_params_(wind), wind_(wind)
{
  const int64_t n = particles_wo.size();
  const mat3 to_head = glm::transpose(head_rest_.rotation_matrix());
  x_rest_head_.resize(size_t(n));
  t_rest_head_.resize(size_t(n));
  is_root_.resize(size_t(n));
  is_fixed_.resize(size_t(n));
  for (int64_t i = 0; i < n; i++) {
    x_rest_head_[size_t(i)] =
        to_head * (particles_wo.positions[size_t(i)] - head_rest_.translation);
    t_rest_head_[size_t(i)] = glm::normalize(to_head * particles_wo.directions[size_t(i)]);
    is_root_[size_t(i)] = s_[size_t(i)] < 0.0f ? 1 : 0;
    is_fixed_[size_t(i)] =
        is_root_[size_t(i)] || (!particles_wo.fixed.empty() && particles_wo.fixed[size_t(i)]);
  }
  separate_close_particles(x_rest_head_, is_fixed_, rest_min_distance(), 20, [](vec3 &) {});

  /* Particle mass: the hair density ρ_h divided by the mean SPH number density of the rest
   * state (eq. 1 with unit masses), so that eq. 1 gives ρ_h on average at rest. */
  neighbors_.update(x_rest_head_, 2.0f * params_.h2, neighbor_skin());
  std::vector<float> unit_masses(size_t(n), 1.0f);
  density_.resize(size_t(n));
  compute_density(x_rest_head_, unit_masses, neighbors_.list(), params_.h2, density_);
  double number_density = 0.0;
  for (const float d : density_) {
    number_density += double(d);
  }
  number_density /= double(std::max<int64_t>(n, 1));
  mass_ = float(double(params_.hair_density) / std::max(number_density, 1e-30));
  masses_.assign(size_t(n), mass_);
  /* Bando 2003, eq. 9: A_i = (m_i / δ)^(2/3). */
  cross_sections_.assign(size_t(n), cross_section(mass_, params_.material_density));

  connections_ = build_connections(x_rest_head_, t_rest_head_, is_fixed_, params_.h1, params_.a0,
                                   params_.neighbor_num);
  build_tethers();
  k_.resize(size_t(connections_.size()));
  alpha_k_.resize(size_t(connections_.size()));
  side_sums_.resize(size_t(2 * n));
  damping_.resize(size_t(n));
  forces_.resize(size_t(n));
  damped_forces_.resize(size_t(n));
  positions_wo_.resize(size_t(n));
  directions_wo_.resize(size_t(n));
  velocities_wo_.resize(size_t(n));
  hair_x_wo_.resize(size_t(n));
  hair_v_wo_.resize(size_t(n));
  hair_drag_wo_.resize(size_t(n));
  reset();
}

void LcpSolver::set_wind(const WindParams &wind)
{
  wind_params_ = wind;
  wind_ = WindField(wind);
  air_x_wo_.clear(); /* The air starts over in the new wind. */
  air_v_wo_.clear();
}

void LcpSolver::set_colliders(const ColliderSet *colliders)
{
  if (colliders == nullptr) {
    set_body_contact({});
    return;
  }
  set_body_contact([colliders](const vec3 &p_wo, Contact &r_contact) {
    return colliders->find_contact(p_wo, r_contact);
  });
}

void LcpSolver::set_body_contact(ContactQuery query)
{
  contact_query_ = std::move(query);
  if (!contact_query_) {
    return;
  }
  const mat3 rotation = head_rest_.rotation_matrix();
  const mat3 to_head = glm::transpose(rotation);
  /* On the surface, a hair's breadth outside. */
  const auto out_of_body = [&](vec3 &x_head) {
    Contact contact;
    if (contact_query_(rotation * x_head + head_rest_.translation, contact)) {
      x_head = to_head *
               (contact.surface_point_wo + 1e-4f * contact.normal_wo - head_rest_.translation);
    }
  };
  parallel_for(int64_t(x_rest_head_.size()), 1024, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      if (!is_fixed_[size_t(i)]) {
        out_of_body(x_rest_head_[size_t(i)]);
      }
    }
  });
  /* The particles put back on the surface land on each other: space them out again. */
  separate_close_particles(x_rest_head_, is_fixed_, rest_min_distance(), 20, out_of_body);
  connections_ = build_connections(x_rest_head_, t_rest_head_, is_fixed_, params_.h1, params_.a0,
                                   params_.neighbor_num);
  build_tethers();
  k_.resize(size_t(connections_.size()));
  alpha_k_.resize(size_t(connections_.size()));
  reset();
}

/* Slack of the tethers over the hair's length: well above the stretch of the loose springs
 * under gravity (a few percent at the default E), so that they only act on hair flung out. */
static constexpr float tether_slack = 0.1f;

void LcpSolver::build_tethers()
{
  const int64_t n = int64_t(x_rest_head_.size());
  std::vector<int32_t> roots;
  for (int64_t i = 0; i < n; i++) {
    if (is_root_[size_t(i)]) {
      roots.push_back(int32_t(i));
    }
  }
  anchor_.assign(size_t(n), -1);
  tether_length_.assign(size_t(n), 0.0f);
  if (roots.empty()) {
    return;
  }
  /* The root particle nearest in (u, v), the scalp point the hair grows from (eq. 3); the
   * hair reaches the particle over s_i − s_r, or the straight distance if that is longer. */
  parallel_for(n, 256, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      if (is_fixed_[size_t(i)]) {
        anchor_[size_t(i)] = int32_t(i);
        continue;
      }
      const vec2 uv(u_[size_t(i)], v_[size_t(i)]);
      float best = std::numeric_limits<float>::max();
      int32_t anchor = roots.front();
      for (const int32_t r : roots) {
        const vec2 d = vec2(u_[size_t(r)], v_[size_t(r)]) - uv;
        const float dist_sq = glm::dot(d, d);
        if (dist_sq < best) {
          best = dist_sq;
          anchor = r;
        }
      }
      anchor_[size_t(i)] = anchor;
      const float reach =
          std::max(s_[size_t(i)] - s_[size_t(anchor)],
                   glm::length(x_rest_head_[size_t(i)] - x_rest_head_[size_t(anchor)]));
      tether_length_[size_t(i)] = (1.0f + tether_slack) * reach;
    }
  });
}

void LcpSolver::enforce_tethers()
{
  tethered_.assign(x_head_.size(), 0);
  if (anchor_.empty() || anchor_.front() < 0) {
    return;
  }
  parallel_for(int64_t(x_head_.size()), 1024, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      if (is_fixed_[size_t(i)]) {
        continue;
      }
      const vec3 d = x_head_[size_t(i)] - x_head_[size_t(anchor_[size_t(i)])];
      const float r = glm::length(d);
      const float length = tether_length_[size_t(i)];
      if (!(r > length)) {
        continue;
      }
      /* Back onto the tether; the outward part of the velocity is lost (inelastic). */
      tethered_[size_t(i)] = 1;
      const vec3 out = d / r;
      x_head_[size_t(i)] -= (r - length) * out;
      vec3 &v = v_head_[size_t(i)];
      v -= std::max(0.0f, glm::dot(v, out)) * out;
    }
  });
}

/* The most air particles the wind may take (each costs SPH work every substep): a box of
 * 50 cm around the hair at the 3 cm default spacing holds about 5,000. */
static constexpr int64_t max_air_particles = 2000000;

/* m/s: no head motion gives hair this speed in the head's frame (a head teleported 100 m in a
 * frame gives 2,400 m/s); a particle past it has run away. */
static constexpr float runaway_speed = 1e4f;

void LcpSolver::check_divergence(const int frame_substep)
{
  const int64_t n = int64_t(x_head_.size());
  const int64_t none = n;
  /* The first bad particle, the same on any thread count. */
  const int64_t bad = parallel_reduce(
      n, 4096, none,
      [&](const IndexRange range) {
        for (int64_t i = range.start; i < range.one_after_last(); i++) {
          const vec3 &x = x_head_[size_t(i)], &v = v_head_[size_t(i)];
          const float reach = glm::length(x - x_head_[size_t(std::max(anchor_[size_t(i)], 0))]);
          const float speed = glm::length(v);
          if (!std::isfinite(reach) || !std::isfinite(speed) || speed > runaway_speed ||
              (anchor_[size_t(i)] >= 0 && reach > 2.0f * tether_length_[size_t(i)] + params_.h2))
          {
            return i;
          }
        }
        return none;
      },
      [](const int64_t a, const int64_t b) {
        return std::min(a, b);
      });
  if (bad == none) {
    return;
  }
  const vec3 &x = x_head_[size_t(bad)], &v = v_head_[size_t(bad)];
  char text[400];
  std::snprintf(text, sizeof(text),
                "LCP diverged at substep %d of the frame: particle %lld (s = %.3g m) is at "
                "(%.3g, %.3g, %.3g) m with velocity (%.3g, %.3g, %.3g) m/s in the head's frame. "
                "Lower the head's speed or raise the substeps.",
                frame_substep, (long long)bad, double(s_[size_t(bad)]), double(x.x), double(x.y),
                double(x.z), double(v.x), double(v.y), double(v.z));
  failure_ = text;
}

void LcpSolver::reset()
{
  x_head_ = x_rest_head_;
  t_head_ = t_rest_head_;
  v_head_.assign(x_head_.size(), vec3(0.0f));
  head_ = head_rest_;
  head_velocity_ = HeadVelocity();
  air_x_wo_.clear();
  air_v_wo_.clear();
  time_ = 0.0f;
  implicit_springs_.reset();
  frames_since_coarse_factor_ = coarse_factor_frames;
  failure_.clear();
  compute_spring_coefficients(connections_, x_head_, cross_sections_, params_.h1,
                              params_.young_modulus, k_, alpha_k_, side_sums_);
  neighbors_.update(x_head_, 2.0f * params_.h2, neighbor_skin());
  compute_density(x_head_, masses_, neighbors_.list(), params_.h2, density_);
  HeadState head;
  head.rotation = head_.rotation_matrix();
  head.translation = head_.translation;
  head.acceleration.center = head.translation;
  last_head_ = head;
  update_world_outputs(head);
  count_interpenetrations();
}

/* Eq. 16's stiffness joins the implicit springs' step (lcp/implicit_springs.hh). */
static bool implicit_pressure(const LcpParams &params)
{
  return params.implicit_pressure && params.implicit_springs && params.attraction_repulsion &&
         params.pressure_stiffness > 0.0f;
}

/* s: the explicit pressure's CFL bound 0.6 h₂ / c, with the sound speed c = √(dP/dρ) = √k_a
 * of eq. 16 (the Fig. 6 scene went unstable near 1.4 h₂ / c); infinite without pressure. */
static float pressure_time_step(const LcpParams &params)
{
  if (!params.attraction_repulsion || !(params.pressure_stiffness > 0.0f) ||
      implicit_pressure(params))
  {
    return std::numeric_limits<float>::infinity();
  }
  return 0.6f * params.h2 / std::sqrt(params.pressure_stiffness);
}

float LcpSolver::wind_time_step() const
{
  return has_wind() ? 2.0f * params_.wind_particle_spacing / fastest_wind()
                    : std::numeric_limits<float>::infinity();
}

/* Substeps of `dt_limit` in a frame, saturating far above any max_substeps. */
static int substeps_for(const float frame_dt, const float dt_limit)
{
  return int(std::min(1e9, std::ceil(double(frame_dt) / double(dt_limit))));
}

/* s: explicit springs are stable below 1.8 / ω, ω² = 2 max_i Σ_j α_ij k_ij / m (Gershgorin
 * bound; symplectic Euler is stable below 2 / ω); infinite when nothing is connected. */
static float spring_time_step(const LcpConnections &connections, const Span<float> alpha_k,
                              const Span<uint8_t> is_root, const float mass)
{
  const float omega =
      std::sqrt(2.0f * max_particle_stiffness(connections, alpha_k, is_root) / mass);
  return std::isfinite(omega) && omega > 0.0f ? 1.8f / omega
                                              : std::numeric_limits<float>::infinity();
}

LcpSolver::SubstepEstimate LcpSolver::estimate_substeps(const float frame_dt) const
{
  char text[300];
  SubstepEstimate estimate{ std::max(1, params_.substeps), "the substeps setting" };
  const float dt_pressure = pressure_time_step(params_);
  if (substeps_for(frame_dt, dt_pressure) > estimate.count) {
    estimate.count = substeps_for(frame_dt, dt_pressure);
    std::snprintf(text, sizeof(text),
                  "the CFL bound of the hair-hair pressure (eq. 16), 0.6 h₂/√k_a = %.3g s: raise "
                  "h₂ or lower k_a",
                  double(dt_pressure));
    estimate.reason = text;
  }
  const float dt_wind = wind_time_step();
  if (substeps_for(frame_dt, dt_wind) > estimate.count) {
    estimate.count = substeps_for(frame_dt, dt_wind);
    std::snprintf(text, sizeof(text),
                  "the wind's speed: its air particles cross at most their support 2h = %.3g m "
                  "a substep, %.3g s: raise the wind particle spacing or lower the wind speed",
                  double(2.0f * params_.wind_particle_spacing), double(dt_wind));
    estimate.reason = text;
  }
  if (!params_.implicit_springs) {
    const float dt_springs = spring_time_step(connections_, alpha_k_, is_fixed_, mass_);
    if (substeps_for(frame_dt, dt_springs) > estimate.count) {
      estimate.count = substeps_for(frame_dt, dt_springs);
      std::snprintf(text, sizeof(text),
                    "the explicit springs' highest frequency (E = %.3g Pa), stable below %.3g s "
                    "a step: turn implicit springs on or lower E",
                    double(params_.young_modulus), double(dt_springs));
      estimate.reason = text;
    }
  }
  return estimate;
}

bool LcpSolver::step(const float frame_dt, const mat4 &head_to_world)
{
  assert(frame_dt > 0.0f);
  if (!failure_.empty()) {
    return false;
  }
  const SubstepEstimate estimate = estimate_substeps(frame_dt);
  if (estimate.count > params_.max_substeps) {
    failure_ = "LCP refused the frame: it needs " + std::to_string(estimate.count) +
               " substeps, more than max_substeps (" + std::to_string(params_.max_substeps) +
               "), set by " + estimate.reason + ".";
    return false;
  }
  /* The head's motion over this frame (core/head_motion.hh): constant velocities between
   * the frame's poses, and their change since the last frame as the accelerations of the
   * fictitious forces (§3.5). */
  const HeadPose next = HeadPose::from_matrix(head_to_world);
  const HeadVelocity velocity = HeadVelocity::between(head_, next, frame_dt);
  const HeadAcceleration acceleration =
      HeadAcceleration::between(head_velocity_, velocity, frame_dt);
  const auto head_at = [&](const float tau) {
    const HeadPose pose = HeadPose::interpolate(head_, next, tau);
    HeadState state;
    state.rotation = pose.rotation_matrix();
    state.translation = pose.translation;
    state.velocity_wo = velocity.linear;
    state.omega_head = glm::transpose(state.rotation) * velocity.angular;
    state.acceleration = acceleration;
    state.acceleration.center = pose.translation;
    return state;
  };

  if (has_wind()) {
    wind_box_ = wind_box_around(positions_wo_, wind_params_.direction,
                                3.0f * params_.wind_particle_spacing);
    const int64_t air_num = wind_box_count(wind_box_, params_.wind_particle_spacing);
    if (air_num > max_air_particles) {
      char text[300];
      std::snprintf(text, sizeof(text),
                    "LCP refused the frame: the wind needs %lld air particles %.3g m apart "
                    "around the hair, more than %lld. Raise the wind particle spacing.",
                    (long long)air_num, double(params_.wind_particle_spacing),
                    (long long)max_air_particles);
      failure_ = text;
      return false;
    }
    if (air_x_wo_.empty()) {
      fill_wind_box(wind_box_, params_.wind_particle_spacing, wind_, time_, uint64_t(params_.seed),
                    air_x_wo_, air_v_wo_);
    }
    wrap_air_particles(wind_box_, wind_, time_, air_x_wo_, air_v_wo_);
  }

  /* The frame is cut into the equal substeps of the estimate: at least `substeps`, short
   * enough for an explicit pressure's CFL bound and the wind. Explicit springs also keep each
   * substep below their stability bound; α grows as connections weaken, so that bound is
   * re-evaluated every substep. */
  const float dt_max = frame_dt / float(estimate.count);
  float elapsed = 0.0f;
  substeps_used_ = 0;
  spring_iterations_ = spring_products_ = 0;
  frames_since_coarse_factor_++;
  while (elapsed < frame_dt * (1.0f - 1e-5f)) {
    if (substeps_used_ == params_.max_substeps) {
      failure_ = "LCP stopped the frame after max_substeps (" +
                 std::to_string(params_.max_substeps) +
                 ") substeps: the explicit springs stiffened as the hair stretched. Turn "
                 "implicit springs on or lower E.";
      return false;
    }
    compute_spring_coefficients(connections_, x_head_, cross_sections_, params_.h1,
                                params_.young_modulus, k_, alpha_k_, side_sums_);
    float dt = std::min(dt_max, frame_dt - elapsed);
    if (!params_.implicit_springs) {
      dt = std::min(dt, spring_time_step(connections_, alpha_k_, is_fixed_, mass_));
    }
    substep(dt, head_at((elapsed + 0.5f * dt) / frame_dt), head_at((elapsed + dt) / frame_dt));
    elapsed += dt;
    time_ += dt;
    substeps_used_++;
    check_divergence(substeps_used_);
    if (!failure_.empty()) {
      return false;
    }
  }
  head_ = next;
  head_velocity_ = velocity;
  update_world_outputs(head_at(1.0f));
  count_interpenetrations();
  return true;
}

void LcpSolver::substep(const float dt, const HeadState &mid, const HeadState &end)
{
  const int64_t n = int64_t(x_head_.size());
  /* 1. Neighbour search (§3.1): a uniform grid, its list kept while no pair can be missing
   * from it (core/spatial_grid.hh's VerletNeighbors). */
  neighbors_.update(x_head_, 2.0f * params_.h2, neighbor_skin());
  /* 2. Density, eq. 1. */
  compute_density(x_head_, masses_, neighbors_.list(), params_.h2, density_);

  /* 3. Forces. */
  std::fill(forces_.begin(), forces_.end(), vec3(0.0f));
  std::fill(damped_forces_.begin(), damped_forces_.end(), vec3(0.0f));
  std::fill(damping_.begin(), damping_.end(), 0.0f);
  /* Springs: k_ij (eq. 7) and α_ij (eq. 13-14) were computed by step() for this state;
   * damped springs α_ij k_ij, here when explicit, after the other forces when implicit. */
  if (!params_.implicit_springs) {
    accumulate_spring_forces(connections_, x_head_, v_head_, alpha_k_, params_.spring_damping,
                             forces_, damped_forces_, damping_);
  }
  /* Hair-hair interactions, eq. 16-18. */
  HairInteractionSettings interactions;
  interactions.h2 = params_.h2;
  interactions.attraction_repulsion = params_.attraction_repulsion;
  interactions.pressure_stiffness = params_.pressure_stiffness;
  interactions.rest_density = params_.rest_density;
  interactions.collision = params_.hair_collision;
  interactions.collision_damping = params_.collision_damping;
  interactions.friction = params_.hair_friction;
  interactions.friction_damping = params_.friction_damping;
  accumulate_hair_interactions(x_head_, v_head_, t_head_, masses_, density_, neighbors_.list(),
                               interactions, forces_, damped_forces_, damping_);
  if (has_wind()) {
    accumulate_wind(dt, mid);
  }

  /* 4. Integrate in the head's frame. */
  const mat3 to_head = glm::transpose(mid.rotation);
  const vec3 gravity_head = to_head * params_.gravity;
  last_head_ = mid;
  const vec3 frame_velocity_head = to_head * mid.velocity_wo;
  const vec3 &w = mid.omega_head;
  parallel_for(n, 1024, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      if (is_fixed_[size_t(i)]) {
        continue; /* Root particles are fixed to the head (§3.2), and so are pinned ones. */
      }
      const vec3 &x = x_head_[size_t(i)];
      vec3 &v = v_head_[size_t(i)];
      const float m = masses_[size_t(i)];
      /* Coriolis force of the head's frame (§3.5), dv/dt = −2 ω × v: exactly, v turned by
       * −2|ω|Δt about ω (Rodrigues). */
      v = rotate_about(v, w, -2.0f * dt);
      /* The other fictitious forces: the transport acceleration (linear, angular and
       * centrifugal) of core/head_motion.hh. */
      const vec3 inertial = -transport_head(mid, x);
      const vec3 acceleration = forces_[size_t(i)] / m + gravity_head + inertial;
      /* Damping between particles (springs, eq. 17-18): the factor 2 bounds the damping of
       * relative velocities too (Gershgorin on Σc). */
      v += dt * acceleration +
           dt * damped_forces_[size_t(i)] / (m + 2.0f * dt * damping_[size_t(i)]);
      /* Air friction against still air, −μ m v_wo (§3.5), integrated implicitly on its own:
       * folded into the pair damping above, strong springs would all but cancel it. */
      const vec3 carried = glm::cross(w, x) + frame_velocity_head;
      v = (v + carried) / (1.0f + params_.air_friction * dt) - carried;
    }
  });
  if (params_.implicit_springs) {
    /* The solve stops when what it leaves would move no particle by solver_tolerance h₂
     * over the step. A particle's block-Jacobi correction alone stays small for an error the
     * particles share (the whole volume lagging a turning head as one), which the coarse
     * correction over groups of about 4 h₂ shows (stop 48, a cap of hair under a 1 rad head
     * turn, explicit pressure, at 5·10⁻⁴ h₂: the mid-turn lag 26% short and the hair ending
     * 0.002 rad ahead of the head with block-Jacobi alone; 0.6% short with the coarse check).
     * The springs alone couple only neighbours: their iterations stay block-Jacobi's and the
     * shared error is checked at the end (at 2,000 particles a coarse solve in every
     * iteration cost about as much as a matrix product, and the frame 18% more). The
     * pressure's stiffness (eq. 16) couples the particles across the whole volume, which
     * block-Jacobi resolves slowly: there the coarse correction joins every iteration's
     * preconditioner (95 iterations a frame at 20,000 particles against 41). The coarse
     * factor is rebuilt on the first substep of every coarse_factor_frames-th frame: any
     * symmetric positive definite coarse matrix gives a valid preconditioner, and one a few
     * frames old takes about as many iterations (20,000
     * particles, 48 frames: 40.0 a frame either way with the benchmark's sway, 73.5 against
     * 76.2 with a head swinging 1 rad, 192.9 against 193.3 swinging 1.5 rad fast) for less
     * work (61 against 56 ms a frame; 2,000 particles 4.2 against 3.4 ms). */
    implicit_springs_.velocity_tolerance = params_.solver_tolerance * params_.h2 / dt;
    implicit_springs_.group_cell = 4.0f * params_.h2;
    implicit_springs_.coarse_in_preconditioner = implicit_pressure(params_);
    implicit_springs_.refactor_coarse =
        substeps_used_ == 0 && frames_since_coarse_factor_ >= coarse_factor_frames;
    if (implicit_springs_.refactor_coarse) {
      frames_since_coarse_factor_ = 0;
    }
    if (implicit_pressure(params_)) {
      compute_density_jacobian(x_head_, masses_, density_, neighbors_.list(), params_.h2,
                               params_.pressure_stiffness, params_.rest_density,
                               pressure_jacobian_);
    }
    const ImplicitSprings::Result solve = implicit_springs_.step(
        connections_, x_head_, alpha_k_, params_.spring_damping, masses_, is_fixed_, dt,
        implicit_pressure(params_) ? &pressure_jacobian_ : nullptr, v_head_);
    spring_iterations_ += solve.iterations;
    spring_products_ += solve.products;
  }
  x_start_ = x_head_;
  parallel_for(n, 4096, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      x_head_[size_t(i)] += dt * v_head_[size_t(i)];
    }
  });

  /* Hair keeps its length (the tethers), then body collisions after integration (§3.5). */
  enforce_tethers();
  if (contact_query_) {
    collide_with_body(end);
  }
  /* A tethered particle moves as far as the tether and the body let it: its velocity is that
   * motion (position-based dynamics' velocity update), so that a particle held between its
   * tether and the body (the straight tether would pass through the head) keeps no velocity
   * it cannot follow. */
  parallel_for(n, 4096, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      if (tethered_[size_t(i)]) {
        v_head_[size_t(i)] = (x_head_[size_t(i)] - x_start_[size_t(i)]) / dt;
      }
    }
  });
  /* 5. Hair directions, eq. 15. */
  update_directions(connections_, x_head_, alpha_k_, is_fixed_, t_head_);
}

void LcpSolver::accumulate_wind(const float dt, const HeadState &mid)
{
  const int64_t n = int64_t(x_head_.size());
  const float h = params_.wind_particle_spacing;
  /* Hair in world space. */
  parallel_for(n, 4096, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      const vec3 &x = x_head_[size_t(i)];
      hair_x_wo_[size_t(i)] = mid.rotation * x + mid.translation;
      hair_v_wo_[size_t(i)] =
          mid.rotation * (v_head_[size_t(i)] + glm::cross(mid.omega_head, x)) + mid.velocity_wo;
    }
  });
  const int64_t air_num = int64_t(air_x_wo_.size());
  const float air_mass = params_.air_density * h * h * h;
  air_volumes_.assign(size_t(air_num), air_mass / params_.air_density);
  air_density_.resize(size_t(air_num));
  air_forces_.assign(size_t(air_num), vec3(0.0f));
  air_damped_forces_.assign(size_t(air_num), vec3(0.0f));
  air_damping_.assign(size_t(air_num), 0.0f);
  std::fill(hair_drag_wo_.begin(), hair_drag_wo_.end(), vec3(0.0f));

  air_grid_.build(air_x_wo_, 2.0f * h);
  hair_grid_wo_.build(hair_x_wo_, 2.0f * h);
  find_neighbors(air_grid_, air_x_wo_, 2.0f * h, true, air_neighbors_);
  find_neighbors(air_grid_, hair_x_wo_, 2.0f * h, false, hair_to_air_);
  find_neighbors(hair_grid_wo_, air_x_wo_, 2.0f * h, false, air_to_hair_);

  /* SPH air: pressure with a sound speed of ten times the wind's fastest (weakly
   * compressible), capped by the step's stability limit 0.4 h / Δt. */
  const float sound_speed = std::min(10.0f * fastest_wind(), 0.4f * h / dt);
  accumulate_air_pressure(air_x_wo_, air_mass, params_.air_density, sound_speed, h, air_neighbors_,
                          air_density_, air_forces_);
  /* Drag both ways (§3.5). */
  hair_drag_damping_.assign(size_t(n), 0.0f);
  accumulate_drag(hair_x_wo_, hair_v_wo_, masses_, air_x_wo_, air_v_wo_, air_volumes_,
                  hair_to_air_, h, params_.wind_drag, hair_drag_wo_, hair_drag_damping_);
  accumulate_drag(air_x_wo_, air_v_wo_, air_volumes_, hair_x_wo_, hair_v_wo_, masses_,
                  air_to_hair_, h, params_.wind_drag, air_damped_forces_, air_damping_);
  const mat3 to_head = glm::transpose(mid.rotation);
  for (int64_t i = 0; i < n; i++) {
    damped_forces_[size_t(i)] += to_head * hair_drag_wo_[size_t(i)];
    damping_[size_t(i)] += hair_drag_damping_[size_t(i)];
  }
  /* Integrate the air (world space): free-stream air keeps its velocity. */
  parallel_for(air_num, 4096, [&](const IndexRange range) {
    for (int64_t j = range.start; j < range.one_after_last(); j++) {
      vec3 &v = air_v_wo_[size_t(j)];
      v += dt * air_forces_[size_t(j)] / air_mass +
           dt * air_damped_forces_[size_t(j)] / (air_mass + 2.0f * dt * air_damping_[size_t(j)]);
      air_x_wo_[size_t(j)] += dt * v;
    }
  });
  wrap_air_particles(wind_box_, wind_, time_ + dt, air_x_wo_, air_v_wo_);
}

void LcpSolver::collide_with_body(const HeadState &end)
{
  const mat3 to_head = glm::transpose(end.rotation);
  parallel_for(int64_t(x_head_.size()), 1024, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      if (is_fixed_[size_t(i)]) {
        continue;
      }
      vec3 &x = x_head_[size_t(i)];
      vec3 &v = v_head_[size_t(i)];
      vec3 p_wo = end.rotation * x + end.translation;
      Contact contact;
      if (!contact_query_(p_wo, contact)) {
        continue;
      }
      /* Velocity relative to the collider, in world space. */
      const vec3 carried_wo = end.rotation * glm::cross(end.omega_head, x) + end.velocity_wo;
      vec3 v_rel_wo = contact.moves_with_head
                          ? end.rotation * v
                          : end.rotation * v + carried_wo - contact.velocity_wo;
      respond_to_contact(contact, params_.body_friction, p_wo, v_rel_wo);
      x = to_head * (p_wo - end.translation);
      v = contact.moves_with_head ? to_head * v_rel_wo
                                  : to_head * (v_rel_wo + contact.velocity_wo - carried_wo);
    }
  });
}

void LcpSolver::update_world_outputs(const HeadState &head)
{
  parallel_for(int64_t(x_head_.size()), 4096, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      const vec3 &x = x_head_[size_t(i)];
      positions_wo_[size_t(i)] = head.rotation * x + head.translation;
      directions_wo_[size_t(i)] = head.rotation * t_head_[size_t(i)];
      velocities_wo_[size_t(i)] =
          head.rotation * (v_head_[size_t(i)] + glm::cross(head.omega_head, x)) + head.velocity_wo;
    }
  });
}

void LcpSolver::count_interpenetrations()
{
  neighbors_.update(x_head_, 2.0f * params_.h2, neighbor_skin());
  interpenetrating_pairs_num_ =
      count_close_pairs(x_head_, is_fixed_, neighbors_.list(), 0.5f * params_.h2);
}

}  // namespace hairdyn
