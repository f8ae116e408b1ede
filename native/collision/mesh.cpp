/* OpenMesh grows its vertex property arrays with default-constructed (deliberately
 * uninitialised) VectorT values that add_vertex then overwrites; GCC 12 flags that inlined
 * copy as maybe-uninitialised. The warning is about OpenMesh's code, not ours. */
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

#include "collision/mesh.hh"

#include <sstream>

namespace hairdyn {

std::string find_mesh_error(const Span<vec3> vertices, const Span<ivec3> triangles)
{
  std::ostringstream msg;
  if (triangles.is_empty()) {
    return "the mesh has no faces";
  }
  for (int64_t i = 0; i < vertices.size(); i++) {
    if (!is_finite(vertices[i])) {
      msg << "vertex " << i << " has a position that is not a finite number";
      return msg.str();
    }
    /* Products of coordinates (cross products, squared distances) must stay finite in single
     * precision: beyond this the exact distance and the rays lose every digit. */
    if (glm::any(glm::greaterThan(glm::abs(vertices[i]), vec3(max_mesh_coordinate)))) {
      msg << "vertex " << i << " is farther than " << max_mesh_coordinate
          << " scene units from the object's origin";
      return msg.str();
    }
  }
  for (int64_t t = 0; t < triangles.size(); t++) {
    const ivec3 tri = triangles[t];
    for (int k = 0; k < 3; k++) {
      if (tri[k] < 0 || tri[k] >= vertices.size()) {
        msg << "triangle " << t << " uses vertex " << tri[k] << " but the mesh has "
            << vertices.size() << " vertices";
        return msg.str();
      }
    }
  }
  return {};
}

ColliderMesh::ColliderMesh(const Span<vec3> vertices, const Span<ivec3> triangles)
{
  assert(find_mesh_error(vertices, triangles).empty());
  mesh_.reserve(size_t(vertices.size()), size_t(triangles.size()) * 3 / 2,
                size_t(triangles.size()));
  for (const vec3 &v : vertices) {
    mesh_.add_vertex(TriMesh::Point(v.x, v.y, v.z));
  }
  for (const ivec3 &tri : triangles) {
    if (tri.x == tri.y || tri.y == tri.z || tri.z == tri.x) {
      skipped_triangles_num_++;
      continue;
    }
    const TriMesh::FaceHandle face = mesh_.add_face(TriMesh::VertexHandle(tri.x),
                                                    TriMesh::VertexHandle(tri.y),
                                                    TriMesh::VertexHandle(tri.z));
    if (!face.is_valid()) {
      skipped_triangles_num_++;
    }
  }
  mesh_.update_normals();
}

int64_t ColliderMesh::boundary_edges_num() const
{
  int64_t count = 0;
  for (const auto edge : mesh_.edges()) {
    count += mesh_.is_boundary(edge) ? 1 : 0;
  }
  return count;
}

}  // namespace hairdyn
