#include "bindings/arrays.hh"

#include <cmath>
#include <vector>

#include "groom/groom.hh"

namespace hairdyn::bindings {

[[noreturn]] void fail(const std::string &message)
{
  throw py::value_error(message);
}

/* A C-contiguous numpy array of `dtype` with shape (rows, *inner). Any other object, dtype,
 * shape or layout raises ValueError naming the argument. */
static py::array check_rows(const py::handle obj, const char *name, const py::dtype &dtype,
                            const char *dtype_name, const std::vector<int64_t> &inner)
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
  bool shape_ok = array.ndim() == py::ssize_t(inner.size() + 1);
  for (size_t d = 0; shape_ok && d < inner.size(); d++) {
    shape_ok = array.shape(py::ssize_t(d + 1)) == inner[d];
  }
  if (!shape_ok) {
    std::string expected = "(N";
    for (const int64_t size : inner) {
      expected += ", " + std::to_string(size);
    }
    expected += inner.empty() ? ",)" : ")";
    std::string shape = "(";
    for (py::ssize_t d = 0; d < array.ndim(); d++) {
      shape += (d ? ", " : "") + std::to_string(array.shape(d));
    }
    shape += array.ndim() == 1 ? ",)" : ")";
    fail(std::string(name) + " must have shape " + expected + ", not " + shape);
  }
  if (!(array.flags() & py::array::c_style)) {
    fail(std::string(name) + " must be C-contiguous (use numpy.ascontiguousarray)");
  }
  return array;
}

/* ValueError naming the first row of `rows_num` rows of `row_size` floats with a NaN or an
 * infinity. */
static void check_finite(const float *data, const int64_t rows_num, const int64_t row_size,
                         const char *name, const char *row_word)
{
  for (int64_t i = 0; i < rows_num * row_size; i++) {
    if (!std::isfinite(data[i])) {
      fail(std::string(name) + " has a value that is not a finite number (NaN or infinity) at " +
           row_word + " " + std::to_string(i / row_size));
    }
  }
}

py::array check_array(const py::handle obj, const char *name, const py::dtype &dtype,
                      const char *dtype_name, const int64_t columns)
{
  return check_rows(obj, name, dtype, dtype_name,
                    columns == 0 ? std::vector<int64_t>{} : std::vector<int64_t>{columns});
}

Span<vec3> as_float3_unchecked(const py::handle obj, const char *name)
{
  const py::array array = check_array(obj, name, py::dtype::of<float>(), "float32", 3);
  return Span<vec3>(static_cast<const vec3 *>(array.data()), array.shape(0));
}

MutableSpan<vec3> as_float3_for_write(const py::handle obj, const char *name, const bool finite)
{
  const Span<vec3> span = finite ? as_float3(obj, name) : as_float3_unchecked(obj, name);
  if (!py::reinterpret_borrow<py::array>(obj).writeable()) {
    fail(std::string(name) + " must be a writeable array (it is changed in place)");
  }
  return MutableSpan<vec3>(const_cast<vec3 *>(span.data()), span.size());
}

Span<float> as_float(const py::handle obj, const char *name)
{
  const py::array array = check_array(obj, name, py::dtype::of<float>(), "float32", 0);
  const Span<float> span(static_cast<const float *>(array.data()), array.shape(0));
  check_finite(span.data(), span.size(), 1, name, "index");
  return span;
}

Span<float> as_radii(const py::handle obj, const int64_t points_num)
{
  if (obj.is_none()) {
    return {};
  }
  const Span<float> radii = as_float(obj, "radii");
  if (radii.size() != points_num) {
    fail("radii must have one value per point (" + std::to_string(points_num) + "), not " +
         std::to_string(radii.size()));
  }
  for (int64_t i = 0; i < radii.size(); i++) {
    if (radii[i] < 0.0f) {
      fail("radii must not be negative (row " + std::to_string(i) + ")");
    }
  }
  return radii;
}

Span<vec3> as_float3(const py::handle obj, const char *name)
{
  const Span<vec3> span = as_float3_unchecked(obj, name);
  check_finite(reinterpret_cast<const float *>(span.data()), span.size(), 3, name, "row");
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

Span<uint8_t> as_bool(const py::handle obj, const char *name)
{
  const py::array array = check_array(obj, name, py::dtype::of<bool>(), "bool", 0);
  static_assert(sizeof(bool) == sizeof(uint8_t));
  return Span<uint8_t>(static_cast<const uint8_t *>(array.data()), array.shape(0));
}

Span<mat3> as_frames(const py::handle obj, const char *name)
{
  const py::array array = check_rows(obj, name, py::dtype::of<float>(), "float32", {3, 3});
  const Span<mat3> span(static_cast<const mat3 *>(array.data()), array.shape(0));
  check_finite(static_cast<const float *>(array.data()), span.size(), 9, name, "frame");
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
  /* The core inverts these matrices (head frame, world to map space): a singular 3×3 part (an
   * object scaled to zero, or flattened onto a plane or a line) has no inverse and would turn
   * every point into NaN. The test is relative to the columns' lengths, so that a small but
   * invertible scale passes. */
  const glm::dmat3 linear(m);
  const double det = glm::determinant(linear);
  const double lengths = glm::length(linear[0]) * glm::length(linear[1]) * glm::length(linear[2]);
  if (!(std::abs(det) > 1e-9 * lengths && lengths > 0.0)) {
    fail(std::string(name) + " is singular: its object is scaled to zero or flattened along "
         "some axis, so it has no inverse; give the object a non-zero scale");
  }
  const mat4 result(m);
  const mat3 inverse = glm::inverse(mat3(result));
  for (int col = 0; col < 4; col++) {
    if (!std::isfinite(result[col].x) || !std::isfinite(result[col].y) ||
        !std::isfinite(result[col].z) || !std::isfinite(result[col].w) ||
        (col < 3 && !is_finite(inverse[col])))
    {
      fail(std::string(name) + " has values beyond single precision (its scale or position is "
           "too large or too small to simulate)");
    }
  }
  return result;
}

void check_groom(const Span<int32_t> curve_offsets, const Span<vec3> positions)
{
  const std::string error = find_groom_error(curve_offsets, positions);
  if (!error.empty()) {
    fail("Invalid hair: " + error + ".");
  }
}

/* A read-only numpy view of `data` with the given shape and strides (bytes); `owner` stays
 * alive as long as the view does. Every *_view below is one of these. */
static py::array read_only_view(const py::dtype &dtype, std::vector<py::ssize_t> shape,
                                std::vector<py::ssize_t> strides, const void *data,
                                const py::handle owner)
{
  py::array view(dtype, std::move(shape), std::move(strides), data, owner);
  view.attr("setflags")(py::arg("write") = false);
  return view;
}

void check_strands(const Span<int32_t> curve_offsets, const Span<vec3> positions)
{
  const std::string error = find_strands_error(curve_offsets, positions.size());
  if (!error.empty()) {
    fail("Invalid hair: " + error + ".");
  }
}

py::array_t<float> new_float3(const int64_t size, MutableSpan<vec3> &r_span)
{
  py::array_t<float> array({size, int64_t(3)});
  r_span = MutableSpan<vec3>(reinterpret_cast<vec3 *>(array.mutable_data()), size);
  return array;
}

py::array float3_view(const Span<vec3> span, const py::handle owner)
{
  return read_only_view(py::dtype::of<float>(), {span.size(), 3},
                        {py::ssize_t(sizeof(vec3)), py::ssize_t(sizeof(float))}, span.data(),
                        owner);
}

py::array frames_view(const Span<mat3> span, const py::handle owner)
{
  static_assert(sizeof(mat3) == 9 * sizeof(float), "mat3 must be 9 packed floats");
  return read_only_view(py::dtype::of<float>(), {span.size(), 3, 3},
                        {py::ssize_t(sizeof(mat3)), py::ssize_t(sizeof(vec3)),
                         py::ssize_t(sizeof(float))},
                        span.data(), owner);
}

py::array int_view(const Span<int32_t> span, const py::handle owner)
{
  return read_only_view(py::dtype::of<int32_t>(), {span.size()}, {py::ssize_t(sizeof(int32_t))},
                        span.data(), owner);
}

py::array float_view(const Span<float> span, const py::handle owner)
{
  return read_only_view(py::dtype::of<float>(), {span.size()}, {py::ssize_t(sizeof(float))},
                        span.data(), owner);
}

Span<vec3> as_root_normals(const py::handle obj, const int64_t curves_num)
{
  if (obj.is_none()) {
    return {};
  }
  const Span<vec3> normals = as_float3(obj, "root_normals_wo");
  if (normals.size() != curves_num) {
    fail("root_normals_wo must have one row per strand (" + std::to_string(curves_num) +
         "), not " + std::to_string(normals.size()));
  }
  for (int64_t i = 0; i < normals.size(); i++) {
    if (glm::length(normals[i]) < 1e-6f) {
      fail("root_normals_wo has a zero-length normal at row " + std::to_string(i));
    }
  }
  return normals;
}

}  // namespace hairdyn::bindings
