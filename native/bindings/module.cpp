/* hairdyn._native: every line of pybind11, and nothing else.
 *
 * Arrays cross the boundary without copies: (N, 3) float32 numpy arrays become Span<vec3>
 * over the same memory, and solver buffers come back as numpy views whose base keeps the
 * solver alive. Everything a caller can get wrong is checked here and raised as ValueError;
 * the core behind it assumes valid input. Native work runs with the GIL released. */
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <string>

#include "collision/mesh.hh"
#include "core/parallel.hh"
#include "groom/follow.hh"
#include "groom/groom.hh"
#include "groom/metrics.hh"

namespace py = pybind11;
using namespace hairdyn;

namespace {

[[noreturn]] void fail(const std::string &message)
{
  throw py::value_error(message);
}

/* A C-contiguous numpy array of `dtype` with shape (rows, columns), or (rows,) when columns
 * is 0. Any other object, dtype, shape or layout raises ValueError naming the argument. */
py::array check_array(const py::handle obj, const char *name, const py::dtype &dtype,
                      const char *dtype_name, const int64_t columns)
{
  if (!py::isinstance<py::array>(obj)) {
    fail(std::string(name) + " must be a numpy array, not " +
         std::string(py::str(obj.get_type().attr("__name__"))));
  }
  py::array array = py::reinterpret_borrow<py::array>(obj);
  if (!array.dtype().is(dtype)) {
    fail(std::string(name) + " must have dtype " + dtype_name + ", not " +
         std::string(py::str(array.dtype())));
  }
  const bool shape_ok = columns == 0 ? array.ndim() == 1 :
                                       (array.ndim() == 2 && array.shape(1) == columns);
  if (!shape_ok) {
    std::string shape = "(";
    for (py::ssize_t d = 0; d < array.ndim(); d++) {
      shape += (d ? ", " : "") + std::to_string(array.shape(d));
    }
    shape += array.ndim() == 1 ? ",)" : ")";
    fail(std::string(name) + " must have shape " +
         (columns == 0 ? std::string("(N,)") : "(N, " + std::to_string(columns) + ")") +
         ", not " + shape);
  }
  if (!(array.flags() & py::array::c_style)) {
    fail(std::string(name) + " must be C-contiguous (use numpy.ascontiguousarray)");
  }
  return array;
}

Span<vec3> as_float3(const py::handle obj, const char *name)
{
  const py::array array = check_array(obj, name, py::dtype::of<float>(), "float32", 3);
  const Span<vec3> span(static_cast<const vec3 *>(array.data()), array.shape(0));
  for (int64_t i = 0; i < span.size(); i++) {
    if (!is_finite(span[i])) {
      fail(std::string(name) + " has a value that is not a finite number (NaN or infinity) at row " +
           std::to_string(i));
    }
  }
  return span;
}

Span<ivec3> as_int3(const py::handle obj, const char *name)
{
  const py::array array = check_array(obj, name, py::dtype::of<int32_t>(), "int32", 3);
  return Span<ivec3>(static_cast<const ivec3 *>(array.data()), array.shape(0));
}

Span<int32_t> as_int(const py::handle obj, const char *name)
{
  const py::array array = check_array(obj, name, py::dtype::of<int32_t>(), "int32", 0);
  return Span<int32_t>(static_cast<const int32_t *>(array.data()), array.shape(0));
}

/* A 4x4 matrix in Blender's row-major order (numpy.array(obj.matrix_world)), any float
 * dtype; glm stores columns, hence the transpose. */
mat4 as_matrix(const py::handle obj, const char *name)
{
  const auto array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(obj);
  if (!array || array.ndim() != 2 || array.shape(0) != 4 || array.shape(1) != 4) {
    fail(std::string(name) + " must be a 4x4 matrix");
  }
  glm::dmat4 m;
  for (int row = 0; row < 4; row++) {
    for (int col = 0; col < 4; col++) {
      m[col][row] = array.at(row, col);
      if (!std::isfinite(m[col][row])) {
        fail(std::string(name) + " has a value that is not a finite number");
      }
    }
  }
  return mat4(m);
}

void check_groom(const Span<int32_t> curve_offsets, const Span<vec3> positions)
{
  const std::string error = find_groom_error(curve_offsets, positions);
  if (!error.empty()) {
    fail("Invalid hair: " + error + ".");
  }
}

/* A numpy (N, 3) float32 view of `span`; `owner` stays alive as long as the view does. */
py::array float3_view(const Span<vec3> span, const py::handle owner)
{
  py::array view(py::dtype::of<float>(), {span.size(), int64_t(3)},
                 {int64_t(sizeof(vec3)), int64_t(sizeof(float))},
                 reinterpret_cast<const float *>(span.data()), owner);
  view.attr("setflags")(py::arg("write") = false);
  return view;
}

}  // namespace

PYBIND11_MODULE(_native, m)
{
  m.doc() = "hairdyn native solver core";
  m.attr("__version__") = "0.1.0";

  m.def(
      "buffer_address",
      [](const py::handle positions) {
        return reinterpret_cast<uintptr_t>(as_float3(positions, "positions").data());
      },
      "Address of the memory the core reads for an (N, 3) float32 array (proves zero-copy).");

  m.def(
      "validate_groom",
      [](const py::handle curve_offsets, const py::handle positions) {
        check_groom(as_int(curve_offsets, "curve_offsets"), as_float3(positions, "positions"));
      },
      py::arg("curve_offsets"), py::arg("positions"),
      "Raise ValueError with a sentence if the strands cannot be simulated.");

  m.def(
      "max_relative_stretch",
      [](const py::handle curve_offsets, const py::handle rest_positions,
         const py::handle positions) {
        const Span<int32_t> offsets = as_int(curve_offsets, "curve_offsets");
        const Span<vec3> rest = as_float3(rest_positions, "rest_positions");
        const py::array current = check_array(positions, "positions", py::dtype::of<float>(),
                                              "float32", 3);
        check_groom(offsets, rest);
        if (current.shape(0) != rest.size()) {
          fail("positions and rest_positions must have the same number of points");
        }
        const Span<vec3> now(static_cast<const vec3 *>(current.data()), current.shape(0));
        py::gil_scoped_release release;
        return max_relative_stretch(offsets, rest, now);
      },
      py::arg("curve_offsets"), py::arg("rest_positions"), py::arg("positions"),
      "Largest relative change of a segment length (0 = no stretch; inf if a point is NaN).");

  m.def(
      "count_nonfinite",
      [](const py::handle positions) {
        const py::array array = check_array(positions, "positions", py::dtype::of<float>(),
                                            "float32", 3);
        return count_nonfinite(
            Span<vec3>(static_cast<const vec3 *>(array.data()), array.shape(0)));
      },
      py::arg("positions"), "Number of points with a NaN or infinite coordinate.");

  m.def("set_thread_num", &set_thread_num, py::arg("thread_num"),
        "Threads the solvers use; 0 means all cores.");
  m.def("thread_num", &thread_num);

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

  py::class_<FollowSolver>(m, "FollowSolver",
                           "Kinematic baseline: strands carried rigidly by the head.")
      .def(py::init([](const py::handle curve_offsets, const py::handle rest_positions_wo,
                       const py::handle head_to_world_rest) {
             const Span<int32_t> offsets = as_int(curve_offsets, "curve_offsets");
             const Span<vec3> rest = as_float3(rest_positions_wo, "rest_positions_wo");
             check_groom(offsets, rest);
             const mat4 head = as_matrix(head_to_world_rest, "head_to_world_rest");
             py::gil_scoped_release release;
             return new FollowSolver(offsets, rest, head);
           }),
           py::arg("curve_offsets"), py::arg("rest_positions_wo"), py::arg("head_to_world_rest"))
      .def(
          "step",
          [](FollowSolver &self, const py::handle head_to_world) {
            const mat4 head = as_matrix(head_to_world, "head_to_world");
            py::gil_scoped_release release;
            self.step(head);
          },
          py::arg("head_to_world"), "Place the strands for the head's current transform.")
      .def("reset", &FollowSolver::reset, py::call_guard<py::gil_scoped_release>())
      .def_property_readonly(
          "positions",
          [](py::object self) { return float3_view(self.cast<FollowSolver &>().positions(), self); },
          "World-space positions (N, 3) float32: a read-only view of the solver's buffer.")
      .def_property_readonly("rest_positions", [](py::object self) {
        return float3_view(self.cast<FollowSolver &>().rest_positions(), self);
      });
}
