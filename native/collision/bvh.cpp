#include "collision/bvh.hh"

#include <algorithm>
#include <cmath>
#include <limits>

namespace hairdyn {

namespace {

constexpr float float_max = std::numeric_limits<float>::max();

/* Squared distance from p to the box [min, max] (0 inside). */
float box_distance_sq(const vec3 &p, const vec3 &min, const vec3 &max)
{
  const vec3 d = glm::max(glm::max(min - p, p - max), vec3(0.0f));
  return glm::dot(d, d);
}

/* Slab test: the parameter interval [r_t_near, r_t_far] of the ray inside the box. */
bool ray_box(const vec3 &origin, const vec3 &inv_dir, const vec3 &min, const vec3 &max,
             float t_max, float &r_t_near, float &r_t_far)
{
  const vec3 t0 = (min - origin) * inv_dir;
  const vec3 t1 = (max - origin) * inv_dir;
  const vec3 t_small = glm::min(t0, t1);
  const vec3 t_big = glm::max(t0, t1);
  r_t_near = std::max(std::max(t_small.x, t_small.y), std::max(t_small.z, 0.0f));
  r_t_far = std::min(std::min(t_big.x, t_big.y), std::min(t_big.z, t_max));
  /* A little slack so that rays grazing a flat box (one thickness 0) still enter it. */
  return r_t_near <= r_t_far * (1.0f + 1e-6f) + 1e-30f;
}

vec3 safe_inverse(const vec3 &d)
{
  vec3 inv;
  for (int k = 0; k < 3; k++) {
    inv[k] = d[k] != 0.0f ? 1.0f / d[k] : std::copysign(1e30f, d[k]);
  }
  return inv;
}

}  // namespace

ClosestPoint closest_point_on_triangle(const vec3 &p, const vec3 &a, const vec3 &b,
                                       const vec3 &c)
{
  ClosestPoint result;
  const auto finish = [&](const vec3 &q, TriangleFeature feature, int index) {
    result.point = q;
    result.feature = feature;
    result.feature_index = int8_t(index);
    const vec3 d = p - q;
    result.distance_sq = glm::dot(d, d);
    return result;
  };
  const vec3 ab = b - a, ac = c - a, ap = p - a;
  const float d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0.0f && d2 <= 0.0f) {
    return finish(a, TriangleFeature::Vertex, 0);
  }
  const vec3 bp = p - b;
  const float d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0.0f && d4 <= d3) {
    return finish(b, TriangleFeature::Vertex, 1);
  }
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) {
    const float v = d1 / (d1 - d3);
    return finish(a + v * ab, TriangleFeature::Edge, 0);
  }
  const vec3 cp = p - c;
  const float d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0.0f && d5 <= d6) {
    return finish(c, TriangleFeature::Vertex, 2);
  }
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) {
    const float w = d2 / (d2 - d6);
    return finish(a + w * ac, TriangleFeature::Edge, 2);
  }
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f) {
    const float w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return finish(b + w * (c - b), TriangleFeature::Edge, 1);
  }
  const float denom = va + vb + vc;
  if (!(denom > 0.0f)) {
    /* Degenerate triangle that passed every region test: its corner a is as good as any. */
    return finish(a, TriangleFeature::Vertex, 0);
  }
  const float v = vb / denom, w = vc / denom;
  return finish(a + ab * v + ac * w, TriangleFeature::Face, 0);
}

bool intersect_ray_triangle(const vec3 &origin, const vec3 &direction, const vec3 &a,
                            const vec3 &b, const vec3 &c, RayHit &r_hit)
{
  const vec3 e1 = b - a, e2 = c - a;
  const vec3 pvec = glm::cross(direction, e2);
  const float det = glm::dot(e1, pvec);
  if (std::abs(det) < 1e-20f) {
    return false;
  }
  const float inv_det = 1.0f / det;
  const vec3 tvec = origin - a;
  const float u = glm::dot(tvec, pvec) * inv_det;
  constexpr float eps = 1e-5f;
  if (u < -eps || u > 1.0f + eps) {
    return false;
  }
  const vec3 qvec = glm::cross(tvec, e1);
  const float v = glm::dot(direction, qvec) * inv_det;
  if (v < -eps || u + v > 1.0f + eps) {
    return false;
  }
  const float t = glm::dot(e2, qvec) * inv_det;
  if (t < 0.0f) {
    return false;
  }
  r_hit.t = t;
  r_hit.u = u;
  r_hit.v = v;
  return true;
}

namespace {

void split_node(const int32_t begin, const int32_t end, const std::vector<vec3> &centroids,
                const int leaf_size, std::vector<int32_t> &order, std::vector<SplitNode> &nodes)
{
  const size_t index = nodes.size();
  nodes.push_back({begin, end, 0});
  vec3 cmin(float_max), cmax(-float_max);
  for (int32_t i = begin; i < end; i++) {
    cmin = glm::min(cmin, centroids[size_t(order[size_t(i)])]);
    cmax = glm::max(cmax, centroids[size_t(order[size_t(i)])]);
  }
  const vec3 extent = cmax - cmin;
  if (end - begin <= leaf_size || std::max(extent.x, std::max(extent.y, extent.z)) <= 0.0f) {
    return;
  }
  const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
  const int32_t mid = begin + (end - begin) / 2;
  std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                   [&](const int32_t a, const int32_t b) {
                     return centroids[size_t(a)][axis] < centroids[size_t(b)][axis] ||
                            (centroids[size_t(a)][axis] == centroids[size_t(b)][axis] && a < b);
                   });
  split_node(begin, mid, centroids, leaf_size, order, nodes);
  nodes[index].right = int32_t(nodes.size());
  split_node(mid, end, centroids, leaf_size, order, nodes);
}

}  // namespace

std::vector<SplitNode> median_split_tree(const Span<vec3> vertices, const Span<ivec3> triangles,
                                         const int leaf_size, std::vector<int32_t> &r_order)
{
  const int32_t tris_num = int32_t(triangles.size());
  r_order.resize(size_t(tris_num));
  std::vector<SplitNode> nodes;
  if (tris_num == 0) {
    return nodes;
  }
  std::vector<vec3> centroids(static_cast<size_t>(tris_num));
  for (int32_t t = 0; t < tris_num; t++) {
    r_order[size_t(t)] = t;
    const ivec3 tri = triangles[t];
    centroids[size_t(t)] = (vertices[tri.x] + vertices[tri.y] + vertices[tri.z]) / 3.0f;
  }
  nodes.reserve(size_t(2 * tris_num / std::max(leaf_size, 1) + 1));
  split_node(0, tris_num, centroids, std::max(leaf_size, 1), r_order, nodes);
  return nodes;
}

TriangleBVH::TriangleBVH(const Span<vec3> vertices, const Span<ivec3> triangles,
                         const int leaf_size)
{
  const std::vector<SplitNode> split =
      median_split_tree(vertices, triangles, leaf_size, triangle_ids_);
  corners_.resize(triangle_ids_.size() * 3);
  for (size_t i = 0; i < triangle_ids_.size(); i++) {
    const ivec3 tri = triangles[triangle_ids_[i]];
    corners_[i * 3 + 0] = vertices[tri.x];
    corners_[i * 3 + 1] = vertices[tri.y];
    corners_[i * 3 + 2] = vertices[tri.z];
  }
  nodes_.reserve(split.size());
  for (const SplitNode &node : split) {
    vec3 min(float_max), max(-float_max);
    for (size_t k = size_t(node.begin) * 3; k < size_t(node.end) * 3; k++) {
      min = glm::min(min, corners_[k]);
      max = glm::max(max, corners_[k]);
    }
    nodes_.push_back({min, max, node.is_leaf() ? node.begin : node.right,
                      node.is_leaf() ? node.end - node.begin : 0});
  }
}

template<typename Fn>
bool TriangleBVH::for_each_ray_hit(const vec3 &origin, const vec3 &direction, const float t_max,
                                   const Fn &fn) const
{
  if (nodes_.empty()) {
    return false;
  }
  const vec3 inv_dir = safe_inverse(direction);
  PendingNodes pending;
  while (!pending.empty()) {
    const int32_t node_index = pending.pop();
    const Node &node = nodes_[size_t(node_index)];
    float t_near, t_far;
    if (!ray_box(origin, inv_dir, node.min, node.max, t_max, t_near, t_far)) {
      continue;
    }
    if (node.count == 0) {
      pending.push(node.first_or_right, node_index + 1);
      continue;
    }
    for (int32_t i = node.first_or_right; i < node.first_or_right + node.count; i++) {
      RayHit hit;
      if (hit_leaf(origin, direction, t_max, i, hit) && fn(i, hit)) {
        return true;
      }
    }
  }
  return false;
}

bool TriangleBVH::hit_leaf(const vec3 &origin, const vec3 &direction, const float t_max,
                           const int32_t leaf, RayHit &r_hit) const
{
  const vec3 *c = &corners_[size_t(leaf) * 3];
  if (intersect_ray_triangle(origin, direction, c[0], c[1], c[2], r_hit) && r_hit.t <= t_max) {
    r_hit.triangle = triangle_ids_[size_t(leaf)];
    return true;
  }
  return false;
}

void TriangleBVH::ray_hits(const vec3 &origin, const vec3 &direction, const float t_max,
                           std::vector<RayHit> &r_hits) const
{
  r_hits.clear();
  for_each_ray_hit(origin, direction, t_max, [&](int32_t /*leaf*/, const RayHit &hit) {
    r_hits.push_back(hit);
    return false;
  });
  std::sort(r_hits.begin(), r_hits.end(), [](const RayHit &a, const RayHit &b) {
    return a.t < b.t || (a.t == b.t && a.triangle < b.triangle);
  });
}

bool TriangleBVH::ray_hits_any(const vec3 &origin, const vec3 &direction, const float t_max,
                               int32_t *const r_leaf) const
{
  int32_t found = -1;
  const bool hit = for_each_ray_hit(origin, direction, t_max,
                                    [&](const int32_t leaf, const RayHit & /*hit*/) {
                                      found = leaf;
                                      return true;
                                    });
  if (r_leaf != nullptr) {
    *r_leaf = found;
  }
  return hit;
}

bool TriangleBVH::ray_hits_leaf(const vec3 &origin, const vec3 &direction, const float t_max,
                                const int32_t leaf) const
{
  RayHit hit;
  return leaf >= 0 && leaf < int32_t(triangle_ids_.size()) &&
         hit_leaf(origin, direction, t_max, leaf, hit);
}

bool TriangleBVH::ray_farthest_hit(const vec3 &origin, const vec3 &direction,
                                   RayHit &r_hit) const
{
  if (nodes_.empty()) {
    return false;
  }
  const vec3 inv_dir = safe_inverse(direction);
  bool found = false;
  float best_t = -1.0f;
  PendingNodes pending;
  while (!pending.empty()) {
    const int32_t node_index = pending.pop();
    const Node &node = nodes_[size_t(node_index)];
    float t_near, t_far;
    if (!ray_box(origin, inv_dir, node.min, node.max, float_max, t_near, t_far) ||
        t_far * (1.0f + 1e-6f) < best_t)
    {
      continue;
    }
    if (node.count == 0) {
      pending.push(node_index + 1, node.first_or_right);
      continue;
    }
    for (int32_t i = node.first_or_right; i < node.first_or_right + node.count; i++) {
      RayHit hit;
      if (hit_leaf(origin, direction, float_max, i, hit) &&
          (hit.t > best_t || (hit.t == best_t && triangle_ids_[size_t(i)] < r_hit.triangle)))
      {
        best_t = hit.t;
        r_hit = hit;
        r_hit.triangle = triangle_ids_[size_t(i)];
        found = true;
      }
    }
  }
  return found;
}

ClosestPoint TriangleBVH::closest_point(const vec3 &p) const
{
  assert(!nodes_.empty());
  return closest_point(p, float_max);
}

ClosestPoint TriangleBVH::closest_point(const vec3 &p, const float max_distance_sq) const
{
  ClosestPoint best;
  best.distance_sq = max_distance_sq;
  if (nodes_.empty()) {
    return best;
  }
  PendingNodes pending;
  while (!pending.empty()) {
    const int32_t node_index = pending.pop();
    const Node &node = nodes_[size_t(node_index)];
    if (box_distance_sq(p, node.min, node.max) >= best.distance_sq) {
      continue;
    }
    if (node.count == 0) {
      const Node &left = nodes_[size_t(node_index + 1)];
      const Node &right = nodes_[size_t(node.first_or_right)];
      const float d_left = box_distance_sq(p, left.min, left.max);
      const float d_right = box_distance_sq(p, right.min, right.max);
      /* Nearer child on top of the stack, visited first. */
      if (d_left < d_right) {
        pending.push(node.first_or_right, node_index + 1);
      }
      else {
        pending.push(node_index + 1, node.first_or_right);
      }
      continue;
    }
    for (int32_t i = node.first_or_right; i < node.first_or_right + node.count; i++) {
      const vec3 *c = &corners_[size_t(i) * 3];
      const ClosestPoint candidate = closest_point_on_triangle(p, c[0], c[1], c[2]);
      if (candidate.distance_sq < best.distance_sq) {
        best = candidate;
        best.triangle = triangle_ids_[size_t(i)];
      }
    }
  }
  return best;
}

}  // namespace hairdyn
