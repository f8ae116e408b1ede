#pragma once
/* Shared checks for everything that crosses into the core: numpy arrays become spans over the
 * same memory after dtype, shape, contiguity and finiteness checks; anything wrong raises
 * ValueError with a sentence that names the argument. Each native area binds itself in its
 * own file through one bind_<area>(module) function, called from module.cpp. */
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <string>

#include "collision/mesh.hh"
#include "core/math.hh"
#include "core/span.hh"

namespace hairdyn::bindings {

namespace py = pybind11;

[[noreturn]] void fail(const std::string &message);

/* A C-contiguous numpy array of `dtype` with shape (rows, columns), or (rows,) when columns
 * is 0. */
py::array check_array(py::handle obj, const char *name, const py::dtype &dtype,
                      const char *dtype_name, int64_t columns);
/* (N, 3) float32, all finite. */
Span<vec3> as_float3(py::handle obj, const char *name);
/* (N, 3) float32, values not checked (for outputs and for measuring broken states). */
Span<vec3> as_float3_unchecked(py::handle obj, const char *name);
/* (N, 3) float32, writeable: a buffer changed in place; all finite unless `finite` is false. */
MutableSpan<vec3> as_float3_for_write(py::handle obj, const char *name, bool finite = true);
/* (N, 3) int32. */
Span<ivec3> as_int3(py::handle obj, const char *name);
/* (N,) int32. */
Span<int32_t> as_int(py::handle obj, const char *name);
/* (N,) bool, as 0 / 1 bytes. */
Span<uint8_t> as_bool(py::handle obj, const char *name);
/* (N,) float32, all finite. */
Span<float> as_float(py::handle obj, const char *name);
/* Per-point radii (N,) float32, finite and ≥ 0, or an empty span for None. */
Span<float> as_radii(py::handle obj, int64_t points_num);
/* (N, 3, 3) float32, all finite: N frames whose rows [i, 0], [i, 1], [i, 2] are the tangent,
 * bitangent and normal (glm's column-major mat3, column by column). */
Span<mat3> as_frames(py::handle obj, const char *name);
/* A 4x4 matrix in Blender's row-major order (numpy.array(obj.matrix_world)), any float dtype;
 * finite, invertible (a singular 3×3 part is refused: the core inverts every transform) and
 * within single precision. */
mat4 as_matrix(py::handle obj, const char *name);
/* Raises "Invalid hair: ..." unless the strands can be simulated. */
void check_groom(Span<int32_t> curve_offsets, Span<vec3> positions);
/* Raises "Invalid hair: ..." unless the offsets split the points into strands of two points or
 * more (find_strands_error): enough to walk them safely, whatever the values. */
void check_strands(Span<int32_t> curve_offsets, Span<vec3> positions);
/* One non-zero normal per strand, (C, 3) float32, or an empty span for None. */
Span<vec3> as_root_normals(py::handle obj, int64_t curves_num);
/* A new (N, 3) float32 array to write into, and its data as a span. */
py::array_t<float> new_float3(int64_t size, MutableSpan<vec3> &r_span);
/* A read-only numpy (N, 3) float32 view of `span`; `owner` lives as long as the view. */
py::array float3_view(Span<vec3> span, py::handle owner);
/* A read-only numpy (N, 3, 3) float32 view of `span` (see as_frames). */
py::array frames_view(Span<mat3> span, py::handle owner);
/* A read-only numpy (N,) int32 view of `span`. */
py::array int_view(Span<int32_t> span, py::handle owner);
/* A read-only numpy (N,) float32 view of `span`. */
py::array float_view(Span<float> span, py::handle owner);

void bind_groom(py::module_ &m);
void bind_collision(py::module_ &m);
void bind_strands(py::module_ &m);
void bind_lcp(py::module_ &m);
void bind_volume(py::module_ &m);
void bind_ssv(py::module_ &m);
void bind_lod(py::module_ &m);

}  // namespace hairdyn::bindings
