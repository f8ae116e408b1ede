/* The kurihara1993 strand model: Kurihara, Anjyo and Thalmann 1993, §2. Each hinge obeys
 *
 *   I θ̈ + γ θ̇ = M,   I φ̈ + γ φ̇ = M                      (Kurihara 1993, eq. 1)
 *
 * with hinge springs toward the rest angles (eq. 4) and the torque M of its own segment's
 * external force only (eq. 5–6), solved segment by segment from root to tip. Integration is
 * explicit (eq. 7) or implicit backward Euler (Ward & Lin 2003, appendix A). */
#include <cmath>

#include "strands/deflection.hh"
#include "strands/strand_solver.hh"

namespace hairdyn {

/* The torque of a force F at the centre turns with the segment: turned by dθ, u F·e_θ changes
 * by −u F·t dθ, and u cos θ F·e_φ by −u F·(t − sin θ x) dφ (x the chart's pole), where t is
 * the segment's direction: a pull along the segment holds it as a spring of stiffness
 * u F·t, u F·(t − sin θ x) would (a pendulum in the air's stream). Eq. 5 takes the torque
 * explicitly, and in a wind of 10 m/s the air's pull on the default hair, 120 times its
 * weight, makes that spring stiff enough that four substeps a frame feed its swing (ω h ≈
 * 2.2 on head_shake.blend's 2.75 cm segments, against the hinge's inertia with the spring's
 * armature): that hair, head still, thrashed at 1.3 m/s. The implicit integrator takes the
 * part of that stiffness that explicit steps cannot hold (beyond ω h = 1 against the step's
 * inertia I + h γ + h² k, within the ω h < 2 that I + h γ / 2 + h² k / 4 gives: see
 * strand_dynamics_articulated.cpp) linearly implicit, as it takes the spring
 * (hinge_integration.hh): the hinge's step as for a spring stiffer by that part. The pull of
 * a hanging segment's weight asks for none at four substeps. */
HingeStep<vec2> StrandSolver::pulled_hinge_step(const size_t i, const float h, const vec2 &k,
                                                const vec3 &force, const vec3 &t,
                                                const vec3 &phi_pull) const
{
  const HingeStep<vec2> &step = hinge_steps_[i];
  if (params_.integrator != Integrator::Implicit) {
    return step;
  }
  const float u = 0.5f * rest_lengths_[i];
  const vec2 pull = glm::max(u * vec2(glm::dot(force, t), glm::dot(force, phi_pull)), vec2(0.0f));
  /* What explicit steps hold: ω h = 1 against the step's inertia, 1 / gain. */
  const vec2 excess = glm::max(pull - 1.0f / (h * h * step.gain), vec2(0.0f));
  if (excess.x == 0.0f && excess.y == 0.0f) {
    return step;
  }
  return hinge_step(params_.integrator, moment_of_inertia(int64_t(i)), k + excess,
                    params_.damping, h);
}

bool StrandSolver::advance_kurihara(const IndexRange points, const Substep &substep, mat3 frame,
                                    vec3 node_velocity, const vec3 &wind_wo, Counts &counts)
{
  const float h = substep.h;
  const float inv_h = 1.0f / h;
  const vec2 k(params_.k_theta, params_.k_phi);
  vec3 node = positions_wo_[size_t(points.start)];
  for (size_t i = size_t(points.start) + 1; i < size_t(points.one_after_last()); i++) {
    const float d = rest_lengths_[i];
    const mat3 chart = frame * rest_rotations_[i];
    vec2 &angles = angles_[i];
    vec2 &omega = angular_velocities_[i];

    /* Where the segment is before its own update: old angles in the parent's new frame. */
    const Deflection old_deflection(trig_[i]);
    const mat3 old_frame = old_deflection.rotate(chart);
    const vec3 tip = node + d * old_frame[2];
    /* Rigid segment: the tip moves with the parent's motion (tip − previous tip) plus its
     * own rotation; the centre moves at the mean of the two ends. */
    const vec3 own_rate = omega.x * old_frame[0] +
                          old_deflection.cos_theta * omega.y * old_frame[1];
    const vec3 tip_velocity = (tip - positions_wo_[i]) * inv_h + d * own_rate;
    const vec3 center = node + (0.5f * d) * old_frame[2];
    const vec3 center_velocity = 0.5f * (node_velocity + tip_velocity);
    const vec3 force = segment_force(substep, i, center, center_velocity, tip, tip_velocity,
                                     wind_wo, counts);

    /* Kurihara 1993, eq. 5: M = u F·e_θ and M = v F·e_φ with u = d / 2 and v = (d / 2) cos θ,
     * half the segment's projection onto the plane normal to the chart's pole. */
    const float u = 0.5f * d;
    const vec2 torque(u * glm::dot(force, old_frame[0]),
                      u * old_deflection.cos_theta * glm::dot(force, old_frame[1]));

    /* Kurihara 1993, eq. 1 and 4: explicit eq. 7 or Ward & Lin 2003, appendix A. */
    advance_hinge(pulled_hinge_step(i, h, k, force, old_frame[2],
                                    old_frame[2] - old_deflection.sin_theta * chart[0]),
                  h, k, torque, angles, omega);
    if (hinge_runs_away(omega, d)) {
      return false;
    }

    /* Rebuild the segment from its new angles: its length cannot change. */
    Deflection deflection(angles);
    frame = deflection.rotate(chart);
    vec3 new_tip = node + d * frame[2];
    if (project_segment(substep, node, new_tip, d, chart, angles, omega)) {
      counts.projections++;
      deflection = Deflection(angles);
      frame = deflection.rotate(chart);
      new_tip = node + d * frame[2];
    }
    trig_[i] = deflection.trig();
    node_velocity = (new_tip - positions_wo_[i]) * inv_h;
    node = new_tip;
    positions_wo_[i] = node;
    velocities_wo_[i] = node_velocity;
  }
  return true;
}

}  // namespace hairdyn
