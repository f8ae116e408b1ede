/* Bindings of the swept-sphere collision of Ward & Lin 2003 §5: the parameters, the hair–hair
 * and hair–object substep passes, and the report measures (crossings, segment penetration). */
#include <cmath>

#include "bindings/arrays.hh"
#include "bindings/params.hh"
#include "collision/hair_hair_ward2003.hh"
#include "collision/ssv_object_ward2003.hh"

namespace hairdyn::bindings {

namespace {

py::dict hair_hair_stats(const HairHairStats &s)
{
  py::dict d;
  d["pairs_num"] = s.pairs_num;
  d["pushed_num"] = s.pushed_num;
  d["averaged_num"] = s.averaged_num;
  d["candidates_num"] = s.candidates_num;
  d["ms"] = s.ms;
  return d;
}

py::dict hair_object_stats(const HairObjectStats &s)
{
  py::dict d;
  d["pushed_num"] = s.pushed_num;
  d["near_num"] = s.near_num;
  d["unresolved_num"] = s.unresolved_num;
  d["ms"] = s.ms;
  return d;
}

}  // namespace

void bind_ssv(py::module_ &m)
{
  bind_params<SweptSphereParams>(
      m, "SweptSphereParams",
      "Parameters of the swept-sphere collision passes (Ward & Lin 2003 section 5).");

  m.def(
      "count_crossings",
      [](const py::handle curve_offsets, const py::handle positions, const py::handle radii,
         const py::handle thickness) {
        const Span<int32_t> offsets = as_int(curve_offsets, "curve_offsets");
        const Span<vec3> points = as_float3(positions, "positions");
        check_groom(offsets, points);
        const Span<float> r = as_radii(radii, points.size());
        const float default_radius = convert_param(&SweptSphereParams::thickness, thickness);
        py::gil_scoped_release release;
        return count_crossings(offsets, points, r, default_radius);
      },
      py::arg("curve_offsets"), py::arg("positions"), py::arg("radii") = py::none(),
      py::arg("thickness") = SweptSphereParams().thickness,
      "Segment pairs of different strands closer than the sum of their radii (per-point radii, "
      "or thickness everywhere when radii is None): the 'crossings' report.");

  m.def(
      "segment_penetration_share",
      [](const py::handle curve_offsets, const py::handle positions, const ColliderSet &colliders,
         const double tolerance) {
        const Span<int32_t> offsets = as_int(curve_offsets, "curve_offsets");
        const Span<vec3> points = as_float3(positions, "positions");
        check_groom(offsets, points);
        if (!std::isfinite(tolerance) || tolerance < 0.0) {
          fail("tolerance must be a distance of 0 or more, not " + std::to_string(tolerance));
        }
        py::gil_scoped_release release;
        return segment_penetration_share(offsets, points, colliders, float(tolerance));
      },
      py::arg("curve_offsets"), py::arg("positions"), py::arg("colliders"), py::arg("tolerance"),
      "Share (0..1) of segments with a point deeper than tolerance (scene units, 0: any depth) "
      "inside any collider of the set, by the exact mesh distance.");

  /* SubstepPass is bound by strands_bindings (bind_strands runs first): StrandSolver.add_pass
   * takes these. */
  py::class_<HairHairPass, SubstepPass>(
      m, "HairHairPass",
      "Hair-hair collision (Ward & Lin 2003 section 5.3), run by the strand solver after every "
      "substep; does nothing while params.hair_hair is off.")
      .def(py::init([](const SweptSphereParams &params) { return new HairHairPass(params); }),
           py::arg("params") = SweptSphereParams())
      .def_property(
          "params", [](const HairHairPass &self) { return self.params(); },
          [](HairHairPass &self, const SweptSphereParams &params) { self.set_params(params); },
          "A copy of the parameters; assign a SweptSphereParams to change them between steps.")
      .def_property_readonly(
          "stats", [](const HairHairPass &self) { return hair_hair_stats(self.stats()); },
          "Sums since reset_stats(): pairs_num (intersecting pairs found, hair_hair_pairs), "
          "pushed_num, averaged_num, candidates_num (pairs sharing a cell), ms.")
      .def("reset_stats", &HairHairPass::reset_stats);

  py::class_<SsvObjectPass, SubstepPass>(
      m, "SsvObjectPass",
      "Hair-object collision of every segment's swept sphere against a BVH of swept spheres "
      "over each collider (Ward & Lin 2003 section 5.4); acts while params.body_collision is "
      "swept spheres or both.")
      .def(py::init([](const ColliderSet &colliders, const SweptSphereParams &params) {
             py::gil_scoped_release release;
             return new SsvObjectPass(&colliders, params);
           }),
           py::arg("colliders"), py::arg("params") = SweptSphereParams(), py::keep_alive<1, 2>())
      .def_property(
          "params", [](const SsvObjectPass &self) { return self.params(); },
          [](SsvObjectPass &self, const SweptSphereParams &params) { self.set_params(params); })
      .def(
          "rebuild",
          [](SsvObjectPass &self) {
            py::gil_scoped_release release;
            self.rebuild();
          },
          "Rebuild the hierarchies after a collider's vertices changed (Collider.rebuild).")
      .def_property_readonly(
          "stats", [](const SsvObjectPass &self) { return hair_object_stats(self.stats()); },
          "Sums since reset_stats(): pushed_num (segment-substeps pushed out), near_num (within "
          "the distance threshold), unresolved_num, ms.")
      .def("reset_stats", &SsvObjectPass::reset_stats);
}

}  // namespace hairdyn::bindings
