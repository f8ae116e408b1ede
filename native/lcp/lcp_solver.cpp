#include "lcp/lcp_solver.hh"

#include <algorithm>
#include <cmath>

#include "core/parallel.hh"
#include "core/sph_kernels.hh"
#include "lcp/interactions_bando2003.hh"

namespace hairdyn {

RigidTransform rigid_part(const mat4 &m)
{
  /* Gram-Schmidt on the columns removes scale and shear. */
  const vec3 x = glm::normalize(vec3(m[0]));
  const vec3 y = glm::normalize(vec3(m[1]) - glm::dot(vec3(m[1]), x) * x);
  const vec3 z = glm::cross(x, y);
  RigidTransform result;
  result.rotation = glm::normalize(glm::quat_cast(mat3(x, y, z)));
  result.translation = vec3(m[3]);
  return result;
}

LcpSolver::LcpSolver(const LcpParams &params, const LcpParticles &particles_wo,
                     const mat4 &head_to_world_rest)
    : params_(params),
      head_rest_(rigid_part(head_to_world_rest)),
      u_(particles_wo.u),
      v_(particles_wo.v),
      s_(particles_wo.s)
{
  const int64_t n = particles_wo.size();
  const mat3 to_head = glm::transpose(head_rest_.matrix());
  x_rest_head_.resize(size_t(n));
  t_rest_head_.resize(size_t(n));
  is_root_.resize(size_t(n));
  for (int64_t i = 0; i < n; i++) {
    x_rest_head_[size_t(i)] = to_head * (particles_wo.positions[size_t(i)] - head_rest_.translation);
    t_rest_head_[size_t(i)] = glm::normalize(to_head * particles_wo.directions[size_t(i)]);
    is_root_[size_t(i)] = s_[size_t(i)] < 0.0f ? 1 : 0;
  }
  separate_close_particles(x_rest_head_, is_root_, rest_min_distance(), 20, [](vec3 &) {});

  /* Particle mass: the hair density ρ_h divided by the mean SPH number density of the rest
   * state (eq. 1 with unit masses), so that eq. 1 gives ρ_h on average at rest. */
  grid_.build(x_rest_head_, 2.0f * params_.h2);
  find_neighbors(grid_, x_rest_head_, 2.0f * params_.h2, true, neighbors_);
  std::vector<float> unit_masses(size_t(n), 1.0f);
  density_.resize(size_t(n));
  compute_density(x_rest_head_, unit_masses, neighbors_, params_.h2, density_);
  double number_density = 0.0;
  for (const float d : density_) {
    number_density += double(d);
  }
  number_density /= double(std::max<int64_t>(n, 1));
  mass_ = float(double(params_.hair_density) / std::max(number_density, 1e-30));
  masses_.assign(size_t(n), mass_);
  /* Bando 2003, eq. 9: A_i = (m_i / δ)^(2/3). */
  cross_sections_.assign(size_t(n), cross_section(mass_, params_.material_density));

  connections_ = build_connections(x_rest_head_, t_rest_head_, is_root_, params_.h1, params_.a0,
                                   params_.neighbor_num);
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

void LcpSolver::set_body_contact(LcpContactQuery query)
{
  contact_query_ = std::move(query);
  if (!contact_query_) {
    return;
  }
  const mat3 rotation = head_rest_.matrix();
  const mat3 to_head = glm::transpose(rotation);
  /* On the surface, a hair's breadth outside. */
  const auto out_of_body = [&](vec3 &x_head) {
    LcpContact contact;
    if (contact_query_(rotation * x_head + head_rest_.translation, contact)) {
      x_head = to_head * (contact.surface_point_wo + 1e-4f * contact.normal_wo -
                          head_rest_.translation);
    }
  };
  parallel_for(int64_t(x_rest_head_.size()), 1024, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      if (!is_root_[size_t(i)]) {
        out_of_body(x_rest_head_[size_t(i)]);
      }
    }
  });
  /* The particles put back on the surface land on each other: space them out again. */
  separate_close_particles(x_rest_head_, is_root_, rest_min_distance(), 20, out_of_body);
  connections_ = build_connections(x_rest_head_, t_rest_head_, is_root_, params_.h1, params_.a0,
                                   params_.neighbor_num);
  k_.resize(size_t(connections_.size()));
  alpha_k_.resize(size_t(connections_.size()));
  reset();
}

void LcpSolver::reset()
{
  x_head_ = x_rest_head_;
  t_head_ = t_rest_head_;
  v_head_.assign(x_head_.size(), vec3(0.0f));
  head_ = head_rest_;
  head_velocity_wo_ = vec3(0.0f);
  head_omega_wo_ = vec3(0.0f);
  air_x_wo_.clear();
  air_v_wo_.clear();
  implicit_springs_.reset();
  compute_spring_coefficients(connections_, x_head_, cross_sections_, params_.h1,
                              params_.young_modulus, k_, alpha_k_, side_sums_);
  grid_.build(x_head_, 2.0f * params_.h2);
  find_neighbors(grid_, x_head_, 2.0f * params_.h2, true, neighbors_);
  compute_density(x_head_, masses_, neighbors_, params_.h2, density_);
  HeadState head;
  head.rotation = head_.matrix();
  head.translation = head_.translation;
  head.velocity_wo = head.omega_head = head.acceleration_head = vec3(0.0f);
  head.angular_acceleration_head = vec3(0.0f);
  update_world_outputs(head);
  count_interpenetrations();
}

void LcpSolver::step(const float frame_dt, const mat4 &head_to_world)
{
  assert(frame_dt > 0.0f);
  const RigidTransform next = rigid_part(head_to_world);
  glm::quat turn = next.rotation * glm::inverse(head_.rotation);
  if (turn.w < 0.0f) {
    turn = -turn;
  }
  /* The head's motion over this frame: constant velocities between the frame's transforms,
   * and the change from the previous frame's velocities spread over the frame as the
   * accelerations of the inertial forces (§3.5). */
  const vec3 velocity_wo = (next.translation - head_.translation) / frame_dt;
  const float angle = 2.0f * std::acos(std::min(turn.w, 1.0f));
  const vec3 axis = vec3(turn.x, turn.y, turn.z);
  const float axis_len = glm::length(axis);
  const vec3 omega_wo = axis_len > 1e-12f ? axis / axis_len * (angle / frame_dt) : vec3(0.0f);
  const vec3 acceleration_wo = (velocity_wo - head_velocity_wo_) / frame_dt;
  const vec3 angular_acceleration_wo = (omega_wo - head_omega_wo_) / frame_dt;

  const auto head_at = [&](const float tau) {
    HeadState state;
    state.rotation = glm::mat3_cast(glm::slerp(head_.rotation, next.rotation, tau));
    state.translation = glm::mix(head_.translation, next.translation, tau);
    const mat3 to_head = glm::transpose(state.rotation);
    state.velocity_wo = velocity_wo;
    state.omega_head = to_head * omega_wo;
    state.acceleration_head = to_head * acceleration_wo;
    state.angular_acceleration_head = to_head * angular_acceleration_wo;
    return state;
  };

  if (params_.wind_speed > 0.0f) {
    wind_box_ = wind_box_around(positions_wo_, params_.wind_heading,
                                3.0f * params_.wind_particle_spacing);
    const vec3 wind_wo = wind_box_.axes_wo[0] * params_.wind_speed;
    if (air_x_wo_.empty()) {
      fill_wind_box(wind_box_, params_.wind_particle_spacing, wind_wo, uint64_t(params_.seed),
                    air_x_wo_, air_v_wo_);
    }
    wrap_air_particles(wind_box_, wind_wo, air_x_wo_, air_v_wo_);
  }

  /* The frame is cut into at least `substeps` equal substeps, short enough for the explicit
   * pressure's CFL bound 0.6 h₂ / c, with the sound speed c = √(dP/dρ) = √k_a of eq. 16
   * (the Fig. 6 scene went unstable near 1.4 h₂ / c). Explicit springs also keep each
   * substep below 1.8 / ω, ω² = 2 max_i Σ_j α_ij k_ij / m (Gershgorin bound; symplectic
   * Euler is stable below 2 / ω); α grows as connections weaken, so ω is re-evaluated every
   * substep. */
  int substeps = std::max(1, params_.substeps);
  if (params_.attraction_repulsion && params_.pressure_stiffness > 0.0f) {
    const float dt_cfl = 0.6f * params_.h2 / std::sqrt(params_.pressure_stiffness);
    substeps = std::max(substeps, int(std::ceil(frame_dt / dt_cfl)));
  }
  const float dt_max = frame_dt / float(substeps);
  float elapsed = 0.0f;
  substeps_used_ = 0;
  spring_iterations_ = 0;
  while (elapsed < frame_dt * (1.0f - 1e-5f) && substeps_used_ < 100000) {
    compute_spring_coefficients(connections_, x_head_, cross_sections_, params_.h1,
                                params_.young_modulus, k_, alpha_k_, side_sums_);
    float dt = std::min(dt_max, frame_dt - elapsed);
    if (!params_.implicit_springs) {
      const float omega = std::sqrt(
          2.0f * max_particle_stiffness(connections_, alpha_k_, is_root_) / mass_);
      if (std::isfinite(omega) && omega > 0.0f) {
        dt = std::min(dt, 1.8f / omega);
      }
    }
    substep(dt, head_at((elapsed + 0.5f * dt) / frame_dt), head_at((elapsed + dt) / frame_dt));
    elapsed += dt;
    substeps_used_++;
  }
  head_ = next;
  head_velocity_wo_ = velocity_wo;
  head_omega_wo_ = omega_wo;
  update_world_outputs(head_at(1.0f));
  count_interpenetrations();
}

void LcpSolver::substep(const float dt, const HeadState &mid, const HeadState &end)
{
  const int64_t n = int64_t(x_head_.size());
  /* 1. Neighbour search: a uniform grid of 2h₂ cells rebuilt every step (§3.1). */
  grid_.build(x_head_, 2.0f * params_.h2);
  find_neighbors(grid_, x_head_, 2.0f * params_.h2, true, neighbors_);
  /* 2. Density, eq. 1. */
  compute_density(x_head_, masses_, neighbors_, params_.h2, density_);

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
  accumulate_hair_interactions(x_head_, v_head_, t_head_, masses_, density_, neighbors_,
                               interactions, forces_, damped_forces_, damping_);
  if (params_.wind_speed > 0.0f) {
    accumulate_wind(dt, mid);
  }

  /* 4. Integrate in the head's frame. */
  const mat3 to_head = glm::transpose(mid.rotation);
  const vec3 gravity_head = to_head * vec3(0.0f, 0.0f, -params_.gravity);
  const vec3 frame_velocity_head = to_head * mid.velocity_wo;
  const vec3 &w = mid.omega_head;
  parallel_for(n, 1024, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      if (is_root_[size_t(i)]) {
        continue; /* Root particles are fixed to the head (§3.2). */
      }
      const vec3 &x = x_head_[size_t(i)];
      vec3 &v = v_head_[size_t(i)];
      const float m = masses_[size_t(i)];
      /* Inertial forces of the head's frame (§3.5): linear, Coriolis, centrifugal and
       * angular acceleration. */
      const vec3 inertial = -mid.acceleration_head - 2.0f * glm::cross(w, v) -
                            glm::cross(w, glm::cross(w, x)) -
                            glm::cross(mid.angular_acceleration_head, x);
      const vec3 acceleration = forces_[size_t(i)] / m + gravity_head + inertial;
      /* Damping between particles (springs, eq. 17-18): the factor 2 bounds the damping of
       * relative velocities too (Gershgorin on Σc). */
      v += dt * acceleration + dt * damped_forces_[size_t(i)] / (m + 2.0f * dt * damping_[size_t(i)]);
      /* Air friction against still air, −μ m v_wo (§3.5), integrated implicitly on its own:
       * folded into the pair damping above, strong springs would all but cancel it. */
      const vec3 carried = glm::cross(w, x) + frame_velocity_head;
      v = (v + carried) / (1.0f + params_.air_friction * dt) - carried;
    }
  });
  if (params_.implicit_springs) {
    spring_iterations_ += implicit_springs_
                              .step(connections_, x_head_, alpha_k_, params_.spring_damping,
                                    masses_, is_root_, dt, v_head_)
                              .iterations;
  }
  parallel_for(n, 4096, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      x_head_[size_t(i)] += dt * v_head_[size_t(i)];
    }
  });

  /* Body collisions after integration (§3.5). */
  if (contact_query_) {
    collide_with_body(end);
  }
  /* 5. Hair directions, eq. 15. */
  update_directions(connections_, x_head_, alpha_k_, is_root_, t_head_);
}

void LcpSolver::accumulate_wind(const float dt, const HeadState &mid)
{
  const int64_t n = int64_t(x_head_.size());
  const float h = params_.wind_particle_spacing;
  const vec3 wind_wo = wind_box_.axes_wo[0] * params_.wind_speed;
  /* Hair in world space. */
  parallel_for(n, 4096, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      const vec3 &x = x_head_[size_t(i)];
      hair_x_wo_[size_t(i)] = mid.rotation * x + mid.translation;
      hair_v_wo_[size_t(i)] = mid.rotation * (v_head_[size_t(i)] + glm::cross(mid.omega_head, x)) +
                              mid.velocity_wo;
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

  /* SPH air: pressure with a sound speed of ten times the wind (weakly compressible), capped
   * by the step's stability limit 0.4 h / Δt. */
  const float sound_speed = std::min(10.0f * params_.wind_speed, 0.4f * h / dt);
  accumulate_air_pressure(air_x_wo_, air_mass, params_.air_density, sound_speed, h,
                          air_neighbors_, air_density_, air_forces_);
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
  wrap_air_particles(wind_box_, wind_wo, air_x_wo_, air_v_wo_);
}

void LcpSolver::collide_with_body(const HeadState &end)
{
  const mat3 to_head = glm::transpose(end.rotation);
  parallel_for(int64_t(x_head_.size()), 1024, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      if (is_root_[size_t(i)]) {
        continue;
      }
      vec3 &x = x_head_[size_t(i)];
      vec3 &v = v_head_[size_t(i)];
      vec3 p_wo = end.rotation * x + end.translation;
      LcpContact contact;
      if (!contact_query_(p_wo, contact)) {
        continue;
      }
      /* Velocity relative to the collider, in world space. */
      const vec3 carried_wo = end.rotation * glm::cross(end.omega_head, x) + end.velocity_wo;
      vec3 v_rel_wo = contact.moves_with_head ?
                          end.rotation * v :
                          end.rotation * v + carried_wo - contact.velocity_wo;
      respond_to_contact(contact, params_.body_friction, p_wo, v_rel_wo);
      x = to_head * (p_wo - end.translation);
      v = contact.moves_with_head ? to_head * v_rel_wo :
                                    to_head * (v_rel_wo + contact.velocity_wo - carried_wo);
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
      velocities_wo_[size_t(i)] = head.rotation * (v_head_[size_t(i)] +
                                                   glm::cross(head.omega_head, x)) +
                                  head.velocity_wo;
    }
  });
}

void LcpSolver::count_interpenetrations()
{
  grid_.build(x_head_, 2.0f * params_.h2);
  find_neighbors(grid_, x_head_, 2.0f * params_.h2, true, neighbors_);
  interpenetrating_pairs_num_ = count_close_pairs(x_head_, is_root_, neighbors_,
                                                  0.5f * params_.h2);
}

}  // namespace hairdyn
