#pragma once
/* Collider meshes: triangles in the collider's object space, held in an OpenMesh TriMesh.
 * Rigid motion is the object's transform, applied to queries, never to the mesh. */
#include <string>

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include "core/math.hh"
#include "core/span.hh"

namespace hairdyn {

static_assert(sizeof(ivec3) == 12, "ivec3 must be packed: it maps onto (T, 3) int32 arrays");

struct MeshTraits : public OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3f;
  using Normal = OpenMesh::Vec3f;
  VertexAttributes(OpenMesh::Attributes::Normal);
  FaceAttributes(OpenMesh::Attributes::Normal);
};
using TriMesh = OpenMesh::TriMesh_ArrayKernelT<MeshTraits>;

/* Empty string when the arrays describe a usable triangle mesh; otherwise one sentence:
 * no faces, an index out of range, a degenerate index triple, a non-finite vertex or one
 * beyond max_mesh_coordinate. */
std::string find_mesh_error(Span<vec3> vertices, Span<ivec3> triangles);

/* Largest |coordinate| of a collider vertex (object units); find_mesh_error refuses more. */
constexpr float max_mesh_coordinate = 1e9f;

class ColliderMesh {
 public:
  /* The arrays must pass find_mesh_error. Triangles that would make the mesh non-manifold
   * are kept out of the half-edge structure and counted in skipped_triangles_num(). */
  ColliderMesh(Span<vec3> vertices, Span<ivec3> triangles);

  const TriMesh &mesh() const { return mesh_; }
  int64_t vertices_num() const { return int64_t(mesh_.n_vertices()); }
  int64_t triangles_num() const { return int64_t(mesh_.n_faces()); }
  /* Triangles OpenMesh refused (complex edges or vertices). */
  int64_t skipped_triangles_num() const { return skipped_triangles_num_; }
  /* Edges with a face on one side only: 0 for a closed mesh. */
  int64_t boundary_edges_num() const;

 private:
  TriMesh mesh_;
  int64_t skipped_triangles_num_ = 0;
};

}  // namespace hairdyn
