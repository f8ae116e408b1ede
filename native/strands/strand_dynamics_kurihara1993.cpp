#include "strands/strand_dynamics_kurihara1993.hh"

#include <algorithm>
#include <cmath>

#include "core/parallel.hh"
#include "core/random.hh"
#include "groom/frames.hh"
#include "groom/groom.hh"
#include "strands/hinge_integration.hh"

namespace hairdyn {

/* ---- wind --------------------------------------------------------------------------------- */

WindField::WindField(const StrandParams &params)
{
  const float direction_length = glm::length(params.wind_direction);
  if (direction_length < 1e-6f || params.wind_speed <= 0.0f) {
    return; /* No wind. */
  }
  const vec3 direction = params.wind_direction / direction_length;
  mean_ = params.wind_speed * direction;
  turbulence_ = params.wind_noise * params.wind_speed;
  /* Frozen turbulence: each wave travels with the mean wind (wave number f / U along the
   * wind) and varies across it on a similar scale, so neighbouring strands sway together and
   * distant ones independently. Frequencies spread over [0.6, 1.4] of the nominal one. */
  RandomNumberGenerator rng(uint64_t(params.seed) * 0x2545f4914f6cdd1dull + 1);
  const float speed = std::max(params.wind_speed, 0.1f);
  for (int component = 0; component < 3; component++) {
    for (int wave = 0; wave < waves_num; wave++) {
      const float omega = 2.0f * float(M_PI) * params.wind_noise_frequency *
                          rng.next_float(0.6f, 1.4f);
      const vec3 across(rng.next_float(-1.0f, 1.0f), rng.next_float(-1.0f, 1.0f),
                        rng.next_float(-1.0f, 1.0f));
      angular_frequencies_[component][wave] = omega;
      wave_vectors_[component][wave] = (omega / speed) * (direction + 0.5f * across);
      phases_[component][wave] = rng.next_float(0.0f, 2.0f * float(M_PI));
    }
  }
}

vec3 WindField::velocity_at(const vec3 &p, const float time) const
{
  if (turbulence_ == 0.0f) {
    return mean_;
  }
  vec3 noise(0.0f);
  for (int component = 0; component < 3; component++) {
    for (int wave = 0; wave < waves_num; wave++) {
      noise[component] += std::sin(angular_frequencies_[component][wave] * time -
                                   glm::dot(wave_vectors_[component][wave], p) +
                                   phases_[component][wave]);
    }
  }
  return mean_ + (turbulence_ / float(waves_num)) * noise;
}

/* ---- solver ------------------------------------------------------------------------------- */

namespace {

/* The deflection D(θ, φ) that turns a segment out of its rest frame (see the header): its
 * columns are e_θ = ∂d/∂θ, e_φ = ∂d/∂φ / cos θ and d = (sin θ, cos θ sin φ, cos θ cos φ). */
struct Deflection {
  float sin_theta, cos_theta, sin_phi, cos_phi;

  explicit Deflection(const vec2 &angles)
      : sin_theta(std::sin(angles.x)),
        cos_theta(std::cos(angles.x)),
        sin_phi(std::sin(angles.y)),
        cos_phi(std::cos(angles.y))
  {
  }
  /* From sines and cosines computed before: (sin θ, cos θ, sin φ, cos φ). */
  explicit Deflection(const vec4 &trig)
      : sin_theta(trig.x), cos_theta(trig.y), sin_phi(trig.z), cos_phi(trig.w)
  {
  }
  vec4 trig() const { return vec4(sin_theta, cos_theta, sin_phi, cos_phi); }

  /* chart · D without forming D: each column of D is a combination of chart's columns. */
  mat3 rotate(const mat3 &chart) const
  {
    const vec3 e_theta = cos_theta * chart[0] - sin_theta * (sin_phi * chart[1] + cos_phi * chart[2]);
    const vec3 e_phi = cos_phi * chart[1] - sin_phi * chart[2];
    const vec3 d = sin_theta * chart[0] + cos_theta * (sin_phi * chart[1] + cos_phi * chart[2]);
    return mat3(e_theta, e_phi, d);
  }
};

constexpr int max_projection_attempts = 4;

/* Where a segment of length d from `root` should point so that its tip, now at `tip` inside a
 * collider, lies on the tangent plane at the contact point T instead: the point of that plane
 * at distance d from the root nearest to the tip's swing. When the plane is out of reach,
 * toward T itself. */
vec3 swing_onto_plane(const vec3 &root, const vec3 &tip, const float d, const Contact &contact)
{
  const vec3 &n = contact.normal_wo;
  const float height = glm::dot(root - contact.surface_point_wo, n);
  if (std::abs(height) >= d) {
    return contact.surface_point_wo;
  }
  const vec3 foot = root - height * n;
  vec3 along = tip - foot;
  along -= glm::dot(along, n) * n;
  const float along_length = glm::length(along);
  if (along_length < 1e-12f) {
    return contact.surface_point_wo;
  }
  return foot + (std::sqrt(d * d - height * height) / along_length) * along;
}

}  // namespace

StrandSolver::StrandSolver(const Span<int32_t> curve_offsets, const Span<vec3> rest_positions_wo,
                           const mat4 &head_to_world_rest, const Span<vec3> root_normals_wo,
                           const StrandParams &params)
    : params_(params),
      wind_(params),
      curve_offsets_(curve_offsets.begin(), curve_offsets.end()),
      rest_positions_wo_(rest_positions_wo.begin(), rest_positions_wo.end()),
      rest_pose_(HeadPose::from_matrix(head_to_world_rest))
{
  assert(find_groom_error(curve_offsets, rest_positions_wo).empty());
  assert(root_normals_wo.is_empty() || root_normals_wo.size() == curves_num());
  const int64_t curves = curves_num();
  const size_t points = rest_positions_wo_.size();
  root_positions_head_.resize(size_t(curves));
  root_frames_head_.resize(size_t(curves));
  root_frames_wo_.resize(size_t(curves));
  rest_lengths_.assign(points, 0.0f);
  rest_rotations_.assign(points, mat3(1.0f));
  angles_.assign(points, vec2(0.0f));
  angular_velocities_.assign(points, vec2(0.0f));
  trig_.assign(points, vec4(0.0f, 1.0f, 0.0f, 1.0f));
  hinge_steps_.assign(points, HingeStep<vec2>{vec2(0.0f), vec2(0.0f)});
  positions_wo_.resize(points);
  velocities_wo_.resize(points);

  compute_root_frames(curve_offsets_, rest_positions_wo_, root_normals_wo, root_frames_wo_);
  const mat3 world_to_head_rotation = glm::transpose(rest_pose_.rotation_matrix());
  parallel_for(curves, 256, [&](const IndexRange range) {
    for (int64_t curve = range.start; curve < range.one_after_last(); curve++) {
      const IndexRange curve_range = curve_points(curve_offsets_, curve);
      const vec3 root_wo = rest_positions_wo_[size_t(curve_range.start)];
      root_positions_head_[size_t(curve)] = (world_to_head_rotation *
                                             (root_wo - rest_pose_.translation)) /
                                            rest_pose_.scale;
      root_frames_head_[size_t(curve)] = world_to_head_rotation * root_frames_wo_[size_t(curve)];
      /* Rest frames by twist-free transport from the root frame; R_i = F_{i-1}ᵀ F_i. */
      mat3 frame = root_frames_wo_[size_t(curve)];
      for (int64_t i = curve_range.start + 1; i < curve_range.one_after_last(); i++) {
        const vec3 segment = rest_positions_wo_[size_t(i)] - rest_positions_wo_[size_t(i - 1)];
        rest_lengths_[size_t(i)] = glm::length(segment);
        const mat3 next = parallel_transport(frame, segment / rest_lengths_[size_t(i)]);
        rest_rotations_[size_t(i)] = glm::transpose(frame) * next;
        frame = next;
      }
    }
  });
  reset();
}

void StrandSolver::set_params(const StrandParams &params)
{
  params_ = params;
  wind_ = WindField(params);
}

void StrandSolver::set_colliders(const ColliderSet *colliders, const CollisionParams &params)
{
  colliders_ = colliders;
  collision_params_ = params;
}

float StrandSolver::moment_of_inertia(const int64_t point) const
{
  /* Kurihara 1993, eq. 2 prints I = (1/3) c k⁴ d³. A uniform rod of line density c and length
   * d turning about its end has I = c d³ / 3; the extra k⁴ (k = segments per strand) is not
   * dimensionally an inertia and would make the motion depend on how finely a strand is cut,
   * so we read it as a typesetting artefact and use the rod: I = c d³ / 3. It matches eq. 5,
   * which applies the segment's load at its centre (lever arm d / 2). */
  const float d = rest_lengths_[size_t(point)];
  return params_.line_density * d * d * d / 3.0f;
}

ForceField::ForceField(const StrandParams &params, const HeadAcceleration &head)
{
  /* Kurihara 1993, eq. 6: F = d (g + a) + d f, with the line density c made explicit: gravity
   * and the head's inertial force act on the segment's mass c d (a head accelerating by a(r)
   * pushes the strand by −c d a(r)), the wind on its length. f = c_air (v_wind − v) is linear
   * drag, so the same term carries the wind and damps motion through still air. The head's
   * field a(r) = a + ω̇ × (r − c) + ω × (ω × (r − c)) is affine in r: a(r) = a + A (r − c) with
   * A = [ω̇]× + [ω]×², so per length F/d = c g − c a + c A c − c A r + c_air (v_wind − v). */
  const vec3 w = head.angular_velocity;
  const vec3 w_dot = head.angular_acceleration;
  const mat3 cross_w_dot(vec3(0.0f, w_dot.z, -w_dot.y), vec3(-w_dot.z, 0.0f, w_dot.x),
                         vec3(w_dot.y, -w_dot.x, 0.0f));
  const mat3 cross_w(vec3(0.0f, w.z, -w.y), vec3(-w.z, 0.0f, w.x), vec3(w.y, -w.x, 0.0f));
  const mat3 a = cross_w_dot + cross_w * cross_w;
  const float c = params.line_density;
  const vec3 gravity(0.0f, 0.0f, -params.gravity);
  base = c * (gravity - head.linear + a * head.center);
  gradient = -c * a;
  air_drag = params.air_drag;
}

void StrandSolver::prepare_hinges(const IndexRange points, const float h)
{
  const vec2 k(params_.k_theta, params_.k_phi);
  for (int64_t i = points.start + 1; i < points.one_after_last(); i++) {
    hinge_steps_[size_t(i)] = hinge_step(params_.integrator, moment_of_inertia(i), k,
                                         params_.damping, h);
  }
}

std::pair<int64_t, int64_t> StrandSolver::step_strand(const int64_t curve,
                                                      const Span<Substep> substeps)
{
  int64_t contacts = 0;
  int64_t projections = 0;
  const IndexRange points = curve_points(curve_offsets_, curve);
  const size_t root = size_t(points.start);
  const size_t end = size_t(points.one_after_last());
  prepare_hinges(points, substeps[0].h);
  const vec2 k(params_.k_theta, params_.k_phi);
  /* Each segment's deflection at the end of a substep is its deflection at the start of the
   * next: its sines and cosines are computed once per substep, not twice. */
  for (size_t i = root + 1; i < end; i++) {
    trig_[i] = Deflection(angles_[i]).trig();
  }
  for (const Substep &substep : substeps) {
    const float h = substep.h;
    const float inv_h = 1.0f / h;
    /* The root frame and root are carried rigidly by the head. */
    mat3 frame = substep.rotation * root_frames_head_[size_t(curve)];
    vec3 node = substep.pose.transform_point(root_positions_head_[size_t(curve)]);
    vec3 node_velocity = (node - positions_wo_[root]) * inv_h;
    positions_wo_[root] = node;
    velocities_wo_[root] = node_velocity;
    const vec3 wind_wo = wind_.velocity_at(node, substep.time);

    /* Root to tip (Kurihara 1993, §2): each segment moves in its parent's new frame. */
    for (size_t i = root + 1; i < end; i++) {
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

      /* The force on this segment, lumped on its tip node (Kurihara 1993, eq. 6). This is the
       * one place where a node's force is assembled: a collision response (eq. 12–15)
       * filters it here, from the node's position `tip` and velocity `tip_velocity`, before
       * it becomes a torque. */
      vec3 force = substep.forces.on_segment(d, center, center_velocity, wind_wo);
      Contact contact;
      if (colliders_ != nullptr && colliders_->find_contact(tip, contact)) {
        /* Kurihara 1993, eq. 12–15, per unit mass: the segment's mass c d sits on its tip. */
        const float mass = params_.line_density * d;
        force = mass * reaction_constraint_force(force / mass, tip_velocity, contact,
                                                 substep.reaction);
        contacts++;
      }

      /* Kurihara 1993, eq. 5: M = u F·e_θ and M = v F·e_φ with u = d / 2 and v = (d / 2) cos θ,
       * half the segment's projection onto the plane normal to the chart's pole. */
      const float u = 0.5f * d;
      const vec2 torque(u * glm::dot(force, old_frame[0]),
                        u * old_deflection.cos_theta * glm::dot(force, old_frame[1]));

      /* Kurihara 1993, eq. 1 and 4: explicit eq. 7 or Ward & Lin 2003, appendix A. */
      advance_hinge(hinge_steps_[i], h, k, torque, angles, omega);

      /* Rebuild the segment from its new angles: its length cannot change. */
      Deflection deflection(angles);
      frame = deflection.rotate(chart);
      vec3 new_tip = node + d * frame[2];
      /* Ward & Lin 2003 §5.5: no node ends a step inside a body. The segment turns about its
       * root until its tip lies on the surface's tangent plane at T, and stops turning (an
       * inelastic contact). On a curved surface one turn can leave the tip a little inside;
       * a few more settle it. */
      for (int attempt = 0; attempt < max_projection_attempts; attempt++) {
        if (colliders_ == nullptr || !colliders_->find_contact(new_tip, contact) ||
            contact.depth <= substep.projection_tolerance_wo)
        {
          break;
        }
        const vec3 target = swing_onto_plane(node, new_tip, d, contact);
        const vec3 local = glm::transpose(chart) * glm::normalize(target - node);
        angles = vec2(std::asin(glm::clamp(local.x, -1.0f, 1.0f)), std::atan2(local.y, local.z));
        omega = vec2(0.0f);
        deflection = Deflection(angles);
        frame = deflection.rotate(chart);
        new_tip = node + d * frame[2];
        projections += attempt == 0 ? 1 : 0;
      }
      trig_[i] = deflection.trig();
      node_velocity = (new_tip - positions_wo_[i]) * inv_h;
      node = new_tip;
      positions_wo_[i] = node;
      velocities_wo_[i] = node_velocity;
    }
  }
  root_frames_wo_[size_t(curve)] = substeps.last().rotation * root_frames_head_[size_t(curve)];
  return {contacts, projections};
}

void StrandSolver::step(const float frame_dt, const mat4 &head_to_world)
{
  assert(frame_dt > 0.0f);
  const HeadPose pose = HeadPose::from_matrix(head_to_world);

  /* The head's velocity over this frame and its change since the last one; within the frame
   * the head moves along the interpolated path with these rates. */
  const HeadVelocity velocity = HeadVelocity::between(pose_, pose, frame_dt);
  HeadAcceleration head;
  head.linear = (velocity.linear - head_velocity_.linear) / frame_dt;
  head.angular_velocity = velocity.angular;
  head.angular_acceleration = (velocity.angular - head_velocity_.angular) / frame_dt;

  const int substeps_num = std::max(params_.substeps, 1);
  std::vector<Substep> substeps(static_cast<size_t>(substeps_num));
  for (int s = 0; s < substeps_num; s++) {
    const float t = float(s + 1) / float(substeps_num);
    Substep &substep = substeps[size_t(s)];
    substep.h = frame_dt / float(substeps_num);
    substep.time = time_ + t * frame_dt;
    substep.pose = HeadPose::interpolate(pose_, pose, t);
    substep.rotation = substep.pose.rotation_matrix();
    head.center = substep.pose.translation;
    substep.forces = ForceField(params_, head);
    if (colliders_ != nullptr) {
      substep.reaction = ReactionConstants::from(collision_params_, substep.h);
      substep.projection_tolerance_wo = collision_params_.projection_tolerance *
                                        colliders_->size_wo();
    }
  }

  /* Counts per chunk of strands, summed in order: deterministic for any thread count. */
  const int64_t grain = 32;
  std::vector<std::pair<int64_t, int64_t>> counts(size_t((curves_num() + grain - 1) / grain));
  parallel_for(curves_num(), grain, [&](const IndexRange range) {
    std::pair<int64_t, int64_t> &chunk = counts[size_t(range.start / grain)];
    for (int64_t curve = range.start; curve < range.one_after_last(); curve++) {
      const auto [contacts, projections] = step_strand(curve, substeps);
      chunk.first += contacts;
      chunk.second += projections;
    }
  });
  contacts_num_ = projections_num_ = 0;
  for (const auto &[contacts, projections] : counts) {
    contacts_num_ += contacts;
    projections_num_ += projections;
  }

  pose_ = pose;
  head_velocity_ = velocity;
  time_ += frame_dt;
}

void StrandSolver::reset_dynamics(const HeadPose &pose)
{
  pose_ = pose;
  head_velocity_ = HeadVelocity();
  time_ = 0.0f;
  std::fill(angles_.begin(), angles_.end(), vec2(0.0f));
  std::fill(angular_velocities_.begin(), angular_velocities_.end(), vec2(0.0f));
  std::fill(velocities_wo_.begin(), velocities_wo_.end(), vec3(0.0f));
  const mat3 rotation = pose.rotation_matrix();
  for (size_t curve = 0; curve < root_frames_wo_.size(); curve++) {
    root_frames_wo_[curve] = rotation * root_frames_head_[curve];
  }
}

void StrandSolver::reset()
{
  reset_dynamics(rest_pose_);
  /* The exact rest shape, not its reconstruction: an unmoved head returns it bit for bit. */
  positions_wo_ = rest_positions_wo_;
}

void StrandSolver::reset(const mat4 &head_to_world)
{
  reset_dynamics(HeadPose::from_matrix(head_to_world));
  parallel_for(curves_num(), 256, [&](const IndexRange range) {
    for (int64_t curve = range.start; curve < range.one_after_last(); curve++) {
      const IndexRange points = curve_points(curve_offsets_, curve);
      mat3 frame = root_frames_wo_[size_t(curve)];
      vec3 node = pose_.transform_point(root_positions_head_[size_t(curve)]);
      positions_wo_[size_t(points.start)] = node;
      for (int64_t i = points.start + 1; i < points.one_after_last(); i++) {
        frame = frame * rest_rotations_[size_t(i)];
        node += rest_lengths_[size_t(i)] * frame[2];
        positions_wo_[size_t(i)] = node;
      }
    }
  });
}

}  // namespace hairdyn
