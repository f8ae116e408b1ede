/* The articulated strand model: the strand as a chain of rigid rods joined by 2-DOF hinges
 * (the (θ, φ) of strand_solver.hh), with the full coupled dynamics of the chain, solved in
 * O(N) per strand by Featherstone's articulated-body algorithm (R. Featherstone, Rigid Body
 * Dynamics Algorithms, 2008, §7.3 and Table 7.1; the form Hadap 2006, "Oriented Strands:
 * dynamics of stiff multi-body system", §3–4, applies to hair). Every hinge feels the inertia
 * and the external forces of everything distal to it, so sag and swing converge as the strand
 * is cut finer (issue 12: Kurihara 1993, eq. 5 gives a hinge only its own segment's load).
 *
 * Quantities are in world axes, each body's referred to its hinge point P_i (the node at its
 * root); accelerations are classical (ω̇, a_P), so a rigid rod of mass m, centre at h from P,
 * obeys (τ_P, f) = I_P (ω̇, a_P) + p with
 *
 *   I_P = [ (m d²/3) 1   m [h]× ]      p = ( −h × F,
 *         [ −m [h]×      m 1    ]            m ω × (ω × h) − F )
 *
 * (Newton–Euler about P; F the external force at the centre). The rod's inertia about P is
 * m d²/3 about its own axis too (see tip_to_root), so it is isotropic and has no gyroscopic
 * torque ω × (I ω).
 * Moving a reference point by r (motion at P_child = motion at P_parent shifted by r):
 * X = [1 0; −[r]× 1], inertia Xᵀ I X, force (τ + r × f, f) (Featherstone eq. 2.21, 2.24).
 *
 * The motion is taken in the head's frame (root fixed, ω and v relative to the head); the
 * head's motion enters as the fictitious force −m a_rel(r, v_rel) with Coriolis, inside F
 * (core/head_motion.hh; Kurihara 1993, eq. 6).
 *
 * Implicit hinges (Hadap 2006, §4, linearly implicit Euler on the joint springs and dampers):
 * the hinge torque −k q − γ q̇ is taken at the end of the step, linearised,
 *   (M + h γ + h² k) Δq̇ = h (τ_ext − bias − k q − (γ + h k) q̇),
 * and since k and γ act on one hinge each, h γ + h² k simply adds to the hinge's joint-space
 * inertia D_i (the "armature" of Featherstone §7.3): still one O(N) pass, unconditionally
 * stable in the springs and damping.
 *
 * Drag (Kurihara 1993, eq. 6, and the form drag: ForceField) is stiff on thin, light hair: in
 * a gale it brings a free hair to the air's speed within a millisecond, a tenth of a substep.
 * The implicit integrator takes it linearly implicit as it does the springs: h ∂F/∂v (bounded
 * isotropically: ForceField::drag_stiffness) adds to each rod's mass in its inertia I_P (not
 * in its bias forces), so the step solves (M + h C) q̈ = F, and the force is taken whole (the
 * explicit integrator limits it over the step instead). Spread along the rod, the drag also
 * puts a couple on a rod that turns about its centre (ForceField::drag_couple): a force at
 * the centre alone leaves the chain's zigzag modes undamped, and a gale fed them until the
 * strand ran away. A chain hung in a steady wind settles at the angle its forces give on any
 * substep (test AChainInASteadyWindHangsAtTheAngleItsForcesGive).
 *
 * Tension stiffens the chain: the external force beyond a hinge that pulls along its
 * segment, T (the drag of the air streaming past a hair, its weight, the head's spin), holds
 * a rod turning about its centre as a spring would, with T d of torque per radian (T at both
 * ends): the chain's zigzag mode, ω² = T d / I, I the rod's inertia about its centre,
 * (m + drag armature) d² / 12. Taken explicitly, with the hinge's spring k and damper γ
 * implicit (their armature h γ + h² k in the step), semi-implicit Euler keeps the mode bounded
 * only while h² T d < 4 (I + h γ / 2 + h² k / 4) (Jury's test on the step's 2 × 2 map):
 * ω h < 2 (max_wave_phase) with I + h γ / 2 + h² k / 4 for I. The air's pull on a hair is
 * large, 20 times its weight at 5 m/s: at four substeps a frame the hinges zigzagged without
 * end at any wind over 2 m/s, and cutting the step to hold ω h < 2 took about three steps a
 * substep for 30 cm strands of 16 segments in a 2 m/s wind (the explicit integrator still
 * cuts so: steps_needed).
 *
 * The implicit integrator takes the stiffness linearly implicit instead, as it does the
 * springs. With the forces held over the step, the potential of a constant force F at r
 * from the rod's hinge point has, in the rod's turn δθ, the Hessian (F · r) 1 − (F rᵀ +
 * r Fᵀ) / 2: the rods' own turns only, one block per body, which the articulated-body
 * recursion takes as it takes the drag's armature. Of it the step keeps the tension's part
 * along the rod, κ (1 − t tᵀ) with κ = T d ≥ 0 (the rest is indefinite and stays explicit),
 * and only beyond what the step holds explicitly, explicit_wave_phase² I / h² (the slow
 * swing, held by the same stiffness, is damped by that share too: see the constant; the air
 * damps it far more). The rod's inertia at its
 * hinge point gains h² κ (1 − t tᵀ), and its bias h κ ω⊥ (its turn across its axis at the
 * step's start rates, relative to the head); the mode is then bounded at any ω h (Jury's test
 * again: h² κ_explicit − h² κ_implicit < 4 I). Strands in a steady breeze come to rest at any
 * wind, and no step is cut for it (BM_StrandStep, a 2 m/s wind: 2.8× faster on one core,
 * 3.2× on two; head_shake.blend's hair in a 100 m/s gale 40×); strands of 16
 * segments caught from rest by a 60 m/s gale hold (with the cut steps, 16 and 32 segments
 * ran away from 60 m/s; 32 still do, and once in 48 frames at 30 m/s in turbulence, which
 * the cut steps held; tests StrandsInASteadyBreezeComeToRest,
 * NoStrandRunsAwayInAGaleFromRest).
 *
 * Gravity, drag, head forces and the velocity products are explicit, taken at the middle of
 * the step (explicit midpoint): at the rates q̇ + h q̈₀ / 2, with q̈₀ the chain's acceleration
 * at the step's start. Taken at q̇ (explicit Euler), they let a tumbling chain gain energy
 * in proportion to the step (a free chain at 50 rad/s: +67%, +26%, +7% in 0.2 s at 128, 512
 * and 2048 substeps), and a strand whipped by a violent head shake, whose segments turn at
 * thousands of rad/s, ran away within a few frames.
 *
 * q̈₀ comes from the last two steps: each step's q̈ is the chain's at its middle, so
 * q̈₀ ≈ (3/2) q̈₋₁ − (1/2) q̈₋₂ (Adams–Bashforth's two-step extrapolation, to the half step
 * beyond the last one), but a component whose sign flipped between those two steps is held
 * at q̈₋₁: the steps do not resolve an oscillation that fast, and extrapolating doubles it
 * (±a gives ±2a). Extrapolated, free strands of Sintel's groom in wind ran away from rest
 * (2 of 9,120 over 48 frames; test NoStrandRunsAwayAlongSintelsBust), their near-root hinges
 * zigzagging ever faster. Where that trend is not there to be read, a predictor stage finds
 * q̈₀ by the same three passes at the step's start rates, and the step itself follows: for
 * the first two steps after a state is set or the strand is put at rest, after a pass
 * changed its rates (take_back_strand), and after contact impulses stopped it. A strand in
 * free motion takes one articulated-body pass per step instead of two (1.3× faster on
 * BM_StrandStep, 1.5× on the README's Blender bench). A free chain turning through the
 * charts' poles keeps its energy within 1.2% and 3.5% over 0.2 s at 128 and at 512 substeps
 * (6.8% and 5.7% extrapolated without the hold; 0.3% and 1.0% with a predictor every step;
 * test AChainTurningThroughTheChartsPolesKeepsItsEnergy).
 *
 * Contact: a segment whose tip ends a step inside a body turns about its root onto the
 * surface (Ward & Lin 2003 §5.5), its child keeping its direction (for up to max_kept_turn
 * of the turn), and the tip's velocity into the surface is stopped by an inelastic impulse
 * through the chain's articulated inertia (stop_at_contact). That never adds energy;
 * stopping the one hinge instead (Kurihara 1993's hinges, where each segment moves on its
 * own) changes the generalised momentum of everything distal to it, and fed a whipping chain
 * energy until it ran away.
 *
 * Strands of one point count step W at a time (StrandSolver::group_strands; W = 8 with
 * AVX-512, 4 otherwise): pass 1 (the shape and forces) in vectors of W floats, the tips'
 * contacts queried in one batch; passes 2 and 3 in vectors of W doubles
 * (strands/chain_lanes.hh), every operation as glm evaluates it, so a strand keeps the bits
 * it has alone (test LanesGiveEachStrandItsOwnBits); the commit's new shapes in vectors of W
 * floats, each lane's projection on its own. Each strand predicts and cuts its steps on its
 * own; a lane without a strand in a stage repeats another's, its result dropped. */
#include <algorithm>
#include <atomic>
#include <cassert>
#include <cmath>
#include <cstring>
#include <vector>

/* The lane functions are always inlined (those of chain_lanes.hh, and ForceField::on_segment
 * on lanes): no vector crosses a call, so GCC's note that one would pass differently with and
 * without AVX does not apply. Set before the headers, whose templates it instantiates. */
#pragma GCC diagnostic ignored "-Wpsabi"

#include "core/cpu.hh"
#include "groom/groom.hh"
#include "strands/chain_lanes.hh"
#include "strands/deflection.hh"
#include "strands/strand_solver.hh"

namespace hairdyn {

/* The recursion runs in double precision: I^a = I^A − U D⁻¹ Uᵀ cancels most of a body's
 * inertia when its hinge is free (short steps leave little of the springs' armature in D),
 * and in single precision what remains of a strand of fine segments (1e-11 kg m² per
 * segment of human hair) was noise: D⁻¹ came out tens of times too large, or indefinite,
 * and the chain ran away. */
using rvec2 = glm::dvec2;
using rvec3 = glm::dvec3;
using rmat2 = glm::dmat2;

/* What pass 1 hands the recursion for one body, in single precision, one lane per strand of
 * W: the recursion widens it and builds the rod's inertia and bias forces from it. */
template<int W> struct alignas(chain::lane_alignment) StrandSolver::ArticulatedTerms {
  using F = chain::Floats<W>;
  chain::V3<F> t, e_theta, pole; /* the segment's direction, frame[1] and its chart's x axis */
  chain::V3<F> arm;              /* r, from the parent's hinge point to this one */
  chain::V3<F> parent_omega;     /* the parent's turn, relative to the head */
  chain::V3<F> relative_turn;    /* θ̇ e_θ − φ̇ x across the hinge */
  chain::V3<F> omega;            /* the segment's turn */
  chain::V3<F> omega_start;      /* the same at the step's start rates */
  chain::V3<F> half;             /* d t / 2, to the segment's centre */
  chain::V3<F> force;            /* F at the centre */
  chain::V3<F> couple;           /* the drag's couple (ForceField::drag_couple) */
  chain::V3<F> tip, tip_velocity; /* the segment's end and its velocity (the contact query's) */
  F rate_product;                /* θ̇ φ̇ */
  chain::M3<F> rest;             /* the rest rotation from the parent's frame */
  F m, d, k;                     /* mass, length, hinge stiffness */
  F drag_mass; /* h times the drag's stiffness over the rod (implicit integrator; else 0), kg */
  /* The share of the tension's stiffness T d the step takes implicitly, N m/rad (implicit
   * integrator; else 0): see the top of the file. */
  F tension_stiffness;
  chain::V2<F> angles, rates;    /* q, q̇ */
};

namespace {

using chain::get;
using chain::Lanes;
using chain::M2;
using chain::M3;
using chain::put;
using chain::S3;
using chain::V2;
using chain::V3;
using chain::widen;

/* What the recursion keeps of a body for pass 3 and for contact impulses, over lanes R
 * (chain_lanes.hh). Aligned for the widest vector loads (chain::lane_alignment), as everything
 * the vector code reads from memory. */
template<class R> struct alignas(chain::lane_alignment) Link {
  V3<R> s_theta, s_phi, arm;
  V3<R> bias_angular, bias_linear;
  V3<R> u_angular[2], u_linear[2]; /* U = I^A S, one column per hinge axis */
  M2<R> d_inverse;
  V2<R> u;                   /* τ − Sᵀ p^A */
  V2<R> acceleration;        /* q̈, pass 3's result */
};

/* Pass 2, tip to root (Table 7.1, second loop), each body's rod built from pass 1's terms as
 * the pass reaches it (in double precision; step_lengths: each lane's h): its hinge axes and
 * velocity products, its inertia at P_i and bias force, and the hinge torque; then U = I^A S,
 * D = Sᵀ U + armature, u = τ − Sᵀ p^A, and the body's articulated inertia and bias less what
 * its hinge absorbs, I^a = I^A − U D⁻¹ Uᵀ and p^a = p^A + I^a c + U D⁻¹ u, moved to the
 * parent's hinge point and handed to it.
 *
 * The rod's inertia about P_i is m d² / 3 about every axis through P_i, its own axis
 * included. A thin rod's about its axis is nearly 0, but a segment never spins by itself: a
 * hinge turns it about its own axis only near the chart's pole (θ = ±π/2, where φ̇ just
 * twists the segment), and there a near-zero inertia let φ̇ grow without bound for a finite
 * motion: the chain ran away (a strand blown flat against the head bends its first segment
 * there). With the transverse inertia about its axis too, turning through the pole costs what
 * any other turn does, as for Kurihara 1993's hinges (eq. 1: the same I for θ and φ); away
 * from the pole the twist is φ̇ sin θ, so bending near rest is unchanged to second order. An
 * isotropic inertia has no gyroscopic torque, and adds to the child's I^a on the diagonals
 * only: I^A = I^a_child + (m d² / 3, m [h]×, m) blockwise. The hinge spring and damper are
 * linearly implicit (see the top of the file). */
template<class R, class Terms>
HAIRDYN_CHAIN_INLINE void tip_to_root(Link<R> *links, const Terms *terms, const size_t n,
                                      const double *step_lengths, const bool implicit,
                                      const double damping)
{
  R hd;
  std::memcpy(&hd, step_lengths, sizeof(hd)); /* no alignment assumed */
  const R zero{};
  /* What the child hands its parent: its I^a and p^a moved to the parent's hinge point (none
   * for the tip). I^a = [a b; bᵀ c] with a and c symmetric: their six entries each. */
  S3<R> child_a{}, child_c{};
  M3<R> child_b{};
  V3<R> child_torque{}, child_force{};
  for (size_t i = n; i-- > 0;) {
    const Terms &x = terms[i];
    Link<R> &body = links[i];
    const V3<R> pole = widen(x.pole), arm = widen(x.arm);
    const V3<R> parent_omega = widen(x.parent_omega), omega = widen(x.omega);
    const V3<R> half = widen(x.half), force = widen(x.force);
    const R m = widen(x.m), d = widen(x.d), k = widen(x.k);
    const R inertial = m + widen(x.drag_mass); /* the rod's mass in I_P, drag's armature added */
    body.s_theta = widen(x.e_theta);
    body.s_phi = -pole;
    body.arm = arm;
    body.bias_angular = cross(parent_omega, widen(x.relative_turn)) -
                        widen(x.rate_product) * cross(pole, body.s_theta);
    body.bias_linear = cross(parent_omega, cross(parent_omega, arm));
    /* I^A and p^A: the rod's own, added to what its child hands it (zero at the tip). */
    const R transverse = inertial * d * d / 3.0;
    S3<R> a = child_a, c = child_c;
    M3<R> b = child_b;
    a.xx = a.xx + transverse;
    a.yy = a.yy + transverse;
    a.zz = a.zz + transverse;
    b.c[0].y = b.c[0].y + inertial * half.z;
    b.c[0].z = b.c[0].z + inertial * -half.y;
    b.c[1].x = b.c[1].x + inertial * -half.z;
    b.c[1].z = b.c[1].z + inertial * half.x;
    b.c[2].x = b.c[2].x + inertial * half.y;
    b.c[2].y = b.c[2].y + inertial * -half.x;
    c.xx = c.xx + inertial;
    c.yy = c.yy + inertial;
    c.zz = c.zz + inertial;
    V3<R> p_torque = child_torque - cross(half, force) - widen(x.couple);
    if (implicit) {
      /* The tension's stiffness beyond what the step holds, κ (1 − t tᵀ) on the rod's turn,
       * linearly implicit: h² κ (1 − t tᵀ) in its inertia, and h κ ω⊥ (its turn across its
       * axis at the step's start) in its bias (see the top of the file). */
      const R kappa = widen(x.tension_stiffness);
      const V3<R> t = widen(x.t);
      const R hhk = hd * hd * kappa;
      a.xx = a.xx + hhk * (1.0 - t.x * t.x);
      a.yy = a.yy + hhk * (1.0 - t.y * t.y);
      a.zz = a.zz + hhk * (1.0 - t.z * t.z);
      a.xy = a.xy - hhk * (t.x * t.y);
      a.xz = a.xz - hhk * (t.x * t.z);
      a.yz = a.yz - hhk * (t.y * t.z);
      const V3<R> w = widen(x.omega_start);
      p_torque = p_torque + (hd * kappa) * (w - dot(w, t) * t);
    }
    const V3<R> p_force = child_force + (m * cross(omega, cross(omega, half)) - force);
    const R gamma = damping * k; /* Kelvin–Voigt: γ = τ k */
    const R armature = implicit ? hd * gamma + hd * hd * k : zero;
    const V2<R> hinge_torque = -k * widen(x.angles) -
                               (implicit ? gamma + hd * k : gamma) * widen(x.rates);

    const V3<R> axes[2] = {body.s_theta, body.s_phi};
    for (int j = 0; j < 2; j++) {
      body.u_angular[j] = a * axes[j];
      body.u_linear[j] = chain::transpose_times(b, axes[j]);
    }
    /* D = Sᵀ I^A S, symmetric, and its inverse. */
    const R d_00 = dot(axes[0], body.u_angular[0]) + armature;
    const R d_01 = dot(axes[1], body.u_angular[0]);
    const R d_11 = dot(axes[1], body.u_angular[1]) + armature;
    const R one_over_determinant = 1.0 / (d_00 * d_11 - d_01 * d_01);
    const R di_01 = -d_01 * one_over_determinant;
    body.d_inverse = {{{d_11 * one_over_determinant, di_01}, {di_01, d_00 * one_over_determinant}}};
    body.u = hinge_torque - V2<R>{dot(axes[0], p_torque), dot(axes[1], p_torque)};
    if (i == 0) {
      break;
    }
    const M2<R> &di = body.d_inverse;
    /* I^a = I^A − U D⁻¹ Uᵀ, blockwise: U D⁻¹ Uᵀ = Σ_jk U_j (D⁻¹)_jk U_kᵀ = Σ_k (U D⁻¹)_k U_kᵀ. */
    const V3<R> wa0 = di.c[0].x * body.u_angular[0] + di.c[0].y * body.u_angular[1];
    const V3<R> wa1 = di.c[1].x * body.u_angular[0] + di.c[1].y * body.u_angular[1];
    const V3<R> wl0 = di.c[0].x * body.u_linear[0] + di.c[0].y * body.u_linear[1];
    const V3<R> wl1 = di.c[1].x * body.u_linear[0] + di.c[1].y * body.u_linear[1];
    a = a - chain::symmetric_outer_sum(wa0, body.u_angular[0], wa1, body.u_angular[1]);
    b = b - outer(wa0, body.u_linear[0]) - outer(wa1, body.u_linear[1]);
    c = c - chain::symmetric_outer_sum(wl0, body.u_linear[0], wl1, body.u_linear[1]);
    /* To the parent's hinge point: Xᵀ I X with R = [r]× (Rᵀ = −R): a − (b R + (b R)ᵀ) − R c R,
     * b + R c, c; R c R is symmetric. */
    const M3<R> rc = cross_times(arm, c);
    const M3<R> br = times_cross(b, arm);
    child_a = {a.xx - (br.c[0].x + br.c[0].x) - (arm.z * rc.c[1].x - arm.y * rc.c[2].x),
               a.yy - (br.c[1].y + br.c[1].y) - (arm.x * rc.c[2].y - arm.z * rc.c[0].y),
               a.zz - (br.c[2].z + br.c[2].z) - (arm.y * rc.c[0].z - arm.x * rc.c[1].z),
               a.xy - (br.c[1].x + br.c[0].y) - (arm.x * rc.c[2].x - arm.z * rc.c[0].x),
               a.xz - (br.c[2].x + br.c[0].z) - (arm.y * rc.c[0].x - arm.x * rc.c[1].x),
               a.yz - (br.c[2].y + br.c[1].z) - (arm.y * rc.c[0].y - arm.x * rc.c[1].y)};
    child_b = b + rc;
    child_c = c;
    const V2<R> du = di * body.u;
    const V3<R> pa_torque = p_torque + a * body.bias_angular + b * body.bias_linear +
                            du.x * body.u_angular[0] + du.y * body.u_angular[1];
    const V3<R> pa_force = p_force + chain::transpose_times(b, body.bias_angular) +
                           c * body.bias_linear + du.x * body.u_linear[0] +
                           du.y * body.u_linear[1];
    child_torque = pa_torque + cross(arm, pa_force);
    child_force = pa_force;
  }
}

/* Pass 3, root to tip (Table 7.1, third loop): q̈ = D⁻¹ (u − Uᵀ a'), with a' the parent's
 * acceleration moved to this hinge plus c; the root is fixed in the head's frame. */
template<class R> HAIRDYN_CHAIN_INLINE void root_to_tip(Link<R> *links, const size_t n)
{
  V3<R> parent_alpha{};
  V3<R> parent_acceleration{};
  for (size_t i = 0; i < n; i++) {
    Link<R> &body = links[i];
    const V3<R> alpha = parent_alpha + body.bias_angular;
    const V3<R> acceleration = parent_acceleration + cross(parent_alpha, body.arm) +
                               body.bias_linear;
    const V2<R> ut_a{
        dot(body.u_angular[0], alpha) + dot(body.u_linear[0], acceleration),
        dot(body.u_angular[1], alpha) + dot(body.u_linear[1], acceleration)};
    const V2<R> q_acceleration = body.d_inverse * (body.u - ut_a);
    parent_alpha = alpha + q_acceleration.x * body.s_theta + q_acceleration.y * body.s_phi;
    parent_acceleration = acceleration;
    body.acceleration = q_acceleration;
  }
}

/* Which vector code the step runs (core/cpu.hh): each has its clone of the whole substep
 * (advance_articulated_as), every lane's bits the same on all (chain_lanes.hh). */
std::atomic<VectorCode> vector_code{cpu_vector_code()};

/* A step's scratch for W lanes: per lane the mid-step rates' q̈ and the projected segments
 * (body, outward normal); pass 1's bodies and the recursion's links (with the step's q̈). */
template<int W> struct LaneScratch {
  /* add_contact_forces's query: the tips, what the colliders say of each, the batch arrays. */
  std::vector<vec3> tips;
  std::vector<uint8_t> hit;
  std::vector<float> depth;
  std::vector<vec3> normal, surface;
  std::unique_ptr<ContactBatch<map_batch_size>> contact_batch;
  std::unique_ptr<MapBatch<map_batch_size>> map_batch;
  std::vector<vec2> mid_accelerations[W];
  std::vector<std::pair<size_t, vec3>> stops[W];
  std::vector<StrandSolver::ArticulatedTerms<W>> terms;
  std::vector<Link<Lanes<W>>> links;
};
template<int W> LaneScratch<W> &lane_scratch()
{
  thread_local LaneScratch<W> scratch;
  return scratch;
}


/* The reaction constraint (Kurihara 1993, eq. 12–15) on the rods whose tips pass 1 put inside
 * a collider, for the lanes `queried`: every tip of the step in one query (queried segment by
 * segment, eight tips at a time, the look-ups cost about four times as much per tip; in one
 * query Sintel's groom steps on its bust 1.19× faster), each force filtered by
 * contact_force(force, d, tip velocity, contact, reaction constants) (StrandSolver's).
 * r_contacts[lane] counts the lane's contacts. */
template<int W, class ContactForce>
void add_contact_forces(const ColliderSet &colliders, const ReactionConstants &substep_reaction,
                        const float *step_lengths, const uint8_t *queried, const size_t n,
                        const ContactForce &contact_force,
                        StrandSolver::ArticulatedTerms<W> *terms, LaneScratch<W> &scratch,
                        int64_t *r_contacts)
{
  std::vector<vec3> &tips = scratch.tips;
  tips.clear();
  for (size_t i = 0; i < n; i++) {
    for (int lane = 0; lane < W; lane++) {
      if (queried[lane]) {
        tips.push_back(get(terms[i].tip, lane));
      }
    }
  }
  if (tips.empty()) {
    return;
  }
  if (scratch.contact_batch == nullptr) {
    scratch.contact_batch.reset(new ContactBatch<map_batch_size>);
    scratch.map_batch.reset(new MapBatch<map_batch_size>);
  }
  scratch.hit.resize(tips.size());
  scratch.depth.resize(tips.size());
  scratch.normal.resize(tips.size());
  scratch.surface.resize(tips.size());
  find_contacts_serial(colliders, tips, scratch.hit, scratch.depth, scratch.normal,
                       scratch.surface, *scratch.contact_batch, *scratch.map_batch);
  size_t q = 0;
  for (size_t i = 0; i < n; i++) {
    for (int lane = 0; lane < W; lane++) {
      if (!queried[lane]) {
        continue;
      }
      if (scratch.hit[q]) {
        const Contact contact{ scratch.depth[q], scratch.normal[q], scratch.surface[q] };
        ReactionConstants reaction = substep_reaction;
        reaction.dt = step_lengths[lane]; /* the substep's collision constants, for this step */
        put(terms[i].force, lane,
            contact_force(get(terms[i].force, lane), terms[i].d[lane],
                          get(terms[i].tip_velocity, lane), contact, reaction));
        r_contacts[lane]++;
      }
      q++;
    }
  }
}

inline rvec3 real(const vec3 &v)
{
  return rvec3(v);
}

/* The inelastic contact at the tip of body `hit` of lane `lane`: if the tip moves into the
 * surface of outward normal n (relative to the head, from the hinge rates and the step's
 * geometry), the impulse λ n with λ = −v_n / (n · Δv(n)) stops that motion, Δv(n) being the
 * tip's velocity change per unit impulse. The impulse's effect on every rate is
 * Featherstone's articulated-body recursion with the impulse as the only force (Table 7.1
 * without velocity products or hinge torques; D and U are the step's, springs' armature
 * included): tip to root, the impulse's bias p^A = (−reach × n, −n) at `hit` and its share
 * p^a = p^A + U D⁻¹ u, u = −Sᵀ p^A, handed to the parents; root to tip,
 * Δq̇ = D⁻¹ (u − Uᵀ a'). The kinetic energy changes by −v_n² / (2 n · Δv(n)) ≤ 0. */
template<class R, class Terms>
void stop_at_contact(const Link<R> *chain, const Terms *terms, const int lane, const size_t n,
                     const size_t hit, const rvec3 &n_out, const MutableSpan<vec2> rates)
{
  const auto s_theta = [&](const size_t k) { return get(chain[k].s_theta, lane); };
  const auto s_phi = [&](const size_t k) { return get(chain[k].s_phi, lane); };
  const auto arm = [&](const size_t k) { return get(chain[k].arm, lane); };
  /* d t, from the hinge point to the segment's tip */
  const rvec3 reach = real(get(terms[hit].d, lane) * get(terms[hit].t, lane));
  /* The tip's velocity: Ω_k = Ω_{k-1} + S_k q̇_k, v(P_k) = v(P_{k-1}) + Ω_{k-1} × r_k. */
  rvec3 omega(0.0), v(0.0);
  for (size_t k = 0; k <= hit; k++) {
    v += glm::cross(omega, arm(k));
    omega += double(rates[int64_t(k)].x) * s_theta(k) + double(rates[int64_t(k)].y) * s_phi(k);
  }
  const double approach = glm::dot(n_out, v + glm::cross(omega, reach));
  if (!(approach < 0.0)) {
    return;
  }
  thread_local std::vector<rvec2> u;
  thread_local std::vector<rvec2> delta;
  u.assign(hit + 1, rvec2(0.0));
  delta.resize(n);
  rvec3 p_torque = -glm::cross(reach, n_out), p_force = -n_out;
  for (size_t k = hit + 1; k-- > 0;) {
    const Link<R> &body = chain[k];
    const rmat2 d_inverse = get(body.d_inverse, lane);
    const rvec3 u_angular[2] = {get(body.u_angular[0], lane), get(body.u_angular[1], lane)};
    const rvec3 u_linear[2] = {get(body.u_linear[0], lane), get(body.u_linear[1], lane)};
    u[k] = -rvec2(glm::dot(s_theta(k), p_torque), glm::dot(s_phi(k), p_torque));
    const rvec2 du = d_inverse * u[k];
    const rvec3 pa_torque = p_torque + du.x * u_angular[0] + du.y * u_angular[1];
    const rvec3 pa_force = p_force + du.x * u_linear[0] + du.y * u_linear[1];
    p_torque = pa_torque + glm::cross(arm(k), pa_force);
    p_force = pa_force;
  }
  rvec3 alpha(0.0), acceleration(0.0), tip_change(0.0);
  for (size_t k = 0; k < n; k++) {
    const Link<R> &body = chain[k];
    const rvec3 u_angular[2] = {get(body.u_angular[0], lane), get(body.u_angular[1], lane)};
    const rvec3 u_linear[2] = {get(body.u_linear[0], lane), get(body.u_linear[1], lane)};
    acceleration += glm::cross(alpha, arm(k));
    const rvec2 ut_a(glm::dot(u_angular[0], alpha) + glm::dot(u_linear[0], acceleration),
                     glm::dot(u_angular[1], alpha) + glm::dot(u_linear[1], acceleration));
    delta[k] = get(body.d_inverse, lane) * ((k <= hit ? u[k] : rvec2(0.0)) - ut_a);
    alpha += delta[k].x * s_theta(k) + delta[k].y * s_phi(k);
    if (k == hit) {
      tip_change = acceleration + glm::cross(alpha, reach);
    }
  }
  const double response = glm::dot(n_out, tip_change);
  if (!(response > 0.0)) {
    return;
  }
  const double lambda = -approach / response;
  for (size_t k = 0; k < n; k++) {
    rates[int64_t(k)] += vec2(lambda * delta[k]);
  }
}

/* The rest rotation, the sines and cosines of the angles and the length of segment
 * points[lane] of W strands, one lane each (from StrandSolver's rest_rotations_, trig_ and
 * rest_lengths_). */
template<int W>
HAIRDYN_CHAIN_INLINE void load_segment_lanes(const size_t *points, const mat3 *rest_rotations,
                                             const vec4 *trigs, const float *rest_lengths,
                                             M3<chain::Floats<W>> &r_rest,
                                             chain::Floats<W> *r_trig,
                                             chain::Floats<W> &r_length)
{
  /* A mat3 is nine consecutive floats, column by column (c0.xyz c1.xyz c2.xyz). */
  const float *head[W], *middle[W], *trig[W];
  for (int lane = 0; lane < W; lane++) {
    const float *rest = &rest_rotations[points[lane]][0][0];
    head[lane] = rest;
    middle[lane] = rest + 4;
    trig[lane] = &trigs[points[lane]][0];
    r_rest.c[2].z[lane] = rest[8];
    r_length[lane] = rest_lengths[points[lane]];
  }
  chain::Floats<W> part[4];
  chain::gather4(head, part);
  r_rest.c[0] = {part[0], part[1], part[2]};
  r_rest.c[1].x = part[3];
  chain::gather4(middle, part);
  r_rest.c[1].y = part[0];
  r_rest.c[1].z = part[1];
  r_rest.c[2].x = part[2];
  r_rest.c[2].y = part[3];
  chain::gather4(trig, r_trig);
}

/* The contacts of W lanes' points in one batched query (the same contacts as one by one; a
 * batch holds a multiple of eight), or none without colliders. */
template<class F>
HAIRDYN_CHAIN_INLINE void find_lane_contacts(const ColliderSet *colliders, const V3<F> &points,
                                             ContactBatch<8> &r_contacts)
{
  if (colliders == nullptr) {
    return;
  }
  constexpr int lanes = int(sizeof(F) / sizeof(float));
  static_assert(lanes <= 8);
  vec3 each[lanes];
  for (int lane = 0; lane < lanes; lane++) {
    each[lane] = get(points, lane);
  }
  r_contacts.load(Span<vec3>(each, lanes));
  MapBatch<8> scratch;
  colliders->accumulate_contacts(r_contacts, scratch);
}

}  // namespace

template<int W>
[[gnu::always_inline]] inline void StrandSolver::articulated_substep(
    const Span<int64_t> curves, const Substep &substep, const Span<mat3> root_frames,
    const Span<vec3> winds, Counts &counts, const MutableSpan<uint8_t> r_finite)
{
  /* The velocity products are explicit: a segment that turns by more than about a radian in
   * one step (a pass's push of a few m/s on a 1 cm segment does) feeds its centripetal and
   * gyroscopic terms from a direction it has long left, and the chain runs away. Such a
   * strand takes shorter steps, each short enough that no turn exceeds max_turn_per_step,
   * down to substep.h / max_turn_steps; the head's pose and forces stay the substep's (the
   * root is already placed). A strand that turns slowly takes the substep in one step. Each
   * strand cuts its own steps; the strands still stepping step together. */
  assert(curves.size() <= group_strands_max);
  const int64_t lanes_num = curves.size();
  const float shortest = substep.h / float(max_turn_steps);
  float step_h[group_strands_max]; /* each strand's step */
  float remaining[group_strands_max];
  bool split_any[group_strands_max];
  int64_t active[group_strands_max]; /* the strands still stepping */
  for (int64_t k = 0; k < lanes_num; k++) {
    step_h[k] = substep.h;
    remaining[k] = substep.h;
    split_any[k] = false;
    r_finite[k] = 1;
    active[k] = k;
  }
  int64_t active_num = lanes_num;
  /* Per strand, the nodes where its substep began, if it cut it into steps. */
  thread_local std::vector<vec3> substep_start[group_strands_max];
  while (active_num > 0) {
    /* The strands that need a predictor stage first: a stage of W lanes runs the predictor
     * for all of them when one needs it (articulated_step), so those step together. A strand
     * has the same bits in any lane. */
    int64_t ordered[group_strands_max];
    int64_t placed = 0;
    for (const bool predicted : { true, false }) {
      for (int64_t j = 0; j < active_num; j++) {
        if (needs_predictor(curves[active[j]]) == predicted) {
          ordered[placed++] = active[j];
        }
      }
    }
    std::copy(ordered, ordered + active_num, active);
    /* One step of every strand still stepping, W at a time: those that cut their steps fill
     * the vectors together, whichever strands they stepped beside at first. */
    int64_t step_curves[group_strands_max];
    uint8_t may_split[group_strands_max];
    mat3 frames[group_strands_max];
    vec3 step_winds[group_strands_max];
    float h[group_strands_max];
    for (int64_t j = 0; j < active_num; j++) {
      const int64_t k = active[j];
      /* What remains in equal steps of at most the step (a thousandth over it allowed for
       * rounding), the last taking exactly what remains. Steps of step_h with the remainder
       * last left a sliver where the rounding of hundreds of steps added up (3e-8 s after 350
       * steps of 3e-5 s), and the steps after it extrapolated the sliver's acceleration (see
       * the top): a strand pressed on the head by a 40 m/s wind turned a hinge from 380 to
       * 9,700 rad/s in the next step and ran away. */
      const float steps = std::ceil(remaining[k] / step_h[k] - 0.001f);
      h[j] = steps <= 1.0f ? remaining[k] : remaining[k] / steps;
      step_h[k] = h[j];
      step_curves[j] = curves[k];
      may_split[j] = h[j] > shortest * 1.5f;
      frames[j] = root_frames[k];
      step_winds[j] = winds[k];
    }
    int outcomes[group_strands_max];
    for (int64_t first = 0; first < active_num; first += W) {
      const int64_t num = std::min<int64_t>(W, active_num - first);
      articulated_step<W>(Span<int64_t>(step_curves + first, num), substep,
                          Span<float>(h + first, num),
                          Span<uint8_t>(may_split + first, num), Span<mat3>(frames + first, num),
                          Span<vec3>(step_winds + first, num), counts,
                          MutableSpan<int>(outcomes + first, num));
    }
    int64_t kept = 0;
    for (int64_t j = 0; j < active_num; j++) {
      const int64_t k = active[j];
      if (outcomes[j] < 0) {
        r_finite[k] = 0;
        continue;
      }
      if (outcomes[j] > 1) {
        if (!split_any[k]) {
          /* The nodes where the substep started: the velocity it hands on is its mean,
           * (x − x_start) / h, as for a substep taken in one step (the passes read x − h v
           * as where a node was). */
          split_any[k] = true;
          const IndexRange points = curve_points(curve_offsets_, curves[k]);
          substep_start[k].assign(positions_wo_.begin() + points.start,
                                  positions_wo_.begin() + points.one_after_last());
        }
        step_h[k] = std::max(h[j] / float(outcomes[j]), shortest);
        active[kept++] = k;
        continue;
      }
      remaining[k] = h[j] == remaining[k] ? 0.0f : remaining[k] - h[j];
      if (remaining[k] > 0.0f) {
        active[kept++] = k;
      }
    }
    active_num = kept;
  }
  const float inv_h = 1.0f / substep.h;
  for (int64_t k = 0; k < lanes_num; k++) {
    if (!split_any[k] || !r_finite[k]) {
      continue;
    }
    const IndexRange points = curve_points(curve_offsets_, curves[k]);
    for (int64_t i = points.start + 1; i < points.one_after_last(); i++) {
      velocities_wo_[size_t(i)] =
          (positions_wo_[size_t(i)] - substep_start[k][size_t(i - points.start)]) * inv_h;
    }
  }
}

/* `last` where `last` and `earlier` have opposite signs (their product's sign bit), else
 * `trend`: selected by bits, with no branch, which the flips' random signs mispredicted (as a
 * branch, or the compares GCC makes one, it cost 9% of BM_StrandStep). */
[[gnu::always_inline]] inline float held_if_flipped(const float last, const float earlier,
                                                    const float trend)
{
  uint32_t product, held, extrapolated;
  const float p = last * earlier;
  std::memcpy(&product, &p, sizeof(float));
  std::memcpy(&held, &last, sizeof(float));
  std::memcpy(&extrapolated, &trend, sizeof(float));
  const uint32_t flipped = uint32_t(int32_t(product) >> 31); /* all ones where negative */
  const uint32_t bits = (held & flipped) | (extrapolated & ~flipped);
  float result;
  std::memcpy(&result, &bits, sizeof(float));
  return result;
}

[[gnu::always_inline]] inline void StrandSolver::mid_step_accelerations(
    const int64_t curve, const MutableSpan<vec2> r_accelerations) const
{
  /* The mid-step rates' q̈ (see the top): the last two steps' extrapolated, a component that
   * flipped its sign between them held, or zero for a predictor stage when they are not both
   * known (a state was set, a pass's changes or contact impulses broke the trend). */
  const size_t first = size_t(curve_offsets_[size_t(curve)]) + 1;
  if (needs_predictor(curve)) {
    std::fill(r_accelerations.begin(), r_accelerations.end(), vec2(0.0f));
    return;
  }
  for (int64_t i = 0; i < r_accelerations.size(); i++) {
    const vec2 last = accelerations_[first + size_t(i)];
    const vec2 earlier = earlier_accelerations_[first + size_t(i)];
    const vec2 trend = 1.5f * last - 0.5f * earlier;
    r_accelerations[i] = vec2(held_if_flipped(last.x, earlier.x, trend.x),
                              held_if_flipped(last.y, earlier.y, trend.y));
  }
}

/* GCC 12 reports the lanes filled one by one below, in pass 1 and the commit (each
 * zero-initialised first), as maybe uninitialised: a false positive of its vector element
 * insertion. */
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
template<int W>
[[gnu::always_inline]] inline void StrandSolver::articulated_forward(
    const Span<int64_t> curves, const Substep &substep, const float *step_lengths,
    const Span<mat3> root_frames, const Span<vec3> winds,
    const Span<const vec2 *> mid_accelerations, ArticulatedTerms<W> *terms,
    float *r_fastest_turn) const
{
  /* Pass 1, root to tip (Table 7.1, first loop), W strands at once: geometry,
   * relative velocities, the rates at the middle of the step and the external force F on
   * each rod, every operation glm's on each lane (the rod's inertia and bias forces follow
   * from these terms in double precision: tip_to_root). */
  using Floats = chain::Floats<W>;
  size_t first[W];
  for (int lane = 0; lane < W; lane++) {
    first[lane] = size_t(curve_offsets_[size_t(curves[lane])]) + 1;
  }
  const size_t n = size_t(curve_points(curve_offsets_, curves[0]).size) - 1;
  const float density = line_density();
  const bool implicit = params_.integrator == Integrator::Implicit;
  /* The head, its forces and the wind field are the substep's for every lane; only the step
   * length h differs between lanes (a strand cutting its substep). */
  const vec3 head_center = substep.pose.translation;
  Floats h{};
  M3<Floats> frame{};
  V3<Floats> node{}, wind{};
  for (int lane = 0; lane < W; lane++) {
    h[lane] = step_lengths[lane];
    for (int j = 0; j < 3; j++) {
      put(frame.c[j], lane, root_frames[lane][j]);
    }
    put(node, lane, positions_wo_[first[lane] - 1]);
    put(wind, lane, winds[lane]);
  }
  const Floats half_h = 0.5f * h;
  V3<Floats> node_velocity{}; /* relative to the head */
  V3<Floats> parent_omega{};  /* relative to the head */
  V3<Floats> parent_omega_start{}; /* the same at the step's start rates */
  V3<Floats> arm{};
  /* (rad/s)², of a segment or across a hinge: squares compared, one square root at the end
   * (the same bits as comparing the lengths, √ being monotonic and correctly rounded). */
  Floats fastest_turn2{};
  for (size_t i = 0; i < n; i++) {
    size_t points[W];
    const float *rate_records[W], *mid_records[W], *angle_records[W];
    Floats k{};
    for (int lane = 0; lane < W; lane++) {
      points[lane] = first[lane] + i;
      k[lane] = hinge_stiffness_[points[lane]];
      rate_records[lane] = &angular_velocities_[points[lane]].x;
      mid_records[lane] = &mid_accelerations[lane][i].x;
      angle_records[lane] = &angles_[points[lane]].x;
    }
    M3<Floats> rest;
    Floats trig[4], d;
    load_segment_lanes<W>(points, rest_rotations_.data(), trig_.data(), rest_lengths_.data(),
                          rest, trig, d);
    V2<Floats> rates, mid, angles;
    chain::gather2(rate_records, rates);
    chain::gather2(mid_records, mid);
    chain::gather2(angle_records, angles);
    const Floats m = density * d;
    const M3<Floats> chart{{frame * rest.c[0], frame * rest.c[1], frame * rest.c[2]}};
    rotate_chart(trig[0], trig[1], trig[2], trig[3], chart.c, frame.c);
    const V3<Floats> t = frame.c[2], e_theta = frame.c[1], pole = chart.c[0];
    const V2<Floats> rate = rates + half_h * mid;
    const V3<Floats> relative_turn = rate.x * e_theta - rate.y * pole;
    node = node + arm;
    node_velocity = node_velocity + cross(parent_omega, arm);
    const V3<Floats> omega = parent_omega + relative_turn;
    const V3<Floats> omega_start = parent_omega_start + (rates.x * e_theta - rates.y * pole);
    fastest_turn2 = chain::max(fastest_turn2,
                               chain::max(dot(omega, omega), dot(relative_turn, relative_turn)));

    /* The external force at the centre (Kurihara 1993, eq. 6; reaction constraint eq. 12–15
     * where the tip is inside a collider), from world velocities. */
    const V3<Floats> half = (0.5f * d) * t;
    const V3<Floats> center = node + half;
    const V3<Floats> tip = node + d * t;
    const V3<Floats> center_velocity = node_velocity + cross(omega, half) +
                                       substep.head_velocity.of_point(center - head_center);
    const V3<Floats> tip_velocity = node_velocity + cross(omega, d * t) +
                                    substep.head_velocity.of_point(tip - head_center);
    ArticulatedTerms<W> &x = terms[i];
    /* The segment's turn across its axis relative to the air, for the drag's couple. */
    const V3<Floats> turn = substep.head_velocity.angular + omega;
    const V3<Floats> spin = turn - dot(turn, t) * t;
    const Floats air_speed = substep.forces.rod_air_speed(d, center_velocity, wind, spin);
    /* The implicit integrator takes the drag's stiffness into the rod's inertia (see the top
     * of the file); the explicit one limits the drag over the step. */
    const Floats drag_h = implicit ? Floats{} : h;
    x.force = substep.forces.on_segment(d, center, center_velocity, wind, drag_h);
    x.couple = substep.forces.drag_couple(d, spin, air_speed, drag_h);
    x.drag_mass = implicit ? h * d * substep.forces.drag_stiffness(air_speed) : Floats{};
    x.tip = tip;
    x.tip_velocity = tip_velocity;
    x.t = t;
    x.e_theta = e_theta;
    x.pole = pole;
    x.arm = arm;
    x.parent_omega = parent_omega;
    x.relative_turn = relative_turn;
    x.omega = omega;
    x.omega_start = omega_start;
    x.half = half;
    x.rate_product = rate.x * rate.y;
    x.rest = rest;
    x.m = m;
    x.d = d;
    x.k = k;
    x.angles = angles;
    x.rates = rates;

    parent_omega = omega;
    parent_omega_start = omega_start;
    arm = d * t;
  }
  /* The tension's zigzag mode (see the top of the file): ω² = T d / I at each rod, T the
   * external force beyond its hinge along it (none if it pushes). The implicit integrator
   * takes the stiffness T d beyond what the step holds explicitly, explicit_wave_phase² I / h²,
   * linearly implicit (tip_to_root); the explicit one reports the mode as the turn rate that
   * asks for as many steps (wave_turn_scale). */
  V3<Floats> distal{};
  Floats fastest_wave2{};
  const Floats held = (explicit_wave_phase * explicit_wave_phase) / (h * h);
  for (size_t i = n; i-- > 0;) {
    ArticulatedTerms<W> &x = terms[i];
    distal = distal + x.force;
    const Floats tension = chain::max(dot(distal, x.t), Floats{});
    /* The share of the hinge's implicit spring and damper that holds the mode, h γ / 2 +
     * h² k / 4 (see the top; γ = τ k, as tip_to_root takes it). */
    const Floats armature =
        implicit ? (h * (0.5f * params_.bending_damping) + (0.25f * h) * h) * x.k : Floats{};
    const Floats inertia = (x.m + x.drag_mass) * (x.d * x.d) * (1.0f / 12.0f) + armature;
    if (implicit) {
      x.tension_stiffness = chain::max(tension * x.d - held * inertia, Floats{});
    }
    else {
      x.tension_stiffness = Floats{};
      fastest_wave2 = chain::max(fastest_wave2, (tension * x.d) / inertia);
    }
  }
  for (int lane = 0; lane < W; lane++) {
    r_fastest_turn[lane] = std::max(std::sqrt(fastest_turn2[lane]),
                                    std::sqrt(fastest_wave2[lane]) * wave_turn_scale);
  }
}

template<int W>
[[gnu::always_inline]] inline void StrandSolver::articulated_commit(
    const Span<int64_t> curves, const Substep &substep, const float *step_lengths,
    const Span<mat3> root_frames, const ArticulatedTerms<W> *terms, const uint8_t *committed,
    const MutableSpan<int> r_outcomes)
{
  using Floats = chain::Floats<W>;
  LaneScratch<W> &scratch = lane_scratch<W>();
  const size_t n = size_t(curve_points(curve_offsets_, curves[0]).size) - 1;
  size_t first[W];
  bool lanes[W]; /* the lanes that commit and have not run away */
  float h[W], inv_h[W];
  for (int lane = 0; lane < W; lane++) {
    first[lane] = size_t(curve_offsets_[size_t(curves[lane])]) + 1;
    lanes[lane] = committed[lane];
    scratch.stops[lane].clear();
    h[lane] = step_lengths[lane];
    inv_h[lane] = 1.0f / h[lane];
  }

  for (int lane = 0; lane < W; lane++) {
    if (!lanes[lane]) {
      continue;
    }
    /* q̇ += h q̈, q += h q̇ (semi-implicit Euler; the springs already implicit through D). */
    for (size_t i = 0; i < n; i++) {
      const size_t p = first[lane] + i;
      const vec2 q_acceleration = vec2(get(scratch.links[i].acceleration, lane));
      earlier_accelerations_[p] = accelerations_[p];
      accelerations_[p] = q_acceleration;
      vec2 &omega = angular_velocities_[p];
      omega += h[lane] * q_acceleration;
      if (hinge_runs_away(omega, terms[i].d[lane])) { /* the rest length pass 1 read */
        r_outcomes[lane] = -1;
        lanes[lane] = false;
        break;
      }
      angles_[p] += h[lane] * omega;
    }
  }

  /* The new shapes, root to tip, W at once, every operation glm's on each lane: the new
   * angles' sines and cosines (the same bits as one by one: sin_cos), the rest rotations and
   * lengths those pass 1 read (`terms`); then each lane's no-penetration projection (Ward &
   * Lin 2003 §5.5) on its own, the lanes' tips queried in one batch. The caller applies the
   * impulses that stop the projected tips' motion into the surfaces (scratch.stops).
   *
   * A projected segment turns alone for up to max_kept_turn: its child keeps the direction it
   * had (its hinge takes the turn back), so the strand beyond moves by the tip's small
   * displacement instead of swinging about the projected segment's root. Swinging it, a
   * strand lying on the head flicked its tip by millimetres at every projection and never
   * came to rest. What a projection turns beyond max_kept_turn the child turns with it: the
   * hinge taking back a larger turn stores it in its stiff spring, energy no motion paid for
   * (see max_kept_turn). */
  M3<Floats> frame{};
  V3<Floats> node{};
  for (int lane = 0; lane < W; lane++) {
    for (int j = 0; j < 3; j++) {
      put(frame.c[j], lane, root_frames[lane][j]);
    }
    put(node, lane, positions_wo_[first[lane] - 1]);
  }
  bool keep_direction[W] = {};
  vec3 kept_direction[W];
  for (size_t i = 0; i < n; i++) {
    const float *angle_records[W];
    for (int lane = 0; lane < W; lane++) {
      angle_records[lane] = &angles_[first[lane] + i].x;
    }
    V2<Floats> q;
    chain::gather2(angle_records, q);
    Floats trig[4];
    sin_cos<Floats, chain::Ints<W>>(q.x, trig[0], trig[1]);
    sin_cos<Floats, chain::Ints<W>>(q.y, trig[2], trig[3]);
    const M3<Floats> &rest = terms[i].rest;
    const Floats &d = terms[i].d;
    const M3<Floats> chart{{frame * rest.c[0], frame * rest.c[1], frame * rest.c[2]}};
    for (int lane = 0; lane < W; lane++) {
      if (keep_direction[lane]) {
        keep_direction[lane] = false;
        const vec4 kept = chart_deflection(get(chart, lane), kept_direction[lane],
                                           angles_[first[lane] + i])
                              .trig();
        for (int j = 0; j < 4; j++) {
          trig[j][lane] = kept[j];
        }
      }
    }
    rotate_chart(trig[0], trig[1], trig[2], trig[3], chart.c, frame.c);
    V3<Floats> tip = node + d * frame.c[2];
    ContactBatch<8> contacts;
    find_lane_contacts(colliders_, tip, contacts);
    for (int lane = 0; lane < W; lane++) {
      if (!lanes[lane]) {
        continue;
      }
      const size_t p = first[lane] + i;
      Deflection deflection(vec4(trig[0][lane], trig[1][lane], trig[2][lane], trig[3][lane]));
      vec3 lane_tip = get(tip, lane);
      vec3 normal;
      Contact contact;
      vec2 stopped_rates; /* the projection's zeros: the hinge keeps its rates, an impulse
                           * through the chain stops the tip (stop_at_contact) */
      if (colliders_ != nullptr && contacts.read(lane, contact) &&
          project_segment(substep, get(node, lane), lane_tip, d[lane], get(chart, lane),
                          angles_[p], stopped_rates, &normal, &contact))
      {
        scratch.stops[lane].emplace_back(i, normal);
        deflection = Deflection(angles_[p]);
        const mat3 projected = deflection.rotate(get(chart, lane));
        const mat3 unprojected = get(frame, lane);
        lane_tip = get(node, lane) + d[lane] * projected[2];
        for (int j = 0; j < 3; j++) {
          put(frame.c[j], lane, projected[j]);
        }
        put(tip, lane, lane_tip);
        if (i + 1 < n) {
          keep_direction[lane] = true;
          kept_direction[lane] = turn_beyond(
              Deflection(angles_[p + 1]).rotate(unprojected * rest_rotations_[p + 1])[2],
              unprojected[2], projected[2], max_kept_turn);
        }
      }
      trig_[p] = deflection.trig();
      velocities_wo_[p] = (lane_tip - positions_wo_[p]) * inv_h[lane];
      positions_wo_[p] = lane_tip;
    }
    node = tip;
  }
  for (int lane = 0; lane < W; lane++) {
    if (lanes[lane]) {
      /* After impulses (they change the rates at once) no trend to extrapolate. */
      uint8_t &known = accelerations_known_[size_t(curves[lane])];
      known = scratch.stops[lane].empty() ? uint8_t(std::min(known + 1, 2)) : 0;
    }
  }
}
#pragma GCC diagnostic pop

template<int W>
[[gnu::always_inline]] inline void StrandSolver::articulated_step(
    const Span<int64_t> curves, const Substep &substep, const Span<float> step_lengths,
    const Span<uint8_t> may_split,
    const Span<mat3> root_frames, const Span<vec3> winds, Counts &counts,
    const MutableSpan<int> r_outcomes)
{
  assert(curves.size() >= 1 && curves.size() <= W);
  const int lanes_num = int(curves.size());
  const size_t n = size_t(curve_points(curve_offsets_, curves[0]).size) - 1;
  LaneScratch<W> &scratch = lane_scratch<W>();
  std::vector<vec2> *lane_mid_accelerations = scratch.mid_accelerations;
  std::vector<Link<Lanes<W>>> &lane_links = scratch.links;
  std::vector<ArticulatedTerms<W>> &lane_terms = scratch.terms;
  lane_links.resize(n);
  lane_terms.resize(n);
  /* Every lane holds a strand: those past the group's repeat its first (their results are
   * dropped). */
  int64_t lane_curves[W];
  float lane_h[W];
  mat3 lane_frames[W];
  vec3 lane_winds[W];
  const vec2 *mids[W];
  bool predict[W];
  bool any_predict = false;
  for (int lane = 0; lane < W; lane++) {
    const int from = lane < lanes_num ? lane : 0;
    lane_curves[lane] = curves[from];
    lane_h[lane] = step_lengths[from];
    lane_frames[lane] = root_frames[from];
    lane_winds[lane] = winds[from];
    lane_mid_accelerations[lane].resize(n);
    mids[lane] = lane_mid_accelerations[from].data();
    predict[lane] = lane < lanes_num && needs_predictor(curves[lane]);
    any_predict |= predict[lane];
    if (lane < lanes_num) {
      r_outcomes[lane] = 1;
    }
  }
  /* The number of steps that keep a strand's turns within max_turn_per_step, if it may cut
   * its step and must. */
  const auto steps_needed = [&](const int lane,
                                const float fastest_turn) HAIRDYN_CHAIN_INLINE_LAMBDA {
    const float turn = step_lengths[lane] * fastest_turn;
    return may_split[lane] && turn > max_turn_per_step ?
               std::min(int(std::ceil(turn / max_turn_per_step)), max_turn_steps) :
               1;
  };
  /* Pass 1 (the contacts queried for the strands that take part, `queried`), then passes 2
   * and 3, for all lanes in vectors. */
  const bool implicit = params_.integrator == Integrator::Implicit;
  float fastest_turn[W];
  int64_t lane_contacts[W];
  const auto stage = [&](const uint8_t *queried) HAIRDYN_CHAIN_INLINE_LAMBDA {
    double hd[W];
    for (int lane = 0; lane < W; lane++) {
      hd[lane] = double(lane_h[lane]);
      lane_contacts[lane] = 0;
    }
    articulated_forward<W>(Span<int64_t>(lane_curves, W), substep, lane_h,
                           Span<mat3>(lane_frames, W), Span<vec3>(lane_winds, W),
                           Span<const vec2 *>(mids, W), lane_terms.data(), fastest_turn);
    if (colliders_ != nullptr) {
      add_contact_forces<W>(
          *colliders_, substep.reaction, lane_h, queried, n,
          [&](const vec3 &force, const float d, const vec3 &tip_velocity,
              const Contact &contact, const ReactionConstants &reaction) {
            return this->contact_force(force, d, tip_velocity, contact, reaction);
          },
          lane_terms.data(), scratch, lane_contacts);
    }
    /* Passes 2 and 3 for all lanes. */
    tip_to_root(lane_links.data(), lane_terms.data(), n, hd, implicit,
                double(params_.bending_damping));
    root_to_tip(lane_links.data(), n);
  };
  /* Stage 0, for the strands whose trend is not known: the predictor's q̈ at the step's start
   * rates (the fastest turn, and so a cut step, judged on them); stage 1 takes the step from
   * the rates at its middle (see the top), and a strand cuts its step if those turn too fast,
   * predicted or not: a strand at rest caught by a gale turns by nothing at the start of its
   * step and by tens of radians over it. */
  uint8_t queried[W];
  if (any_predict) {
    for (int lane = 0; lane < W; lane++) {
      queried[lane] = predict[lane];
      if (predict[lane]) {
        mid_step_accelerations(curves[lane], lane_mid_accelerations[lane]);
      }
    }
    stage(queried);
    for (int lane = 0; lane < lanes_num; lane++) {
      if (predict[lane]) {
        r_outcomes[lane] = steps_needed(lane, fastest_turn[lane]);
        for (size_t i = 0; i < n; i++) {
          lane_mid_accelerations[lane][i] = vec2(get(lane_links[i].acceleration, lane));
        }
      }
    }
  }
  for (int lane = 0; lane < W; lane++) {
    queried[lane] = lane < lanes_num && r_outcomes[lane] == 1;
    if (queried[lane] && !predict[lane]) {
      mid_step_accelerations(curves[lane], lane_mid_accelerations[lane]);
    }
  }
  stage(queried);
  /* The strands that take the step commit it (a strand that cuts it is left unchanged). */
  uint8_t committed[W] = {};
  for (int lane = 0; lane < lanes_num; lane++) {
    if (r_outcomes[lane] == 1) {
      r_outcomes[lane] = steps_needed(lane, fastest_turn[lane]);
    }
    if (r_outcomes[lane] > 1) {
      continue;
    }
    committed[lane] = 1;
    counts.contacts += lane_contacts[lane];
  }
  articulated_commit<W>(Span<int64_t>(lane_curves, W), substep, lane_h,
                        Span<mat3>(lane_frames, W), lane_terms.data(), committed,
                        MutableSpan<int>(r_outcomes.data(), lanes_num));
  for (int lane = 0; lane < lanes_num; lane++) {
    if (!committed[lane] || r_outcomes[lane] < 0) {
      continue;
    }
    const size_t first = size_t(curve_offsets_[size_t(curves[lane])]) + 1;
    counts.projections += int64_t(scratch.stops[lane].size());
    for (const auto &[body, normal] : scratch.stops[lane]) {
      stop_at_contact(lane_links.data(), lane_terms.data(), lane, n, body, real(normal),
                      MutableSpan<vec2>(angular_velocities_).slice(int64_t(first), int64_t(n)));
    }
  }
}

/* Each vector code's clone of the substep, with the lane width its registers hold best:
 * AVX-512 steps eight strands at once (the recursion's doubles in 512-bit vectors, pass 1's
 * floats in 256-bit ones, and 32 registers for the 3×3 blocks), AVX2 and the baseline four
 * (eight lanes on AVX2's 16 registers spill: 1.6× slower); the same bits on all (figures per
 * code: README, Performance). */
template<>
void StrandSolver::advance_articulated_as<VectorCode::Baseline>(
    const Span<int64_t> curves, const Substep &substep, const Span<mat3> root_frames,
    const Span<vec3> winds, Counts &counts, const MutableSpan<uint8_t> r_finite)
{
  articulated_substep<4>(curves, substep, root_frames, winds, counts, r_finite);
}
#if defined(__x86_64__)
template<>
__attribute__((target("avx2"))) void StrandSolver::advance_articulated_as<VectorCode::Avx2>(
    const Span<int64_t> curves, const Substep &substep, const Span<mat3> root_frames,
    const Span<vec3> winds, Counts &counts, const MutableSpan<uint8_t> r_finite)
{
  articulated_substep<4>(curves, substep, root_frames, winds, counts, r_finite);
}
template<>
__attribute__((target("avx2,avx512f,avx512vl,prefer-vector-width=256"))) void
StrandSolver::advance_articulated_as<VectorCode::Avx512>(
    const Span<int64_t> curves, const Substep &substep, const Span<mat3> root_frames,
    const Span<vec3> winds, Counts &counts, const MutableSpan<uint8_t> r_finite)
{
  articulated_substep<8>(curves, substep, root_frames, winds, counts, r_finite);
}
#endif

void StrandSolver::advance_articulated(const Span<int64_t> curves, const Substep &substep,
                                       const Span<mat3> root_frames, const Span<vec3> winds,
                                       Counts &counts, const MutableSpan<uint8_t> r_finite)
{
  switch (vector_code.load(std::memory_order_relaxed)) {
#if defined(__x86_64__)
    case VectorCode::Avx512:
      advance_articulated_as<VectorCode::Avx512>(curves, substep, root_frames, winds, counts,
                                                 r_finite);
      return;
    case VectorCode::Avx2:
      advance_articulated_as<VectorCode::Avx2>(curves, substep, root_frames, winds, counts,
                                               r_finite);
      return;
#endif
    default:
      advance_articulated_as<VectorCode::Baseline>(curves, substep, root_frames, winds, counts,
                                                   r_finite);
  }
}

VectorCode articulated_vector_code()
{
  return vector_code;
}

void set_articulated_vector_code(const VectorCode code)
{
  vector_code = std::min(code, cpu_vector_code());
}

}  // namespace hairdyn
