#include "lod/lod_solver_ward2003.hh"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <utility>

#include "collision/collider.hh"
#include "core/parallel.hh"
#include "groom/groom.hh"
#include "lod/skinning_ward2003.hh"

namespace hairdyn {

LodSolver::LodSolver(const Span<int32_t> curve_offsets, const Span<vec3> rest_positions_wo,
                     const Span<vec2> root_uvs, const Span<vec3> root_normals_wo,
                     const mat4 &head_to_world_rest, const StrandParams &strand_params,
                     const WindParams &wind, const LodParams &lod_params)
    : hierarchy_(curve_offsets, rest_positions_wo, root_uvs, root_normals_wo, lod_params),
      lod_params_(lod_params),
      rest_pose_(HeadPose::from_matrix(head_to_world_rest))
{
  finest_ = lod_params.finest_level < 0 ? hierarchy_.max_depth() :
                                          std::min(lod_params.finest_level, hierarchy_.max_depth());
  coarsest_ = std::min(lod_params.coarsest_level, finest_);

  /* One strand solver over every node's skeleton, curve i being node i; set_stepped picks the
   * ones a frame advances. */
  const int32_t n = hierarchy_.skeleton_points_num();
  const int64_t nodes = hierarchy_.nodes_num();
  std::vector<int32_t> offsets(size_t(nodes) + 1);
  std::vector<vec3> skeletons;
  std::vector<vec3> normals;
  skeletons.reserve(size_t(nodes * n));
  for (int64_t node = 0; node < nodes; node++) {
    offsets[size_t(node) + 1] = int32_t((node + 1) * n);
    const Span<vec3> skeleton = hierarchy_.rest_skeleton(node);
    skeletons.insert(skeletons.end(), skeleton.begin(), skeleton.end());
    /* Every skeleton of a tree measures its angles from the same root normal, so equal angles
     * mean equal turns on parent and child and the state can pass between them as it is
     * (§6.2, §6.3). The normal only orients the angles' chart. */
    normals.push_back(hierarchy_.root_normal(hierarchy_.top_node(node)));
  }
  solver_ = std::make_unique<StrandSolver>(offsets, skeletons, head_to_world_rest, normals,
                                           strand_params, wind);
  stepped_.assign(size_t(nodes), 0);

  active_.assign(size_t(nodes), 0);
  shown_.assign(size_t(nodes), 0);
  current_.assign(size_t(nodes), 1);
  visible_.assign(size_t(nodes), 1);
  wanted_.assign(size_t(nodes), 0);
  frames_.resize(size_t(nodes * n));
  strand_nodes_.assign(size_t(hierarchy_.strands_num()), 0);
  for (int32_t node = 0; node < int32_t(nodes); node++) {
    if (hierarchy_.kind(node) == LodKind::Strip) {
      strip_nodes_.push_back(node);
    }
  }
  const int64_t points = hierarchy_.rest_positions().size();
  positions_wo_.resize(size_t(points));
  residuals_wo_.assign(size_t(points), vec3(0.0f));
  offsets_.resize(size_t(points));
  offset_nodes_.assign(size_t(hierarchy_.strands_num()), -1);
  rest_lengths_.assign(size_t(points), 0.0f);
  const Span<vec3> rest = hierarchy_.rest_positions();
  for (int64_t strand = 0; strand < hierarchy_.strands_num(); strand++) {
    const IndexRange strand_points = curve_points(hierarchy_.curve_offsets(), strand);
    for (int64_t i = strand_points.start + 1; i < strand_points.one_after_last(); i++) {
      rest_lengths_[size_t(i)] = glm::length(rest[i] - rest[i - 1]);
    }
  }
  point_levels_.assign(size_t(points), 0);
  reset(head_to_world_rest);
}

void LodSolver::set_colliders(const ColliderSet *colliders, const CollisionParams &params)
{
  solver_->set_colliders(colliders, params);
  set_bodies(colliders);
  set_occluders(colliders);
}

void LodSolver::set_bodies(const ColliderSet *bodies)
{
  bodies_ = bodies;
  rest_depths_.clear();
  if (bodies != nullptr && bodies->colliders_num() > 0) {
    const Span<vec3> rest = hierarchy_.rest_positions();
    rest_depths_.resize(size_t(rest.size()));
    find_body_contacts(rest, rest_depths_);
  }
}

void LodSolver::find_body_contacts(const Span<vec3> points, const MutableSpan<float> r_depths)
{
  /* The buffers keep their largest size (shrinking and growing them again would clear 8 MB a
   * frame on Sintel's groom). */
  const int64_t n = points.size();
  const auto grow = [&](auto &buffer) { buffer.resize(std::max(buffer.size(), size_t(n))); };
  grow(contact_hit_);
  grow(contact_normal_);
  grow(contact_surface_);
  find_contacts(*bodies_, points, MutableSpan<uint8_t>(contact_hit_.data(), n), r_depths,
                MutableSpan<vec3>(contact_normal_.data(), n),
                MutableSpan<vec3>(contact_surface_.data(), n));
}

void LodSolver::add_pass(SubstepPass *const pass, const float strand_radius)
{
  strand_radius_ = strand_radius;
  update_pass_volumes();
  solver_->add_pass(pass);
}

void LodSolver::set_radii(const Span<float> point_radii)
{
  node_radii_.clear();
  if (!point_radii.is_empty()) {
    const int32_t n = hierarchy_.skeleton_points_num();
    const std::vector<float> strand_radii = hierarchy_.at_control_points(point_radii);
    node_radii_.assign(size_t(hierarchy_.nodes_num()) * size_t(n), 0.0f);
    parallel_for(hierarchy_.nodes_num(), 64, [&](const IndexRange range) {
      for (int64_t node = range.start; node < range.one_after_last(); node++) {
        for (const int32_t strand : hierarchy_.strands(node)) {
          for (int32_t k = 0; k < n; k++) {
            float &radius = node_radii_[size_t(node * n + k)];
            radius = std::max(radius, strand_radii[size_t(strand) * size_t(n) + size_t(k)]);
          }
        }
      }
    });
  }
  update_pass_volumes();
}

void LodSolver::update_pass_volumes()
{
  const int32_t n = hierarchy_.skeleton_points_num();
  const int64_t points = hierarchy_.nodes_num() * n;
  PassVolumes volumes;
  volumes.radii.resize(size_t(points));
  volumes.strip_half_widths_hs.resize(size_t(points));
  volumes.rest_positions_hs.resize(size_t(points));
  if (colliders_ != nullptr && colliders_->colliders_num() > 0) {
    volumes.rest_clearances.resize(size_t(points));
  }
  const mat3 world_to_head = glm::transpose(rest_pose_.rotation_matrix());
  /* Each collider's world-to-object transform and scale, for the clearances. */
  std::vector<std::pair<mat4, float>> to_objects;
  for (int64_t c = 0; c < (volumes.rest_clearances.empty() ? 0 : colliders_->colliders_num());
       c++)
  {
    const Collider &collider = colliders_->collider(c);
    to_objects.emplace_back(collider.world_to_object(), uniform_scale(collider.object_to_world()));
  }
  parallel_for(hierarchy_.nodes_num(), 64, [&](const IndexRange range) {
    for (int64_t node = range.start; node < range.one_after_last(); node++) {
      const Span<float> spread = hierarchy_.spread(node);
      const Span<vec3> half_width = hierarchy_.half_width(node);
      const Span<vec3> rest = hierarchy_.rest_skeleton(node);
      for (int32_t k = 0; k < n; k++) {
        const size_t i = size_t(node * n + k);
        volumes.radii[i] = (node_radii_.empty() ? strand_radius_ : node_radii_[i]) + spread[k];
        volumes.strip_half_widths_hs[i] = world_to_head * half_width[k];
        /* Groups overlap at rest where their strands interleave: they may stay as close as
         * that (GroupVolumes). */
        volumes.rest_positions_hs[i] = world_to_head * (rest[k] - rest_pose_.translation);
        if (!volumes.rest_clearances.empty()) {
          /* And a skeleton may stay as near the body as it was at rest (the colliders where
           * they are now: the groom's rest pose). */
          float clearance = std::numeric_limits<float>::max();
          for (size_t c = 0; c < to_objects.size(); c++) {
            const vec3 p = transform_point(to_objects[c].first, rest[k]);
            clearance = std::min(clearance, colliders_->collider(int64_t(c)).exact()
                                                    .signed_distance(p) *
                                                to_objects[c].second);
          }
          volumes.rest_clearances[i] = std::max(clearance, 0.0f);
        }
      }
    }
  });
  solver_->set_pass_volumes(std::move(volumes));
}

void LodSolver::set_active(const int32_t node, const bool active)
{
  active_[size_t(node)] = active ? 1 : 0;
  if (active) {
    for (const int32_t strand : hierarchy_.strands(node)) {
      strand_nodes_[size_t(strand)] = node;
    }
  }
}

void LodSolver::reset(const mat4 &head_to_world)
{
  solver_->reset(head_to_world);
  head_rotation_ = HeadPose::from_matrix(head_to_world).rotation_matrix() *
                   glm::transpose(rest_pose_.rotation_matrix());
  std::fill(active_.begin(), active_.end(), 0);
  for (const int32_t node : hierarchy_.level_nodes(lod_params_.enabled ? coarsest_ : finest_)) {
    set_active(node, true);
  }
  /* Every skeleton is at rest where the head is. */
  shown_ = active_;
  std::fill(current_.begin(), current_.end(), 1);
  placed_nodes_ = strand_nodes_;
  std::fill(residuals_wo_.begin(), residuals_wo_.end(), vec3(0.0f));
  splits_num_ = merges_num_ = collapses_num_ = 0;
  starting_ = true;
  update_frames();
  place_strands(0.0f);
}

Span<vec3> LodSolver::skeleton(const int64_t node) const
{
  const int32_t n = hierarchy_.skeleton_points_num();
  return solver_->positions().slice(node * n, n);
}

Span<mat3> LodSolver::frames(const int64_t node) const
{
  const int32_t n = hierarchy_.skeleton_points_num();
  return Span<mat3>(frames_).slice(node * n, n);
}

Span<vec2> LodSolver::angles(const int64_t node) const
{
  const int32_t n = hierarchy_.skeleton_points_num();
  return solver_->angles().slice(node * n, n);
}

Span<vec2> LodSolver::angular_velocities(const int64_t node) const
{
  const int32_t n = hierarchy_.skeleton_points_num();
  return solver_->angular_velocities().slice(node * n, n);
}

void LodSolver::update_frames()
{
  /* Only the skeletons that drive strands now or did at the last placement are read. */
  const int32_t n = hierarchy_.skeleton_points_num();
  parallel_for(hierarchy_.nodes_num(), 64, [&](const IndexRange range) {
    for (int64_t node = range.start; node < range.one_after_last(); node++) {
      if (!active_[size_t(node)] && !shown_[size_t(node)]) {
        continue;
      }
      current_skeleton_frames(skeleton(node), hierarchy_.rest_frames(node), head_rotation_,
                              MutableSpan<mat3>(frames_.data() + node * n, n));
    }
  });
}

void LodSolver::strip_ribbons(const MutableSpan<vec3> r_vertices_wo) const
{
  const int32_t n = hierarchy_.skeleton_points_num();
  assert(r_vertices_wo.size() == int64_t(strip_nodes_.size()) * 2 * n);
  for (size_t s = 0; s < strip_nodes_.size(); s++) {
    const int32_t node = strip_nodes_[s];
    const MutableSpan<vec3> ribbon = r_vertices_wo.slice(int64_t(s) * 2 * n, 2 * n);
    if (!active_[size_t(node)]) {
      const int32_t strand = hierarchy_.strands(node)[0];
      std::fill(ribbon.begin(), ribbon.end(), positions_wo_[hierarchy_.curve_offsets()[strand]]);
      continue;
    }
    const Span<vec3> skeleton = this->skeleton(node);
    const Span<mat3> frames = this->frames(node), rest_frames = hierarchy_.rest_frames(node);
    const Span<vec3> half_width = hierarchy_.half_width(node);
    for (int32_t k = 0; k < n; k++) {
      const vec3 side = frames[k] * (glm::transpose(rest_frames[k]) * half_width[k]);
      ribbon[2 * k] = skeleton[k] - side;
      ribbon[2 * k + 1] = skeleton[k] + side;
    }
  }
}

void LodSolver::take_state(const int32_t node, const Span<vec2> angles, const Span<vec2> rates)
{
  const int32_t n = hierarchy_.skeleton_points_num();
  const Span<vec2> old_angles = this->angles(node);
  const Span<vec2> old_rates = angular_velocities(node);
  bool same = current_[size_t(node)] != 0;
  for (int32_t k = 1; k < n && same; k++) {
    same = old_angles[k] == angles[k] && old_rates[k] == rates[k];
  }
  if (!same) {
    solver_->set_curve_state(node, angles, rates);
    current_[size_t(node)] = 1;
  }
}

void LodSolver::absorb(const int32_t node, const Span<int32_t> sources)
{
  /* §6.3: the parent takes the average of its children's dynamic states (angles and their
   * rates), weighted by the strands each carries. Written as s0 + Σ w (s − s0) so that equal
   * states average to themselves bit for bit. */
  const int32_t n = hierarchy_.skeleton_points_num();
  std::vector<vec2> new_angles(size_t(n), vec2(0.0f)), new_rates(size_t(n), vec2(0.0f));
  const Span<vec2> first_angles = angles(sources[0]);
  const Span<vec2> first_rates = angular_velocities(sources[0]);
  const float total = float(hierarchy_.strands(node).size());
  for (int32_t k = 1; k < n; k++) {
    vec2 angle_sum(0.0f), rate_sum(0.0f);
    for (const int32_t source : sources) {
      const float w = float(hierarchy_.strands(source).size()) / total;
      angle_sum += w * (angles(source)[k] - first_angles[k]);
      rate_sum += w * (angular_velocities(source)[k] - first_rates[k]);
    }
    new_angles[size_t(k)] = first_angles[k] + angle_sum;
    new_rates[size_t(k)] = first_rates[k] + rate_sum;
  }
  take_state(node, new_angles, new_rates);
  for (const int32_t source : sources) {
    active_[size_t(source)] = 0;
  }
  set_active(node, true);
}

void LodSolver::split(const int32_t node)
{
  assert(active_[size_t(node)] && !hierarchy_.is_leaf(node));
  /* §6.2: each child inherits its parent's dynamic state; its own rest shape carries its
   * stored offset, since the angles are offsets from each skeleton's rest. */
  const Span<vec2> parent_angles = angles(node);
  const Span<vec2> parent_rates = angular_velocities(node);
  const IndexRange kids = hierarchy_.children(node);
  for (int64_t child = kids.start; child < kids.one_after_last(); child++) {
    take_state(int32_t(child), parent_angles, parent_rates);
    set_active(int32_t(child), true);
  }
  active_[size_t(node)] = 0;
}

void LodSolver::merge(const int32_t parent)
{
  const IndexRange kids = hierarchy_.children(parent);
  std::vector<int32_t> children;
  for (int64_t child = kids.start; child < kids.one_after_last(); child++) {
    assert(active_[size_t(child)]);
    children.push_back(int32_t(child));
  }
  absorb(parent, children);
}

float LodSolver::merge_deviation(const int32_t parent) const
{
  /* §6.3: average the parent's control points as the children place them, then measure how
   * far each child's control points are from their place on that average. */
  const int32_t n = hierarchy_.skeleton_points_num();
  const IndexRange kids = hierarchy_.children(parent);
  std::vector<vec3> estimates(size_t(kids.size * n));
  std::vector<vec3> mean(static_cast<size_t>(n), vec3(0.0f));
  for (int64_t c = 0; c < kids.size; c++) {
    const int64_t child = kids.start + c;
    const MutableSpan<vec3> estimate(estimates.data() + c * n, n);
    parent_from_child(skeleton(child), frames(child), hierarchy_.rest_frames(child),
                      hierarchy_.rest_frames(parent), hierarchy_.offsets(child), estimate);
    for (int32_t k = 0; k < n; k++) {
      mean[size_t(k)] += estimate[k] / float(kids.size);
    }
  }
  float deviation = 0.0f;
  for (int64_t c = 0; c < kids.size; c++) {
    for (int32_t k = 0; k < n; k++) {
      deviation = std::max(deviation, glm::length(estimates[size_t(c * n + k)] - mean[size_t(k)]));
    }
  }
  return deviation;
}

void LodSolver::select(const LodCamera &camera)
{
  const int32_t n = hierarchy_.skeleton_points_num();
  const int64_t nodes = hierarchy_.nodes_num();
  const bool occlusion = lod_params_.use_occlusion;
  const float margin_scale = colliders_ != nullptr && colliders_->colliders_num() > 0 ?
                                 0.01f * colliders_->size_wo() :
                                 0.0f;
  if (occluders_.size() != size_t(nodes * occlusion_samples)) {
    occluders_.assign(size_t(nodes * occlusion_samples), -1);
    seen_sample_.assign(size_t(nodes), 0);
  }
  /* §6.1: visibility first, then distance and velocity, per active hair group. */
  parallel_for(nodes, 64, [&](const IndexRange range) {
    for (int64_t node = range.start; node < range.one_after_last(); node++) {
      if (!active_[size_t(node)]) {
        continue;
      }
      const Span<vec3> points = skeleton(node);
      const Span<vec3> velocities = solver_->velocities().slice(node * n, n);
      vec3 centre(0.0f);
      float speed = 0.0f;
      for (int32_t k = 0; k < n; k++) {
        centre += points[k] / float(n);
        speed += glm::length(velocities[k] - velocities[0]) / float(n - 1);
      }
      float bound = 0.0f;
      for (int32_t k = 0; k < n; k++) {
        bound = std::max(bound, glm::length(points[k] - centre));
      }
      bool visible = camera.sees_sphere(centre, bound + hierarchy_.radius(node));
      if (visible && occlusion && colliders_ != nullptr && !camera.is_orthographic()) {
        /* Hidden when the body is in front of every sampled control point past the root
         * (the one that showed the node at the last frame first). */
        visible = false;
        const float margin = hierarchy_.radius(node) + margin_scale;
        const int32_t samples[occlusion_samples] = {n / 4, n / 2, (3 * n) / 4, n - 1};
        uint8_t &seen = seen_sample_[size_t(node)];
        for (int j = 0; j < occlusion_samples; j++) {
          const int sample = (seen + j) % occlusion_samples;
          const int32_t k = samples[sample];
          int64_t &occluder = occluders_[size_t(node * occlusion_samples + sample)];
          if (k > 0 &&
              !hidden_by_colliders(*colliders_, camera.position_wo(), points[k], margin, &occluder))
          {
            visible = true;
            seen = uint8_t(sample);
            break;
          }
        }
      }
      visible_[size_t(node)] = visible ? 1 : 0;
      wanted_[size_t(node)] = visible || !occlusion ?
                                  wanted_level(camera.distance_to(centre), speed, lod_params_,
                                               coarsest_, finest_) :
                                  coarsest_;
    }
  });

  /* §6.1: "a transition caused by an occlusion permits the hair representation to transform
   * into the coarsest strip representation regardless of its current location". A tree
   * whose active groups are all hidden collapses to the coarsest level at once. */
  std::vector<uint8_t> tree_visible(size_t(hierarchy_.top_nodes_num()), 0);
  for (int64_t node = 0; node < nodes; node++) {
    if (active_[size_t(node)] && visible_[size_t(node)]) {
      tree_visible[size_t(hierarchy_.top_node(node))] = 1;
    }
  }
  std::vector<uint8_t> changed(size_t(nodes), 0);
  if (occlusion) {
    for (int64_t top = 0; top < hierarchy_.top_nodes_num(); top++) {
      if (tree_visible[size_t(top)]) {
        continue;
      }
      /* Group the tree's active nodes deeper than the coarsest level by their ancestor there. */
      std::vector<std::pair<int32_t, int32_t>> moves; /* (coarse ancestor, active node) */
      std::vector<int32_t> stack{int32_t(top)};
      while (!stack.empty()) {
        const int32_t node = stack.back();
        stack.pop_back();
        if (active_[size_t(node)]) {
          int32_t ancestor = node;
          while (hierarchy_.depth(ancestor) > coarsest_) {
            ancestor = hierarchy_.parent(ancestor);
          }
          if (ancestor != node) {
            moves.emplace_back(ancestor, node);
          }
          continue;
        }
        const IndexRange kids = hierarchy_.children(node);
        for (int64_t child = kids.start; child < kids.one_after_last(); child++) {
          stack.push_back(int32_t(child));
        }
      }
      std::stable_sort(moves.begin(), moves.end(),
                       [](const auto &a, const auto &b) { return a.first < b.first; });
      for (size_t i = 0; i < moves.size();) {
        size_t j = i;
        std::vector<int32_t> sources;
        while (j < moves.size() && moves[j].first == moves[i].first) {
          sources.push_back(moves[j].second);
          j++;
        }
        absorb(moves[i].first, sources);
        changed[size_t(moves[i].first)] = 1;
        collapses_num_++;
        i = j;
      }
    }
  }

  /* §6.2: one level down where more detail is wanted. */
  for (int64_t node = 0; node < nodes; node++) {
    if (active_[size_t(node)] && !changed[size_t(node)] && !hierarchy_.is_leaf(node) &&
        hierarchy_.depth(node) < finest_ && wanted_[size_t(node)] > hierarchy_.depth(node))
    {
      split(int32_t(node));
      const IndexRange kids = hierarchy_.children(node);
      for (int64_t child = kids.start; child < kids.one_after_last(); child++) {
        changed[size_t(child)] = 1;
      }
      splits_num_++;
    }
  }

  /* §6.3: one level up where every child is active, ready (wants its parent's level or
   * coarser) and close enough to its place on the merged parent. */
  for (int64_t parent = 0; parent < nodes; parent++) {
    if (active_[size_t(parent)] || hierarchy_.is_leaf(parent) ||
        hierarchy_.depth(parent) < coarsest_)
    {
      continue;
    }
    const IndexRange kids = hierarchy_.children(parent);
    bool ready = true;
    for (int64_t child = kids.start; child < kids.one_after_last() && ready; child++) {
      ready = active_[size_t(child)] && !changed[size_t(child)] &&
              wanted_[size_t(child)] <= hierarchy_.depth(parent);
    }
    if (ready && merge_deviation(int32_t(parent)) <= lod_params_.merge_threshold) {
      merge(int32_t(parent));
      changed[size_t(parent)] = 1;
      merges_num_++;
    }
  }
}

void LodSolver::place_strands(const float frame_dt)
{
  const float tau = lod_params_.transition_time;
  const float decay = tau > 0.0f ? std::exp(-frame_dt / tau) : 0.0f;
  const Span<int32_t> offsets = hierarchy_.curve_offsets();
  parallel_for(hierarchy_.strands_num(), 256, [&](const IndexRange strands) {
    for (int64_t strand = strands.start; strand < strands.one_after_last(); strand++) {
      const IndexRange points = curve_points(offsets, strand);
      const MutableSpan<vec3> out(positions_wo_.data() + points.start, points.size);
      const MutableSpan<vec3> residual(residuals_wo_.data() + points.start, points.size);
      const int32_t node = strand_nodes_[size_t(strand)];
      const int32_t old_node = placed_nodes_[size_t(strand)];
      /* §6.3: on a switch the jump between the old and the new skeleton's placement is
       * kept, and the spring pulls it to zero over the next frames. */
      const bool switched = old_node != node && tau > 0.0f;
      if (switched) {
        skin_strand(hierarchy_, old_node, strand, skeleton(old_node), frames(old_node), out);
      }
      for (int64_t i = 0; i < points.size; i++) {
        residual[i] = switched ? decay * residual[i] + out[i] : decay * residual[i];
      }
      const MutableSpan<vec3> on_node(offsets_.data() + points.start, points.size);
      if (offset_nodes_[size_t(strand)] != node) {
        strand_offsets(hierarchy_, node, strand, on_node);
        offset_nodes_[size_t(strand)] = node;
      }
      skin_strand(hierarchy_, strand, on_node, skeleton(node), frames(node), out);
      for (int64_t i = 0; i < points.size; i++) {
        if (switched) {
          residual[i] -= out[i];
        }
        out[i] += residual[i];
      }
      for (int64_t i = 0; i < points.size; i++) {
        point_levels_[size_t(points.start + i)] = hierarchy_.depth(node);
      }
      placed_nodes_[size_t(strand)] = node;
    }
    keep_lengths(strands);
  });
}

void LodSolver::keep_lengths(const IndexRange strands)
{
  /* The strands get their segment lengths back (follow) point by point from the root, the
   * range's strands side by side (their serial chains of a square root and a division per
   * point overlap). With bodies, a strand placed by its offset from a skeleton goes where the
   * skeleton takes it, through the body where the skeleton bends toward it (a strip's edge
   * strands wrap a shoulder its middle clears): on Sintel's bust, 0.5-0.9% of the placed
   * points lay more than 9 mm deep, the deepest 8-12 cm. So each point, once at its length
   * from the point before, is queried against the collision maps (the range's points of one
   * index in one batch). A point deeper inside than at rest, by more than 1% of its segment,
   * goes to the plane through the point as deep as at rest less that 1% (normal the maps'),
   * at its length from the point before: the segment turns about that point out of the body,
   * and the points after it follow from there. Pushing every point out along the normal and
   * then giving the strands their lengths back took points back in: four rounds left a head
   * pressed by wind 3.9 mm deep (now 0.5 mm; test PlacedStrandsStayOutOfTheHead), and cost
   * 5.5 ms of a 22 ms frame of Sintel's level of detail (the frame now takes 19.5 ms). */
  struct Scratch {
    std::vector<vec3> points;
    std::vector<int64_t> indices;
    std::vector<uint8_t> hit;
    std::vector<float> depth;
    std::vector<vec3> normal, surface;
    std::unique_ptr<ContactBatch<map_batch_size>> contacts{ new ContactBatch<map_batch_size> };
    std::unique_ptr<MapBatch<map_batch_size>> batch{ new MapBatch<map_batch_size> };
  };
  thread_local Scratch scratch;
  const Span<int32_t> offsets = hierarchy_.curve_offsets();
  int64_t points_num = 0;
  for (int64_t strand = strands.start; strand < strands.one_after_last(); strand++) {
    points_num = std::max(points_num, curve_points(offsets, strand).size);
  }
  for (auto *buffer : { &scratch.points, &scratch.normal, &scratch.surface }) {
    buffer->resize(size_t(strands.size));
  }
  scratch.indices.resize(size_t(strands.size));
  scratch.hit.resize(size_t(strands.size));
  scratch.depth.resize(size_t(strands.size));
  const bool bodies = !rest_depths_.empty();
  for (int64_t i = 1; i < points_num; i++) {
    int64_t n = 0;
    for (int64_t strand = strands.start; strand < strands.one_after_last(); strand++) {
      const IndexRange strand_points = curve_points(offsets, strand);
      if (i >= strand_points.size) {
        continue;
      }
      const int64_t point = strand_points.start + i;
      follow(positions_wo_[size_t(point) - 1], rest_lengths_[size_t(point)],
             positions_wo_[size_t(point)]);
      if (bodies) { /* the batch to query */
        scratch.points[size_t(n)] = positions_wo_[size_t(point)];
        scratch.indices[size_t(n++)] = point;
      }
    }
    if (!bodies) {
      continue;
    }
    find_contacts_serial(*bodies_, Span<vec3>(scratch.points.data(), n),
                         MutableSpan<uint8_t>(scratch.hit.data(), n),
                         MutableSpan<float>(scratch.depth.data(), n),
                         MutableSpan<vec3>(scratch.normal.data(), n),
                         MutableSpan<vec3>(scratch.surface.data(), n), *scratch.contacts,
                         *scratch.batch);
    for (int64_t k = 0; k < n; k++) {
      const int64_t point = scratch.indices[size_t(k)];
      const float excess = scratch.depth[size_t(k)] - rest_depths_[size_t(point)];
      /* Less than 1% of a segment deeper than at rest is left (a point near the scalp moves
       * that much within the maps' surface as its skeleton sways). */
      const float margin = 0.01f * rest_lengths_[size_t(point)];
      if (scratch.hit[size_t(k)] && excess > margin) {
        /* Onto the plane through the point moved out, at the segment's length. */
        const vec3 normal = scratch.normal[size_t(k)];
        const vec3 previous = positions_wo_[size_t(point) - 1];
        const vec3 out = positions_wo_[size_t(point)] + (excess + margin) * normal;
        const float rest_length = rest_lengths_[size_t(point)];
        const vec3 d = out - previous;
        const float height = glm::dot(normal, d); /* of the plane above the point before */
        const vec3 across = d - height * normal;
        const float across_length = glm::length(across);
        if (height >= rest_length || across_length <= 1e-6f * rest_length) {
          positions_wo_[size_t(point)] = previous + rest_length * normal;
        }
        else {
          const float reach =
              std::sqrt(std::max(rest_length * rest_length - height * height, 0.0f));
          positions_wo_[size_t(point)] =
              previous + height * normal + (reach / across_length) * across;
        }
      }
    }
  }
}

void LodSolver::step(const float frame_dt, const mat4 &head_to_world, const mat4 &view_projection)
{
  splits_num_ = merges_num_ = collapses_num_ = 0;
  if (lod_params_.enabled) {
    const LodCamera camera(view_projection);
    select(camera);
    /* The first frame after a reset has no previous frame to jump from: it starts at the
     * levels the camera asks for (the hair is at rest, so the splits are exact). */
    for (int32_t pass = 0; starting_ && splits_num_ > 0 && pass < hierarchy_.max_depth(); pass++) {
      const int64_t splits_before = splits_num_;
      update_frames();
      select(camera);
      if (splits_num_ == splits_before) {
        break;
      }
    }
    if (starting_) {
      placed_nodes_ = strand_nodes_; /* Nothing was shown yet: no jump to smooth. */
    }
    starting_ = false;
  }
  /* Only the active skeletons, and on a switch the ones that drove strands at the last frame
   * (place_strands measures the jump between the two at this frame), are stepped, in
   * parallel; the passes see only the active ones. */
  for (int64_t node = 0; node < hierarchy_.nodes_num(); node++) {
    stepped_[size_t(node)] = active_[size_t(node)] || shown_[size_t(node)];
    current_[size_t(node)] = stepped_[size_t(node)];
  }
  solver_->set_stepped(stepped_, active_);
  solver_->step(frame_dt, head_to_world);
  head_rotation_ = HeadPose::from_matrix(head_to_world).rotation_matrix() *
                   glm::transpose(rest_pose_.rotation_matrix());
  update_frames();
  place_strands(frame_dt);
  shown_ = active_;
}

std::vector<int64_t> LodSolver::stepped_per_level() const
{
  std::vector<int64_t> counts(size_t(hierarchy_.max_depth() + 1), 0);
  for (int64_t node = 0; node < hierarchy_.nodes_num(); node++) {
    counts[size_t(hierarchy_.depth(node))] += stepped_[size_t(node)];
  }
  return counts;
}

std::vector<int64_t> LodSolver::active_per_level() const
{
  std::vector<int64_t> counts(size_t(hierarchy_.max_depth() + 1), 0);
  for (int64_t node = 0; node < hierarchy_.nodes_num(); node++) {
    counts[size_t(hierarchy_.depth(node))] += active_[size_t(node)];
  }
  return counts;
}

int64_t LodSolver::active_num() const
{
  int64_t count = 0;
  for (const uint8_t a : active_) {
    count += a;
  }
  return count;
}

double mean_distance(const Span<vec3> a, const Span<vec3> b)
{
  assert(a.size() == b.size());
  if (a.is_empty()) {
    return 0.0;
  }
  const double sum = parallel_sum(a.size(), 4096, [&](const IndexRange range) {
    double s = 0.0;
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      s += double(glm::length(a[i] - b[i]));
    }
    return s;
  });
  return sum / double(a.size());
}

}  // namespace hairdyn
