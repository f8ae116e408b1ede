/* Bindings of native/volume (Petrovic, Henne and Anderson 2006): the parameters, the density
 * grid, the hair shell and its transported normals, and the substep pass. */
#include <cmath>
#include <memory>

#include "bindings/arrays.hh"
#include "bindings/params.hh"
#include "groom/groom.hh"
#include "volume/hair_shell_petrovic2006.hh"
#include "volume/volume_pass.hh"

namespace hairdyn::bindings {

namespace {

mat4 as_head(const py::handle obj, const char *name)
{
  return obj.is_none() ? mat4(1.0f) : as_matrix(obj, name);
}

/* A grid's vertex values as a numpy array indexed [i, j, k] (Fortran order: i varies fastest,
 * as the grid stores them), copied. */
py::array grid_values(const GridFrame &grid, const Span<float> values)
{
  const py::ssize_t f = sizeof(float);
  py::array_t<float> array({py::ssize_t(grid.size.x), py::ssize_t(grid.size.y),
                            py::ssize_t(grid.size.z)},
                           {f, f * grid.size.x, f * grid.size.x * grid.size.y});
  std::copy(values.begin(), values.end(), array.mutable_data());
  return std::move(array);
}

/* Blender's row-major 4x4 of a glm matrix. */
py::array matrix_rows(const mat4 &m)
{
  py::array_t<float> array({4, 4});
  for (int row = 0; row < 4; row++) {
    for (int column = 0; column < 4; column++) {
      array.mutable_at(row, column) = m[column][row];
    }
  }
  return std::move(array);
}

Span<int32_t> as_groom(const py::handle curve_offsets, const Span<vec3> positions)
{
  const Span<int32_t> offsets = as_int(curve_offsets, "curve_offsets");
  check_groom(offsets, positions);
  return offsets;
}

std::unique_ptr<HairShell> make_shell(const py::handle curve_offsets,
                                      const py::handle rest_positions_wo,
                                      const py::handle head_to_world_rest,
                                      const VolumeParams &params)
{
  const Span<vec3> rest = as_float3(rest_positions_wo, "rest_positions_wo");
  const Span<int32_t> offsets = as_groom(curve_offsets, rest);
  const mat4 head = as_head(head_to_world_rest, "head_to_world_rest");
  std::unique_ptr<HairShell> shell;
  float densest = 0.0f;
  {
    py::gil_scoped_release release;
    shell = std::make_unique<HairShell>(offsets, rest, head, params);
    densest = max_value(shell->density());
  }
  if (!(densest > params.shell_threshold)) {
    fail("No part of the hair reaches the shell threshold (" +
         std::to_string(params.shell_threshold) + " nodes per grid vertex; the densest vertex has " +
         std::to_string(densest) + "): lower shell_threshold or raise shell_cell_size");
  }
  return shell;
}

}  // namespace

void bind_volume(py::module_ &m)
{
  bind_params<VolumeParams>(
      m, "VolumeParams",
      "Parameters of the volumetric hair methods (Petrovic, Henne and Anderson 2006).");

  m.def(
      "density_grid",
      [](const py::handle curve_offsets, const py::handle positions_wo,
         const py::handle head_to_world, const double cell_size) {
        const Span<vec3> positions = as_float3(positions_wo, "positions_wo");
        const Span<int32_t> offsets = as_groom(curve_offsets, positions);
        const mat4 head = rigid_head_to_world(as_head(head_to_world, "head_to_world"));
        const float cell = convert_param(&VolumeParams::cell_size, py::float_(cell_size));
        GridFrame grid;
        std::vector<float> density;
        {
          py::gil_scoped_release release;
          grid = grid_around(head_box(positions, glm::inverse(head)),
                             cell > 0.0f ? cell :
                                           std::max(mean_segment_length(offsets, positions),
                                                    min_segment_length(positions)),
                             1, head);
          PointBins bins;
          bin_points(grid, positions, bins);
          density.resize(size_t(grid.vertices_num()));
          std::vector<float> scratch;
          splat_density(grid, bins, density, scratch);
        }
        return py::make_tuple(grid_values(grid, density), matrix_rows(grid.grid_to_world()));
      },
      py::arg("curve_offsets"), py::arg("positions_wo"), py::arg("head_to_world") = py::none(),
      py::arg("cell_size") = 0.0,
      "The hair density of eq. 1 (Petrovic 2006) on a grid fixed to the head around the hair: "
      "(density, grid_to_world), density float32 indexed [i, j, k] in nodes per vertex, "
      "grid_to_world the 4x4 (row-major) taking vertex (i, j, k) to world space. cell_size 0 "
      "uses the mean segment length.");

  py::class_<HairShell>(
      m, "HairShell",
      "The hair shell of a rest groom (Petrovic 2006, §4.1): the iso-surface of the density at "
      "params.shell_threshold, its signed distance S (|∇S| = 1, fast sweeping), the normals "
      "N = ∇S (eq. 2) at the rest points, carried to any pose by parallel transport along the "
      "strands.")
      .def(py::init(&make_shell), py::arg("curve_offsets"), py::arg("rest_positions_wo"),
           py::arg("head_to_world_rest") = py::none(), py::arg("params") = VolumeParams())
      .def_property_readonly(
          "rest_normals",
          [](py::object self) { return float3_view(self.cast<HairShell &>().rest_normals(), self); },
          "Unit normals (N, 3) float32 at the rest points, world space (eq. 2).")
      .def_property_readonly(
          "density",
          [](const HairShell &self) { return grid_values(self.grid(), self.density()); },
          "The rest density (after shell_blur), indexed [i, j, k].")
      .def_property_readonly(
          "signed_distance",
          [](const HairShell &self) { return grid_values(self.grid(), self.signed_distance()); },
          "S in meters, negative inside the hair, indexed [i, j, k].")
      .def_property_readonly(
          "grid_to_world",
          [](const HairShell &self) { return matrix_rows(self.grid().grid_to_world()); },
          "4x4 (row-major) taking grid vertex (i, j, k) to world space at the rest head.")
      .def(
          "transport",
          [](const HairShell &self, const py::handle positions_wo, const py::handle head_to_world) {
            const Span<vec3> positions = as_float3(positions_wo, "positions_wo");
            if (positions.size() != self.rest_normals().size()) {
              fail("positions_wo must have one row per point of the rest groom (" +
                   std::to_string(self.rest_normals().size()) + "), not " +
                   std::to_string(positions.size()));
            }
            const mat4 head = as_head(head_to_world, "head_to_world");
            py::array_t<float> normals({positions.size(), int64_t(3)});
            const MutableSpan<vec3> r_normals(reinterpret_cast<vec3 *>(normals.mutable_data()),
                                              positions.size());
            py::gil_scoped_release release;
            self.transport(positions, head, r_normals);
            return normals;
          },
          py::arg("positions_wo"), py::arg("head_to_world") = py::none(),
          "The rest normals carried to these positions of the same strands, the head at "
          "head_to_world (Petrovic 2006, §4.1): (N, 3) float32.");

  m.def(
      "shell_normals",
      [](const py::handle curve_offsets, const py::handle rest_positions_wo,
         const py::handle head_to_world_rest, const VolumeParams &params) {
        const std::unique_ptr<HairShell> shell = make_shell(curve_offsets, rest_positions_wo,
                                                            head_to_world_rest, params);
        const Span<vec3> normals = shell->rest_normals();
        py::array_t<float> result({normals.size(), int64_t(3)});
        std::copy(normals.begin(), normals.end(), reinterpret_cast<vec3 *>(result.mutable_data()));
        return result;
      },
      py::arg("curve_offsets"), py::arg("rest_positions_wo"),
      py::arg("head_to_world_rest") = py::none(), py::arg("params") = VolumeParams(),
      "The hair-shell normals N = ∇S (Petrovic 2006, eq. 2) at the rest points: (N, 3) float32.");

  py::class_<VolumePass, SubstepPass>(
      m, "VolumePass",
      "Velocity smoothing (Petrovic 2006, §5.1) and density targeting (§5.2, eq. 3) on a grid "
      "fixed to the head, run after every substep of the strand solver.")
      .def(py::init<const VolumeParams &>(), py::arg("params") = VolumeParams())
      .def_property(
          "params", [](const VolumePass &self) { return self.params(); },
          [](VolumePass &self, const VolumeParams &params) { self.set_params(params); },
          "A copy of the parameters; assign a VolumeParams to change them.")
      .def(
          "set_target",
          [](VolumePass &self, const py::handle curve_offsets, const py::handle positions_wo,
             const py::handle head_to_world) {
            const Span<vec3> positions = as_float3(positions_wo, "positions_wo");
            as_groom(curve_offsets, positions);
            const mat4 head = as_head(head_to_world, "head_to_world");
            py::gil_scoped_release release;
            self.set_target(positions, head);
          },
          py::arg("curve_offsets"), py::arg("positions_wo"), py::arg("head_to_world") = py::none(),
          "The target shape of §5.2: any strands (another groom, or a frame of a bake), in world "
          "space with the head at head_to_world; it moves with the head. Targeting starts on the "
          "coarsest grid level.")
      .def("clear_target", &VolumePass::clear_target)
      .def_property_readonly("has_target", &VolumePass::has_target)
      .def("reset", &VolumePass::reset,
           "Targeting back to the coarsest level; the report figures cleared.")
      .def(
          "apply",
          [](VolumePass &self, const py::handle curve_offsets, const py::handle positions_wo,
             const py::handle velocities_wo, const double h, const py::handle head_to_world) {
            const MutableSpan<vec3> positions = as_float3_for_write(positions_wo, "positions_wo");
            const MutableSpan<vec3> velocities = as_float3_for_write(velocities_wo,
                                                                     "velocities_wo");
            if (velocities.size() != positions.size()) {
              fail("velocities_wo must have one row per point (" +
                   std::to_string(positions.size()) + "), not " +
                   std::to_string(velocities.size()));
            }
            if (!std::isfinite(h) || h <= 0.0 || h > 10.0) {
              fail("h must be between 0 and 10 seconds, not " + std::to_string(h));
            }
            SubstepState state;
            state.h = float(h);
            state.curve_offsets = as_groom(curve_offsets, positions);
            state.positions_wo = positions;
            state.velocities_wo = velocities;
            state.head_to_world = as_head(head_to_world, "head_to_world");
            py::gil_scoped_release release;
            self.apply(state);
          },
          py::arg("curve_offsets"), py::arg("positions_wo"), py::arg("velocities_wo"),
          py::arg("h"), py::arg("head_to_world") = py::none(),
          "Run one substep of length h over float32 (N, 3) arrays, changed in place (roots kept).")
      .def_property_readonly("volume_ms", &VolumePass::volume_ms,
                             "Milliseconds spent in the pass since the last reset.")
      .def_property_readonly("substeps_num", &VolumePass::substeps_num,
                             "Substeps the pass ran since the last reset.")
      .def_property_readonly("density_max", &VolumePass::density_max,
                             "Largest density of eq. 1 at the last substep (nodes per vertex).")
      .def_property_readonly("target_error", &VolumePass::target_error,
                             "E of eq. 3 on the finest grid at the last substep (0 without a "
                             "target).")
      .def_property_readonly("target_level", &VolumePass::target_level,
                             "Current coarse-to-fine level: cells of 2^level · cell_size.")
      .def_property_readonly("cell_size", &VolumePass::cell_size,
                             "Cell size in use, m (0 until the first substep when automatic).");
}

}  // namespace hairdyn::bindings
