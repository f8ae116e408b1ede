#include "collision/radial_map.hh"

#include <algorithm>

namespace hairdyn {

mat4 MapFrame::map_to_object() const
{
  const vec3 z = glm::cross(reference, axis);
  mat4 m(1.0f);
  m[0] = vec4(reference, 0.0f);
  m[1] = vec4(axis, 0.0f);
  m[2] = vec4(z, 0.0f);
  m[3] = vec4(origin, 1.0f);
  return m;
}

mat4 MapFrame::object_to_map() const
{
  /* Inverse of a rigid transform: transpose the rotation, rotate the translation back. */
  const mat3 rotation_t = glm::transpose(mat3(map_to_object()));
  mat4 m(rotation_t);
  m[3] = vec4(-(rotation_t * origin), 1.0f);
  return m;
}

MapFrame make_frame(const vec3 &origin, const vec3 &axis, const vec3 &reference)
{
  MapFrame frame;
  frame.origin = origin;
  const float axis_len = glm::length(axis);
  frame.axis = axis_len > 0.0f ? axis / axis_len : vec3(0.0f, 1.0f, 0.0f);
  vec3 ref = reference - glm::dot(reference, frame.axis) * frame.axis;
  if (!(glm::length(ref) > 1e-6f * std::max(glm::length(reference), 1.0f))) {
    /* Any direction perpendicular to the axis. */
    const vec3 helper = std::abs(frame.axis.x) < 0.9f ? vec3(1, 0, 0) : vec3(0, 1, 0);
    ref = helper - glm::dot(helper, frame.axis) * frame.axis;
  }
  frame.reference = glm::normalize(ref);
  return frame;
}

namespace {

/* Eigenvectors of a symmetric 3x3 matrix by cyclic Jacobi rotations; columns of r_vectors,
 * sorted by decreasing eigenvalue. */
void symmetric_eigen(glm::dmat3 a, glm::dvec3 &r_values, glm::dmat3 &r_vectors)
{
  glm::dmat3 v(1.0);
  for (int sweep = 0; sweep < 50; sweep++) {
    const double off = a[1][0] * a[1][0] + a[2][0] * a[2][0] + a[2][1] * a[2][1];
    if (off < 1e-30 * (a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2]) + 1e-300) {
      break;
    }
    for (int p = 0; p < 2; p++) {
      for (int q = p + 1; q < 3; q++) {
        if (a[q][p] == 0.0) {
          continue;
        }
        const double theta = (a[q][q] - a[p][p]) / (2.0 * a[q][p]);
        const double t = (theta >= 0.0 ? 1.0 : -1.0) /
                         (std::abs(theta) + std::sqrt(theta * theta + 1.0));
        const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
        glm::dmat3 rot(1.0);
        rot[p][p] = c;
        rot[q][q] = c;
        rot[q][p] = s;
        rot[p][q] = -s;
        a = glm::transpose(rot) * a * rot;
        v = v * rot;
      }
    }
  }
  int order[3] = {0, 1, 2};
  std::sort(order, order + 3, [&](const int i, const int j) { return a[i][i] > a[j][j]; });
  for (int k = 0; k < 3; k++) {
    r_values[k] = a[order[k]][order[k]];
    r_vectors[k] = v[order[k]];
  }
}

/* Deterministic sign: the largest component positive. */
vec3 canonical_sign(const glm::dvec3 &d)
{
  int largest = 0;
  for (int k = 1; k < 3; k++) {
    largest = std::abs(d[k]) > std::abs(d[largest]) ? k : largest;
  }
  return vec3(d[largest] < 0.0 ? -d : d);
}

}  // namespace

MapFrame fit_frame(const Span<vec3> vertices, const Span<ivec3> triangles)
{
  double area_sum = 0.0;
  glm::dvec3 centroid(0.0);
  for (const ivec3 &tri : triangles) {
    const glm::dvec3 a(vertices[tri.x]), b(vertices[tri.y]), c(vertices[tri.z]);
    const double area = 0.5 * glm::length(glm::cross(b - a, c - a));
    area_sum += area;
    centroid += area * (a + b + c) / 3.0;
  }
  if (!(area_sum > 0.0)) {
    return make_frame(vertices.is_empty() ? vec3(0.0f) : vertices[triangles[0].x],
                      vec3(0, 1, 0), vec3(1, 0, 0));
  }
  centroid /= area_sum;
  glm::dmat3 covariance(0.0);
  for (const ivec3 &tri : triangles) {
    const glm::dvec3 a(vertices[tri.x]), b(vertices[tri.y]), c(vertices[tri.z]);
    const double area = 0.5 * glm::length(glm::cross(b - a, c - a));
    const glm::dvec3 d = (a + b + c) / 3.0 - centroid;
    covariance += area * glm::outerProduct(d, d);
  }
  glm::dvec3 values;
  glm::dmat3 vectors;
  symmetric_eigen(covariance, values, vectors);
  return make_frame(vec3(centroid), canonical_sign(vectors[0]), canonical_sign(vectors[1]));
}

int64_t RadialTable::empty_cells_num() const
{
  return std::count_if(cells_.begin(), cells_.end(),
                       [](const MapCell &cell) { return cell.radius < 0.0f; });
}

void RadialTable::update_max_radius()
{
  max_radius_ = 0.0f;
  for (const MapCell &cell : cells_) {
    max_radius_ = std::max(max_radius_, cell.radius);
  }
}

void fill_cell_from_ray(const TriangleBVH &bvh, const Span<vec3> vertices,
                        const Span<ivec3> triangles, const mat4 &map_to_object,
                        const vec3 &origin_map, const vec3 &direction_map, MapCell &r_cell)
{
  const vec3 origin = transform_point(map_to_object, origin_map);
  const vec3 direction = mat3(map_to_object) * direction_map;
  RayHit hit;
  if (!bvh.ray_farthest_hit(origin, direction, hit)) {
    r_cell = MapCell{};
    return;
  }
  const ivec3 tri = triangles[hit.triangle];
  const vec3 face_normal = glm::cross(vertices[tri.y] - vertices[tri.x],
                                      vertices[tri.z] - vertices[tri.x]);
  const float len = glm::length(face_normal);
  /* Normal in map space (the frame is a rotation: its transpose is its inverse). */
  vec3 normal = len > 0.0f ? glm::transpose(mat3(map_to_object)) * (face_normal / len) :
                             direction_map;
  if (glm::dot(normal, direction_map) < 0.0f) {
    normal = -normal;
  }
  const float radius = hit.t * glm::length(direction_map);
  /* A mesh at the edge of single precision (coordinates near 1e19) can give a hit at an
   * infinite or NaN distance: such a ray describes nothing, its cell stays empty. */
  if (!(std::isfinite(radius) && radius >= 0.0f && is_finite(normal))) {
    r_cell = MapCell{};
    return;
  }
  r_cell.normal = normal;
  r_cell.radius = radius;
}

}  // namespace hairdyn
