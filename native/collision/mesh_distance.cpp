#include "collision/mesh_distance.hh"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/parallel.hh"

namespace hairdyn {

MeshDistance::MeshDistance(const Span<vec3> vertices, const Span<ivec3> triangles)
    : bvh_(vertices, triangles)
{
  const size_t tris_num = size_t(triangles.size());
  face_normals_.resize(tris_num);
  edge_normals_.assign(tris_num * 3, vec3(0.0f));
  vertex_normals_.resize(tris_num * 3);
  std::vector<vec3> vertex_sum(size_t(vertices.size()), vec3(0.0f));
  for (size_t t = 0; t < tris_num; t++) {
    const ivec3 tri = triangles[int64_t(t)];
    const vec3 n = glm::cross(vertices[tri.y] - vertices[tri.x], vertices[tri.z] - vertices[tri.x]);
    const float len = glm::length(n);
    face_normals_[t] = len > 0.0f ? n / len : vec3(0.0f);
    /* Angle-weighted vertex pseudo-normals. */
    for (int k = 0; k < 3; k++) {
      const vec3 a = vertices[tri[k]];
      const vec3 e1 = vertices[tri[(k + 1) % 3]] - a, e2 = vertices[tri[(k + 2) % 3]] - a;
      const float l1 = glm::length(e1), l2 = glm::length(e2);
      if (l1 > 0.0f && l2 > 0.0f) {
        const float angle = std::acos(std::clamp(glm::dot(e1, e2) / (l1 * l2), -1.0f, 1.0f));
        vertex_sum[size_t(tri[k])] += angle * face_normals_[t];
      }
    }
  }
  /* Edge pseudo-normals: the sum of the normals of the faces on the edge, found by sorting
   * the (smaller vertex, larger vertex) keys of all triangle edges. */
  struct EdgeKey {
    uint64_t key;
    uint32_t corner;
  };
  std::vector<EdgeKey> keys(tris_num * 3);
  for (size_t t = 0; t < tris_num; t++) {
    const ivec3 tri = triangles[int64_t(t)];
    for (int k = 0; k < 3; k++) {
      const uint32_t a = uint32_t(tri[k]), b = uint32_t(tri[(k + 1) % 3]);
      keys[t * 3 + size_t(k)] = {(uint64_t(std::min(a, b)) << 32) | std::max(a, b),
                                 uint32_t(t * 3 + size_t(k))};
    }
  }
  std::sort(keys.begin(), keys.end(), [](const EdgeKey &x, const EdgeKey &y) {
    return x.key < y.key || (x.key == y.key && x.corner < y.corner);
  });
  for (size_t begin = 0; begin < keys.size();) {
    size_t end = begin;
    vec3 sum(0.0f);
    for (; end < keys.size() && keys[end].key == keys[begin].key; end++) {
      sum += face_normals_[keys[end].corner / 3];
    }
    for (size_t e = begin; e < end; e++) {
      edge_normals_[keys[e].corner] = sum;
    }
    begin = end;
  }
  for (size_t t = 0; t < tris_num; t++) {
    const ivec3 tri = triangles[int64_t(t)];
    for (int k = 0; k < 3; k++) {
      vertex_normals_[t * 3 + size_t(k)] = vertex_sum[size_t(tri[k])];
    }
  }
}

float MeshDistance::signed_distance(const vec3 &p) const
{
  const ClosestPoint cp = bvh_.closest_point(p);
  const size_t t = size_t(cp.triangle);
  vec3 pseudo_normal;
  switch (cp.feature) {
    case TriangleFeature::Face:
      pseudo_normal = face_normals_[t];
      break;
    case TriangleFeature::Edge:
      pseudo_normal = edge_normals_[t * 3 + size_t(cp.feature_index)];
      break;
    case TriangleFeature::Vertex:
    default:
      pseudo_normal = vertex_normals_[t * 3 + size_t(cp.feature_index)];
      break;
  }
  const float distance = std::sqrt(cp.distance_sq);
  return glm::dot(p - cp.point, pseudo_normal) < 0.0f ? -distance : distance;
}

float MeshDistance::depth(const vec3 &p) const
{
  const vec3 lo = bvh_.bounds_min(), hi = bvh_.bounds_max();
  if (p.x < lo.x || p.y < lo.y || p.z < lo.z || p.x > hi.x || p.y > hi.y || p.z > hi.z) {
    return 0.0f;
  }
  return std::max(-signed_distance(p), 0.0f);
}

bool MeshDistance::deeper_on_segment(const vec3 &a, const vec3 &b, const int samples,
                                     const float tolerance) const
{
  const vec3 lo = bvh_.bounds_min(), hi = bvh_.bounds_max();
  const float slack = 1e-5f * glm::length(hi - lo); /* as accumulate_depths */
  const float steps = float(std::max(samples, 1));
  const float spacing = glm::length(b - a) / steps;
  for (int j = 0; j <= samples;) {
    const vec3 p = glm::mix(a, b, float(j) / steps);
    const bool outside_box = p.x < lo.x || p.y < lo.y || p.z < lo.z || p.x > hi.x ||
                             p.y > hi.y || p.z > hi.z;
    /* Outside the bounding box the distance to the box bounds the distance to the mesh. */
    const float distance = outside_box ?
                               glm::length(glm::max(glm::max(lo - p, p - hi), vec3(0.0f))) :
                               signed_distance(p);
    if (!outside_box && -distance > tolerance) {
      return true;
    }
    const float reach = distance + tolerance - slack;
    j += 1 + (reach > 0.0f && spacing > 0.0f ? int(std::min(reach / spacing, float(samples))) :
                                                0);
  }
  return false;
}

void MeshDistance::accumulate_depths(const mat4 &world_to_object, const float scale,
                                     const Span<vec3> points_wo,
                                     const MutableSpan<float> r_depth) const
{
  std::lock_guard<std::mutex> lock(bounds_->mutex);
  std::vector<vec3> &reference = bounds_->points;
  std::vector<float> &bound = bounds_->distances;
  if (reference.size() != size_t(points_wo.size())) {
    reference.assign(size_t(points_wo.size()), vec3(0.0f));
    bound.assign(size_t(points_wo.size()), std::numeric_limits<float>::quiet_NaN()); /* unknown */
  }
  const vec3 lo = bvh_.bounds_min(), hi = bvh_.bounds_max();
  /* What float rounding of a distance may miss, in object units. */
  const float slack = 1e-5f * glm::length(hi - lo);
  parallel_for(points_wo.size(), 256, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      const vec3 p = transform_point(world_to_object, points_wo[i]);
      const float moved = glm::length(p - reference[size_t(i)]);
      if (bound[size_t(i)] - moved > slack) {
        continue; /* still outside */
      }
      if (moved <= slack && !std::isnan(bound[size_t(i)])) {
        /* Within rounding of where it was asked (a root carried with the head, which the
         * transform's rounding moves by 1e-7): that answer, off by at most `moved`; the
         * reference stays, so the drift never adds up past the slack. A positive bound is no
         * depth either way. */
        r_depth[i] = std::max(r_depth[i], std::max(-bound[size_t(i)], 0.0f) * scale);
        continue;
      }
      float distance;
      if (!is_finite(p)) {
        distance = std::numeric_limits<float>::quiet_NaN(); /* unknown: asked again */
      }
      else if (p.x < lo.x || p.y < lo.y || p.z < lo.z || p.x > hi.x || p.y > hi.y || p.z > hi.z) {
        /* Outside the bounding box: the distance to the box bounds the distance to the mesh. */
        distance = glm::length(glm::max(glm::max(lo - p, p - hi), vec3(0.0f)));
      }
      else {
        distance = signed_distance(p);
        r_depth[i] = std::max(r_depth[i], std::max(-distance, 0.0f) * scale);
      }
      reference[size_t(i)] = p;
      bound[size_t(i)] = distance;
    }
  });
}

float uniform_scale(const mat4 &m)
{
  return std::cbrt(std::abs(glm::determinant(mat3(m))));
}

void accumulate_penetration_depths(const MeshDistance &mesh, const mat4 &object_to_world,
                                   const Span<vec3> points_wo, const MutableSpan<float> r_depth_wo)
{
  assert(points_wo.size() == r_depth_wo.size());
  mesh.accumulate_depths(glm::inverse(object_to_world), uniform_scale(object_to_world), points_wo,
                         r_depth_wo);
}

PenetrationStats penetration_stats(const Span<float> depths_wo, const float tolerance_wo)
{
  PenetrationStats stats;
  stats.points_num = depths_wo.size();
  for (const float depth : depths_wo) {
    stats.max_depth = std::max(stats.max_depth, depth);
    stats.deeper_num += depth > tolerance_wo ? 1 : 0;
  }
  stats.share = stats.points_num > 0 ? float(double(stats.deeper_num) / double(stats.points_num)) :
                                       0.0f;
  return stats;
}

PenetrationStats penetration_stats(const MeshDistance &mesh, const mat4 &object_to_world,
                                   const Span<vec3> points_wo, const float tolerance_wo)
{
  std::vector<float> depths(size_t(points_wo.size()), 0.0f);
  accumulate_penetration_depths(mesh, object_to_world, points_wo, depths);
  return penetration_stats(depths, tolerance_wo);
}

}  // namespace hairdyn
