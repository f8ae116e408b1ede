#include "strands/strand_solver.hh"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "core/parallel.hh"
#include "groom/frames.hh"
#include "groom/groom.hh"
#include "groom/pins.hh"
#include "strands/deflection.hh"

namespace hairdyn {

namespace {

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

/* κ of the articulated take-back's φ̇ near the chart's pole (take_back_strand): the twist's
 * weight against the node's velocity. The rate is c² / (c² + κ) of the exact one (c = cos θ):
 * with 0.01, 98% while |c| > 0.7 (a hinge within 45° of its rest direction), 90% at |c| = 0.3;
 * and at most 5 times the node's speed over the segment's length. */
constexpr float pole_twist_weight = 0.01f;

/* The part of a change δ of a hinge's rates ω = (θ̇, φ̇) that only slows them: each moves
 * toward zero by at most its own size, never past it (see take_back_strand). */
vec2 slowing_part(const vec2 &omega, const vec2 &delta)
{
  const vec2 low = glm::min(omega, vec2(0.0f)), high = glm::max(omega, vec2(0.0f));
  return glm::clamp(omega + delta, low, high) - omega;
}

mat4 pose_matrix(const HeadPose &pose)
{
  return glm::translate(mat4(1.0f), pose.translation) * glm::mat4_cast(pose.rotation) *
         glm::scale(mat4(1.0f), pose.scale);
}

}  // namespace

StrandSolver::StrandSolver(const Span<int32_t> curve_offsets, const Span<vec3> rest_positions_wo,
                           const mat4 &head_to_world_rest, const Span<vec3> root_normals_wo,
                           const StrandParams &params, const WindParams &wind,
                           const glm::dvec3 &origin_wo)
    : params_(params),
      origin_wo_(origin_wo),
      wind_params_(wind),
      wind_(wind),
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
  accelerations_.assign(points, vec2(0.0f));
  earlier_accelerations_.assign(points, vec2(0.0f));
  accelerations_known_.assign(size_t(curves_num()), 0);
  group_strands();
  trig_.assign(points, vec4(0.0f, 1.0f, 0.0f, 1.0f));
  hinge_steps_.assign(points, HingeStep<vec2>{vec2(0.0f), vec2(0.0f)});
  hinge_stiffness_.assign(points, 0.0f);
  positions_wo_.resize(points);
  velocities_wo_.resize(points);
  pinned_.assign(points, 0);

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
  shortest_segment_ = std::numeric_limits<float>::infinity();
  for (int64_t curve = 0; curve < curves; curve++) {
    const IndexRange curve_range = curve_points(curve_offsets_, curve);
    for (int64_t i = curve_range.start + 1; i < curve_range.one_after_last(); i++) {
      shortest_segment_ = std::min(shortest_segment_, rest_lengths_[size_t(i)]);
    }
  }
  update_hinge_stiffness();
  reset();
}

void StrandSolver::set_params(const StrandParams &params)
{
  params_ = params;
  update_hinge_stiffness();
}

void StrandSolver::set_wind(const WindParams &wind)
{
  wind_params_ = wind;
  wind_ = WindField(wind);
}

void StrandSolver::set_colliders(const ColliderSet *colliders, const CollisionParams &params)
{
  colliders_ = colliders;
  collision_params_ = params;
}

void StrandSolver::add_pass(SubstepPass *pass)
{
  assert(pass != nullptr);
  passes_.push_back(pass);
  pass_ms_.push_back(0.0);
}

void StrandSolver::clear_passes()
{
  passes_.clear();
  pass_ms_.clear();
}

void StrandSolver::set_pinned(const Span<uint8_t> pinned)
{
  assert(pinned.is_empty() || pinned.size() == int64_t(rest_positions_wo_.size()));
  const int64_t curves = curves_num();
  std::fill(pinned_.begin(), pinned_.end(), 0);
  pins_.clear();
  pins_rest_head_.clear();
  pin_offsets_.assign(size_t(curves + 1), 0);
  for (int64_t curve = 0; curve < curves && !pinned.is_empty(); curve++) {
    const IndexRange points = curve_points(curve_offsets_, curve);
    for (int64_t i = points.start + 1; i < points.one_after_last(); i++) {
      if (pinned[i]) {
        pinned_[size_t(i)] = 1;
        pins_.push_back(i);
        pins_rest_head_.push_back(
            rest_pose_.inverse_transform_point(rest_positions_wo_[size_t(i)]));
      }
    }
    pin_offsets_[size_t(curve + 1)] = int64_t(pins_.size());
  }
  if (pins_.empty()) {
    pin_offsets_.clear();
  }
  /* A strand with pins takes them back after every substep, with or without passes. */
  positions_before_.resize(rest_positions_wo_.size());
  velocities_before_.resize(rest_positions_wo_.size());
}

void StrandSolver::set_stepped(const Span<uint8_t> stepped, const Span<uint8_t> in_passes)
{
  assert(stepped.is_empty() || stepped.size() == curves_num());
  assert(in_passes.is_empty() || in_passes.size() == curves_num());
  stepped_.assign(stepped.begin(), stepped.end());
  stepped_curves_.clear();
  pass_view_.curves.clear();
  for (int64_t curve = 0; curve < stepped.size(); curve++) {
    if (stepped[curve]) {
      stepped_curves_.push_back(curve);
    }
  }
  const bool narrowed = !in_passes.is_empty();
  for (int64_t curve = 0; curve < curves_num(); curve++) {
    if ((stepped.is_empty() || stepped[curve]) && (!narrowed || in_passes[curve])) {
      pass_view_.curves.push_back(curve);
    }
  }
  pass_view_used_ = !stepped.is_empty() || narrowed;
  pass_view_.offsets.assign(1, 0);
  for (const int64_t curve : pass_view_.curves) {
    pass_view_.offsets.push_back(pass_view_.offsets.back() +
                                 int32_t(curve_points(curve_offsets_, curve).size));
  }
  gather_view_volumes();
  group_strands();
}

void StrandSolver::set_pass_volumes(PassVolumes volumes)
{
  const size_t points = rest_positions_wo_.size();
  assert(volumes.radii.empty() || volumes.radii.size() == points);
  assert(volumes.strip_half_widths_hs.empty() || volumes.strip_half_widths_hs.size() == points);
  assert(volumes.rest_positions_hs.empty() || volumes.rest_positions_hs.size() == points);
  assert(volumes.rest_clearances.empty() || volumes.rest_clearances.size() == points);
  (void)points;
  pass_volumes_ = std::move(volumes);
  gather_view_volumes();
}

namespace {

/* The points of `curves` (their new offsets `offsets`) out of a per point array, or nothing
 * from an empty one. */
template<typename T>
void gather_points(const Span<int32_t> curve_offsets, const Span<int64_t> curves,
                   const Span<int32_t> offsets, const std::vector<T> &from, std::vector<T> &to)
{
  to.resize(from.empty() ? 0 : size_t(offsets[offsets.size() - 1]));
  if (from.empty()) {
    return;
  }
  parallel_for(curves.size(), 256, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      const IndexRange points = curve_points(curve_offsets, curves[i]);
      std::copy_n(&from[size_t(points.start)], points.size, &to[size_t(offsets[i])]);
    }
  });
}

}  // namespace

void StrandSolver::gather_pass_view()
{
  PassView &view = pass_view_;
  gather_points(curve_offsets_, view.curves, view.offsets, positions_wo_, view.positions);
  gather_points(curve_offsets_, view.curves, view.offsets, velocities_wo_, view.velocities);
  gather_points(curve_offsets_, view.curves, view.offsets, positions_start_,
                view.start_positions);
}

void StrandSolver::gather_view_volumes()
{
  PassView &view = pass_view_;
  if (!pass_view_used_) {
    view.volumes = {};
    return;
  }
  const auto gather = [&](const auto &from, auto &to) {
    gather_points(curve_offsets_, view.curves, view.offsets, from, to);
  };
  gather(pass_volumes_.radii, view.volumes.radii);
  gather(pass_volumes_.strip_half_widths_hs, view.volumes.strip_half_widths_hs);
  gather(pass_volumes_.rest_positions_hs, view.volumes.rest_positions_hs);
  gather(pass_volumes_.rest_clearances, view.volumes.rest_clearances);
}

void StrandSolver::scatter_pass_view()
{
  const PassView &view = pass_view_;
  parallel_for(int64_t(view.curves.size()), 256, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      const IndexRange to = curve_points(curve_offsets_, view.curves[size_t(i)]);
      const size_t from = size_t(view.offsets[size_t(i)]), n = size_t(to.size);
      std::copy_n(&view.positions[from], n, &positions_wo_[size_t(to.start)]);
      std::copy_n(&view.velocities[from], n, &velocities_wo_[size_t(to.start)]);
    }
  });
}

void StrandSolver::group_strands()
{
  /* Each strand joins the open group of its point count, in the order the strands come; a
   * full group closes. A group holds the stepped strands / (16 × threads), within
   * group_strands_min and group_strands_max: 16 groups for each thread. The groups change no
   * strand's bits (each strand keeps the bits it has alone). */
  groups_.clear();
  std::unordered_map<int32_t, size_t> open; /* point count -> group */
  const bool masked = !stepped_.empty();
  const int64_t stepped_num = masked ? int64_t(stepped_curves_.size()) : curves_num();
  grouped_for_threads_ = thread_num();
  const int64_t group_size = std::clamp<int64_t>(stepped_num / (16 * grouped_for_threads_),
                                                 group_strands_min, group_strands_max);
  for (int64_t index = 0; index < stepped_num; index++) {
    const int64_t curve = masked ? stepped_curves_[size_t(index)] : index;
    const int32_t points_num = curve_offsets_[size_t(curve + 1)] - curve_offsets_[size_t(curve)];
    auto [slot, fresh] = open.try_emplace(points_num, groups_.size());
    if (fresh || groups_[slot->second].size == group_size) {
      slot->second = groups_.size();
      groups_.emplace_back();
    }
    StrandGroup &group = groups_[slot->second];
    group.curves[group.size++] = curve;
  }
}

void StrandSolver::place_curve(const int64_t curve)
{
  /* The dynamics' own placement (a segment's frame is its parent's, times its rest rotation,
   * times its deflection), with the velocities the rates give: a segment turns at
   * Ω_i = Ω_{i-1} + θ̇ e_φ − φ̇ x (x the chart's pole, see take_back_strand) on top of the
   * head's turn, and its tip moves at v_i = v_{i-1} + d Ω_i × t. */
  const IndexRange points = curve_points(curve_offsets_, curve);
  accelerations_known_[size_t(curve)] = 0;
  mat3 frame = pose_.rotation_matrix() * root_frames_head_[size_t(curve)];
  root_frames_wo_[size_t(curve)] = frame;
  vec3 node = pose_.transform_point(root_positions_head_[size_t(curve)]);
  vec3 node_velocity = head_velocity_.of_point(node - pose_.translation);
  vec3 omega = head_velocity_.angular;
  positions_wo_[size_t(points.start)] = node;
  velocities_wo_[size_t(points.start)] = node_velocity;
  for (int64_t i = points.start + 1; i < points.one_after_last(); i++) {
    const float d = rest_lengths_[size_t(i)];
    const mat3 chart = frame * rest_rotations_[size_t(i)];
    const Deflection deflection(angles_[size_t(i)]);
    frame = deflection.rotate(chart);
    trig_[size_t(i)] = deflection.trig();
    const vec2 rate = angular_velocities_[size_t(i)];
    omega += rate.x * frame[1] - rate.y * chart[0];
    node += d * frame[2];
    node_velocity += d * glm::cross(omega, frame[2]);
    positions_wo_[size_t(i)] = node;
    velocities_wo_[size_t(i)] = node_velocity;
  }
}

void StrandSolver::set_curve_state(const int64_t curve, const Span<vec2> angles,
                                   const Span<vec2> angular_velocities)
{
  const IndexRange points = curve_points(curve_offsets_, curve);
  assert(angles.size() == points.size && angular_velocities.size() == points.size);
  for (int64_t k = 1; k < points.size; k++) {
    angles_[size_t(points.start + k)] = angles[k];
    angular_velocities_[size_t(points.start + k)] = angular_velocities[k];
  }
  place_curve(curve);
}

double StrandSolver::pass_ms(const std::string &name) const
{
  double ms = 0.0;
  for (size_t i = 0; i < passes_.size(); i++) {
    ms += name == passes_[i]->name() ? pass_ms_[i] : 0.0;
  }
  return ms;
}

float StrandSolver::moment_of_inertia(const int64_t point) const
{
  /* Kurihara 1993, eq. 2 prints I = (1/3) c k⁴ d³. A uniform rod of line density c and length
   * d turning about its end has I = c d³ / 3; the extra k⁴ (k = segments per strand) is not
   * dimensionally an inertia and would make the motion depend on how finely a strand is cut,
   * so we read it as a typesetting artefact and use the rod: I = c d³ / 3. It matches eq. 5,
   * which applies the segment's load at its centre (lever arm d / 2). */
  const float d = rest_lengths_[size_t(point)];
  return line_density() * d * d * d / 3.0f;
}

ForceField::ForceField(const StrandParams &params, const float line_density,
                       const HeadAcceleration &head, const HeadVelocity &head_velocity)
{
  /* Kurihara 1993, eq. 6: F = d (g + a) + d f, with the line density c made explicit: gravity
   * and the head's fictitious force act on the segment's mass c d, the wind on its length.
   * f = c_air (v_wind − v) is linear drag, so the same term carries the wind and damps motion
   * through still air. The head's a_rel(r, v_rel) = a + A (r − c) + 2 ω × v_rel with
   * A = [ω̇]× + [ω]×² and v_rel = v − v_head − ω × (r − c) (core/head_motion.hh), so per length
   *   F/d = c g − c a + c A c − c A r − 2c [ω]× (v − v_head + [ω]× c − [ω]× r) + c_air (v_wind − v).
   */
  const float c = line_density;
  const mat3 a = head.transport_gradient();
  const mat3 w = cross_matrix(head.angular_velocity);
  const mat3 coriolis = 2.0f * c * w;
  base = c * (params.gravity - head.linear + a * head.center) +
         coriolis * (head_velocity.linear - w * head.center);
  position_gradient = -c * a + coriolis * w;
  velocity_gradient = -coriolis - mat3(params.air_drag);
  air_drag = params.air_drag;
  constexpr float air_density = 1.2f; /* kg/m³, at 20 °C */
  form_drag = air_density * params.form_drag * params.strand_radius;
  mass_per_length = c;
}

void StrandSolver::update_hinge_stiffness()
{
  /* The discrete bending energy ½ Σ EI κ² l with κ = angle / l at each hinge, l the length of
   * strand the hinge stands for (its Voronoi length): k = EI(s) / l at arc length s. */
  parallel_for(curves_num(), 256, [&](const IndexRange range) {
    for (int64_t curve = range.start; curve < range.one_after_last(); curve++) {
      const IndexRange points = curve_points(curve_offsets_, curve);
      double length = 0.0;
      for (int64_t i = points.start + 1; i < points.one_after_last(); i++) {
        length += rest_lengths_[size_t(i)];
      }
      double s = 0.0;
      for (int64_t i = points.start + 1; i < points.one_after_last(); i++) {
        const double d = rest_lengths_[size_t(i)];
        const double voronoi = i == points.start + 1 ? 0.5 * d :
                                                       0.5 * (d + rest_lengths_[size_t(i - 1)]);
        hinge_stiffness_[size_t(i)] = float(params_.bending_stiffness_at(s, length) / voronoi);
        s += d;
      }
    }
  });
}

void StrandSolver::prepare_strand(const int64_t curve, const float h)
{
  if (params_.model == StrandModel::Articulated) {
    return; /* its hinge stiffnesses follow the params (update_hinge_stiffness) */
  }
  /* Kurihara 1993's hinges: the integrator's coefficients for this frame's h. (The sines and
   * cosines of the angles, trig_, are kept with the angles by everything that sets them.) */
  const IndexRange points = curve_points(curve_offsets_, curve);
  const vec2 k(params_.k_theta, params_.k_phi);
  for (int64_t i = points.start + 1; i < points.one_after_last(); i++) {
    hinge_steps_[size_t(i)] = hinge_step(params_.integrator, moment_of_inertia(i), k,
                                         params_.damping, h);
  }
}

vec3 StrandSolver::segment_force(const Substep &substep, const size_t i, const vec3 &center,
                                 const vec3 &center_velocity, const vec3 &tip,
                                 const vec3 &tip_velocity, const vec3 &wind_wo,
                                 Counts &counts) const
{
  const float d = rest_lengths_[i];
  const vec3 force = substep.forces.on_segment(d, center, center_velocity, wind_wo, substep.h);
  Contact contact;
  if (colliders_ == nullptr || !colliders_->find_contact(tip, contact)) {
    return force;
  }
  counts.contacts++;
  return contact_force(force, d, tip_velocity, contact, substep.reaction);
}

vec3 StrandSolver::contact_force(const vec3 &force, const float d, const vec3 &tip_velocity,
                                 const Contact &contact, const ReactionConstants &reaction) const
{
  /* Kurihara 1993, eq. 12–15, per unit mass: the segment's mass c d sits on its tip. */
  const float mass = line_density() * d;
  return mass * reaction_constraint_force(force / mass, tip_velocity, contact, reaction);
}

bool StrandSolver::project_segment(const Substep &substep, const vec3 &node, vec3 tip,
                                   const float d, const mat3 &chart, vec2 &angles,
                                   vec2 &omega, vec3 *r_normal,
                                   const Contact *contact_at_tip) const
{
  if (colliders_ == nullptr) {
    return false;
  }
  /* Ward & Lin 2003 §5.5: no node ends a step inside a body. The segment turns about its root
   * until its tip lies on the surface's tangent plane at T, and stops turning (an inelastic
   * contact). On a curved surface one turn can leave the tip a little inside; a few more
   * settle it. */
  bool moved = false;
  Contact contact;
  for (int attempt = 0; attempt < max_projection_attempts; attempt++) {
    const bool known = attempt == 0 && contact_at_tip != nullptr;
    if (known) {
      contact = *contact_at_tip;
    }
    if (!(known || colliders_->find_contact(tip, contact)) ||
        contact.depth <= substep.projection_tolerance_wo) {
      break;
    }
    if (glm::dot(node - contact.surface_point_wo, contact.normal_wo) <= -d) {
      /* The root is deeper than the segment is long (a groom grown inside the body, as
       * Sintel's roots are): no turn brings the tip out, and forcing it to T each step made
       * the articulated chain run away. The reaction constraint pushes it out instead. */
      break;
    }
    const vec3 along = swing_onto_plane(node, tip, d, contact) - node;
    omega = vec2(0.0f);
    if (r_normal != nullptr) {
      *r_normal = contact.normal_wo;
    }
    tip = node + d * chart_deflection(chart, along, angles).rotate(chart)[2];
    moved = true;
  }
  return moved;
}

vec3 StrandSolver::place_root(const int64_t curve, const Substep &substep, mat3 &r_frame)
{
  const size_t root = size_t(curve_offsets_[size_t(curve)]);
  /* The root frame and root are carried rigidly by the head. */
  r_frame = substep.rotation * root_frames_head_[size_t(curve)];
  const vec3 node = substep.pose.transform_point(root_positions_head_[size_t(curve)]);
  const vec3 node_velocity = (node - positions_wo_[root]) / substep.h;
  positions_wo_[root] = node;
  velocities_wo_[root] = node_velocity;
  root_frames_wo_[size_t(curve)] = r_frame;
  return wind_.velocity_at(node, substep.time);
}

void StrandSolver::advance_strands(const Span<int64_t> curves, const Substep &substep,
                                   Counts &counts, const MutableSpan<uint8_t> r_finite)
{
  mat3 frames[group_strands_max];
  vec3 winds[group_strands_max];
  for (int64_t k = 0; k < curves.size(); k++) {
    winds[k] = place_root(curves[k], substep, frames[k]);
  }
  if (params_.model == StrandModel::Kurihara1993) {
    for (int64_t k = 0; k < curves.size(); k++) {
      const IndexRange points = curve_points(curve_offsets_, curves[k]);
      r_finite[k] = advance_kurihara(points, substep, frames[k],
                                     velocities_wo_[size_t(points.start)], winds[k], counts);
    }
  }
  else {
    advance_articulated(curves, substep, Span<mat3>(frames, curves.size()),
                        Span<vec3>(winds, curves.size()), counts, r_finite);
  }
  for (int64_t k = 0; k < curves.size(); k++) {
    if (!r_finite[k]) {
      /* Diverged: counted, and the strand put back at rest. */
      counts.diverged++;
      place_at_rest(curves[k], substep.pose);
    }
  }
}

void StrandSolver::pin_strand(const int64_t curve, const Substep &substep)
{
  /* The nodes a pin moves, before it moved them (per thread: strands run in parallel). */
  thread_local std::vector<vec3> unpinned;
  int64_t held = curve_points(curve_offsets_, curve).start; /* the root, then each pin */
  /* Roots are kinematic whatever a pass did (as take_back_strand has them). */
  positions_wo_[size_t(held)] = substep.pose.transform_point(root_positions_head_[size_t(curve)]);
  for (int64_t k = pin_offsets_[size_t(curve)]; k < pin_offsets_[size_t(curve + 1)]; k++) {
    const int64_t pin = pins_[size_t(k)];
    const int64_t n = pin - held + 1;
    const vec3 target = substep.pose.transform_point(pins_rest_head_[size_t(k)]);
    const MutableSpan<vec3> chain = MutableSpan<vec3>(positions_wo_).slice(held, n);
    const Span<float> lengths = Span<float>(rest_lengths_).slice(held, n);
    float length = 0.0f;
    for (int64_t i = 1; i < n; i++) {
      length += lengths[i];
    }
    unpinned.assign(chain.begin(), chain.end());
    reach_pin(chain, lengths, target, pin_tolerance_relative * length);
    /* The chain's nodes move as a position-based constraint moves them: the correction is
     * velocity (Müller et al. 2007, "Position based dynamics", §3.1, v = (x_new − x) / h),
     * so no velocity keeps pulling them off the pin. The pin moves with the head. */
    for (int64_t i = 1; i + 1 < n; i++) {
      velocities_wo_[size_t(held + i)] += (chain[i] - unpinned[size_t(i)]) / substep.h;
    }
    velocities_wo_[size_t(pin)] = substep.head_velocity.of_point(target -
                                                                  substep.pose.translation);
    held = pin;
  }
}

bool StrandSolver::settle_strand(const int64_t curve, const Substep &substep, Counts &counts)
{
  if (has_pins(curve)) {
    pin_strand(curve, substep);
  }
  take_back_strand(curve, substep);
  if (strand_is_sane(curve)) {
    return true;
  }
  counts.diverged++;
  place_at_rest(curve, substep.pose);
  return false;
}

void StrandSolver::take_back_strand(const int64_t curve, const Substep &substep)
{
  /* What the passes changed (positions_before_, velocities_before_ hold the nodes as the
   * strands left them) comes back root to tip: a moved node turns its segment toward it about
   * the segment's (possibly moved) root, the same swing as the collision projection, and a
   * change of a node's velocity changes its hinge's rates.
   *
   * The rates are relative to the parent segment, which carries everything distal to it (in
   * both models a segment's frame is its parent's frame times its own deflection): segment i
   * turns at Ω_i = Ω_{i-1} + θ̇ e_φ − φ̇ x (x the chart's pole), and its tip moves at
   * v_i = v_{i-1} + d Ω_i × t = v_{i-1} + d Ω_{i-1} × t + d (θ̇ e_θ + φ̇ cos θ e_φ). So a hinge
   * takes only the part of its node's change that its parents' new rates do not already
   * give: with ΔΩ and Δv̂ the changes the new rates make up to the parent,
   *   d (Δθ̇ e_θ + Δφ̇ cos θ e_φ) = Δv_i − (Δv̂_{i-1} + d ΔΩ_{i-1} × t).
   * (Taking Δv_i − Δv_{i-1} instead gives a pass's uniform push to the first hinge and again
   * to every hinge below it: the tip of a strand of n segments would move n times as fast.)
   * The along-segment part of a change, which no rate can give, is dropped and not passed on.
   * A strand the passes left alone keeps its bits.
   *
   * In Kurihara 1993's model a pass may only slow a hinge: each of its rates moves toward zero,
   * never past it, and never grows. Its hinges are independent oscillators (eq. 1), each with
   * its own segment's inertia whatever it carries, so the exact rates of a local change (the
   * hinge beside it turning, the hinges below turning back to keep their nodes in place, a φ̇
   * of 1 / cos θ times the speed near the chart's pole) are not kept in balance by its step:
   * strands pushed by hair–hair collision every substep gained energy until they ran away
   * (9–13 of 24–28 limp strands over 40 frames of the two-sheet scene). Slowing-only changes
   * take energy out of eq. 1's oscillators and never put it in. The positions a pass gives
   * come back whole, so a pass still moves a strand.
   *
   * The articulated model takes the changes whole, but never with more kinetic energy (relative
   * to the head) than the strand had before the passes or than the passes left it: imposing a
   * node's velocity on an inextensible chain moves every node below it that the chain's shape
   * couples to it (a zigzag strand whose node is pushed sideways translates its whole tip), and
   * the same rates on a shape the passes moved are other node velocities (a φ̇ near the chart's
   * pole, large for a slow node, is fast once a push turns the hinge away from the pole). Either
   * can give the strand more energy than any pass did: hair–hair collision every substep then
   * ran strands away, in wind at many substeps (298 of 300 at 5 m/s and 200 substeps). Where
   * the taken-back rates carry more energy, all the strand's rates are scaled down to it. */
  const IndexRange points = curve_points(curve_offsets_, curve);
  const size_t root = size_t(points.start);
  mat3 frame = substep.rotation * root_frames_head_[size_t(curve)];
  vec3 node = positions_before_[root]; /* Roots are kinematic whatever a pass did. */
  positions_wo_[root] = node;
  velocities_wo_[root] = velocities_before_[root];
  bool moved = false;
  vec3 parent_delta_omega(0.0f); /* ΔΩ_{i-1}, rad/s */
  vec3 parent_delta_v(0.0f);     /* Δv̂_{i-1}, m/s */
  /* The energy cap (articulated model): Σ d_i |v_i − v_head(x_i)|² before the passes, as they
   * left the nodes, and of the rates taken back, whose node velocities relative to the head
   * (relative_v, with relative_omega the rates' part of Ω_i) are linear in the rates. */
  const bool articulated = params_.model != StrandModel::Kurihara1993;
  const auto relative = [&](const vec3 &v, const vec3 &x) {
    return v - substep.head_velocity.of_point(x - substep.pose.translation);
  };
  float energy_before = 0.0f, energy_passes = 0.0f, energy_after = 0.0f;
  vec3 relative_omega(0.0f), relative_v(0.0f);
  bool changed = false;
  for (size_t i = root + 1; i < size_t(points.one_after_last()); i++) {
    const float d = rest_lengths_[i];
    const mat3 chart = frame * rest_rotations_[i];
    if (articulated) {
      const vec3 before = relative(velocities_before_[i], positions_before_[i]);
      const vec3 passes = relative(velocities_wo_[i], positions_wo_[i]);
      energy_before += d * glm::dot(before, before);
      energy_passes += d * glm::dot(passes, passes);
    }
    moved = moved || positions_wo_[i] != positions_before_[i];
    if (moved) {
      const vec3 along = positions_wo_[i] - node;
      trig_[i] = glm::dot(along, along) > 1e-12f * d * d ?
                     chart_deflection(chart, along, angles_[i]).trig() :
                     Deflection(angles_[i]).trig();
    }
    const Deflection deflection(trig_[i]);
    frame = deflection.rotate(chart);
    const vec3 delta_v = velocities_wo_[i] - velocities_before_[i];
    const vec3 carried = parent_delta_v + d * glm::cross(parent_delta_omega, frame[2]);
    if (delta_v != carried) {
      const vec3 own = (delta_v - carried) / d;
      /* Δφ̇ = (own · e_φ) / cos θ (cos θ < 0 for a hinge turned past the chart's pole); at
       * the pole φ is undefined and takes nothing. The articulated model's rods have their
       * transverse inertia about their own axis too (strand_dynamics_articulated.cpp), so
       * there φ̇ costs as much energy whatever θ, while it moves the node only cos θ as fast:
       * its rate is the least-squares one with that twist charged, (own · e_φ) c / (c² + κ),
       * nearly exact off the pole (pole_twist_weight) and bounded at it. */
      const float c = deflection.cos_theta;
      const bool off_pole = std::abs(c) > 1e-3f;
      const float kappa = articulated ? pole_twist_weight : 0.0f;
      vec2 delta_rate(glm::dot(own, frame[0]),
                      off_pole ? glm::dot(own, frame[1]) * c / (c * c + kappa) : 0.0f);
      if (params_.model == StrandModel::Kurihara1993) {
        delta_rate = slowing_part(angular_velocities_[i], delta_rate);
      }
      const float along_phi = c * delta_rate.y;
      angular_velocities_[i] += delta_rate;
      accelerations_known_[size_t(curve)] = 0; /* a pass's change: no trend of the steps */
      parent_delta_omega += delta_rate.x * frame[1] - delta_rate.y * chart[0];
      parent_delta_v = carried + d * (delta_rate.x * frame[0] + along_phi * frame[1]);
      changed = true;
    }
    else {
      parent_delta_v = carried;
    }
    if (moved) {
      positions_wo_[i] = node + d * frame[2];
    }
    node = positions_wo_[i];
    if (articulated) { /* as place_curve moves the nodes, without the head's part */
      const vec2 rate = angular_velocities_[i];
      relative_omega += rate.x * frame[1] - rate.y * chart[0];
      relative_v += d * glm::cross(relative_omega, frame[2]);
      energy_after += d * glm::dot(relative_v, relative_v);
    }
  }
  const float allowed = std::max(energy_before, energy_passes);
  if (articulated && (moved || changed) && energy_after > allowed) {
    const float scale = std::sqrt(allowed / energy_after);
    for (size_t i = root + 1; i < size_t(points.one_after_last()); i++) {
      angular_velocities_[i] *= scale;
    }
    accelerations_known_[size_t(curve)] = 0;
  }
}

void StrandSolver::step(const float frame_dt, const mat4 &head_to_world)
{
  assert(frame_dt > 0.0f);
  const HeadPose pose = HeadPose::from_matrix(head_to_world);

  /* The head's velocity over this frame and its change since the last one; within the frame
   * the head moves along the interpolated path with these rates. */
  const HeadVelocity velocity = HeadVelocity::between(pose_, pose, frame_dt);
  HeadAcceleration head = HeadAcceleration::between(head_velocity_, velocity, frame_dt);

  if (grouped_for_threads_ != thread_num()) {
    group_strands();
  }
  const int substeps_num = std::max(params_.substeps, 1);
  std::vector<Substep> substeps(static_cast<size_t>(substeps_num));
  for (int s = 0; s < substeps_num; s++) {
    const float t = float(s + 1) / float(substeps_num);
    Substep &substep = substeps[size_t(s)];
    substep.h = frame_dt / float(substeps_num);
    substep.time = time_ + t * frame_dt;
    substep.pose = HeadPose::interpolate(pose_, pose, t);
    substep.rotation = substep.pose.rotation_matrix();
    substep.head_velocity = velocity;
    head.center = substep.pose.translation;
    substep.forces = ForceField(params_, line_density(), head, velocity);
    if (colliders_ != nullptr) {
      substep.projection_tolerance_wo = collision_params_.projection_tolerance *
                                        colliders_->size_wo();
      substep.reaction = ReactionConstants::from(collision_params_, substep.h,
                                                 substep.projection_tolerance_wo);
    }
  }

  /* Counts per chunk of strands, summed in order: deterministic for any thread count. Only
   * the strands set_stepped keeps (all without a mask) are visited. */
  const int64_t grain = 32;
  const bool masked = !stepped_.empty();
  const int64_t stepped_num = masked ? int64_t(stepped_curves_.size()) : curves_num();
  const int64_t groups_num = int64_t(groups_.size());
  const int64_t group_grain = std::max<int64_t>(1, grain / group_strands_max);
  std::vector<Counts> counts(size_t(std::max((stepped_num + grain - 1) / grain,
                                             (groups_num + group_grain - 1) / group_grain)));
  const auto for_each_curve = [&](auto &&fn) {
    parallel_for(stepped_num, grain, [&](const IndexRange range) {
      Counts &chunk = counts[size_t(range.start / grain)];
      for (int64_t index = range.start; index < range.one_after_last(); index++) {
        fn(masked ? stepped_curves_[size_t(index)] : index, chunk);
      }
    });
  };
  /* fn(group, counts) for each group of strands (group_strands): the strands advance a group
   * at a time. */
  const auto for_each_group = [&](auto &&fn) {
    parallel_for(groups_num, group_grain, [&](const IndexRange range) {
      Counts &chunk = counts[size_t(range.start / group_grain)];
      for (int64_t index = range.start; index < range.one_after_last(); index++) {
        fn(groups_[size_t(index)], chunk);
      }
    });
  };
  std::fill(pass_ms_.begin(), pass_ms_.end(), 0.0);
  if (passes_.empty()) {
    /* Strands are independent between passes: each group runs all its substeps in a row (the
     * same result as substep by substep, with its data hot in cache). A strand that diverged
     * sits out the frame's remaining substeps. */
    for_each_group([&](const StrandGroup &group, Counts &chunk) {
      int64_t active[group_strands_max];
      int64_t active_num = group.size;
      std::copy_n(group.curves, group.size, active);
      for (int64_t k = 0; k < active_num; k++) {
        prepare_strand(active[k], substeps[0].h);
      }
      for (const Substep &substep : substeps) {
        uint8_t finite[group_strands_max];
        advance_strands(Span<int64_t>(active, active_num), substep, chunk,
                        MutableSpan<uint8_t>(finite, active_num));
        int64_t kept = 0;
        for (int64_t k = 0; k < active_num; k++) {
          const int64_t curve = active[k];
          if (!finite[k]) {
            continue;
          }
          if (has_pins(curve)) {
            const IndexRange points = curve_points(curve_offsets_, curve);
            std::copy_n(&positions_wo_[size_t(points.start)], points.size,
                        &positions_before_[size_t(points.start)]);
            std::copy_n(&velocities_wo_[size_t(points.start)], points.size,
                        &velocities_before_[size_t(points.start)]);
            if (!settle_strand(curve, substep, chunk)) {
              continue;
            }
          }
          active[kept++] = curve;
        }
        active_num = kept;
      }
    });
  }
  else {
    for_each_curve([&](const int64_t curve, Counts &) { prepare_strand(curve, substeps[0].h); });
    std::vector<uint8_t> diverged(size_t(curves_num()), 0);
    for (const Substep &substep : substeps) {
      positions_start_ = positions_wo_;
      /* A strand that has diverged stays on its rest shape, carried by the head, whatever the
       * passes do to its nodes, until the frame ends (the next frame starts it from there). */
      for_each_group([&](const StrandGroup &group, Counts &chunk) {
        int64_t live[group_strands_max];
        int64_t live_num = 0;
        for (int64_t k = 0; k < group.size; k++) {
          if (diverged[size_t(group.curves[k])]) {
            place_at_rest(group.curves[k], substep.pose);
          }
          else {
            live[live_num++] = group.curves[k];
          }
        }
        uint8_t finite[group_strands_max];
        advance_strands(Span<int64_t>(live, live_num), substep, chunk,
                        MutableSpan<uint8_t>(finite, live_num));
        for (int64_t k = 0; k < live_num; k++) {
          diverged[size_t(live[k])] = finite[k] ? 0 : 1;
        }
      });
      positions_before_ = positions_wo_;
      velocities_before_ = velocities_wo_;
      SubstepState state;
      state.h = substep.h;
      state.time = substep.time;
      state.head_to_world = pose_matrix(substep.pose);
      if (pass_view_used_) {
        /* The passes see only their strands: gathered here, scattered back after. */
        gather_pass_view();
        state.curve_offsets = pass_view_.offsets;
        state.positions_wo = pass_view_.positions;
        state.velocities_wo = pass_view_.velocities;
        state.start_positions_wo = pass_view_.start_positions;
        state.set_volumes(pass_view_.volumes);
      }
      else {
        state.curve_offsets = curve_offsets_;
        state.positions_wo = positions_wo_;
        state.velocities_wo = velocities_wo_;
        state.start_positions_wo = positions_start_;
        state.set_volumes(pass_volumes_);
      }
      for (size_t p = 0; p < passes_.size(); p++) {
        const auto start = std::chrono::steady_clock::now();
        passes_[p]->apply(state);
        pass_ms_[p] += std::chrono::duration<double, std::milli>(
                           std::chrono::steady_clock::now() - start)
                           .count();
      }
      if (pass_view_used_) {
        scatter_pass_view();
      }
      for_each_curve([&](const int64_t curve, Counts &chunk) {
        if (diverged[size_t(curve)]) {
          place_at_rest(curve, substep.pose);
        }
        else if (!settle_strand(curve, substep, chunk)) {
          diverged[size_t(curve)] = 1;
        }
      });
    }
  }
  stepped_num_ = stepped_num;
  contacts_num_ = projections_num_ = diverged_num_ = 0;
  for (const Counts &chunk : counts) {
    contacts_num_ += chunk.contacts;
    projections_num_ += chunk.projections;
    diverged_num_ += chunk.diverged;
  }

  pose_ = pose;
  head_velocity_ = velocity;
  time_ += frame_dt;
}

bool StrandSolver::strand_is_sane(const int64_t curve) const
{
  const IndexRange points = curve_points(curve_offsets_, curve);
  for (int64_t i = points.start; i < points.one_after_last(); i++) {
    const vec3 v = velocities_wo_[size_t(i)];
    if (!(glm::dot(v, v) < runaway_speed * runaway_speed) || !is_finite(positions_wo_[size_t(i)]))
    {
      return false;
    }
  }
  return true;
}

void StrandSolver::place_at_rest(const int64_t curve, const HeadPose &pose)
{
  const IndexRange points = curve_points(curve_offsets_, curve);
  accelerations_known_[size_t(curve)] = 0;
  mat3 frame = pose.rotation_matrix() * root_frames_head_[size_t(curve)];
  root_frames_wo_[size_t(curve)] = frame;
  vec3 node = pose.transform_point(root_positions_head_[size_t(curve)]);
  positions_wo_[size_t(points.start)] = node;
  velocities_wo_[size_t(points.start)] = vec3(0.0f);
  for (int64_t i = points.start + 1; i < points.one_after_last(); i++) {
    frame = frame * rest_rotations_[size_t(i)];
    node += rest_lengths_[size_t(i)] * frame[2];
    positions_wo_[size_t(i)] = node;
    velocities_wo_[size_t(i)] = vec3(0.0f);
    angles_[size_t(i)] = vec2(0.0f);
    angular_velocities_[size_t(i)] = vec2(0.0f);
    trig_[size_t(i)] = vec4(0.0f, 1.0f, 0.0f, 1.0f);
  }
}

void StrandSolver::reset_dynamics(const HeadPose &pose)
{
  pose_ = pose;
  head_velocity_ = HeadVelocity();
  time_ = 0.0f;
  diverged_num_ = 0;
  std::fill(angles_.begin(), angles_.end(), vec2(0.0f));
  std::fill(angular_velocities_.begin(), angular_velocities_.end(), vec2(0.0f));
  std::fill(velocities_wo_.begin(), velocities_wo_.end(), vec3(0.0f));
  std::fill(accelerations_known_.begin(), accelerations_known_.end(), 0);
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
      place_at_rest(curve, pose_);
    }
  });
}

}  // namespace hairdyn
