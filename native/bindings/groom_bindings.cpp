/* Bindings of native/groom: validation, metrics, the follow-head baseline. */
#include "bindings/arrays.hh"

#include <cmath>

#include "core/columns.hh"
#include "core/parallel.hh"
#include "groom/follow.hh"
#include "groom/groom.hh"
#include "groom/metrics.hh"

namespace hairdyn::bindings {

void bind_groom(py::module_ &m)
{
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
      "degenerate_strands",
      [](const py::handle curve_offsets, const py::handle positions) {
        const Span<int32_t> offsets = as_int(curve_offsets, "curve_offsets");
        const Span<vec3> points = as_float3(positions, "positions");
        const std::string error = find_groom_error(offsets, points, false);
        if (!error.empty()) {
          fail("Invalid hair: " + error + ".");
        }
        py::array_t<bool> result(offsets.size() - 1);
        const MutableSpan<uint8_t> flags(reinterpret_cast<uint8_t *>(result.mutable_data()),
                                         offsets.size() - 1);
        py::gil_scoped_release release;
        find_degenerate_curves(offsets, points, flags);
        return result;
      },
      py::arg("curve_offsets"), py::arg("positions"),
      "(C,) bool: the strands with a segment shorter than min_segment_length(positions), which "
      "a reader drops (with a warning) rather than refusing the groom.");

  m.def(
      "min_segment_length",
      [](const py::handle positions) { return min_segment_length(as_float3(positions, "positions")); },
      py::arg("positions"),
      "Shortest segment a groom may have: a millionth of its bounding-box diagonal.");

  m.def(
      "point_tangents",
      [](const py::handle curve_offsets, const py::handle positions) {
        const Span<int32_t> offsets = as_int(curve_offsets, "curve_offsets");
        const Span<vec3> points = as_float3_unchecked(positions, "positions");
        check_strands(offsets, points);
        MutableSpan<vec3> tangents;
        py::array_t<float> result = new_float3(points.size(), tangents);
        py::gil_scoped_release release;
        point_tangents(offsets, points, tangents);
        return result;
      },
      py::arg("curve_offsets"), py::arg("positions"),
      "(N, 3) float32: each point's unit direction along its strand (its segment's; a tip its "
      "last segment's; zero for a zero-length segment, NaN where a point is NaN).");

  m.def(
      "strand_frame",
      [](const py::handle curve_offsets, const py::handle rest_positions,
         const py::handle positions, const py::handle previous_positions,
         const py::handle r_velocities, const py::handle r_tangents, const float dt) {
        const Span<int32_t> offsets = as_int(curve_offsets, "curve_offsets");
        const Span<vec3> rest = as_float3(rest_positions, "rest_positions");
        const Span<vec3> now = as_float3_unchecked(positions, "positions");
        const MutableSpan<vec3> previous =
            as_float3_for_write(previous_positions, "previous_positions", false);
        const MutableSpan<vec3> velocities = as_float3_for_write(r_velocities, "velocities", false);
        const MutableSpan<vec3> tangents = as_float3_for_write(r_tangents, "tangents", false);
        check_strands(offsets, rest);
        for (const int64_t size : {now.size(), previous.size(), velocities.size(), tangents.size()})
        {
          if (size != rest.size()) {
            fail("every array must have one row per point of rest_positions");
          }
        }
        if (!(dt > 0.0f && dt < INFINITY)) {
          fail("dt must be a positive number of seconds");
        }
        py::gil_scoped_release release;
        const StrandFrame frame =
            strand_frame(offsets, rest, now, dt, previous, velocities, tangents);
        return std::make_pair(frame.nonfinite, frame.stretch);
      },
      py::arg("curve_offsets"), py::arg("rest_positions"), py::arg("positions"),
      py::arg("previous_positions"), py::arg("velocities"), py::arg("tangents"), py::arg("dt"),
      "One pass over a frame's strand positions, into writeable (N, 3) float32 arrays: "
      "velocities = (positions - previous_positions) / dt, tangents = point_tangents, then "
      "previous_positions = positions. Returns (count_nonfinite, max_relative_stretch).");

  m.def(
      "point_bounds",
      [](const py::handle positions) {
        const Span<vec3> points = as_float3_unchecked(positions, "positions");
        py::array_t<float> result({2, 3});
        vec3 low, high;
        {
          py::gil_scoped_release release;
          point_bounds(points, low, high);
        }
        std::copy_n(glm::value_ptr(low), 3, result.mutable_data(0, 0));
        std::copy_n(glm::value_ptr(high), 3, result.mutable_data(1, 0));
        return result;
      },
      py::arg("positions"),
      "(2, 3) float32: the lowest and highest coordinates of (N, 3) float32 positions, NaN "
      "ignored (inf and -inf for none).");

  m.def(
      "split_columns",
      [](const py::handle table, const py::sequence outputs) {
        /* The table's width from its own shape, so that anything but a 2-D array fails in
         * check_array's words. */
        const bool two_d = py::isinstance<py::array>(table) &&
                           py::reinterpret_borrow<py::array>(table).ndim() == 2;
        const int64_t width = two_d ? py::reinterpret_borrow<py::array>(table).shape(1) : 1;
        const py::array source = check_array(table, "table", py::dtype::of<float>(), "float32",
                                             width);
        const int64_t rows = source.shape(0);
        std::vector<ColumnSpan> columns;
        /* Each item owned while it is read, and each output array until the copy is done: a
         * sequence may make its items as they are asked for (a numpy array's rows), and a
         * handle to one that nothing else holds dangled (a crash the fuzz test found). */
        std::vector<py::array> kept;
        for (const py::object item : outputs) {
          const py::tuple pair = item.cast<py::tuple>();
          if (pair.size() != 2) {
            fail("each output must be (array, first column)");
          }
          py::array out = check_array(pair[0], "output", py::dtype::of<float>(), "float32", 0);
          const int64_t start = pair[1].cast<int64_t>();
          const int64_t out_width = rows > 0 ? out.shape(0) / rows : 0;
          if (!out.writeable() || out.shape(0) != rows * out_width || start < 0 ||
              start + out_width > width || (rows > 0 && out_width == 0))
          {
            fail("an output must be a writable float32 array of whole rows of columns "
                 "inside the table");
          }
          columns.push_back({static_cast<float *>(out.mutable_data()), start, out_width});
          kept.push_back(std::move(out));
        }
        const float *values = static_cast<const float *>(source.data());
        py::gil_scoped_release release;
        return split_columns(values, rows, width, columns);
      },
      py::arg("table"), py::arg("outputs"),
      "Copy columns of a (N, W) float32 table into flat float32 arrays, outputs a sequence of "
      "(array of N * w values, first column), in one pass that also checks the whole table: "
      "returns whether every value is finite (the outputs are filled either way).");

  m.def("set_thread_num", &set_thread_num, py::arg("thread_num"),
        "Threads the solvers use; 0 means all cores.");
  m.def("thread_num", &thread_num);

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
          [](FollowSolver &self, const double frame_dt, const py::handle head_to_world) {
            if (!(std::isfinite(frame_dt) && frame_dt > 0.0)) {
              fail("frame_dt must be a positive number of seconds, not " + std::to_string(frame_dt));
            }
            const mat4 head = as_matrix(head_to_world, "head_to_world");
            py::gil_scoped_release release;
            self.step(head);
          },
          py::arg("frame_dt"), py::arg("head_to_world"),
          "Place the strands for the head's current transform. frame_dt is accepted so that "
          "every solver steps alike; the baseline has no dynamics and ignores it.")
      .def("reset", &FollowSolver::reset, py::call_guard<py::gil_scoped_release>())
      .def_property_readonly(
          "positions",
          [](py::object self) { return float3_view(self.cast<FollowSolver &>().positions(), self); },
          "World-space positions (N, 3) float32: a read-only view of the solver's buffer.")
      .def_property_readonly("rest_positions", [](py::object self) {
        return float3_view(self.cast<FollowSolver &>().rest_positions(), self);
      });
}

}  // namespace hairdyn::bindings
