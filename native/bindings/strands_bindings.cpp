/* Bindings of native/strands (Kurihara 1993 strand dynamics) and the child hairs of
 * native/groom/children_kurihara1993. */
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "bindings/arrays.hh"
#include "bindings/params.hh"
#include "pybind11/stl.h"
#include "groom/children_kurihara1993.hh"
#include "groom/frames.hh"
#include "groom/groom.hh"
#include "strands/strand_solver.hh"

namespace hairdyn::bindings {

namespace {

Span<mat3> as_guide_frames(const py::handle obj, const char *name, const int64_t guides_num)
{
  const Span<mat3> frames = as_frames(obj, name);
  if (frames.size() != guides_num) {
    fail(std::string(name) + " must have one frame per guide (" + std::to_string(guides_num) +
         "), not " + std::to_string(frames.size()));
  }
  return frames;
}

glm::dvec3 as_origin(const py::handle obj)
{
  if (obj.is_none()) {
    return glm::dvec3(0.0);
  }
  const auto values = py::cast<std::vector<double>>(obj);
  if (values.size() != 3 || !std::isfinite(values[0]) || !std::isfinite(values[1]) ||
      !std::isfinite(values[2])) {
    fail("origin_wo must be three finite numbers (meters, world space)");
  }
  return glm::dvec3(values[0], values[1], values[2]);
}

/* Single precision resolves about 1.2e-7 of a coordinate's magnitude: refuse coordinates so
 * far from the simulation origin that a step of the float is over a thousandth of the
 * shortest segment, and say how to fix it. */
void check_precision(const float magnitude, const float shortest_segment, const char *what)
{
  const float resolution = magnitude * std::numeric_limits<float>::epsilon();
  if (resolution > 1e-3f * shortest_segment) {
    fail(std::string(what) + " lies " + std::to_string(magnitude) +
         " m from the simulation origin, where single precision only resolves " +
         std::to_string(resolution) + " m, too coarse for segments of " +
         std::to_string(shortest_segment) +
         " m. Pass positions and transforms relative to a point near the character and give "
         "that point as origin_wo (the head's position, in double precision).");
  }
}

float max_magnitude(const Span<vec3> points)
{
  float result = 0.0f;
  for (const vec3 &p : points) {
    result = std::max({result, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
  }
  return result;
}

float translation_magnitude(const mat4 &m)
{
  return std::max({std::abs(m[3].x), std::abs(m[3].y), std::abs(m[3].z)});
}

}  // namespace

void bind_strands(py::module_ &m)
{
  bind_params<StrandParams>(m, "StrandParams",
                            "Parameters of the Strands method (Kurihara 1993; Ward & Lin 2003).");
  bind_params<WindParams>(m, "WindParams",
                          "The wind every method feels: a mean plus smooth turbulence.");
  py::class_<SubstepPass>(m, "SubstepPass",
                          "A groom-wide pass the strand solver runs after every substep "
                          "(volume, hair-hair collision, level of detail).")
      .def_property_readonly("name", [](const SubstepPass &self) { return std::string(self.name()); });

  m.def(
      "strand_gamma",
      [](const StrandParams &params, const double length) {
        if (!std::isfinite(length) || length <= 0.0) {
          fail("length must be a positive number of meters, not " + std::to_string(length));
        }
        return params.gamma(length);
      },
      py::arg("params"), py::arg("length"),
      "Γ = c g L³ / EI of a strand of `length` meters under the articulated model's material "
      "(c = ρ π r², EI = E π r⁴ / 4, g = |params.gravity|): well below 1 a strand stands "
      "nearly straight, well above 100 it hangs like a chain; a horizontal strand's tip drops "
      "about Γ/8 of its length while Γ is small. The panel shows it for the groom's mean "
      "strand length.");

  m.def(
      "root_frames",
      [](const py::handle curve_offsets, const py::handle positions,
         const py::handle root_normals) {
        const Span<int32_t> offsets = as_int(curve_offsets, "curve_offsets");
        const Span<vec3> points = as_float3(positions, "positions");
        check_groom(offsets, points);
        const Span<vec3> normals = as_root_normals(root_normals, offsets.size() - 1);
        py::array_t<float> frames({offsets.size() - 1, int64_t(3), int64_t(3)});
        const MutableSpan<mat3> r_frames(reinterpret_cast<mat3 *>(frames.mutable_data()),
                                         offsets.size() - 1);
        py::gil_scoped_release release;
        compute_root_frames(offsets, points, normals, r_frames);
        return frames;
      },
      py::arg("curve_offsets"), py::arg("positions"), py::arg("root_normals") = py::none(),
      "Each strand's root frame (C, 3, 3) float32, rows tangent, bitangent, normal; the normal "
      "is the first segment's direction where root_normals is None.");

  py::class_<StrandSolver>(
      m, "StrandSolver",
      "Strands as chains of rigid segments whose angles obey Kurihara 1993, eq. 1-7, integrated "
      "explicitly or implicitly (Ward & Lin 2003, appendix A).")
      .def(py::init([](const py::handle curve_offsets, const py::handle rest_positions_wo,
                       const py::handle head_to_world_rest, const py::handle root_normals_wo,
                       const StrandParams &params, const WindParams &wind,
                       const py::handle origin_wo) {
             const Span<int32_t> offsets = as_int(curve_offsets, "curve_offsets");
             const Span<vec3> rest = as_float3(rest_positions_wo, "rest_positions_wo");
             check_groom(offsets, rest);
             const Span<vec3> normals = as_root_normals(root_normals_wo, offsets.size() - 1);
             const mat4 head = as_matrix(head_to_world_rest, "head_to_world_rest");
             const glm::dvec3 origin = as_origin(origin_wo);
             std::unique_ptr<StrandSolver> solver;
             {
               py::gil_scoped_release release;
               solver = std::make_unique<StrandSolver>(offsets, rest, head, normals, params,
                                                       wind, origin);
             }
             check_precision(max_magnitude(rest), solver->shortest_segment(), "The groom");
             check_precision(translation_magnitude(head), solver->shortest_segment(),
                             "The head");
             return solver.release();
           }),
           py::arg("curve_offsets"), py::arg("rest_positions_wo"), py::arg("head_to_world_rest"),
           py::arg("root_normals_wo") = py::none(), py::arg("params") = StrandParams(),
           py::arg("wind") = WindParams(), py::arg("origin_wo") = py::none(),
           "Every position and transform is relative to origin_wo (3 floats, world meters, "
           "default 0): choose a point near the character so that precision does not depend "
           "on where it stands.")
      .def(
          "step",
          [](StrandSolver &self, const double frame_dt, const py::handle head_to_world) {
            if (!std::isfinite(frame_dt) || frame_dt <= 0.0 || frame_dt > 10.0) {
              fail("frame_dt must be between 0 and 10 seconds, not " + std::to_string(frame_dt));
            }
            const mat4 head = as_matrix(head_to_world, "head_to_world");
            check_precision(translation_magnitude(head), self.shortest_segment(), "The head");
            py::gil_scoped_release release;
            self.step(float(frame_dt), head);
          },
          py::arg("frame_dt"), py::arg("head_to_world"),
          "Advance one frame of frame_dt seconds (params.substeps substeps), the head moving to "
          "head_to_world.")
      .def(
          "reset",
          [](StrandSolver &self, const py::handle head_to_world) {
            if (head_to_world.is_none()) {
              py::gil_scoped_release release;
              self.reset();
              return;
            }
            const mat4 head = as_matrix(head_to_world, "head_to_world");
            py::gil_scoped_release release;
            self.reset(head);
          },
          py::arg("head_to_world") = py::none(),
          "Back to the rest shape, at rest; with head_to_world, carried rigidly to that head "
          "transform (the start frame of a bake).")
      .def_property(
          "params", [](const StrandSolver &self) { return self.params(); },
          [](StrandSolver &self, const StrandParams &params) { self.set_params(params); },
          "A copy of the parameters; assign a StrandParams to change them between steps.")
      .def_property(
          "wind", [](const StrandSolver &self) { return self.wind(); },
          [](StrandSolver &self, const WindParams &wind) { self.set_wind(wind); },
          "A copy of the wind; assign a WindParams to change it between steps.")
      .def(
          "add_pass",
          [](StrandSolver &self, SubstepPass *pass) {
            if (pass == nullptr) {
              fail("add_pass needs a SubstepPass, not None");
            }
            self.add_pass(pass);
          },
          py::arg("substep_pass"), py::keep_alive<1, 2>(),
          "Run substep_pass after every substep, after the passes added before (kept alive by "
          "the solver).")
      .def("clear_passes", &StrandSolver::clear_passes, "Remove every pass.")
      .def(
          "set_radii",
          [](StrandSolver &self, const py::handle radii) {
            PassVolumes volumes;
            const Span<float> values = as_radii(radii, self.positions().size());
            volumes.radii.assign(values.begin(), values.end());
            self.set_pass_volumes(std::move(volumes));
          },
          py::arg("radii"),
          "The strands' radius per point, (N,) float32 in meters (a Curves radius attribute), "
          "for the passes' swept spheres (Ward & Lin 2003 §5.2); None: each pass's own "
          "thickness everywhere.")
      .def(
          "set_pinned",
          [](StrandSolver &self, const py::handle pinned) {
            if (pinned.is_none()) {
              py::gil_scoped_release release;
              self.set_pinned({});
              return;
            }
            const Span<uint8_t> mask = as_bool(pinned, "pinned");
            if (mask.size() != self.positions().size()) {
              fail("pinned must have one value per point (" +
                   std::to_string(self.positions().size()) + "), not " +
                   std::to_string(mask.size()));
            }
            py::gil_scoped_release release;
            self.set_pinned(mask);
          },
          py::arg("pinned"),
          "Hold the points where pinned (N,) bool is True on their rest positions carried by "
          "the head, like the roots (TressFX's immovable vertices; the Curves attribute "
          "hairdyn_fixed); None pins only the roots.")
      .def_property_readonly(
          "pins_num", &StrandSolver::pins_num, "Points pinned after the roots (set_pinned).")
      .def("pass_ms", &StrandSolver::pass_ms, py::arg("name"),
           "Milliseconds the pass of that name took during the last step (0 if none has it).")
      .def_property_readonly(
          "diverged_num", &StrandSolver::diverged_num,
          "Strands whose state became non-finite or ran away (faster than 1 km/s) in the last "
          "step; they were put back on their rest shape. Non-zero: fail the frame, the "
          "settings are unstable (stiff hinges or strong drag on the explicit integrator, or a "
          "gale past about 50 m/s: more substeps, the implicit integrator, less wind or air "
          "drag).")
      .def(
          "set_colliders",
          [](StrandSolver &self, const ColliderSet *colliders, const CollisionParams &params) {
            self.set_colliders(colliders, params);
          },
          py::arg("colliders"), py::arg("params") = CollisionParams(), py::keep_alive<1, 2>(),
          "Collide with a ColliderSet (kept alive by the solver), or None for no collision. "
          "The set's colliders are read at every step: update their transforms first.")
      .def_property_readonly("contacts_num", &StrandSolver::contacts_num,
                             "Node-substeps the reaction constraint acted on in the last step.")
      .def_property_readonly("projections_num", &StrandSolver::projections_num,
                             "Node-substeps put back on a collider's surface in the last step.")
      .def_property_readonly(
          "origin_wo",
          [](const StrandSolver &self) {
            return py::make_tuple(self.origin().x, self.origin().y, self.origin().z);
          },
          "The world point every position is relative to (meters, double precision).")
      .def(
          "world_positions",
          [](const StrandSolver &self) {
            const Span<vec3> local = self.positions();
            py::array_t<double> result({local.size(), int64_t(3)});
            double *out = result.mutable_data();
            for (int64_t i = 0; i < local.size(); i++) {
              for (int axis = 0; axis < 3; axis++) {
                out[3 * i + axis] = self.origin()[axis] + double(local[i][axis]);
              }
            }
            return result;
          },
          "World positions (N, 3) float64: origin_wo + positions, exact wherever the "
          "character stands (convert to object space in double precision).")
      .def_property_readonly("curves_num", &StrandSolver::curves_num)
      .def_property_readonly(
          "points_num", [](const StrandSolver &self) { return self.positions().size(); })
      .def_property_readonly(
          "curve_offsets",
          [](py::object self) { return int_view(self.cast<StrandSolver &>().curve_offsets(), self); })
      .def_property_readonly(
          "positions",
          [](py::object self) { return float3_view(self.cast<StrandSolver &>().positions(), self); },
          "World-space positions (N, 3) float32: a read-only view of the solver's buffer.")
      .def_property_readonly(
          "velocities",
          [](py::object self) {
            return float3_view(self.cast<StrandSolver &>().velocities(), self);
          },
          "World-space velocities (N, 3) float32 in m/s at the end of the last substep.")
      .def_property_readonly(
          "rest_positions",
          [](py::object self) {
            return float3_view(self.cast<StrandSolver &>().rest_positions(), self);
          })
      .def_property_readonly(
          "root_frames",
          [](py::object self) {
            return frames_view(self.cast<StrandSolver &>().root_frames(), self);
          },
          "Each strand's current root frame (C, 3, 3) float32, rows tangent, bitangent, normal "
          "(for ChildHairs.update).");

  py::class_<ChildHairs>(m, "ChildHairs",
                         "Render hairs that follow simulated guides (Kurihara 1993, section 4).")
      .def_static(
          "around_guides",
          [](const py::handle guide_offsets, const py::handle children_per_guide,
             const py::handle child_spread, const py::handle seed) {
            const Span<int32_t> offsets = as_int(guide_offsets, "guide_offsets");
            if (offsets.size() < 2 || offsets[0] != 0) {
              fail("guide_offsets must start at 0 and describe at least one guide");
            }
            for (int64_t guide = 0; guide + 1 < offsets.size(); guide++) {
              if (offsets[guide + 1] - offsets[guide] < 2) {
                fail("guide " + std::to_string(guide) + " has fewer than 2 points");
              }
            }
            const int32_t children_num = convert_param(&StrandParams::children_per_guide,
                                                       children_per_guide);
            const float spread = convert_param(&StrandParams::child_spread, child_spread);
            const int32_t seed_value = convert_param(&StrandParams::seed, seed);
            py::gil_scoped_release release;
            return ChildHairs::around_guides(offsets, children_num, spread, uint32_t(seed_value));
          },
          py::arg("guide_offsets"), py::arg("children_per_guide"), py::arg("child_spread"),
          py::arg("seed") = 0,
          "children_per_guide children per guide, rooted within child_spread meters of its root.")
      .def_static(
          "between_guides",
          [](const py::handle guide_offsets, const py::handle guide_rest_positions_wo,
             const py::handle guide_rest_root_frames, const py::handle roots_wo,
             const int neighbours_num) {
            const Span<int32_t> offsets = as_int(guide_offsets, "guide_offsets");
            const Span<vec3> rest = as_float3(guide_rest_positions_wo, "guide_rest_positions_wo");
            check_groom(offsets, rest);
            const Span<mat3> frames = as_guide_frames(guide_rest_root_frames,
                                                      "guide_rest_root_frames", offsets.size() - 1);
            const Span<vec3> roots = as_float3(roots_wo, "roots_wo");
            if (neighbours_num < 1 || neighbours_num > 16) {
              fail("neighbours_num must be between 1 and 16, not " + std::to_string(neighbours_num));
            }
            py::gil_scoped_release release;
            return ChildHairs::between_guides(offsets, rest, frames, roots, neighbours_num);
          },
          py::arg("guide_offsets"), py::arg("guide_rest_positions_wo"),
          py::arg("guide_rest_root_frames"), py::arg("roots_wo"), py::arg("neighbours_num") = 3,
          "One hair per root in roots_wo, blending the nearest guides by inverse root distance.")
      .def(
          "update",
          [](ChildHairs &self, const py::handle guide_positions_wo,
             const py::handle guide_root_frames) {
            const Span<vec3> positions = as_float3(guide_positions_wo, "guide_positions_wo");
            if (positions.size() != self.guide_points_num()) {
              fail("guide_positions_wo must have " + std::to_string(self.guide_points_num()) +
                   " rows, one per guide point, not " + std::to_string(positions.size()));
            }
            const Span<mat3> frames = as_guide_frames(guide_root_frames, "guide_root_frames",
                                                      self.guides_num());
            py::gil_scoped_release release;
            self.update(positions, frames);
          },
          py::arg("guide_positions_wo"), py::arg("guide_root_frames"),
          "Place the children on the guides' current shapes (e.g. StrandSolver.positions and "
          "StrandSolver.root_frames).")
      .def(
          "blend",
          [](const ChildHairs &self, const py::handle guide_values) {
            const Span<vec3> values = as_float3(guide_values, "guide_values");
            if (values.size() != self.guide_points_num()) {
              fail("guide_values must have " + std::to_string(self.guide_points_num()) +
                   " rows, one per guide point, not " + std::to_string(values.size()));
            }
            py::array_t<float> result({py::ssize_t(self.curve_offsets().last()), py::ssize_t(3)});
            {
              py::gil_scoped_release release;
              self.blend(values, MutableSpan<vec3>(reinterpret_cast<vec3 *>(result.mutable_data()),
                                                   self.curve_offsets().last()));
            }
            return result;
          },
          py::arg("guide_values"),
          "A value per guide point (N, 3) carried to every child point as the positions are, "
          "without the root offset (e.g. shading normals; renormalise them): (children's "
          "points, 3) float32.")
      .def_property_readonly("curves_num", &ChildHairs::curves_num)
      .def_property_readonly(
          "curve_offsets",
          [](py::object self) { return int_view(self.cast<ChildHairs &>().curve_offsets(), self); })
      .def_property_readonly(
          "positions",
          [](py::object self) { return float3_view(self.cast<ChildHairs &>().positions(), self); },
          "World-space child positions (M, 3) float32 after the last update (zeros before).");
}

}  // namespace hairdyn::bindings
