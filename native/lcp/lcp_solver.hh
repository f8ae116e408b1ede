#pragma once
/* Loosely connected particles (Bando, Chen, Nishita 2003): the solver owns the particle
 * state and runs the paper's loop (§3.1) in a straight-line step():
 *   1. neighbour search (uniform grid, 2h₂)      2. density, eq. 1
 *   3. forces: springs eq. 7-14, interactions eq. 16-18, gravity, air friction, wind,
 *      inertia of the head's frame (§3.5)        4. integrate, then body collisions
 *   5. hair directions, eq. 15.
 * The equations of motion are written in the head's frame: positions and velocities are
 * relative to the head, whose motion enters as the fictitious forces of core/head_motion.hh
 * (the one head-motion model of every method). The frame is the head pose's rotation and
 * translation: the hair's lengths are physical, so the head's scale does not scale them.
 * Inputs and outputs are in world space.
 *
 * Integration: symplectic Euler. The damping forces, linear in the velocities (eq. 17-18,
 * air friction, wind drag), are divided by m_i + Δt Σc, the diagonal of their backward-Euler
 * matrix, so that no damping constant can make a step unstable; they vanish at rest, so
 * equilibria are unchanged. The damped springs then take a backward-Euler step of their own
 * (lcp/implicit_springs.hh), stable at any time step; or, with implicit_springs off, they are
 * explicit and each frame takes as many substeps as their highest frequency needs. The
 * Coriolis force of the head's frame turns velocities without changing their magnitude and is
 * integrated as that exact rotation (explicit Euler would grow |v| by √(1 + (2ωΔt)²) every
 * substep: a head spinning at 50 rad/s multiplies the speeds by ~1.4 per substep).
 *
 * Hair does not stretch: no particle can be farther from the root particle it grows from than
 * its hair's length to it (arc length s, eq. 3), plus slack for the loose springs' own give.
 * A particle flung past that tether is put back on it and loses its outward velocity, as a
 * strand's inextensible segments would hold it. A violent shake can tear the loose
 * connections (they end at 2h₁); the tether keeps the torn hair on its root.
 *
 * A frame whose stability bounds need more than params.max_substeps substeps is refused, and
 * a state that is not finite or has run away from the tethers marks the solver as failed;
 * failure() says why in a sentence, until reset(). */
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>

#include "collision/collider.hh"
#include "core/head_motion.hh"
#include "core/math.hh"
#include "core/span.hh"
#include "core/spatial_grid.hh"
#include "lcp/body_collision_bando2003.hh"
#include "lcp/implicit_springs.hh"
#include "lcp/interactions_bando2003.hh"
#include "lcp/lcp_params.hh"
#include "lcp/sampling_bando2003.hh"
#include "lcp/springs_bando2003.hh"
#include "lcp/wind_bando2003.hh"

namespace hairdyn {

class LcpSolver {
 public:
  /* `particles_wo`: positions and directions in world space with the head at
   * `head_to_world_rest`; s < 0 marks root particles, fixed to the head, and
   * particles_wo.fixed (when given) other particles held by the head like them: they stand for
   * hair the groom pins (groom/pins.hh). They stay on their rest positions in the head's
   * frame, keep their springs to free neighbours and their direction, and anchor no tether. */
  LcpSolver(const LcpParams &params, const LcpParticles &particles_wo,
            const mat4 &head_to_world_rest, const WindParams &wind = WindParams());

  /* Advances one frame of `frame_dt` seconds to the head transform `head_to_world` (the
   * head's motion is interpolated over the substeps). False, with failure() set, when the
   * frame was refused or diverged; a failed solver does not step again until reset(). */
  bool step(float frame_dt, const mat4 &head_to_world);
  /* Why the last step failed (a sentence for the user), empty when it did not. */
  const std::string &failure() const { return failure_; }

  /* The substeps a frame of `frame_dt` needs from the current state, and which bound sets
   * them (for the add-on to warn before a bake). */
  struct SubstepEstimate {
    int count = 1;
    std::string reason;
  };
  SubstepEstimate estimate_substeps(float frame_dt) const;
  /* Back to the rest state and the rest head transform; the wind starts over. */
  void reset();
  /* The body the hair collides with (§3.5, lcp/body_collision_bando2003.hh; an empty query
   * turns collisions off). Rest particles inside it (a beam-shaped initial
   * hair ignores the body) are first moved onto its surface, spaced out again and connected
   * again, so the simulation starts from a state the contact response will not tear apart;
   * then reset(). */
  void set_body_contact(ContactQuery query);
  /* The same with the scene's colliders (ColliderSet::find_contact), or none for nullptr. The
   * set must outlive the solver or the next call. */
  void set_colliders(const ColliderSet *colliders);

  const LcpParams &params() const { return params_; }
  /* The wind (core/wind.hh): the free-stream velocity of the air particles. */
  const WindParams &wind() const { return wind_params_; }
  void set_wind(const WindParams &wind);
  int64_t particles_num() const { return int64_t(x_head_.size()); }
  int64_t pairs_num() const { return connections_.size(); }
  /* Pairs of particles closer than h₂/2 (see count_close_pairs), after the last step. */
  int64_t interpenetrating_pairs_num() const { return interpenetrating_pairs_num_; }
  /* Substeps of the last frame: params.substeps, or more when the springs need them. */
  int substeps_used() const { return substeps_used_; }
  /* Neighbour searches since the solver was made. */
  int64_t neighbor_searches() const { return neighbors_.builds(); }
  /* Conjugate-gradient iterations of the implicit springs over the last frame, and their
   * matrix products (the iterations' and the first guesses'). */
  int spring_iterations() const { return spring_iterations_; }
  int spring_products() const { return spring_products_; }

  /* World space, after the last step. */
  Span<vec3> positions() const { return positions_wo_; }
  Span<vec3> directions() const { return directions_wo_; }
  Span<vec3> velocities() const { return velocities_wo_; }
  Span<float> density() const { return density_; }
  Span<float> u() const { return u_; }
  Span<float> v() const { return v_; }
  Span<float> s() const { return s_; }
  Span<uint8_t> is_root() const { return is_root_; }
  /* Particles held by the head: the roots and those particles_wo.fixed marks. */
  Span<uint8_t> is_fixed() const { return is_fixed_; }
  float particle_mass() const { return mass_; }

  /* Air particles of the wind (world space). */
  Span<vec3> air_positions() const { return air_x_wo_; }
  Span<vec3> air_velocities() const { return air_v_wo_; }

  /* Internals for tests: the connections and the current α_ij k_ij. */
  const LcpConnections &connections() const { return connections_; }
  Span<float> alpha_k() const { return alpha_k_; }
  Span<float> cross_sections() const { return cross_sections_; }
  /* The root particle each particle is tethered to (itself for a root) and the tether's
   * length: the most its distance to that root can be. */
  /* The head frame's fictitious acceleration on particle i in its current state (head
   * components): −Rᵀ a_rel(x, v_rel) of core/head_motion.hh with the head's motion of the last
   * substep. The integrator applies exactly this: the transport part as it is, the Coriolis
   * part −2 ω × v as the exact rotation of v whose rate it is. */
  vec3 fictitious_acceleration(int64_t i) const;
  Span<int32_t> tether_anchors() const { return anchor_; }
  Span<float> tether_lengths() const { return tether_length_; }

 private:
  struct HeadState {
    mat3 rotation{ 1.0f }; /* Head to world, at the time the quantity applies. */
    vec3 translation{ 0.0f };
    vec3 velocity_wo{ 0.0f };      /* Of the head frame's origin. */
    vec3 omega_head{ 0.0f };       /* Angular velocity, head components. */
    HeadAcceleration acceleration; /* World; its center is `translation`. */
  };
  /* −Rᵀ of the transport acceleration at particle i's position x (head components). */
  static vec3 transport_head(const HeadState &head, const vec3 &x);
  /* Rest particles are spaced at least this far apart (separate_close_particles): above the
   * h₂/2 of count_close_pairs, so the rest state has no interpenetrating pair. */
  float rest_min_distance() const { return 0.6f * params_.h2; }
  /* The neighbour list's skin: it is found again once a particle has moved h₂ / 8. */
  float neighbor_skin() const { return 0.25f * params_.h2; }
  void substep(float dt, const HeadState &mid, const HeadState &end);
  void accumulate_wind(float dt, const HeadState &mid);
  bool has_wind() const
  {
    return wind_params_.speed > 0.0f && glm::length(wind_params_.direction) > 0.0f;
  }
  /* m/s, the wind's fastest: its speed with the turbulence on top. */
  float fastest_wind() const { return wind_params_.speed * (1.0f + wind_params_.turbulence); }
  /* s: the air particles of the wind (§3.5) cross at most their SPH support 2h a substep, so
   * that none skips the hair it passes through (explicit SPH air, hair-air drag); infinite
   * without wind. */
  float wind_time_step() const;
  void collide_with_body(const HeadState &end);
  void update_world_outputs(const HeadState &head);
  void count_interpenetrations();
  void build_tethers();
  void enforce_tethers();
  /* Sets failure_ if a particle's state is not finite or has run away from its tether. */
  void check_divergence(int frame_substep);

  LcpParams params_;
  HeadPose head_rest_;
  /* Rest state, head frame. */
  std::vector<vec3> x_rest_head_, t_rest_head_;
  std::vector<float> u_, v_, s_;
  std::vector<uint8_t> is_root_;
  std::vector<uint8_t> is_fixed_; /* is_root_, or held by the head (a pin's particle) */
  float mass_ = 0.0f;
  std::vector<float> masses_, cross_sections_;
  LcpConnections connections_;
  std::vector<int32_t> anchor_;
  std::vector<float> tether_length_;

  /* State, head frame. */
  std::vector<vec3> x_head_, v_head_, t_head_;
  HeadPose head_;
  HeadVelocity head_velocity_;
  HeadState last_head_; /* Of the last substep's middle. */

  /* Per step buffers. The hair's neighbours within 2h₂ (head frame). */
  VerletNeighbors neighbors_;
  std::vector<float> density_, k_, alpha_k_, side_sums_, damping_;
  int substeps_used_ = 0, spring_iterations_ = 0, spring_products_ = 0;
  ImplicitSprings implicit_springs_;
  /* The implicit solve's coarse factor is rebuilt every coarse_factor_frames frames. */
  static constexpr int coarse_factor_frames = 4;
  int frames_since_coarse_factor_ = coarse_factor_frames;
  DensityJacobian pressure_jacobian_; /* eq. 16's stiffness, when implicit */
  std::vector<vec3> forces_, damped_forces_;
  std::vector<vec3> x_start_;     /* positions at the substep's start */
  std::vector<uint8_t> tethered_; /* moved back onto their tether this substep */

  /* Wind. */
  WindParams wind_params_;
  WindField wind_;
  float time_ = 0.0f; /* s, simulated since reset (the wind's clock). */
  WindBox wind_box_;
  std::vector<vec3> air_x_wo_, air_v_wo_, air_forces_, air_damped_forces_;
  std::vector<float> air_density_, air_damping_, air_volumes_;
  std::vector<vec3> hair_x_wo_, hair_v_wo_, hair_drag_wo_;
  std::vector<float> hair_drag_damping_;
  SpatialGrid air_grid_, hair_grid_wo_;
  NeighborList air_neighbors_, hair_to_air_, air_to_hair_;

  ContactQuery contact_query_;

  /* Outputs. */
  std::vector<vec3> positions_wo_, directions_wo_, velocities_wo_;
  int64_t interpenetrating_pairs_num_ = 0;
  std::string failure_;
};

}  // namespace hairdyn
