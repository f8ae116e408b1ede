#include "collision/ssv_object_ward2003.hh"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>

#include "core/head_motion.hh"
#include "core/parallel.hh"

namespace hairdyn {

SsvBVH::SsvBVH(const Span<vec3> vertices, const Span<ivec3> triangles, const int leaf_size)
{
  const std::vector<SplitNode> split =
      median_split_tree(vertices, triangles, leaf_size, leaf_triangles_);
  const size_t tris_num = size_t(triangles.size());
  corners_.resize(tris_num * 3);
  normals_.resize(tris_num);
  for (size_t t = 0; t < tris_num; t++) {
    const ivec3 tri = triangles[int64_t(t)];
    vec3 *c = &corners_[t * 3];
    c[0] = vertices[tri.x];
    c[1] = vertices[tri.y];
    c[2] = vertices[tri.z];
    const vec3 n = glm::cross(c[1] - c[0], c[2] - c[0]);
    const float len = glm::length(n);
    normals_[t] = len > 0.0f ? n / len : vec3(0.0f);
  }
  nodes_.reserve(split.size());
  for (const SplitNode &node : split) {
    /* The node's PSS: centred on its box, through its farthest corner. */
    constexpr float big = std::numeric_limits<float>::max();
    vec3 min(big), max(-big);
    for (int32_t i = node.begin; i < node.end; i++) {
      for (int k = 0; k < 3; k++) {
        min = glm::min(min, corners_[size_t(leaf_triangles_[size_t(i)]) * 3 + size_t(k)]);
        max = glm::max(max, corners_[size_t(leaf_triangles_[size_t(i)]) * 3 + size_t(k)]);
      }
    }
    const vec3 center = 0.5f * (min + max);
    float radius_sq = 0.0f;
    for (int32_t i = node.begin; i < node.end; i++) {
      for (int k = 0; k < 3; k++) {
        const vec3 d = corners_[size_t(leaf_triangles_[size_t(i)]) * 3 + size_t(k)] - center;
        radius_sq = std::max(radius_sq, glm::dot(d, d));
      }
    }
    nodes_.push_back({{center, std::sqrt(radius_sq) * (1.0f + 1e-6f)},
                      node.is_leaf() ? node.begin : node.right,
                      node.is_leaf() ? node.end - node.begin : 0});
  }
}

void SsvBVH::segment_contacts(const vec3 &a, const vec3 &b, const float max_distance,
                              std::vector<TriangleContact> &r_contacts, const vec3 &side) const
{
  if (nodes_.empty()) {
    return;
  }
  const bool strip = side != vec3(0.0f);
  const float side_len = glm::length(side);
  const vec3 axis = b - a;
  const float axis_sq = glm::dot(axis, axis);
  /* The SSV of the query against each node's PSS (§5.4: "recursively traversing the BVH
   * testing the hair's SSV against the bounding volumes"); a rectangle lies within its half
   * width of its segment. The core's box grown by max_distance (and a rounding margin): a
   * triangle whose box it misses is out of reach. */
  const vec3 grow(max_distance * 1.0001f + glm::length(glm::abs(a) + glm::abs(b)) * 1e-6f);
  const vec3 low = glm::min(a, b) - glm::abs(side) - grow;
  const vec3 high = glm::max(a, b) + glm::abs(side) + grow;
  PendingNodes pending;
  while (!pending.empty()) {
    const int32_t node_index = pending.pop();
    const Node &node = nodes_[size_t(node_index)];
    if (point_segment_distance(node.volume.center, a, b).distance - node.volume.radius -
            side_len >
        max_distance)
    {
      continue;
    }
    if (node.count == 0) {
      pending.push(node.first_or_right, node_index + 1);
      continue;
    }
    for (int32_t i = node.first_or_right; i < node.first_or_right + node.count; i++) {
      const int32_t t = leaf_triangles_[size_t(i)];
      const vec3 *c = corners(t);
      if (glm::any(glm::lessThan(glm::max(glm::max(c[0], c[1]), c[2]), low)) ||
          glm::any(glm::greaterThan(glm::min(glm::min(c[0], c[1]), c[2]), high)))
      {
        continue;
      }
      /* The triangle's plane bounds its distance from below: a core whose every point lies
       * farther than max_distance on one side of it is out of reach (most triangles of a
       * leaf), without the exact distance. The margin covers float rounding. */
      const vec3 &n = normal(t);
      if (n != vec3(0.0f)) {
        const float da = glm::dot(a - c[0], n), db = glm::dot(b - c[0], n);
        const float widen = strip ? std::abs(glm::dot(side, n)) : 0.0f;
        const float reach = max_distance * 1.0001f + widen +
                            1e-6f * (glm::length(a - c[0]) + glm::length(b - c[0]));
        if (std::min(da, db) > reach || std::max(da, db) < -reach) {
          continue;
        }
      }
      CoreDistance core;
      if (strip) {
        core = rectangle_triangle_distance({a - side, axis, 2.0f * side, 0.0f}, c[0], c[1], c[2]);
        core.s = axis_sq > 0.0f ?
                     std::clamp(glm::dot(core.point_a - a, axis) / axis_sq, 0.0f, 1.0f) :
                     0.0f;
      }
      else {
        core = segment_triangle_distance(a, b, c[0], c[1], c[2]);
      }
      if (core.distance <= max_distance) {
        r_contacts.push_back({t, core});
      }
    }
  }
}

namespace {

/* The shortest lever (share of the segment's length) a turn about the base is computed
 * with. */
constexpr float min_lever = 0.05f;

/* What one contact asks of a segment (object space): move the core's point at
 * (`s`, `across`) (SegmentCore::at) by `need` along `direction` (need ≤ 0: within reach, not
 * penetrating). */
struct Push {
  float need = -std::numeric_limits<float>::infinity();
  vec3 direction{0.0f};
  float s = 0.0f;
  /* Over a face: some of the core above the face lies within the radius of its plane or in
   * front of it. False when all of it lies farther behind (the far side of a thin body,
   * outside it). */
  bool reaches_face = true;
  float across = 0.0f;
};

/* The core of a segment's swept sphere (§5.2): the segment a–b, or a strip's rectangle, the
 * segment widened by `side` (orthogonal to it) both ways. */
struct SegmentCore {
  vec3 a, b;
  vec3 side{0.0f};

  vec3 at(const float s, const float across) const { return a + s * (b - a) + across * side; }
  /* The `across` of a point of the rectangle. */
  float across_of(const vec3 &p) const
  {
    const float side_sq = glm::dot(side, side);
    return side_sq > 0.0f ? glm::dot(p - a, side) / side_sq : 0.0f;
  }
};

/* A strip's side across segment a–b: its half width made orthogonal to the segment, its length
 * kept (as RectSS::from_segment makes the rectangle). Zero stays zero. */
vec3 strip_side(const vec3 &half_width, const vec3 &a, const vec3 &b)
{
  if (half_width == vec3(0.0f)) {
    return half_width;
  }
  return 0.5f *
         RectSS::from_segment(a, b, half_width, 2.0f * glm::length(half_width), 0.0f).edge_v;
}

/* §5.4: the penetration of a segment's core (radius r) into the body at one triangle, and the
 * direction to push it: over the face, the face's normal and the depth of the core's deepest
 * point over the face; at an edge or corner, along the closest-point vector. */
Push push_out_of_triangle(const SegmentCore &core, const float r, const SsvBVH &bvh,
                          const TriangleContact &contact)
{
  Push push;
  const vec3 n = bvh.normal(contact.triangle);
  const vec3 *t = bvh.corners(contact.triangle);
  if (n == vec3(0.0f)) {
    return push;
  }
  /* The core's corners (a segment: its two ends, a polygon of two) clipped to the triangle's
   * prism along n (Sutherland–Hodgman; each of the three planes adds at most one corner). */
  struct Corner {
    float s, across;
  };
  std::array<Corner, 8> polygon, clipped;
  int corners_num = 0;
  if (core.side == vec3(0.0f)) {
    polygon[0] = {0.0f, 0.0f};
    polygon[1] = {1.0f, 0.0f};
    corners_num = 2;
  }
  else {
    polygon[0] = {0.0f, -1.0f};
    polygon[1] = {1.0f, -1.0f};
    polygon[2] = {1.0f, 1.0f};
    polygon[3] = {0.0f, 1.0f};
    corners_num = 4;
  }
  for (int k = 0; k < 3 && corners_num > 0; k++) {
    const vec3 inward = glm::cross(n, t[(k + 1) % 3] - t[k]);
    std::array<float, 8> sides; /* each corner's, once */
    for (int i = 0; i < corners_num; i++) {
      const Corner &c = polygon[size_t(i)];
      sides[size_t(i)] = glm::dot(core.at(c.s, c.across) - t[k], inward);
    }
    int kept = 0;
    for (int i = 0; i < corners_num; i++) {
      const int j = (i + 1) % corners_num;
      const Corner &p = polygon[size_t(i)], &q = polygon[size_t(j)];
      const float fp = sides[size_t(i)], fq = sides[size_t(j)];
      if (fp >= 0.0f) {
        clipped[size_t(kept++)] = p;
      }
      if ((fp >= 0.0f) != (fq >= 0.0f)) {
        const float w = fp / (fp - fq);
        clipped[size_t(kept++)] = {p.s + w * (q.s - p.s), p.across + w * (q.across - p.across)};
      }
    }
    polygon = clipped;
    corners_num = kept;
  }
  if (corners_num > 0) {
    /* The deepest corner (of equal ones the farthest along: the longest lever). */
    float lowest = std::numeric_limits<float>::infinity();
    float highest = -lowest;
    for (int i = 0; i < corners_num; i++) {
      const Corner &c = polygon[size_t(i)];
      const float height = glm::dot(core.at(c.s, c.across) - t[0], n);
      highest = std::max(highest, height);
      if (height < lowest || (height == lowest && c.s > push.s)) {
        lowest = height;
        push.s = c.s;
        push.across = c.across;
      }
    }
    push.need = r - lowest;
    push.direction = n;
    push.reaches_face = highest >= -r;
    return push;
  }
  const float d = contact.core.distance;
  const vec3 away = contact.core.point_a - contact.core.point_b;
  if (d > 0.0f && glm::dot(away, n) >= 0.0f) {
    push.direction = away / d;
    push.need = r - d;
  }
  /* A core through the triangle's edge (d = 0) pierces a neighbour's face: that face's prism
   * gives its push. */
  push.s = contact.core.s;
  push.across = core.across_of(contact.core.point_a);
  return push;
}

/* The contacts of one segment: the deepest decides whether it is inside and how its velocity
 * is restricted; each iteration removes the shallowest penetration (a segment through a thin
 * body near its edge leaves it across the edge, not through its far face). */
struct Candidates {
  explicit Candidates(const float strand_radius) : radius(strand_radius) {}
  float radius; /* m, world */
  bool any = false;
  Push deepest;
  Push shallowest; /* of the penetrating ones (need > 0) */

  void add(const Push &push)
  {
    any = true;
    if (push.need > deepest.need) {
      deepest = push;
    }
    /* A push at the base deeper than the radius cannot be made by turning about the base:
     * it says how deep the segment is, not where to turn it. */
    const bool turnable = push.s > min_lever || push.need <= radius;
    if (turnable && push.need > 0.0f &&
        (!(shallowest.need > 0.0f) || push.need < shallowest.need)) {
      shallowest = push;
    }
  }
};

/* The tip of segment a–b (length kept) turned about a so that its point at push.s rises by
 * push.need along push.direction, to first order: the tip moves across the segment, along the
 * normal's component n⊥ perpendicular to it, by need / (s |n⊥|²). A segment pointing steeply
 * into the body (more than 60° from the surface) whose first-order turn would take the tip
 * farther than the segment's length is mirrored in the surface's plane instead. A shallow
 * push of a steep segment (its point grazing an edge) stays a small turn: mirrored, a
 * segment hanging past a thin body's edge would flip over onto its top. */
vec3 turn_out(const vec3 &a, const vec3 &b, const float length, const Push &push)
{
  const vec3 n = push.direction;
  const float len = glm::length(b - a);
  if (!(len > 0.0f) || !(length > 0.0f)) {
    return b;
  }
  const vec3 u = (b - a) / len;
  const float along = glm::dot(u, n);
  const vec3 across = n - along * u;
  const float lever = std::max(push.s, min_lever);
  const float step = 1.01f * push.need / (lever * glm::dot(across, across)) + 1e-7f;
  vec3 direction;
  if (along < -0.5f && !(step < length)) {
    direction = u - 2.0f * along * n;
  }
  else {
    direction = b + std::min(step, length) * across - a;
  }
  const float direction_len = glm::length(direction);
  return direction_len > 0.0f ? a + direction * (length / direction_len) : b;
}

}  // namespace

SsvObjectPass::SsvObjectPass(const ColliderSet *colliders, const SweptSphereParams &params)
    : colliders_(colliders), params_(params)
{
  rebuild();
}

void SsvObjectPass::rebuild()
{
  bodies_.clear();
  if (colliders_ == nullptr) {
    return;
  }
  for (int64_t i = 0; i < colliders_->colliders_num(); i++) {
    const Collider &collider = colliders_->collider(i);
    Body body;
    body.collider = &collider;
    body.bvh = SsvBVH(collider.vertices(), collider.triangles());
    bodies_.push_back(std::move(body));
  }
}

void SsvObjectPass::apply(const SubstepState &state)
{
  const MutableSpan<vec3> x = state.positions_wo;
  const MutableSpan<vec3> v = state.velocities_wo;
  const bool have_previous = int64_t(previous_velocities_.size()) == v.size();
  /* Strips' half widths turn with the head. */
  const mat3 head_turn = HeadPose::from_matrix(state.head_to_world).rotation_matrix();
  const auto keep_previous = [&]() {
    previous_velocities_.assign(v.begin(), v.end());
    previous_positions_.assign(x.begin(), x.end());
    previous_head_turn_ = head_turn;
  };
  if (!params_.uses_swept_spheres() || colliders_ == nullptr || bodies_.empty()) {
    keep_previous();
    return;
  }
  if (int64_t(bodies_.size()) != colliders_->colliders_num()) {
    rebuild();
  }
  const auto start = std::chrono::steady_clock::now();
  struct Frame {
    mat4 world_to_object, previous_world_to_object;
    mat3 direction_to_world; /* for unit vectors: rotation part (a similarity) */
    float scale;
  };
  std::vector<Frame> frames;
  for (Body &body : bodies_) {
    const mat4 &m = body.collider->object_to_world();
    const mat4 previous = body.has_previous ? body.previous_object_to_world : m;
    const float scale = uniform_scale(m);
    frames.push_back(
        {body.collider->world_to_object(), glm::inverse(previous), mat3(m) / scale, scale});
  }
  const Span<int32_t> offsets = state.curve_offsets;
  const float h = state.h;
  const float threshold = params_.distance_threshold;
  const float mu = params_.friction;
  constexpr int iterations_num = 8;

  struct Counts {
    int64_t pushed = 0, near = 0, unresolved = 0;
  };
  const Counts counts = parallel_reduce(
      offsets.size() - 1, 32, Counts{},
      [&](const IndexRange curves) {
        Counts local;
        std::vector<TriangleContact> contacts;
        for (int64_t c = curves.start; c < curves.one_after_last(); c++) {
          vec3 original_base = x[offsets[c]];
          for (int32_t k = offsets[c]; k + 1 < offsets[c + 1]; k++) {
            const vec3 a = x[k];
            const vec3 base_before = original_base;
            const float length = glm::length(x[k + 1] - base_before);
            original_base = x[k + 1];
            /* A strip's segment meets the body as its rectangle swept sphere (§5.2): the
             * segment widened by its half width both ways, grown by its radius. */
            float r = segment_radius(state.radii, params_.thickness, int64_t(k));
            const vec3 half_width_hs = segment_half_width(state.strip_half_widths_hs, int64_t(k));
            /* No farther out than its nodes were at rest (a group's skeleton nearer the body
             * than its radius, where its strands rest on it). */
            if (!state.rest_clearances.is_empty()) {
              r = std::min(r, std::min(state.rest_clearances[k], state.rest_clearances[k + 1]));
            }
            /* The base moved (the previous segment was pushed): keep this segment's length. */
            if (a != base_before) {
              const vec3 dir = x[k + 1] - a;
              const float len = glm::length(dir);
              if (len > 0.0f) {
                x[k + 1] = a + dir * (length / len);
              }
            }
            const vec3 v_tip_before = v[k + 1];
            /* How far the segment moved in the substep: a face it crossed within the substep
             * is within that reach of it even when it went deeper than the threshold (a node
             * pressed at 0.2 m/s into a thin body's edge crosses 2 mm per 1/96 s), and the
             * face it came through is the one to leave by. */
            const float swept = h * std::max(glm::length(v[k]), glm::length(v[k + 1]));
            bool pushed = false, resolved = false;
            Push deepest_wo;
            /* The strip's side where it was at the substep's start. */
            const vec3 side_before_wo =
                have_previous ? strip_side(previous_head_turn_ * half_width_hs,
                                           previous_positions_[size_t(k)],
                                           previous_positions_[size_t(k) + 1]) :
                                strip_side(head_turn * half_width_hs, a, x[k + 1]);
            for (int iteration = 0; iteration <= iterations_num; iteration++) {
              const vec3 b = x[k + 1];
              const vec3 side_wo = strip_side(head_turn * half_width_hs, a, b);
              /* Faces met from behind count only when no face within reach was met from the
               * front (the segment was inside before: it still goes out along the normal). */
              Candidates front(r), behind(r);
              for (size_t i = 0; i < bodies_.size(); i++) {
                const Frame &f = frames[i];
                const vec3 a_o = transform_point(f.world_to_object, a);
                const vec3 b_o = transform_point(f.world_to_object, b);
                const SegmentCore core{a_o, b_o, mat3(f.world_to_object) * side_wo};
                const float r_o = r / f.scale;
                contacts.clear();
                bodies_[i].bvh.segment_contacts(a_o, b_o, (r + threshold + swept) / f.scale,
                                                contacts, core.side);
                for (const TriangleContact &contact : contacts) {
                  const Push push = push_out_of_triangle(core, r_o, bodies_[i].bvh, contact);
                  if (push.need > -std::numeric_limits<float>::infinity()) {
                    /* Only faces the segment met from their front at the substep's start:
                     * its point closest to the triangle was in front then. A segment whose
                     * part over a face lies all farther behind it than its radius (past a
                     * thin body's edge, its closest point level with the far face and
                     * its part over that face beyond the near one, outside the body) must
                     * also have had the point the push moves in front. */
                    const vec3 *t = bodies_[i].bvh.corners(contact.triangle);
                    const vec3 &n_o = bodies_[i].bvh.normal(contact.triangle);
                    const auto was_in_front = [&](const float s, const float across) {
                      /* Where the point was at the substep's start: as the last substep
                       * left it, or (on the first) back along its velocity. */
                      const vec3 p_before_wo =
                          (have_previous ?
                               glm::mix(previous_positions_[size_t(k)],
                                        previous_positions_[size_t(k) + 1], s) :
                               glm::mix(a, b, s) - h * glm::mix(v[k], v[k + 1], s)) +
                          across * side_before_wo;
                      const vec3 p_before_o =
                          transform_point(f.previous_world_to_object, p_before_wo);
                      return glm::dot(p_before_o - t[0], n_o) >= -r_o;
                    };
                    const bool from_front =
                        was_in_front(contact.core.s, core.across_of(contact.core.point_a)) &&
                        (push.reaches_face || was_in_front(push.s, push.across));
                    /* The base is placed: an overlap within the radius at the base (the
                     * base resting on the surface) is contact, not a penetration a turn
                     * about the base could remove; taken as the shallowest it would use up
                     * the iterations on a segment whose real penetration lies farther
                     * along. */
                    const bool base_overlap = push.s <= min_lever && push.need <= r_o;
                    (from_front ? front : behind)
                        .add({ base_overlap ? 0.0f : push.need * f.scale,
                               glm::normalize(f.direction_to_world * push.direction), push.s });
                  }
                }
              }
              const Candidates &used = front.any ? front : behind;
              deepest_wo = used.deepest;
              if (!(deepest_wo.need > 0.0f)) {
                resolved = true;
                break;
              }
              /* The turn: the shallowest of the faces met from the front, else of those met
               * from behind. */
              const Push &turn = used.shallowest.need > 0.0f ? used.shallowest :
                                                               behind.shallowest;
              if (iteration == iterations_num || !(turn.need > 0.0f)) {
                break;
              }
              /* §5.4: push the segment out along the normal by its penetration; its base is
               * placed, so its tip turns about it (a little past, to stop on the surface). */
              pushed = true;
              x[k + 1] = turn_out(a, b, length, turn);
            }
            local.pushed += pushed ? 1 : 0;
            local.unresolved += resolved ? 0 : 1;
            if (deepest_wo.need > -threshold) {
              /* §5.4: within the threshold, no velocity into the body; friction μ_f opposes
               * the tangential motion with the tangential acceleration's magnitude. */
              local.near++;
              const vec3 n = deepest_wo.direction;
              vec3 &vel = v[k + 1];
              const float into = glm::dot(vel, n);
              if (into < 0.0f) {
                vel -= into * n;
              }
              if (mu > 0.0f && have_previous && h > 0.0f) {
                const vec3 accel = (v_tip_before - previous_velocities_[size_t(k) + 1]) / h;
                const vec3 accel_t = accel - glm::dot(accel, n) * n;
                const vec3 vel_t = vel - glm::dot(vel, n) * n;
                const float speed_t = glm::length(vel_t);
                if (speed_t > 0.0f) {
                  const float slow = std::min(mu * glm::length(accel_t) * h, speed_t);
                  vel -= vel_t * (slow / speed_t);
                }
              }
            }
          }
        }
        return local;
      },
      [](const Counts &p, const Counts &q) {
        return Counts{p.pushed + q.pushed, p.near + q.near, p.unresolved + q.unresolved};
      });
  for (Body &body : bodies_) {
    body.previous_object_to_world = body.collider->object_to_world();
    body.has_previous = true;
  }
  keep_previous();
  stats_.pushed_num += counts.pushed;
  stats_.near_num += counts.near;
  stats_.unresolved_num += counts.unresolved;
  stats_.ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                   .count();
}

float segment_penetration_share(const Span<int32_t> curve_offsets, const Span<vec3> positions_wo,
                                const ColliderSet &colliders, const float tolerance_wo)
{
  const int64_t curves_num = curve_offsets.size() - 1;
  const int64_t segments_num = positions_wo.size() - curves_num;
  if (segments_num <= 0 || colliders.colliders_num() == 0) {
    return 0.0f;
  }
  /* Each collider's tolerance in its object units. */
  std::vector<float> tolerances;
  for (int64_t i = 0; i < colliders.colliders_num(); i++) {
    tolerances.push_back(tolerance_wo / uniform_scale(colliders.collider(i).object_to_world()));
  }
  const double cutting = parallel_sum(curves_num, 16, [&](const IndexRange curves) {
    double count = 0.0;
    for (int64_t c = curves.start; c < curves.one_after_last(); c++) {
      for (int32_t k = curve_offsets[c]; k + 1 < curve_offsets[c + 1]; k++) {
        bool cuts = false;
        for (int64_t i = 0; i < colliders.colliders_num() && !cuts; i++) {
          const Collider &collider = colliders.collider(i);
          const float tolerance = tolerances[size_t(i)];
          const vec3 a = transform_point(collider.world_to_object(), positions_wo[k]);
          const vec3 b = transform_point(collider.world_to_object(), positions_wo[k + 1]);
          /* At most a quarter of the tolerance apart, and at most max_segment_samples. */
          const float length = glm::length(b - a);
          const float spacing = std::max(0.25f * tolerance, length / float(max_segment_samples));
          const int samples = spacing > 0.0f ? 1 + int(std::ceil(length / spacing)) : 1;
          cuts = collider.exact().deeper_on_segment(a, b, samples, tolerance);
        }
        count += cuts ? 1.0 : 0.0;
      }
    }
    return count;
  });
  return float(cutting / double(segments_num));
}

}  // namespace hairdyn
