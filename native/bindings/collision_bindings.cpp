/* Bindings of native/collision. */
#include "bindings/arrays.hh"

#include "collision/mesh.hh"

namespace hairdyn::bindings {

void bind_collision(py::module_ &m)
{
  py::class_<ColliderMesh>(m, "ColliderMesh",
                           "A collider's triangles in its object space (OpenMesh).")
      .def(py::init([](const py::handle vertices, const py::handle triangles) {
             const Span<vec3> verts = as_float3(vertices, "vertices");
             const Span<ivec3> tris = as_int3(triangles, "triangles");
             const std::string error = find_mesh_error(verts, tris);
             if (!error.empty()) {
               fail("Invalid collider mesh: " + error + ".");
             }
             py::gil_scoped_release release;
             return new ColliderMesh(verts, tris);
           }),
           py::arg("vertices"), py::arg("triangles"))
      .def_property_readonly("vertices_num", &ColliderMesh::vertices_num)
      .def_property_readonly("triangles_num", &ColliderMesh::triangles_num)
      .def_property_readonly("skipped_triangles_num", &ColliderMesh::skipped_triangles_num)
      .def_property_readonly("boundary_edges_num", &ColliderMesh::boundary_edges_num);

}

}  // namespace hairdyn::bindings
