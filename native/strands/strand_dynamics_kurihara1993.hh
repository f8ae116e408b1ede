#pragma once
/* Strand dynamics of Kurihara, Anjyo and Thalmann 1993 (§2): each strand is a chain of rigid
 * segments of fixed length whose shape is the angles between them; the angles obey
 *
 *   I θ̈ + γ θ̇ = M,   I φ̈ + γ φ̇ = M                      (Kurihara 1993, eq. 1)
 *
 * with hinge springs toward the rest angles (eq. 4) and external torques from gravity, wind and
 * the head's acceleration (eq. 5–6), solved segment by segment from root to tip. Integration is
 * explicit (eq. 7) or implicit backward Euler (Ward & Lin 2003, appendix A).
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
 * the springs of eq. 4 are −k θ and −k φ.
 *
 * Positions are rebuilt from the angles root to tip, so no segment ever changes length.
 *
 * Data is a struct of arrays over points (Blender's layout): per-segment quantities are
 * stored at the segment's tip point; a strand's root slot holds nothing. */
#include <vector>

#include "collision/collider.hh"
#include "collision/reaction_constraint_kurihara1993.hh"
#include "core/math.hh"
#include "core/span.hh"
#include "strands/head_motion.hh"
#include "strands/hinge_integration.hh"
#include "strands/strand_params.hh"

namespace hairdyn {

using glm::vec2;

/* The wind as a field of air velocity: a uniform mean plus smooth turbulence that travels
 * with it (deterministic for a seed). */
class WindField {
 public:
  WindField() = default;
  explicit WindField(const StrandParams &params);
  /* m/s, the air's velocity at world point p and time t. */
  vec3 velocity_at(const vec3 &p, float time) const;

 private:
  static constexpr int waves_num = 2; /* Sine waves per component of the turbulence. */
  vec3 mean_ = vec3(0.0f);
  float turbulence_ = 0.0f; /* m/s, amplitude of each component. */
  vec3 wave_vectors_[3][waves_num] = {};
  float angular_frequencies_[3][waves_num] = {};
  float phases_[3][waves_num] = {};
};

/* The external force per length on a strand element (Kurihara 1993, eq. 6) during one
 * substep: gravity and the head's inertial force, an affine function of position, plus the
 * air's drag toward the wind's velocity. */
struct ForceField {
  vec3 base = vec3(0.0f);      /* N/m */
  mat3 gradient = mat3(0.0f);  /* N/m², from the head's turning */
  float air_drag = 0.0f;       /* N·s/m², c_air */

  ForceField() = default;
  ForceField(const StrandParams &params, const HeadAcceleration &head);

  /* N, the force on a segment of length d whose centre is at r, moving at v. */
  vec3 on_segment(const float d, const vec3 &r, const vec3 &v, const vec3 &wind) const
  {
    return d * (base + gradient * r + air_drag * (wind - v));
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
  ForceField forces;
};

class StrandSolver {
 public:
  /* `head_to_world_rest` is the head's object-to-world matrix when the groom had
   * `rest_positions_wo`. `root_normals_wo` holds one unit normal per strand, or is empty: then
   * each strand's rest first segment gives its root normal. The groom must pass
   * find_groom_error. */
  StrandSolver(Span<int32_t> curve_offsets, Span<vec3> rest_positions_wo,
               const mat4 &head_to_world_rest, Span<vec3> root_normals_wo,
               const StrandParams &params);

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
  /* Hair–object collision (Kurihara 1993 §3; Ward & Lin 2003 §5.5): every node's force passes
   * the reaction constraint where the node is inside a collider, and no node ends a substep
   * deeper than params.projection_tolerance × the colliders' size. The colliders are the
   * caller's and must stay alive while the solver steps; nullptr turns collision off. */
  void set_colliders(const ColliderSet *colliders, const CollisionParams &params);
  /* Nodes whose force the reaction constraint changed, and nodes put back on the surface,
   * during the last step (all substeps). */
  int64_t contacts_num() const { return contacts_num_; }
  int64_t projections_num() const { return projections_num_; }

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
  /* kg·m², I = c d³ / 3 of the segment ending at `point` (Kurihara 1993, eq. 2). */
  float moment_of_inertia(int64_t point) const;
  /* m, the fixed length of the segment ending at `point`. */
  float segment_length(int64_t point) const { return rest_lengths_[size_t(point)]; }

 private:
  /* Zero angles and rates, the head at `pose` and still. */
  void reset_dynamics(const HeadPose &pose);
  /* The integrator's coefficients of each segment for substeps of length h. */
  void prepare_hinges(IndexRange points, float h);
  /* Steps one strand through the substeps; returns (contacts, projections). */
  std::pair<int64_t, int64_t> step_strand(int64_t curve, Span<Substep> substeps);

  StrandParams params_;
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
  std::vector<HingeStep<vec2>> hinge_steps_; /* the integrator's coefficients this frame */
  std::vector<vec4> trig_; /* (sin θ, cos θ, sin φ, cos φ) of the angles, within a step */

  /* Per point. */
  std::vector<vec3> positions_wo_;
  std::vector<vec3> velocities_wo_;

  /* Collision: the caller's colliders (or nullptr) and what the last step did with them. */
  const ColliderSet *colliders_ = nullptr;
  CollisionParams collision_params_;
  int64_t contacts_num_ = 0;
  int64_t projections_num_ = 0;

  /* The head at the end of the last step, and its velocity over that step. */
  HeadPose rest_pose_;
  HeadPose pose_;
  HeadVelocity head_velocity_;
  float time_ = 0.0f;
};

}  // namespace hairdyn
