/* Bindings of native/collision. */
#include "bindings/arrays.hh"
#include "bindings/params.hh"

#include <pybind11/stl.h>

#include <cmath>

#include "collision/collider.hh"
#include "collision/mesh.hh"
#include "collision/reaction_constraint_kurihara1993.hh"

namespace hairdyn::bindings {

namespace {

/* `parts`: None (the whole mesh), one (K,) int32 array of vertex indices, or a list of them.
 * Fills offsets and vertex indices; the arrays stay owned by the caller's objects. */
void gather_parts(const py::handle parts, std::vector<int32_t> &r_offsets,
                  std::vector<int32_t> &r_vertices)
{
  if (parts.is_none()) {
    return;
  }
  std::vector<py::handle> items;
  if (py::isinstance<py::array>(parts)) {
    items.push_back(parts);
  }
  else if (py::isinstance<py::list>(parts) || py::isinstance<py::tuple>(parts)) {
    for (const py::handle item : parts) {
      items.push_back(item);
    }
    if (items.empty()) {
      fail("parts must not be an empty list (pass None for the whole mesh)");
    }
  }
  else {
    fail("parts must be None, an int32 array of vertex indices, or a list of them");
  }
  r_offsets.push_back(0);
  for (size_t p = 0; p < items.size(); p++) {
    const std::string name = "parts[" + std::to_string(p) + "]";
    const Span<int32_t> part = as_int(items[p], name.c_str());
    r_vertices.insert(r_vertices.end(), part.begin(), part.end());
    r_offsets.push_back(int32_t(r_vertices.size()));
  }
}

/* None, or a (P, 3, 3) float array of [origin, axis, reference] rows per part. */
std::vector<MapFrame> gather_frames(const py::handle frames)
{
  std::vector<MapFrame> result;
  if (frames.is_none()) {
    return result;
  }
  const auto array = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(frames);
  if (!array || array.ndim() != 3 || array.shape(1) != 3 || array.shape(2) != 3) {
    fail("frames must have shape (P, 3, 3): per part the rows origin, axis, reference");
  }
  for (py::ssize_t p = 0; p < array.shape(0); p++) {
    vec3 rows[3];
    for (int r = 0; r < 3; r++) {
      for (int c = 0; c < 3; c++) {
        rows[r][c] = float(array.at(p, r, c));
      }
      if (!is_finite(rows[r])) {
        fail("frames has a value that is not a finite number");
      }
    }
    if (glm::length(rows[1]) == 0.0f) {
      fail("frames[" + std::to_string(p) + "] has a zero axis");
    }
    result.push_back(make_frame(rows[0], rows[1], rows[2]));
  }
  return result;
}

py::dict contacts_dict(const ColliderSet &set, const py::handle points)
{
  const Span<vec3> p = as_float3(points, "points");
  py::array_t<bool> hit(p.size());
  py::array_t<float> depth(p.size());
  MutableSpan<vec3> normal_span, surface_span;
  py::array_t<float> normal = new_float3(p.size(), normal_span);
  py::array_t<float> surface = new_float3(p.size(), surface_span);
  const MutableSpan<uint8_t> hit_span(reinterpret_cast<uint8_t *>(hit.mutable_data()), p.size());
  const MutableSpan<float> depth_span(depth.mutable_data(), p.size());
  {
    py::gil_scoped_release release;
    find_contacts(set, p, hit_span, depth_span, normal_span, surface_span);
  }
  py::dict result;
  result["hit"] = hit;
  result["depth"] = depth;
  result["normal"] = normal;
  result["surface_point"] = surface;
  return result;
}

py::dict stats_dict(const PenetrationStats &stats, const float tolerance_wo,
                    const bool with_roots = false)
{
  py::dict result;
  result["penetration_max"] = stats.max_depth;
  result["penetration_share"] = stats.share;
  result["deeper_num"] = stats.deeper_num;
  result["points_num"] = stats.points_num;
  result["tolerance"] = tolerance_wo;
  if (with_roots) {
    result["roots_inside"] = stats.roots_inside;
    result["roots_penetration_max"] = stats.roots_depth_max;
  }
  return result;
}

/* None, or (C + 1,) int32 curve offsets over `points_num` points. */
Span<int32_t> optional_curve_offsets(const py::handle curve_offsets, const int64_t points_num)
{
  if (curve_offsets.is_none()) {
    return {};
  }
  const Span<int32_t> offsets = as_int(curve_offsets, "curve_offsets");
  if (offsets.size() < 2 || offsets[0] != 0 || offsets.last() != points_num) {
    fail("curve_offsets must start at 0 and end at the number of points (" +
         std::to_string(points_num) + ")");
  }
  for (int64_t i = 0; i + 1 < offsets.size(); i++) {
    if (offsets[i + 1] < offsets[i]) {
      fail("curve_offsets must not decrease (strand " + std::to_string(i) + ")");
    }
  }
  return offsets;
}

float tolerance_or_default(const py::handle tolerance, const float fallback)
{
  if (tolerance.is_none()) {
    return fallback;
  }
  const float value = py::cast<float>(tolerance);
  if (!(std::isfinite(value) && value >= 0.0f)) {
    fail("tolerance must be a finite number >= 0 (scene units)");
  }
  return value;
}

ColliderSet single_set(const std::shared_ptr<Collider> &collider)
{
  ColliderSet set;
  set.add(collider);
  return set;
}

const char *map_kind_name(const MapKind kind)
{
  return kind == MapKind::Sphere ? "sphere" : "cylinder";
}

}  // namespace

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

  bind_params<CollisionParams>(
      m, "CollisionParams",
      "Hair–object collision: maps (Kurihara 1993 §3.1, §5), reaction constraint (eq. 12–15), "
      "friction, projection and penetration report.");

  py::class_<Collider, std::shared_ptr<Collider>>(
      m, "Collider",
      "A collider object: per part a cylindrical or spherical map built once in object space; "
      "rigid motion through set_transform, deformation through rebuild.")
      .def(py::init([](const py::handle vertices, const py::handle triangles,
                       const py::handle parts, const CollisionParams &params,
                       const py::handle frames) {
             const Span<vec3> verts = as_float3(vertices, "vertices");
             const Span<ivec3> tris = as_int3(triangles, "triangles");
             std::string error = find_mesh_error(verts, tris);
             if (!error.empty()) {
               fail("Invalid collider mesh: " + error + ".");
             }
             std::vector<int32_t> offsets, part_vertices;
             gather_parts(parts, offsets, part_vertices);
             const std::vector<MapFrame> part_frames = gather_frames(frames);
             py::gil_scoped_release release;
             const ColliderMesh mesh(verts, tris);
             error = find_collider_error(mesh, offsets, part_vertices, int64_t(part_frames.size()));
             if (!error.empty()) {
               py::gil_scoped_acquire acquire;
               fail("Invalid collider: " + error + ".");
             }
             return std::make_shared<Collider>(mesh, offsets, part_vertices, params, part_frames);
           }),
           py::arg("vertices"), py::arg("triangles"), py::arg("parts") = py::none(),
           py::arg("params") = CollisionParams(), py::arg("frames") = py::none(),
           "vertices (V, 3) float32 and triangles (T, 3) int32 in object space; parts: None "
           "(whole mesh), an int32 array of vertex indices (a vertex group) or a list of them; "
           "frames: None, or (P, 3, 3) rows origin, axis, reference per part.")
      .def(
          "set_transform",
          [](Collider &self, const py::handle object_to_world) {
            self.set_transform(as_matrix(object_to_world, "object_to_world"));
          },
          py::arg("object_to_world"), "The object's 4x4 matrix_world for this frame (no rebuild).")
      .def(
          "rebuild",
          [](Collider &self, const py::handle vertices) {
            const Span<vec3> verts = as_float3(vertices, "vertices");
            if (verts.size() != int64_t(self.vertices().size())) {
              fail("vertices must have " + std::to_string(self.vertices().size()) +
                   " rows (the collider's vertex count), not " + std::to_string(verts.size()));
            }
            py::gil_scoped_release release;
            self.rebuild(verts);
          },
          py::arg("vertices"), "New object-space vertex positions of a deforming collider.")
      .def(
          "find_contacts",
          [](const std::shared_ptr<Collider> &self, const py::handle points_wo) {
            return contacts_dict(single_set(self), points_wo);
          },
          py::arg("points_wo"),
          "Contacts of (N, 3) float32 world points: dict of hit (N,) bool, depth (N,) (> 0 "
          "inside), normal (N, 3), surface_point (N, 3).")
      .def(
          "penetration_stats",
          [](const std::shared_ptr<Collider> &self, const py::handle points_wo,
             const py::handle tolerance) {
            const Span<vec3> p = as_float3(points_wo, "points_wo");
            const float tol = tolerance_or_default(
                tolerance, self->params().penetration_tolerance * self->size_wo());
            PenetrationStats stats;
            {
              py::gil_scoped_release release;
              stats = single_set(self).penetration_stats(p, tol);
            }
            return stats_dict(stats, tol);
          },
          py::arg("points_wo"), py::arg("tolerance") = py::none(),
          "Exact penetration into the real triangles: penetration_max (scene units), "
          "penetration_share (share deeper than tolerance; default penetration_tolerance × size_wo).")
      .def_property_readonly("build_ms", &Collider::build_ms,
                             "Milliseconds the last build or rebuild took.")
      .def_property_readonly("size", &Collider::size, "Bounding-box diagonal, object units.")
      .def_property_readonly("size_wo", &Collider::size_wo, "Bounding-box diagonal, scene units.")
      .def_property_readonly("parts_num", &Collider::parts_num)
      .def_property_readonly("map_kinds",
                             [](const Collider &self) {
                               std::vector<std::string> kinds;
                               for (int64_t p = 0; p < self.parts_num(); p++) {
                                 kinds.emplace_back(map_kind_name(self.part_map(p).kind));
                               }
                               return kinds;
                             },
                             "'cylinder' or 'sphere' per part.")
      .def_property_readonly("map_errors",
                             [](const Collider &self) {
                               std::vector<std::pair<float, float>> errors;
                               for (int64_t p = 0; p < self.parts_num(); p++) {
                                 errors.emplace_back(self.part_cylinder_error(p),
                                                     self.part_sphere_error(p));
                               }
                               return errors;
                             },
                             "(cylinder, sphere) mean depth error per part, object units; -1 if "
                             "not measured (kind forced).")
      .def_property_readonly("boundary_edges_num", &Collider::boundary_edges_num)
      .def_property_readonly("skipped_triangles_num", &Collider::skipped_triangles_num)
      .def_property_readonly("params", &Collider::params);

  py::class_<ColliderSet>(m, "ColliderSet", "The scene's colliders, queried together.")
      .def(py::init([](const std::vector<std::shared_ptr<Collider>> &colliders) {
             auto set = std::make_unique<ColliderSet>();
             for (const std::shared_ptr<Collider> &collider : colliders) {
               if (!collider) {
                 fail("colliders must not contain None");
               }
               set->add(collider);
             }
             return set;
           }),
           py::arg("colliders") = std::vector<std::shared_ptr<Collider>>())
      .def(
          "add",
          [](ColliderSet &self, const std::shared_ptr<Collider> &collider) {
            if (!collider) {
              fail("collider must not be None");
            }
            self.add(collider);
          },
          py::arg("collider"))
      .def_property_readonly("colliders_num", &ColliderSet::colliders_num)
      .def_property_readonly("size_wo", &ColliderSet::size_wo,
                             "The smallest collider's size (bounding-box diagonal), scene units.")
      .def("find_contacts", &contacts_dict, py::arg("points_wo"),
           "As Collider.find_contacts, deepest contact over all colliders.")
      .def(
          "penetration_stats",
          [](const ColliderSet &self, const py::handle points_wo, const float tolerance,
             const py::handle curve_offsets) {
            const Span<vec3> p = as_float3(points_wo, "points_wo");
            const float tol = tolerance_or_default(py::float_(tolerance), 0.0f);
            const Span<int32_t> offsets = optional_curve_offsets(curve_offsets, p.size());
            PenetrationStats stats;
            {
              py::gil_scoped_release release;
              stats = self.penetration_stats(p, tol, offsets);
            }
            return stats_dict(stats, tol, !offsets.is_empty());
          },
          py::arg("points_wo"), py::arg("tolerance"), py::arg("curve_offsets") = py::none(),
          "Exact penetration into all colliders; tolerance in scene units. With the strands' "
          "curve_offsets the roots (kinematic: one that starts inside stays inside) are left "
          "out of penetration_max / penetration_share / points_num and reported apart: "
          "roots_inside (roots deeper than the tolerance) and roots_penetration_max.")
      .def(
          "apply_reaction_constraint",
          [](const ColliderSet &self, const py::handle positions_wo, const py::handle velocities_wo,
             const py::handle forces, const CollisionParams &params, const float dt) {
            const Span<vec3> x = as_float3(positions_wo, "positions_wo");
            const Span<vec3> v = as_float3(velocities_wo, "velocities_wo");
            const Span<vec3> f = as_float3(forces, "forces");
            if (v.size() != x.size() || f.size() != x.size()) {
              fail("positions_wo, velocities_wo and forces must have the same number of rows");
            }
            if (!(std::isfinite(dt) && dt > 0.0f)) {
              fail("dt must be a positive number of seconds");
            }
            MutableSpan<vec3> out_span;
            py::array_t<float> out = new_float3(x.size(), out_span);
            int64_t contacts_num;
            {
              py::gil_scoped_release release;
              contacts_num = apply_reaction_constraint(self, x, v, f,
                                                       ReactionConstants::from(params, dt), out_span);
            }
            return py::make_tuple(out, contacts_num);
          },
          py::arg("positions_wo"), py::arg("velocities_wo"), py::arg("forces"),
          py::arg("params") = CollisionParams(), py::arg("dt") = 1.0f / 24.0f,
          "Kurihara 1993 eq. 12–15 (+ friction μ) on per-unit-mass forces: returns (forces, "
          "number of nodes in contact).")
      .def(
          "project_out",
          [](const ColliderSet &self, const py::handle positions_wo, const py::handle velocities_wo,
             const float tolerance) {
            const Span<vec3> x = as_float3(positions_wo, "positions_wo");
            const Span<vec3> v = as_float3(velocities_wo, "velocities_wo");
            if (v.size() != x.size()) {
              fail("positions_wo and velocities_wo must have the same number of rows");
            }
            const float tol = tolerance_or_default(py::float_(tolerance), 0.0f);
            MutableSpan<vec3> x_out, v_out;
            py::array_t<float> x_array = new_float3(x.size(), x_out);
            py::array_t<float> v_array = new_float3(x.size(), v_out);
            int64_t moved;
            {
              py::gil_scoped_release release;
              std::copy(x.begin(), x.end(), x_out.begin());
              std::copy(v.begin(), v.end(), v_out.begin());
              moved = project_out_of_colliders(self, tol, x_out, v_out);
            }
            return py::make_tuple(x_array, v_array, moved);
          },
          py::arg("positions_wo"), py::arg("velocities_wo"), py::arg("tolerance"),
          "Ward & Lin 2003 §5.5: nodes deeper than tolerance (scene units) go to the surface and "
          "lose inward velocity; returns (positions, velocities, number moved).");
}

}  // namespace hairdyn::bindings
