/* Bindings of native/lod: the level of detail of Ward & Lin 2003 (§4, §6). */
#include <cmath>
#include <string>

#include <pybind11/stl.h>

#include "bindings/arrays.hh"
#include "bindings/params.hh"
#include "lod/lod_solver_ward2003.hh"

namespace hairdyn::bindings {

namespace {

/* (C, 2) float32 scalp coordinates, one row per strand, all finite; None gives an empty span. */
Span<vec2> as_root_uvs(const py::handle obj, const int64_t curves_num)
{
  if (obj.is_none()) {
    return {};
  }
  const py::array array = check_array(obj, "root_uvs", py::dtype::of<float>(), "float32", 2);
  const Span<vec2> uvs(static_cast<const vec2 *>(array.data()), array.shape(0));
  if (uvs.size() != curves_num) {
    fail("root_uvs must have one row per strand (" + std::to_string(curves_num) + "), not " +
         std::to_string(uvs.size()));
  }
  for (int64_t i = 0; i < uvs.size(); i++) {
    if (!std::isfinite(uvs[i].x) || !std::isfinite(uvs[i].y)) {
      fail("root_uvs has a value that is not a finite number at row " + std::to_string(i));
    }
  }
  return uvs;
}

void check_lod_params(const LodParams &params)
{
  const std::string error = find_lod_params_error(params);
  if (!error.empty()) {
    fail("Level of detail: " + error);
  }
}

}  // namespace

void bind_lod(py::module_ &m)
{
  bind_params<LodParams>(m, "LodParams",
                         "Parameters of the level of detail (Ward & Lin 2003, sections 4 and 6).");

  m.def(
      "mean_distance",
      [](const py::handle a, const py::handle b) {
        const Span<vec3> first = as_float3(a, "a");
        const Span<vec3> second = as_float3(b, "b");
        if (first.size() != second.size()) {
          fail("a and b must have the same number of rows (" + std::to_string(first.size()) +
               " and " + std::to_string(second.size()) + ")");
        }
        py::gil_scoped_release release;
        return mean_distance(first, second);
      },
      py::arg("a"), py::arg("b"),
      "Mean distance (m) between corresponding rows of two (N, 3) float32 arrays: lod_error "
      "when a is LodSolver.positions and b a fine simulation of the same frames.");

  py::class_<LodSolver>(
      m, "LodSolver",
      "Strands simulated on a hierarchy of strips, clusters and strand groups that split and "
      "merge as the camera and the motion ask (Ward & Lin 2003); every strand of the groom "
      "follows the skeleton that drives it.")
      .def(py::init([](const py::handle curve_offsets, const py::handle rest_positions_wo,
                       const py::handle head_to_world_rest, const py::handle root_uvs,
                       const py::handle root_normals_wo, const StrandParams &strand_params,
                       const WindParams &wind, const LodParams &lod_params) {
             const Span<int32_t> offsets = as_int(curve_offsets, "curve_offsets");
             const Span<vec3> rest = as_float3(rest_positions_wo, "rest_positions_wo");
             check_groom(offsets, rest);
             const Span<vec2> uvs = as_root_uvs(root_uvs, offsets.size() - 1);
             const Span<vec3> normals = as_root_normals(root_normals_wo, offsets.size() - 1);
             const mat4 head = as_matrix(head_to_world_rest, "head_to_world_rest");
             check_lod_params(lod_params);
             py::gil_scoped_release release;
             return new LodSolver(offsets, rest, uvs, normals, head, strand_params, wind, lod_params);
           }),
           py::arg("curve_offsets"), py::arg("rest_positions_wo"), py::arg("head_to_world_rest"),
           py::arg("root_uvs") = py::none(), py::arg("root_normals_wo") = py::none(),
           py::arg("strand_params") = StrandParams(), py::arg("wind") = WindParams(),
           py::arg("lod_params") = LodParams(),
           "Builds the hierarchy (section 4) over root_uvs ((C, 2) float32 scalp coordinates, "
           "or None for a projection of the roots) and one strand solver per level.")
      .def(
          "step",
          [](LodSolver &self, const double frame_dt, const py::handle head_to_world,
             const py::handle view_projection) {
            if (!std::isfinite(frame_dt) || frame_dt <= 0.0 || frame_dt > 10.0) {
              fail("frame_dt must be between 0 and 10 seconds, not " + std::to_string(frame_dt));
            }
            const mat4 head = as_matrix(head_to_world, "head_to_world");
            const mat4 camera = as_matrix(view_projection, "view_projection");
            py::gil_scoped_release release;
            self.step(float(frame_dt), head, camera);
          },
          py::arg("frame_dt"), py::arg("head_to_world"), py::arg("view_projection"),
          "One frame: choose the levels (section 6.1) for the camera whose view-projection "
          "matrix (projection @ view, 4x4) is given, split and merge (6.2, 6.3), step, place the "
          "strands.")
      .def(
          "reset",
          [](LodSolver &self, const py::handle head_to_world) {
            const mat4 head = as_matrix(head_to_world, "head_to_world");
            py::gil_scoped_release release;
            self.reset(head);
          },
          py::arg("head_to_world"),
          "The rest shape carried by the head, at rest, at the coarsest level.")
      .def("set_colliders", &LodSolver::set_colliders, py::arg("colliders"),
           py::arg("params") = CollisionParams(), py::keep_alive<1, 2>(),
           "Collide every skeleton with a ColliderSet (kept alive by the solver), let it hide "
           "hair from the camera and keep the placed strands out of it; None for none of them.")
      .def("set_bodies", &LodSolver::set_bodies, py::arg("bodies"), py::keep_alive<1, 2>(),
           "Keep the placed strands out of a ColliderSet (kept alive by the solver), as deep as "
           "at rest at most, when the skeletons collide by a pass instead; None for none.")
      .def("set_occluders", &LodSolver::set_occluders, py::arg("occluders"),
           py::keep_alive<1, 2>(),
           "Let a ColliderSet (kept alive by the solver) hide hair from the camera without the "
           "skeletons colliding with it by the maps; None for none.")
      .def(
          "add_pass",
          [](LodSolver &self, SubstepPass *pass, const float strand_radius) {
            if (pass == nullptr) {
              fail("add_pass needs a SubstepPass, not None");
            }
            if (!(strand_radius >= 0.0f) || !std::isfinite(strand_radius)) {
              fail("strand_radius must be a finite length of 0 m or more");
            }
            self.add_pass(pass, strand_radius);
          },
          py::arg("substep_pass"), py::arg("strand_radius"), py::keep_alive<1, 2>(),
          "Run substep_pass after every substep over the active skeletons, each the swept-sphere "
          "volume of its group (Ward & Lin 2003 section 5.2: a strip a rectangle swept sphere, a "
          "cluster or strand group a line swept sphere, strand_radius in m plus the group's "
          "spread); kept alive by the solver.")
      .def(
          "set_radii",
          [](LodSolver &self, const py::handle radii) {
            self.set_radii(as_radii(radii, self.positions().size()));
          },
          py::arg("radii"),
          "The strands' radius per point, (N,) float32 in meters (a Curves radius attribute), "
          "for the passes' group volumes: at each skeleton point a group's widest strand's "
          "radius there plus its spread; None: add_pass's strand_radius.")
      .def("pass_ms", &LodSolver::pass_ms, py::arg("name"),
           "Milliseconds the pass named `name` took during the last step (0: no such pass).")
      .def_property_readonly(
          "positions",
          [](py::object self) { return float3_view(self.cast<LodSolver &>().positions(), self); },
          "World-space positions (N, 3) float32 of every strand of the groom.")
      .def_property_readonly(
          "lod_level",
          [](py::object self) { return int_view(self.cast<LodSolver &>().point_levels(), self); },
          "Per point (N,) int32: the level (depth in the hierarchy, 0 = top strips) of the "
          "skeleton that drives its strand.")
      .def_property_readonly(
          "strand_nodes",
          [](py::object self) { return int_view(self.cast<LodSolver &>().strand_nodes(), self); },
          "Per strand (C,) int32: the hierarchy node that drives it.")
      .def_property_readonly(
          "strip_ribbons",
          [](const LodSolver &self) {
            const int64_t vertices = int64_t(self.strip_nodes().size()) * 2 *
                                     self.hierarchy().skeleton_points_num();
            MutableSpan<vec3> out;
            py::array_t<float> array = new_float3(vertices, out);
            self.strip_ribbons(out);
            return array;
          },
          "Every strip of the hierarchy as a ribbon, (2 n S, 3) float32 world positions: per "
          "strip (strip_levels' order) and control point k, the skeleton point less (2k) and "
          "plus (2k + 1) its half width in the strip's current frames; a strip that is not "
          "active has every vertex at the root of its first strand (no area).")
      .def_property_readonly(
          "strip_levels",
          [](const LodSolver &self) {
            std::vector<int32_t> levels;
            for (const int32_t node : self.strip_nodes()) {
              levels.push_back(self.hierarchy().depth(node));
            }
            return levels;
          },
          "Per strip of strip_ribbons, its level (depth in the hierarchy).")
      .def_property_readonly(
          "skeletons_per_level", &LodSolver::active_per_level,
          "Active skeletons at each level (depth 0 .. max_depth) after the last step.")
      .def_property_readonly("active_num", &LodSolver::active_num,
                             "Active skeletons after the last step.")
      .def_property_readonly("contacts_num", &LodSolver::contacts_num,
                             "Skeleton nodes inside a collider during the last step, over its "
                             "substeps (the reaction constraint's contacts).")
      .def_property_readonly("stepped_num", &LodSolver::stepped_num,
                             "Skeletons the last step simulated: the active ones, and on a "
                             "switch those that drove strands at the frame before.")
      .def_property_readonly(
          "lod_switches",
          [](const LodSolver &self) {
            return self.splits_num() + self.merges_num() + self.collapses_num();
          },
          "Splits, merges and occlusion collapses made by the last step.")
      .def_property_readonly("splits_num", &LodSolver::splits_num)
      .def_property_readonly("merges_num", &LodSolver::merges_num)
      .def_property_readonly("collapses_num", &LodSolver::collapses_num)
      .def_property_readonly(
          "nodes_num", [](const LodSolver &self) { return self.hierarchy().nodes_num(); },
          "Nodes (skeletons) in the whole hierarchy.")
      .def_property_readonly(
          "top_nodes_num", [](const LodSolver &self) { return self.hierarchy().top_nodes_num(); },
          "Top-level strips.")
      .def_property_readonly(
          "max_depth", [](const LodSolver &self) { return self.hierarchy().max_depth(); })
      .def_property_readonly(
          "skeleton_points_num",
          [](const LodSolver &self) { return self.hierarchy().skeleton_points_num(); })
      .def_property_readonly("coarsest_level", &LodSolver::coarsest_level)
      .def_property_readonly("finest_level", &LodSolver::finest_level)
      .def_property_readonly(
          "lod_params", [](const LodSolver &self) { return self.lod_params(); },
          "A copy of the level-of-detail parameters.");
}

}  // namespace hairdyn::bindings
