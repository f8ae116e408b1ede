/* Bindings of native/lcp: loosely connected particles (Bando 2003). */
#include "bindings/arrays.hh"
#include "bindings/params.hh"

#include <algorithm>

#include "collision/collider.hh"
#include "groom/groom.hh"
#include "lcp/lcp_solver.hh"
#include "lcp/sampling_bando2003.hh"
#include "lcp/scalp_map_bando2003.hh"
#include "lcp/strand_skin_bando2003.hh"

namespace hairdyn::bindings {

namespace {

void check_lcp_params(const LcpParams &params)
{
  if (!(params.h2 > 0.0f)) {
    fail("h2 (h₂) must be greater than 0 m: it is the reach of the hair-hair interactions");
  }
  if (!(params.h1 > 0.0f)) {
    fail("h1 (h₁) must be greater than 0 m: it is the reach of the connections");
  }
}

/* (N, 2) float32 as vec2, all finite; empty when None. */
Span<vec2> as_float2_or_empty(const py::handle obj, const char *name, const int64_t rows)
{
  if (obj.is_none()) {
    return {};
  }
  const py::array array = check_array(obj, name, py::dtype::of<float>(), "float32", 2);
  const Span<vec2> span(static_cast<const vec2 *>(array.data()), array.shape(0));
  if (span.size() != rows) {
    fail(std::string(name) + " must have one row per strand (" + std::to_string(rows) + ")");
  }
  for (const vec2 &v : span) {
    if (!std::isfinite(v.x) || !std::isfinite(v.y)) {
      fail(std::string(name) + " has a value that is not a finite number");
    }
  }
  return span;
}

void check_scalp(const Span<vec3> vertices, const Span<ivec3> triangles)
{
  if (triangles.is_empty() || vertices.is_empty()) {
    fail("No scalp: mark the part of the head that grows hair (the scalp patch has no faces).");
  }
  const std::string error = find_scalp_error(vertices, triangles);
  if (!error.empty()) {
    fail("Invalid scalp: " + error + ".");
  }
}

/* A head matrix the skin can invert. */
mat4 as_head_matrix(const py::handle obj, const char *name)
{
  const mat4 m = as_matrix(obj, name);
  const double det = glm::determinant(glm::dmat3(mat3(m)));
  if (!std::isfinite(det) || std::abs(det) < 1e-30) {
    fail(std::string(name) + " is singular (a zero scale?): the head's space is undefined");
  }
  return m;
}

py::dict particles_dict(LcpParticles &&particles)
{
  const int64_t n = particles.size();
  py::array_t<float> positions({n, int64_t(3)}), directions({n, int64_t(3)});
  py::array_t<float> u(n), v(n), s(n);
  std::copy_n(reinterpret_cast<const float *>(particles.positions.data()), 3 * n, positions.mutable_data());
  std::copy_n(reinterpret_cast<const float *>(particles.directions.data()), 3 * n, directions.mutable_data());
  std::copy_n(particles.u.data(), n, u.mutable_data());
  std::copy_n(particles.v.data(), n, v.mutable_data());
  std::copy_n(particles.s.data(), n, s.mutable_data());
  py::dict result;
  result["positions"] = positions;
  result["directions"] = directions;
  result["u"] = u;
  result["v"] = v;
  result["s"] = s;
  if (!particles.fixed.empty()) {
    py::array_t<bool> fixed(n);
    std::copy_n(particles.fixed.data(), n, reinterpret_cast<uint8_t *>(fixed.mutable_data()));
    result["fixed"] = fixed;
  }
  return result;
}

}  // namespace

void bind_lcp(py::module_ &m)
{
  bind_params<LcpParams>(m, "LcpParams",
                         "Loosely connected particles (Bando, Chen, Nishita 2003) parameters.");

  m.def(
      "harmonic_scalp_map",
      [](const py::handle vertices, const py::handle triangles) {
        const Span<vec3> v = as_float3(vertices, "vertices");
        const Span<ivec3> t = as_int3(triangles, "triangles");
        check_scalp(v, t);
        py::array_t<float> uv({v.size(), int64_t(2)});
        bool ok = false;
        {
          py::gil_scoped_release release;
          ok = compute_harmonic_map(v, t, MutableSpan<vec2>(reinterpret_cast<vec2 *>(uv.mutable_data()), v.size()));
        }
        if (!ok) {
          fail("The scalp's harmonic map could not be solved (degenerate triangles?).");
        }
        return uv;
      },
      py::arg("vertices"), py::arg("triangles"),
      "(u, v) in the unit square for each scalp vertex (Bando 2003, §3.2): (V, 2) float32.");

  m.def(
      "sample_lcp_particles",
      [](const LcpParams &params, const py::handle vertices_wo, const py::handle triangles,
         const py::handle length_weights, const py::handle length_image) {
        check_lcp_params(params);
        const Span<vec3> v = as_float3(vertices_wo, "scalp_vertices");
        const Span<ivec3> t = as_int3(triangles, "scalp_triangles");
        check_scalp(v, t);
        Span<float> weights;
        if (!length_weights.is_none()) {
          weights = as_float(length_weights, "length_weights");
          if (weights.size() != v.size()) {
            fail("length_weights must have one value per scalp vertex");
          }
        }
        LengthMap length;
        py::array image_array;
        if (!length_image.is_none()) {
          image_array = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(length_image);
          if (!image_array || image_array.ndim() != 2 || image_array.size() == 0) {
            fail("length_image must be a 2D array of grey values (rows from v = 0)");
          }
          length.image = Span<float>(static_cast<const float *>(image_array.data()), image_array.size());
          length.image_height = image_array.shape(0);
          length.image_width = image_array.shape(1);
        }
        LcpParticles particles;
        std::string error;
        {
          py::gil_scoped_release release;
          const ScalpMap scalp(v, t, weights);
          const std::string invalid = scalp.is_valid() ?
                                          find_length_map_error(scalp, length) :
                                          "the scalp's harmonic map could not be solved";
          const std::string too_large =
              invalid.empty() ?
                  find_sampling_size_error(plan_scalp_sampling(scalp, length, params), params) :
                  "";
          if (!invalid.empty()) {
            error = "Invalid length map or scalp: " + invalid + ".";
          }
          else if (!too_large.empty()) {
            error = "Too many particles: " + too_large + ".";
          }
          else {
            particles = sample_scalp_particles(scalp, length, params, vec3(0.0f, 0.0f, -1.0f));
          }
        }
        if (!error.empty()) {
          fail(error);
        }
        if (particles.size() == 0 ||
            std::none_of(particles.s.begin(), particles.s.end(), [](float s) { return s < 0.0f; }))
        {
          fail("No particles at the roots: the particle spacing is too large for this scalp and "
               "length map.");
        }
        return particles_dict(std::move(particles));
      },
      py::arg("params"), py::arg("scalp_vertices"), py::arg("scalp_triangles"),
      py::arg("length_weights") = py::none(), py::arg("length_image") = py::none(),
      "Poisson-disc particles over a world-space scalp (Bando 2003, §3.2): a dict of positions, "
      "directions (N, 3) and u, v, s (N,) float32; s < 0 are the fixed root particles.");

  m.def(
      "lcp_particles_from_groom",
      [](const LcpParams &params, const py::handle curve_offsets, const py::handle positions,
         const py::handle root_uv, const py::handle pinned) {
        check_lcp_params(params);
        const Span<int32_t> offsets = as_int(curve_offsets, "curve_offsets");
        const Span<vec3> points = as_float3(positions, "positions");
        check_groom(offsets, points);
        const Span<vec2> uv = as_float2_or_empty(root_uv, "root_uv", offsets.size() - 1);
        Span<uint8_t> pins;
        if (!pinned.is_none()) {
          pins = as_bool(pinned, "pinned");
          if (pins.size() != points.size()) {
            fail("pinned must have one value per point (" + std::to_string(points.size()) +
                 "), not " + std::to_string(pins.size()));
          }
        }
        const int64_t candidates = groom_candidates_num(offsets, points, params);
        if (candidates > max_groom_candidates) {
          fail("Too many particles: a particle spacing of " +
               std::to_string(params.particle_spacing) + " m samples the strands at " +
               std::to_string(candidates) + " places, more than the " +
               std::to_string(max_groom_candidates) + " hairdyn may hold: raise the spacing.");
        }
        LcpParticles particles;
        {
          py::gil_scoped_release release;
          particles = sample_groom_particles(offsets, points, uv, params, pins);
        }
        if (particles.size() == 0) {
          fail("No particles: the strands are shorter than the particle spacing.");
        }
        if (particles.size() > max_lcp_particles) {
          fail("Too many particles: the particle spacing places " +
               std::to_string(particles.size()) + " along the strands, more than the " +
               std::to_string(max_lcp_particles) +
               " an LCP simulation may hold: raise the spacing or set a particle count.");
        }
        return particles_dict(std::move(particles));
      },
      py::arg("params"), py::arg("curve_offsets"), py::arg("positions"),
      py::arg("root_uv") = py::none(), py::arg("pinned") = py::none(),
      "Particles sampled along an existing groom (u, v from the roots, s from arc length). "
      "pinned (N,) bool, the groom's pinned points: the dict then has 'fixed' (M,) bool, the "
      "particles whose nearest groom point along their strand is pinned.");

  py::class_<LcpSolver>(m, "LcpSolver", "Loosely connected particles (Bando 2003).")
      .def(py::init([](const LcpParams &params, const py::handle positions_wo,
                       const py::handle directions_wo, const py::handle u, const py::handle v,
                       const py::handle s, const py::handle head_to_world_rest,
                       const WindParams &wind, const py::handle fixed) {
             check_lcp_params(params);
             LcpParticles particles;
             const Span<vec3> x = as_float3(positions_wo, "positions");
             const Span<vec3> t = as_float3(directions_wo, "directions");
             const Span<float> su = as_float(u, "u"), sv = as_float(v, "v"), ss = as_float(s, "s");
             if (x.is_empty()) {
               fail("No particles: sample the hair volume first (zero particles given).");
             }
             if (t.size() != x.size() || su.size() != x.size() || sv.size() != x.size() ||
                 ss.size() != x.size())
             {
               fail("positions, directions, u, v and s must have the same length");
             }
             for (const vec3 &d : t) {
               if (glm::length(d) < 1e-6f) {
                 fail("directions must be non-zero vectors");
               }
             }
             const mat4 head = as_matrix(head_to_world_rest, "head_to_world_rest");
             particles.positions.assign(x.begin(), x.end());
             particles.directions.assign(t.begin(), t.end());
             particles.u.assign(su.begin(), su.end());
             particles.v.assign(sv.begin(), sv.end());
             particles.s.assign(ss.begin(), ss.end());
             if (!fixed.is_none()) {
               const Span<uint8_t> mask = as_bool(fixed, "fixed");
               if (mask.size() != x.size()) {
                 fail("fixed must have one value per particle (" + std::to_string(x.size()) +
                      "), not " + std::to_string(mask.size()));
               }
               particles.fixed.assign(mask.begin(), mask.end());
             }
             py::gil_scoped_release release;
             return new LcpSolver(params, particles, head, wind);
           }),
           py::arg("params"), py::arg("positions"), py::arg("directions"), py::arg("u"),
           py::arg("v"), py::arg("s"), py::arg("head_to_world_rest"),
           py::arg("wind") = WindParams(), py::arg("fixed") = py::none(),
           "wind: the shared WindParams, the free stream of the SPH air particles (§3.5); "
           "fixed: None or (N,) bool, particles held by the head like the roots (s < 0).")
      .def("set_wind", &LcpSolver::set_wind, py::arg("wind"),
           "Change the wind (WindParams); the air particles start over in it.")
      .def_property_readonly("wind", &LcpSolver::wind)
      .def(
          "step",
          [](LcpSolver &self, const float frame_dt, const py::handle head_to_world) {
            if (!(frame_dt > 0.0f) || !std::isfinite(frame_dt)) {
              fail("frame_dt must be a positive number of seconds");
            }
            const mat4 head = as_matrix(head_to_world, "head_to_world");
            bool ok = false;
            {
              py::gil_scoped_release release;
              ok = self.step(frame_dt, head);
            }
            if (!ok) {
              fail(self.failure());
            }
          },
          py::arg("frame_dt"), py::arg("head_to_world"),
          "Advance one frame of frame_dt seconds to the head's transform. ValueError with the "
          "reason when the frame is refused (more substeps than max_substeps) or the state "
          "diverges; the positions then stay those of the last good frame, and the solver "
          "steps again only after reset().")
      .def_property_readonly("failure", [](const LcpSolver &self) { return self.failure(); },
                             "Why the last step failed, or an empty string.")
      .def(
          "estimate_substeps",
          [](const LcpSolver &self, const float frame_dt) {
            if (!(frame_dt > 0.0f) || !std::isfinite(frame_dt)) {
              fail("frame_dt must be a positive number of seconds");
            }
            const LcpSolver::SubstepEstimate estimate = self.estimate_substeps(frame_dt);
            return py::make_tuple(estimate.count, estimate.reason);
          },
          py::arg("frame_dt"),
          "(count, reason): the substeps a frame of frame_dt needs from the current state and "
          "the bound that sets them; a count above params.max_substeps will be refused.")
      .def("reset", &LcpSolver::reset, py::call_guard<py::gil_scoped_release>())
      .def(
          "set_colliders",
          [](LcpSolver &self, const ColliderSet *colliders) {
            /* Body collision (Bando 2003 §3.5) through the cylindrical / spherical maps. */
            py::gil_scoped_release release;
            self.set_colliders(colliders);
          },
          py::arg("colliders"), py::keep_alive<1, 2>(),
          "Collide with a ColliderSet (kept alive by the solver; its transforms must be at the "
          "rest frame now), or None. Rest particles inside a body move onto its surface.")
      .def_property_readonly("particles_num", &LcpSolver::particles_num)
      .def_property_readonly("pairs_num", &LcpSolver::pairs_num)
      .def_property_readonly("interpenetrating_pairs_num", &LcpSolver::interpenetrating_pairs_num,
                             "Particle pairs closer than h₂/2 after the last step.")
      .def_property_readonly("substeps_used", &LcpSolver::substeps_used)
      .def_property_readonly("particle_mass", &LcpSolver::particle_mass)
      .def_property_readonly("positions", [](py::object self) {
        return float3_view(self.cast<LcpSolver &>().positions(), self);
      })
      .def_property_readonly("directions", [](py::object self) {
        return float3_view(self.cast<LcpSolver &>().directions(), self);
      })
      .def_property_readonly("velocities", [](py::object self) {
        return float3_view(self.cast<LcpSolver &>().velocities(), self);
      })
      .def_property_readonly("density", [](py::object self) {
        return float_view(self.cast<LcpSolver &>().density(), self);
      })
      .def_property_readonly("u", [](py::object self) { return float_view(self.cast<LcpSolver &>().u(), self); })
      .def_property_readonly("v", [](py::object self) { return float_view(self.cast<LcpSolver &>().v(), self); })
      .def_property_readonly("s", [](py::object self) { return float_view(self.cast<LcpSolver &>().s(), self); })
      .def_property_readonly(
          "is_fixed",
          [](const LcpSolver &self) {
            const Span<uint8_t> fixed = self.is_fixed();
            py::array_t<bool> result(fixed.size());
            std::copy_n(fixed.data(), fixed.size(),
                        reinterpret_cast<uint8_t *>(result.mutable_data()));
            return result;
          },
          "(N,) bool: particles held by the head, the roots (s < 0) and the pinned ones.")
      .def_property_readonly("air_positions", [](py::object self) {
        return float3_view(self.cast<LcpSolver &>().air_positions(), self);
      })
      .def_property_readonly("air_velocities", [](py::object self) {
        return float3_view(self.cast<LcpSolver &>().air_velocities(), self);
      });

  py::class_<ParticleSkin>(
      m, "ParticleSkin",
      "LCP's motion on the groom's strands (Bando 2003, §4): each strand point follows the "
      "particles nearest its (u, v, s), strands keep their segment lengths and are swung out "
      "of the body.")
      .def(py::init([](const py::handle groom, const py::handle solver,
                       const py::handle head_matrix, const int neighbours_num,
                       const bool shape_from_particles) {
             /* Duck-typed arguments: a missing array is a TypeError naming it. */
             const auto array = [](const py::handle owner, const char *owner_name,
                                   const char *name) {
               if (!py::hasattr(owner, name)) {
                 throw py::type_error(std::string(owner_name) + " has no '" + name + "' array");
               }
               return owner.attr(name);
             };
             const py::object offsets_obj = array(groom, "groom", "curve_offsets");
             const py::object points_obj = array(groom, "groom", "positions_wo");
             const Span<int32_t> offsets = as_int(offsets_obj, "curve_offsets");
             const Span<vec3> points = as_float3(points_obj, "positions_wo");
             check_groom(offsets, points);
             /* The particles: an LcpSolver, or anything with the same arrays. */
             const py::object x_obj = array(solver, "solver", "positions"),
                              t_obj = array(solver, "solver", "directions");
             const py::object u_obj = array(solver, "solver", "u"),
                              v_obj = array(solver, "solver", "v"),
                              s_obj = array(solver, "solver", "s");
             const Span<vec3> x = as_float3(x_obj, "positions"), t = as_float3(t_obj, "directions");
             const Span<float> u = as_float(u_obj, "u"), v = as_float(v_obj, "v"),
                               s = as_float(s_obj, "s");
             if (x.is_empty() || t.size() != x.size() || u.size() != x.size() ||
                 v.size() != x.size() || s.size() != x.size())
             {
               fail("the solver's positions, directions, u, v and s must have the same "
                    "non-zero length");
             }
             if (neighbours_num < 1 || neighbours_num > 64) {
               fail("neighbours_num must be between 1 and 64, not " +
                    std::to_string(neighbours_num));
             }
             const mat4 head = as_head_matrix(head_matrix, "head_matrix");
             py::gil_scoped_release release;
             return new ParticleSkin(offsets, points, x, t, u, v, s, head, neighbours_num,
                                     shape_from_particles);
           }),
           py::arg("groom"), py::arg("solver"), py::arg("head_matrix"),
           py::arg("neighbours_num") = 4, py::arg("shape_from_particles") = false,
           "groom: any object with curve_offsets (C+1,) int32 and positions_wo (N, 3) float32 "
           "at rest; solver: the LcpSolver at rest (or any object with its positions, "
           "directions, u, v, s arrays); head_matrix: the head's 4x4 matrix then. "
           "shape_from_particles: the strands take the particles' shape (with their own "
           "lengths) instead of the groom's, for particles that do not come from the groom.")
      .def(
          "apply",
          [](ParticleSkin &self, const py::handle particles_wo, const py::handle head_matrix,
             const ColliderSet *colliders, const py::handle directions_wo) {
            const Span<vec3> x = as_float3(particles_wo, "particles_wo");
            if (x.size() != self.particles_num()) {
              fail("particles_wo must have one row per particle (" +
                   std::to_string(self.particles_num()) + "), not " + std::to_string(x.size()));
            }
            Span<vec3> t;
            if (self.shape_from_particles()) {
              if (directions_wo.is_none()) {
                fail("a skin built with shape_from_particles needs the particles' directions");
              }
              t = as_float3(directions_wo, "directions_wo");
              if (t.size() != x.size()) {
                fail("directions_wo must have one row per particle (" + std::to_string(x.size()) +
                     "), not " + std::to_string(t.size()));
              }
            }
            const mat4 head = as_head_matrix(head_matrix, "head_matrix");
            py::array_t<float> result({self.points_num(), int64_t(3)});
            {
              py::gil_scoped_release release;
              self.apply(x, head, colliders,
                         MutableSpan<vec3>(reinterpret_cast<vec3 *>(result.mutable_data()),
                                           self.points_num()),
                         t);
            }
            return result;
          },
          py::arg("particles_wo"), py::arg("head_matrix"), py::arg("colliders") = py::none(),
          py::arg("directions_wo") = py::none(),
          "Strand positions (N, 3) float32 for the particles' current world positions; "
          "colliders (a ColliderSet, or None) keeps the points out of the body; "
          "directions_wo, the particles' current unit directions, for a skin built with "
          "shape_from_particles (ignored otherwise).")
      .def(
          "set_pinned",
          [](ParticleSkin &self, const py::handle pinned) {
            if (pinned.is_none()) {
              self.set_pinned({});
              return;
            }
            const Span<uint8_t> mask = as_bool(pinned, "pinned");
            if (mask.size() != self.points_num()) {
              fail("pinned must have one value per groom point (" +
                   std::to_string(self.points_num()) + "), not " + std::to_string(mask.size()));
            }
            self.set_pinned(mask);
          },
          py::arg("pinned"),
          "Carry the groom points where pinned (N,) bool is True rigidly with the head, like "
          "the roots (the Curves attribute hairdyn_fixed); None: only the roots.")
      .def_property_readonly("points_num", &ParticleSkin::points_num)
      .def_property_readonly("particles_num", &ParticleSkin::particles_num);
}

}  // namespace hairdyn::bindings
