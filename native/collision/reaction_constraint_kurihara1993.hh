#pragma once
/* Collision response by reaction constraint (Kurihara 1993 §3.2, after Platt and Barr 1988),
 * with Coulomb friction as an extension, and the hard no-penetration projection that Ward and
 * Lin 2003 §5.5 apply to hair–object collision.
 *
 * Forces are per unit mass (accelerations): k in 1/s², c in 1/s. Sign convention: N is the
 * outward normal and d = |PT| > 0 the depth, so the spring term of eq. 13, read with PT as the
 * signed offset of P from T along N (-d inside), pushes outwards:
 *   F_constrained = -(k (P - T)·N + c V·N) N = (k d - c V·N) N.
 * The spring and damper are taken at the end of the step dt (backward Euler, the node's depth
 * and normal velocity after the step): (k d - (c + dt k) V·N) / (1 + dt c + dt² k), the
 * paper's value as dt → 0 and stable at any dt (see reaction_constraint_force). The spring
 * acts on the depth beyond rest_depth; within it the surface only stops inward motion, with
 * max(F·N, −V·N / dt); it never pulls.                                                       */
#include "collision/collider.hh"
#include "collision/contact.hh"
#include "core/math.hh"
#include "core/span.hh"

namespace hairdyn {

struct ReactionConstants {
  float stiffness = 1.0e4f; /* k, 1/s². */
  float damping = 0.0f;     /* c, 1/s: use CollisionParams::damping_or_critical() (√(2k)). */
  float friction = 0.0f;    /* μ. */
  float dt = 1.0f / 24.0f;  /* Time step, s: bounds friction so it stops, never reverses, sliding. */
  /* m: a node may rest this deep without the spring pushing it (the projection's tolerance):
   * pushed out to the surface exactly, it fell back in by g dt² every time it left it. */
  float rest_depth = 0.0f;

  static ReactionConstants from(const CollisionParams &params, float dt, float rest_depth = 0.0f);
};

/* The output force for one node in contact (Kurihara 1993, eq. 12–15):
 * when the applied force does not lift the node off the surface (F_input · N < 0), its normal
 * part is replaced by the constraint force (k d - c V·N) N, taken at the end of the step,
 * and its tangential part is kept;
 * otherwise the force is returned unchanged (inelastic contact). Friction (μ > 0) then opposes
 * the tangential velocity the step would produce, by at most μ times the normal force the
 * surface exerts, and never more than what stops the sliding within dt. */
vec3 reaction_constraint_force(const vec3 &force, const vec3 &velocity, const Contact &contact,
                               const ReactionConstants &constants);

/* r_forces[i] = the reaction-constrained force of node i where it is inside a collider,
 * forces[i] elsewhere. r_forces may alias forces. Returns the number of nodes in contact. */
int64_t apply_reaction_constraint(const ColliderSet &colliders, Span<vec3> positions_wo,
                                  Span<vec3> velocities_wo, Span<vec3> forces,
                                  const ReactionConstants &constants, MutableSpan<vec3> r_forces);

/* The hard guarantee (Ward & Lin 2003 §5.5): every node deeper than tolerance_wo (scene
 * units) is put on the surface point T of its contact, and the inward normal component of
 * its velocity is removed (tangential and outward motion are kept). Returns the number of
 * nodes moved. */
int64_t project_out_of_colliders(const ColliderSet &colliders, float tolerance_wo,
                                 MutableSpan<vec3> r_positions_wo, MutableSpan<vec3> r_velocities_wo);

}  // namespace hairdyn
