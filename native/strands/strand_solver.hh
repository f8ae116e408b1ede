#pragma once
/* The strand solver: strands as chains of rigid segments whose shape is the two hinge angles
 * of each segment in its parent's frame (Kurihara, Anjyo and Thalmann 1993, §2). Segments
 * never stretch; the root is carried by the head. One solver, two models of the per-strand
 * dynamics (StrandModel): Kurihara 1993's per-hinge equations (strand_dynamics_kurihara1993.cpp)
 * and the articulated chain (strand_dynamics_articulated.cpp). Everything else is shared:
 * external forces, collision, passes, divergence checks.
 *
 * Each substep every strand advances, then the registered SubstepPass list runs over the node
 * positions and velocities (substep_pass.hh), then the solver takes the corrected nodes back
 * into its angles and rates root to tip (lengths kept, roots kinematic).
 *
 * Pinned points (groom/pins.hh, set_pinned) are kinematic too: after the passes of every
 * substep each pin goes to its rest position carried by the head, the chain between it and the
 * root (or the pin before) reaches it with lengths kept, the points between take the move as
 * velocity, the pin takes the head's velocity there, and the same take-back turns it all into
 * angles and rates; the points beyond a pin swing after it.
 *
 * Coordinates. Segment i's frame F_i has z along the segment. At rest, F_0 is the root frame
 * (root normal + a deterministic tangent) and F_i is F_{i-1} transported without twist onto
 * segment i; the fixed rotation R_i = F_{i-1}ᵀ F_i at rest encodes the groom's rest shape
 * (curls included). Moving, F_i = F_{i-1} R_i D(θ_i, φ_i), where the deflection D turns the
 * segment out of its rest direction: in the rest frame (x, y, z) the segment points along
 *
 *   d = (sin θ, cos θ sin φ, cos θ cos φ),
 *
 * i.e. θ and φ are the polar angles of d in the parent's frame measured from the rest
 * direction, with the chart's pole placed on x, a quarter turn away from the rest direction.
 * Kurihara puts the pole on the parent segment, where every straight strand sits and the
 * azimuth is undefined; placing it a quarter turn from rest keeps both angles regular (metric
 * factor cos²θ ≈ 1) around any rest shape. Both angles are stored as offsets from rest, so
 * the hinge springs (Kurihara 1993, eq. 4) are −k θ and −k φ. D = R_x(−φ) R_y(θ): the hinge
 * turns the segment about e_φ at rate θ̇ and about the chart's −x at rate φ̇.
 *
 * Data is a struct of arrays over points (Blender's layout): per-segment quantities are
 * stored at the segment's tip point; a strand's root slot holds nothing. */
#include <string>
#include <utility>
#include <vector>

#include "collision/collider.hh"
#include "collision/reaction_constraint_kurihara1993.hh"
#include "core/cpu.hh"
#include "core/head_motion.hh"
#include "core/math.hh"
#include "core/span.hh"
#include "core/wind.hh"
#include "strands/hinge_integration.hh"
#include "strands/strand_params.hh"
#include "strands/substep_pass.hh"

namespace hairdyn {

using glm::vec2;

/* The external force per length on a strand element during one substep (Kurihara 1993,
 * eq. 6): gravity, the head's fictitious force −c a_rel(r, v_rel) (transport and Coriolis,
 * core/head_motion.hh) and air drag toward the wind: linear, c_air (v_wind − v), and form
 * drag, q |v_wind − v| (v_wind − v). All but the form drag are affine in the element's
 * position r and velocity v: F / length = base + G r + V v + c_air v_wind + form drag. */
struct ForceField {
  vec3 base = vec3(0.0f);             /* N/m */
  mat3 position_gradient = mat3(0.0f); /* G, N/m² */
  mat3 velocity_gradient = mat3(0.0f); /* V, N·s/m² */
  float air_drag = 0.0f;              /* c_air, N·s/m² */
  float form_drag = 0.0f;             /* ½ ρ_air C_d 2r, kg/m² */
  float mass_per_length = 0.0f;       /* c, kg/m */

  ForceField() = default;
  ForceField(const StrandParams &params, float line_density, const HeadAcceleration &head,
             const HeadVelocity &head_velocity);

  /* N, the force on a segment of length d whose centre is at r, moving at v, over a step of
   * h. The form drag is explicit; it is limited to what it can do over the step, q |u|² / (1 +
   * h q |u| / c) (linearly implicit in the speed |u| relative to the air), so it slows a
   * segment down and never turns it around, whatever the step. h = 0: the drag itself, for a
   * step that takes its stiffness into the inertia instead (drag_stiffness). S and V: float
   * and vec3, or several segments in lanes (strands/chain_lanes.hh). */
  template<class S, class V>
  V on_segment(const S &d, const V &r, const V &v, const V &wind, const S &h) const
  {
    const V relative = wind - v;
    const S drag = limited(form_drag * length(relative), h);
    return d * (base + position_gradient * r + velocity_gradient * v + air_drag * wind +
                drag * relative);
  }

  /* m/s: the speed of the air past a rod of length d whose centre moves at v and which turns
   * at `spin` across its axis (relative to the air): |v_wind − v| + |spin| d / √12, the speed
   * at its centre plus its spin's RMS speed along it (at most √2 times the RMS of the two). */
  template<class S, class V>
  [[gnu::always_inline]] S rod_air_speed(const S &d, const V &v, const V &wind,
                                         const V &spin) const
  {
    return length(wind - v) + length(spin) * (d * 0.28867513f);
  }

  /* N·m, beside on_segment's force at the centre: the couple the drag puts on a rod of length
   * d turning at `spin` across its axis, −(c_air + q ū) d³ / 12 spin, ū its rod_air_speed.
   * For the linear drag it is exact (∫ s t × (−c_air spin × s t) ds over the rod); the form
   * drag is taken at ū everywhere along the rod (a rod spinning in still air: q |spin| d⁴ / 32
   * exactly, 0.77 times that here). A force at the centre alone leaves a segment that turns
   * about its centre undamped: the chain's zigzag modes, which a gale fed until the strand
   * ran away. Limited over a step of h as on_segment's form drag. */
  template<class S, class V>
  [[gnu::always_inline]] V drag_couple(const S &d, const V &spin, const S &air_speed,
                                       const S &h) const
  {
    return (-(d * d * d) * (1.0f / 12.0f)) * (air_drag + limited(form_drag * air_speed, h)) *
           spin;
  }

  /* kg/m/s, per length: a bound of the rate at which the drag's force changes with the
   * element's velocity, ‖∂(c_air u + q |u| u) / ∂v‖ = c_air + 2 q |u| (u = v_wind − v, the
   * form drag's q (|u| 1 + u uᵀ / |u|) having 2 q |u| along u), at the rod's air speed
   * (rod_air_speed ≥ |u|, which covers the couple's too). A linearly implicit step adds h
   * times this to the element's mass in its inertia (the articulated model's implicit
   * integrator). */
  template<class S> [[gnu::always_inline]] S drag_stiffness(const S &air_speed) const
  {
    return air_drag + 2.0f * form_drag * air_speed;
  }

 private:
  /* A drag rate (kg/m/s) limited to what it can do over a step of h: rate / (1 + h rate / c).
   * h = 0: the rate itself. */
  template<class S> [[gnu::always_inline]] S limited(const S &rate, const S &h) const
  {
    return mass_per_length > 0.0f ? rate * mass_per_length / (mass_per_length + h * rate) :
                                    rate;
  }
};

/* What every strand needs to know about one substep. */
struct Substep {
  float h = 0.0f;    /* s, the substep's length */
  ReactionConstants reaction; /* the collision response's constants for this h */
  float projection_tolerance_wo = 0.0f; /* m, deepest a node may end the substep */
  float time = 0.0f; /* s, simulated time at its end (for the wind) */
  HeadPose pose;     /* the head at its end */
  mat3 rotation = mat3(1.0f);
  HeadVelocity head_velocity; /* the head's velocity over the frame */
  ForceField forces;
};

/* The vector code the articulated model's step runs: by default the widest the CPU has.
 * A narrower one may be set (a wider one is clamped to the CPU's), for the test that all give
 * the same bits; not to be changed while a step runs. */
VectorCode articulated_vector_code();
void set_articulated_vector_code(VectorCode code);

class StrandSolver {
 public:
  /* `head_to_world_rest` is the head's object-to-world matrix when the groom had
   * `rest_positions_wo`. `root_normals_wo` holds one unit normal per strand, or is empty: then
   * each strand's rest first segment gives its root normal. The groom must pass
   * find_groom_error. */
  /* Far from the world origin single precision cannot resolve a strand (at x = 1e8 m a float
   * steps by 8 m), so every position and transform the solver takes or gives (rest
   * positions, head matrices, colliders, passes, outputs) is relative to `origin_wo`, a point
   * near the character chosen by the caller in double precision (the head's rest position):
   * the simulation runs in head-relative coordinates wherever the character stands, and
   * world = origin_wo + position. */
  StrandSolver(Span<int32_t> curve_offsets, Span<vec3> rest_positions_wo,
               const mat4 &head_to_world_rest, Span<vec3> root_normals_wo,
               const StrandParams &params, const WindParams &wind = WindParams(),
               const glm::dvec3 &origin_wo = glm::dvec3(0.0));

  /* Advances one frame of `frame_dt` seconds in params().substeps substeps, the head moving
   * from its previous transform to `head_to_world`. */
  void step(float frame_dt, const mat4 &head_to_world);
  /* Back to the rest shape, at rest, with the head at its rest transform. */
  void reset();
  /* The rest shape carried rigidly by the head at `head_to_world`, at rest: the start of a
   * bake whose first frame has the head elsewhere. */
  void reset(const mat4 &head_to_world);

  const StrandParams &params() const { return params_; }
  void set_params(const StrandParams &params);
  const WindParams &wind() const { return wind_params_; }
  void set_wind(const WindParams &wind);
  /* Hair–object collision (Kurihara 1993 §3; Ward & Lin 2003 §5.5): every node's force passes
   * the reaction constraint where the node is inside a collider, and no node ends a substep
   * deeper than params.projection_tolerance × the colliders' size. The colliders are the
   * caller's and must stay alive while the solver steps; nullptr turns collision off. */
  void set_colliders(const ColliderSet *colliders, const CollisionParams &params);
  /* Passes run in order after every substep (substep_pass.hh). The passes are the caller's
   * and must stay alive while the solver steps. */
  void add_pass(SubstepPass *pass);
  /* Marks points kinematic like the roots (TressFX's immovable vertices): per point, non-zero
   * for pinned; roots are pinned whatever the mask says; an empty span pins only the roots.
   * Each pin is held on its rest position carried by the head from the next substep on. */
  void set_pinned(Span<uint8_t> pinned);
  /* Per point, 1 where set_pinned pinned a point after a root (0 everywhere before any). */
  Span<uint8_t> pinned() const { return pinned_; }
  /* Points pinned after the roots. */
  int64_t pins_num() const { return int64_t(pins_.size()); }
  void clear_passes();
  Span<SubstepPass *> passes() const { return passes_; }
  /* What the passes see of each strand's swept-sphere volume (SubstepState): per point, each
   * array empty or one per point. */
  void set_pass_volumes(PassVolumes volumes);
  /* Milliseconds the pass named `name` took during the last step (all substeps); 0 for a
   * name no pass has. */
  double pass_ms(const std::string &name) const;

  /* Steps only some strands: per strand, non-zero for the strands the next steps advance;
   * an empty span (the default) advances every strand, bit for bit as without a mask.
   * `in_passes`, when given, narrows what the substep passes see to the stepped strands it
   * marks (level of detail keeps a skeleton it steps only to measure a switch out of hair–hair
   * collision with the one that replaced it); empty: every stepped strand.
   *
   * A strand left out is held, not simulated: its angles and rates stay as they are, i.e. it
   * keeps its shape relative to its root frame, which the head carries; nothing of it is
   * integrated, collided or counted (the passes do not see it), and its nodes, velocities and
   * root frame stay where its last step (or place_curve) left them, however far the head
   * has moved since. Before it is stepped again, place_curve puts it where the head is now
   * on whatever angles and rates it then has (a state written through angles_for_write), so
   * its first substep sees no jump of its root and its velocities come from its rates: a
   * strand kept out for a long time resumes as one whose state was just written. (A strand
   * that was stepped by the last step and whose state nobody wrote since needs no
   * place_curve: its nodes are where the head and its angles put them.) */
  void set_stepped(Span<uint8_t> stepped, Span<uint8_t> in_passes = {});
  /* Per strand, the mask set_stepped keeps (empty: every strand is stepped). */
  Span<uint8_t> stepped() const { return stepped_; }
  /* Strands the last step advanced. */
  int64_t stepped_num() const { return stepped_num_; }
  /* Strand `curve`'s nodes, root frame and velocities from its angles and rates, with the
   * head where the last step left it (its pose and velocity): the root and root frame carried
   * by the head, each segment at its angles in its parent's frame (as the dynamics place it),
   * each node moving with the head plus the turns its hinges' rates make. The way to make a
   * state written through angles_for_write and angular_velocities_for_write the strand's
   * state now, not only from the next step. */
  void place_curve(int64_t curve);
  /* Writes strand `curve`'s angles and rates (one per point of the strand; the root slot is
   * ignored) and places it (place_curve). */
  void set_curve_state(int64_t curve, Span<vec2> angles, Span<vec2> angular_velocities);

  /* Nodes whose force the reaction constraint changed, and nodes put back on the surface,
   * during the last step (all substeps). */
  int64_t contacts_num() const { return contacts_num_; }
  int64_t projections_num() const { return projections_num_; }
  /* Strands whose state became non-finite or ran away (a node faster than
   * runaway_speed) during the last step. Such a strand is put back on its rest shape carried
   * by the head, so no NaN ever leaves the solver; the caller should fail the frame. */
  int64_t diverged_num() const { return diverged_num_; }
  static constexpr float runaway_speed = 1000.0f; /* m/s: no hair moves this fast. */
  /* Whether hinge rates `omega` (rad/s) swing a segment of length d faster than runaway_speed,
   * or are not numbers: both strand models stop such a strand before it reaches a collider. */
  static bool hinge_runs_away(const vec2 &omega, const float d)
  {
    return !((std::abs(omega.x) + std::abs(omega.y)) * d < runaway_speed);
  }
  /* A pin is reached to this share of the length of strand before it (3 µm on a 0.3 m
   * strand, far under what shows), within pin_iterations Newton steps (groom/pins.hh). */
  static constexpr float pin_tolerance_relative = 1e-5f;
  /* rad: the most an articulated segment may turn (or turn against its parent) in one step
   * of its explicit velocity products; a faster strand takes up to max_turn_steps shorter
   * steps in a substep. 0.1 while they were taken at the step's start; at mid-step (second
   * order) 0.3 keeps every test and the soak (a third of the steps: BM_StrandStep's
   * articulated frame 697 -> 320 ms on one core). */
  static constexpr float max_turn_per_step = 0.3f;
  /* rad: the most the chain's tension-stiffened zigzag mode may advance its phase in one step
   * of the articulated model's explicit integrator, ω h (strand_dynamics_articulated.cpp, at
   * the top; semi-implicit Euler keeps the mode bounded below 2). A strand whose mode is
   * faster cuts its steps as one that turns fast does, the mode's ω counting as a turn rate of
   * ω wave_turn_scale. */
  static constexpr float max_wave_phase = 2.0f;
  static constexpr float wave_turn_scale = max_turn_per_step / max_wave_phase;
  /* rad: the implicit integrator takes the tension's stiffness explicitly up to the zigzag
   * mode's ω h of this (each rod's, from its inertia about its centre), and the rest linearly
   * implicit (no step is cut for it). The same stiffness holds a strand's slow swing, so the
   * implicit share damps that too: a 30 cm strand hanging in no air, released swinging, keeps
   * 53–62% of its amplitude after 2 s at four substeps of 24 fps (97% with 1.4 or more here,
   * or with the cut steps); with the default air drag, 6% either way, the same to 0.1%. Of
   * 1.8, 1.4, 1, 0.5, 0.25 and 0.1, 0.25 held the most winds on 30 cm strands of 8, 16 and 32
   * segments caught from rest (10, 20, 25, 30, 40, 50, 60 and 100 m/s, steady and turbulent:
   * 7 of 48 ran a strand away, as many as with the cut steps but not the same 7; 13 with 1.8);
   * the strands' motion in turbulent wind was the same within 1% (mean node speed) on all. */
  static constexpr float explicit_wave_phase = 0.25f;
  /* rad: the most of a contact projection's turn that the projected segment's child takes back
   * in its hinge, keeping its direction (articulated model; the rest it turns with the
   * segment). A strand resting on a body is projected by small turns, 99% of them under
   * 0.15 rad in the soak of StrandsRobustness. A segment pushed out of a body it lies deep in
   * (Sintel's strands along the bust) turns 0.3–1 rad; its child's stiff spring took that
   * back as energy from nowhere, and 4 to 33 of the 9,120 strands of the bust scene ran away
   * each frame (none over 24 frames with the cap, which also runs 3× faster: test
   * NoStrandRunsAwayAlongSintelsBust). */
  static constexpr float max_kept_turn = 0.2f;
  static constexpr int max_turn_steps = 1024;

  const glm::dvec3 &origin() const { return origin_wo_; }
  /* m, the shortest segment of the groom (what single precision must resolve). */
  float shortest_segment() const { return shortest_segment_; }

  int64_t curves_num() const { return int64_t(curve_offsets_.size()) - 1; }
  Span<int32_t> curve_offsets() const { return curve_offsets_; }
  Span<vec3> rest_positions() const { return rest_positions_wo_; }
  /* World-space positions and velocities (m/s) at the end of the last step. */
  Span<vec3> positions() const { return positions_wo_; }
  Span<vec3> velocities() const { return velocities_wo_; }
  /* Each strand's current root frame in world space: columns tangent, bitangent, normal. */
  Span<mat3> root_frames() const { return root_frames_wo_; }
  /* Per segment, at its tip point: (θ, φ) offsets from rest (rad) and their rates (rad/s).
   * Writing them sets the state; positions follow at the next step. */
  Span<vec2> angles() const { return angles_; }
  Span<vec2> angular_velocities() const { return angular_velocities_; }
  MutableSpan<vec2> angles_for_write() { return angles_; }
  MutableSpan<vec2> angular_velocities_for_write() { return angular_velocities_; }
  /* kg/m, c: the material's (articulated) or params.line_density (kurihara1993). */
  float line_density() const
  {
    return params_.model == StrandModel::Articulated ? float(params_.material_line_density()) :
                                                      params_.line_density;
  }
  /* N·m/rad, the articulated model's hinge spring at `point` after the last step: EI over
   * the length of strand the hinge stands for (half of each neighbouring segment; half the
   * first segment at the clamped root). */
  float hinge_stiffness(int64_t point) const { return hinge_stiffness_[size_t(point)]; }
  /* kg·m², I = c d³ / 3 of the segment ending at `point` (Kurihara 1993, eq. 2). */
  float moment_of_inertia(int64_t point) const;
  /* m, the fixed length of the segment ending at `point`. */
  float segment_length(int64_t point) const { return rest_lengths_[size_t(point)]; }

 /* What pass 1 of the articulated step hands its recursion for a segment, for the strands of
   * a group, W at once (strand_dynamics_articulated.cpp). */
  template<int W> struct ArticulatedTerms;

 private:
  struct Counts {
    int64_t contacts = 0;
    int64_t projections = 0;
    int64_t diverged = 0;
  };

  /* Zero angles and rates, the head at `pose` and still. */
  void reset_dynamics(const HeadPose &pose);
  /* Strand `curve` on its rest shape carried by the head at `pose`, at rest. */
  void place_at_rest(int64_t curve, const HeadPose &pose);
  /* Per-strand coefficients that stay fixed over one step of substeps of length h. */
  void prepare_strand(int64_t curve, float h);
  /* The articulated model's hinge stiffnesses from the params and the rest lengths. */
  void update_hinge_stiffness();
  /* Strand `curve`'s root and root frame (r_frame) carried by the head to the end of the
   * substep; returns the wind at the root. */
  vec3 place_root(int64_t curve, const Substep &substep, mat3 &r_frame);
  /* One substep of each of `curves` (at most group_strands_max, one point count: a group of
   * group_strands): the roots carried by the head, then the model's dynamics. r_finite[k] = 0
   * where strand k diverged (it is then counted and put back at rest). */
  void advance_strands(Span<int64_t> curves, const Substep &substep, Counts &counts,
                       MutableSpan<uint8_t> r_finite);
  /* The stepped strands in groups of one point count, up to group_strands_max each
   * (groups_). */
  void group_strands();
  /* Hinge i's step (hinge_steps_[i]) with the stiffness of the pull `force` along t and
   * phi_pull that explicit steps of h cannot hold taken implicitly (implicit integrator;
   * strand_dynamics_kurihara1993.cpp). */
  HingeStep<vec2> pulled_hinge_step(size_t i, float h, const vec2 &k, const vec3 &force,
                                    const vec3 &t, const vec3 &phi_pull) const;
  /* Kurihara 1993 §2: each hinge alone (strand_dynamics_kurihara1993.cpp). */
  bool advance_kurihara(IndexRange points, const Substep &substep, mat3 frame,
                        vec3 node_velocity, const vec3 &wind_wo, Counts &counts);
  /* False when a node of the strand is not finite or faster than runaway_speed. */
  bool strand_is_sane(int64_t curve) const;
  /* The articulated chain (strand_dynamics_articulated.cpp): one substep of up to
   * group_strands_max strands of one point count, their roots placed (root_frames, winds),
   * each cut into shorter steps while it turns fast (see articulated_step); the strands
   * stepping W at a time (the vector code's lanes), their double-precision recursions in one
   * vector. r_finite[k] = 0 where strand k ran away (the caller puts it at rest). */
  void advance_articulated(Span<int64_t> curves, const Substep &substep, Span<mat3> root_frames,
                           Span<vec3> winds, Counts &counts, MutableSpan<uint8_t> r_finite);
  /* advance_articulated compiled for one vector code (articulated_vector_code()), the whole
   * substep inlined into it: articulated_substep with the code's lane width W, then
   * articulated_step and its passes. */
  template<VectorCode code>
  void advance_articulated_as(Span<int64_t> curves, const Substep &substep,
                              Span<mat3> root_frames, Span<vec3> winds, Counts &counts,
                              MutableSpan<uint8_t> r_finite);
  template<int W>
  void articulated_substep(Span<int64_t> curves, const Substep &substep, Span<mat3> root_frames,
                           Span<vec3> winds, Counts &counts, MutableSpan<uint8_t> r_finite);
  /* One step of step_lengths[k] within `substep` for each of `curves` (one point count, up to
   * W).
   * r_outcomes[k]: 1 when strand k took it; -1 when it ran away; n > 1 when it may cut its
   * step (may_split[k]) and turns more than max_turn_per_step within it: then it is left
   * unchanged, and n equal steps (at most max_turn_steps) keep every turn within the bound.
   * Each strand's bits are those it has stepped alone. */
  template<int W>
  void articulated_step(Span<int64_t> curves, const Substep &substep, Span<float> step_lengths,
                        Span<uint8_t> may_split, Span<mat3> root_frames, Span<vec3> winds,
                        Counts &counts, MutableSpan<int> r_outcomes);
  /* Whether strand `curve`'s next step needs a predictor stage: the q̈ of its last two steps
   * are not both known (strand_dynamics_articulated.cpp). */
  bool needs_predictor(const int64_t curve) const
  {
    return accelerations_known_[size_t(curve)] < 2;
  }
  /* The q̈ that the mid-step rates of strand `curve`'s next step take: the last two steps'
   * extrapolated, or zeros (a predictor stage's) when they are not both known. */
  void mid_step_accelerations(int64_t curve, MutableSpan<vec2> r_accelerations) const;
  /* Pass 1 of an articulated step, root to tip, for W strands of one point count at once,
   * one lane each (a lane may repeat another's strand): the shape, the rates at the
   * middle of the step (q̇ + h q̈ / 2 with q̈ = mid_accelerations[lane]), the velocity
   * products, the external forces but the colliders' (their reaction constraint is added
   * from the tips it leaves in `terms`: add_contact_forces) and the hinges, into `terms` (one
   * per segment). Writes each lane's fastest turn (rad/s) of a segment or across a hinge. */
  template<int W>
  void articulated_forward(Span<int64_t> curves, const Substep &substep,
                           const float *step_lengths, Span<mat3> root_frames,
                           Span<vec3> winds, Span<const vec2 *> mid_accelerations,
                           ArticulatedTerms<W> *terms, float *r_fastest_turn) const;
  /* For the lanes `committed` of W strands (a lane may repeat another's strand), the step's
   * hinge accelerations (the recursion's, in the lane scratch) into rates and angles, then the
   * new shapes from pass 1's `terms` (rest rotations and lengths), W at once, with each lane's
   * no-penetration projection; each lane's projected segments are left in a list whose
   * impulses the caller applies. r_outcomes[lane] = -1 where the strand ran away. */
  template<int W>
  void articulated_commit(Span<int64_t> curves, const Substep &substep,
                          const float *step_lengths, Span<mat3> root_frames,
                          const ArticulatedTerms<W> *terms, const uint8_t *committed,
                          MutableSpan<int> r_outcomes);
  /* Each pin of the strand to its rest position carried by the head at the end of the
   * substep, the chain before it reaching it (groom/pins.hh), positions and velocities only:
   * take_back_strand turns them into angles and rates. */
  void pin_strand(int64_t curve, const Substep &substep);
  bool has_pins(int64_t curve) const
  {
    return !pin_offsets_.empty() && pin_offsets_[size_t(curve + 1)] > pin_offsets_[size_t(curve)];
  }
  /* Positions and velocities after passes back into angles and rates, root to tip. */
  void take_back_strand(int64_t curve, const Substep &substep);
  /* After the passes of a substep: the strand's pins, the take-back, and the sanity check;
   * false (counted, the strand put at rest) when it diverged. */
  bool settle_strand(int64_t curve, const Substep &substep, Counts &counts);

  /* The force on the segment ending at point i (centre `center` moving at `center_velocity`),
   * filtered by the reaction constraint where its tip (at `tip`, moving at `tip_velocity`) is
   * inside a collider: Kurihara 1993, eq. 6 and 12–15. */
  vec3 segment_force(const Substep &substep, size_t i, const vec3 &center,
                     const vec3 &center_velocity, const vec3 &tip, const vec3 &tip_velocity,
                     const vec3 &wind_wo, Counts &counts) const;
  /* The external `force` on a segment of length d whose tip, moving at tip_velocity, is inside
   * a collider at `contact`, filtered by the reaction constraint (Kurihara 1993, eq. 12–15):
   * the one place both models take it. */
  vec3 contact_force(const vec3 &force, float d, const vec3 &tip_velocity,
                     const Contact &contact, const ReactionConstants &reaction) const;
  /* Ward & Lin 2003 §5.5: when the segment from `node` (chart `chart`, angles `angles`) ends
   * at `tip` deeper than the tolerance inside a collider, it turns about `node` onto the
   * surface and stops turning. Returns true when it moved; r_normal, if given, receives the
   * outward normal of the surface it was turned onto. `contact_at_tip`, if given, is the
   * contact of `tip` the caller found (it is inside a collider). */
  bool project_segment(const Substep &substep, const vec3 &node, vec3 tip, float d,
                       const mat3 &chart, vec2 &angles, vec2 &omega, vec3 *r_normal = nullptr,
                       const Contact *contact_at_tip = nullptr) const;

  StrandParams params_;
  glm::dvec3 origin_wo_;
  float shortest_segment_ = 0.0f;
  WindParams wind_params_;
  WindField wind_;
  std::vector<int32_t> curve_offsets_;
  std::vector<vec3> rest_positions_wo_;

  /* Per strand: the root in the head's frame. */
  std::vector<vec3> root_positions_head_;
  std::vector<mat3> root_frames_head_;
  std::vector<mat3> root_frames_wo_;

  /* Per segment, at its tip point. */
  std::vector<float> rest_lengths_;
  std::vector<mat3> rest_rotations_; /* R_i = F_{i-1}ᵀ F_i at rest */
  std::vector<vec2> angles_;
  std::vector<vec2> angular_velocities_;
  /* rad/s², per hinge: q̈ of the last articulated step and of the one before (the mid-step
   * rates' extrapolation, strand_dynamics_articulated.cpp), and per strand how many of the
   * two are known (none once a state is set or the strand is put at rest). */
  std::vector<vec2> accelerations_, earlier_accelerations_;
  std::vector<uint8_t> accelerations_known_;
  std::vector<HingeStep<vec2>> hinge_steps_; /* the integrator's coefficients this frame */
  std::vector<float> hinge_stiffness_; /* articulated: k = EI / l (update_hinge_stiffness) */
  std::vector<vec4> trig_; /* (sin θ, cos θ, sin φ, cos φ) of the angles, within a step */

  /* Per point. */
  std::vector<vec3> positions_wo_;
  std::vector<vec3> velocities_wo_;

  /* Collision: the caller's colliders (or nullptr) and what the last step did with them. */
  const ColliderSet *colliders_ = nullptr;
  CollisionParams collision_params_;
  int64_t contacts_num_ = 0;
  int64_t projections_num_ = 0;
  int64_t diverged_num_ = 0;

  /* Pinned points after the roots: the mask per point, the pins strand by strand (pins_ from
   * pin_offsets_[c] to pin_offsets_[c + 1], root to tip) and each pin's rest position in the
   * head's frame. */
  std::vector<uint8_t> pinned_;
  std::vector<int64_t> pin_offsets_;
  std::vector<int64_t> pins_;
  std::vector<vec3> pins_rest_head_;

  /* Strands of one point count that advance a substep together, as many at a time as the
   * vector code has lanes (chain_lanes.hh); a group is one chunk of the parallel loop. The
   * more a group holds, the fuller the vectors of its strands that cut their substeps into
   * steps (with 32, 26% of the 8-lane steps of BM_StrandStep were part empty; with 128, 12%);
   * at least 16 groups a thread keep the threads evenly loaded (group_strands). */
  static constexpr int group_strands_min = 32;
  static constexpr int group_strands_max = 128;
  int grouped_for_threads_ = 0; /* the thread count groups_ was made for */
  struct StrandGroup {
    int64_t curves[group_strands_max];
    int64_t size = 0;
  };
  std::vector<StrandGroup> groups_; /* the stepped strands, grouped (group_strands) */

  /* Per strand, the set_stepped mask (empty: all), and the strands the last step advanced. */
  std::vector<uint8_t> stepped_;
  std::vector<int64_t> stepped_curves_; /* the strands the mask keeps, in order */
  int64_t stepped_num_ = 0;

  std::vector<SubstepPass *> passes_;
  std::vector<vec3> positions_before_; /* the nodes before the passes of a substep */
  std::vector<vec3> velocities_before_;
  std::vector<vec3> positions_start_; /* the nodes at the start of a substep (with passes) */
  std::vector<double> pass_ms_;
  PassVolumes pass_volumes_;
  /* What the passes see when some strands are not (set_stepped): those strands' curves in
   * order, their offsets, their nodes gathered before the passes and scattered after, and
   * their volumes, gathered when the view or the volumes change. */
  struct PassView {
    std::vector<int64_t> curves;
    std::vector<int32_t> offsets;
    std::vector<vec3> positions, velocities, start_positions;
    PassVolumes volumes;
  };
  PassView pass_view_;
  bool pass_view_used_ = false;
  void gather_pass_view();
  void gather_view_volumes();
  void scatter_pass_view();

  /* The head at the end of the last step, and its velocity over that step. */
  HeadPose rest_pose_;
  HeadPose pose_;
  HeadVelocity head_velocity_;
  float time_ = 0.0f;
};

}  // namespace hairdyn
