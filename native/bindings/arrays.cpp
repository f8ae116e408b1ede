#include "bindings/arrays.hh"

#include <cmath>

#include "groom/groom.hh"

namespace hairdyn::bindings {

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

Span<vec3> as_float3_unchecked(const py::handle obj, const char *name)
{
  const py::array array = check_array(obj, name, py::dtype::of<float>(), "float32", 3);
  return Span<vec3>(static_cast<const vec3 *>(array.data()), array.shape(0));
}

Span<float> as_float(const py::handle obj, const char *name)
{
  const py::array array = check_array(obj, name, py::dtype::of<float>(), "float32", 0);
  const Span<float> span(static_cast<const float *>(array.data()), array.shape(0));
  for (int64_t i = 0; i < span.size(); i++) {
    if (!std::isfinite(span[i])) {
      fail(std::string(name) + " has a value that is not a finite number (NaN or infinity) at index " +
           std::to_string(i));
    }
  }
  return span;
}

Span<vec3> as_float3(const py::handle obj, const char *name)
{
  const Span<vec3> span = as_float3_unchecked(obj, name);
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

Span<mat3> as_frames(const py::handle obj, const char *name)
{
  if (!py::isinstance<py::array>(obj)) {
    fail(std::string(name) + " must be a numpy array, not " +
         std::string(py::str(obj.get_type().attr("__name__"))));
  }
  const py::array array = py::reinterpret_borrow<py::array>(obj);
  if (!array.dtype().is(py::dtype::of<float>())) {
    fail(std::string(name) + " must have dtype float32, not " + std::string(py::str(array.dtype())));
  }
  if (array.ndim() != 3 || array.shape(1) != 3 || array.shape(2) != 3) {
    fail(std::string(name) + " must have shape (N, 3, 3)");
  }
  if (!(array.flags() & py::array::c_style)) {
    fail(std::string(name) + " must be C-contiguous (use numpy.ascontiguousarray)");
  }
  const Span<mat3> span(static_cast<const mat3 *>(array.data()), array.shape(0));
  for (int64_t i = 0; i < span.size(); i++) {
    if (!is_finite(span[i][0]) || !is_finite(span[i][1]) || !is_finite(span[i][2])) {
      fail(std::string(name) + " has a value that is not a finite number (NaN or infinity) at frame " +
           std::to_string(i));
    }
  }
  return span;
}

/* A 4x4 matrix in Blender's row-major order (numpy.array(obj.matrix_world)), any float
 * dtype; glm stores columns, hence the transpose. */
mat4 as_matrix(const py::handle obj, const char *name)
{
  const auto array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(obj);
  if (!array || array.ndim() != 2 || array.shape(0) != 4 || array.shape(1) != 4) {
    fail(std::string(name) + " must be a 4x4 matrix");
  }
  glm::dmat4 m(0.0);
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

py::array frames_view(const Span<mat3> span, const py::handle owner)
{
  static_assert(sizeof(mat3) == 9 * sizeof(float), "mat3 must be 9 packed floats");
  py::array view(py::dtype::of<float>(), {span.size(), int64_t(3), int64_t(3)},
                 {int64_t(sizeof(mat3)), int64_t(sizeof(vec3)), int64_t(sizeof(float))},
                 reinterpret_cast<const float *>(span.data()), owner);
  view.attr("setflags")(py::arg("write") = false);
  return view;
}

py::array int_view(const Span<int32_t> span, const py::handle owner)
{
  py::array view(py::dtype::of<int32_t>(), {span.size()}, {int64_t(sizeof(int32_t))},
                 span.data(), owner);
  view.attr("setflags")(py::arg("write") = false);
  return view;
}

}  // namespace hairdyn::bindings
