#pragma once
/* Small LCP scenes shared by the test_lcp_*.cpp files: scalp patches, a head cap, a curtain
 * of back hair, analytic colliders. */
#include <algorithm>
#include <cmath>
#include <vector>

#include "core/sph_kernels.hh"
#include "lcp/lcp_solver.hh"
#include "lcp/sampling_bando2003.hh"
#include "lcp/scalp_map_bando2003.hh"

namespace hairdyn::lcp_scenes {

struct Patch {
  std::vector<vec3> vertices;
  std::vector<ivec3> triangles;
};

/* Rings of vertices around a pole, `rings` deep with `segments` around; `position(ring_t,
 * angle)` places them (ring_t in (0, 1]). Triangles wind counter-clockwise seen from +normal
 * when `position` is counter-clockwise around the pole. */
template<typename Fn> Patch ring_patch(const int rings, const int segments, Fn &&position)
{
  Patch patch;
  patch.vertices.push_back(position(0.0f, 0.0f));
  for (int r = 1; r <= rings; r++) {
    for (int s = 0; s < segments; s++) {
      patch.vertices.push_back(
          position(float(r) / float(rings), 2.0f * pi_f * float(s) / float(segments)));
    }
  }
  const auto index = [&](const int r, const int s) {
    return r == 0 ? 0 : 1 + (r - 1) * segments + ((s % segments) + segments) % segments;
  };
  for (int s = 0; s < segments; s++) {
    patch.triangles.push_back(ivec3(0, index(1, s), index(1, s + 1)));
  }
  for (int r = 1; r < rings; r++) {
    for (int s = 0; s < segments; s++) {
      patch.triangles.push_back(ivec3(index(r, s), index(r + 1, s), index(r + 1, s + 1)));
      patch.triangles.push_back(ivec3(index(r, s), index(r + 1, s + 1), index(r, s + 1)));
    }
  }
  return patch;
}

inline Patch disc_patch(const int rings, const int segments, const float radius)
{
  return ring_patch(rings, segments, [&](const float t, const float a) {
    return vec3(radius * t * std::cos(a), radius * t * std::sin(a), 0.0f);
  });
}

/* The cap of a sphere around +Z up to polar angle `max_polar` (normals outward). */
inline Patch cap_patch(const int rings, const int segments, const float radius,
                       const float max_polar, const vec3 &center = vec3(0.0f))
{
  return ring_patch(rings, segments, [&](const float t, const float a) {
    const float polar = t * max_polar;
    return center + radius * vec3(std::sin(polar) * std::cos(a), std::sin(polar) * std::sin(a),
                                  std::cos(polar));
  });
}

/* A flat rectangle in the plane z = 0 facing −Z (hair grows straight down). */
inline Patch down_facing_rectangle(const float width, const float depth, const int nx, const int ny)
{
  Patch patch;
  for (int y = 0; y <= ny; y++) {
    for (int x = 0; x <= nx; x++) {
      patch.vertices.push_back(vec3(width * (float(x) / float(nx) - 0.5f), depth * float(y) / float(ny), 0.0f));
    }
  }
  for (int y = 0; y < ny; y++) {
    for (int x = 0; x < nx; x++) {
      const int a = y * (nx + 1) + x, b = a + 1, c = a + nx + 1, d = c + 1;
      patch.triangles.push_back(ivec3(a, c, b)); /* Clockwise from above: normal −Z. */
      patch.triangles.push_back(ivec3(b, c, d));
    }
  }
  return patch;
}

/* Parameters scaled to a particle spacing r (the defaults' ratios h₁ ≈ 1.33 r, h₂ ≈ 0.92 r). */
inline LcpParams params_for_spacing(const float r)
{
  LcpParams params;
  params.particle_spacing = r;
  params.particle_num = 0; /* the scenes are defined by their spacing */
  params.h1 = 1.33f * r;
  params.h2 = 0.92f * r;
  return params;
}

inline LcpParticles sample(const Patch &patch, const LcpParams &params)
{
  const ScalpMap scalp(patch.vertices, patch.triangles, {});
  return sample_scalp_particles(scalp, LengthMap{}, params, vec3(0.0f, 0.0f, -1.0f));
}

/* The back-hair curtain of Bando Fig. 6: 12 cm wide, 2 cm deep, hanging 18 cm from z = 0. */
inline LcpParticles curtain(const LcpParams &params)
{
  return sample(down_facing_rectangle(0.12f, 0.02f, 12, 2), params);
}

/* A sphere collider (world space) that moves with the head. */
inline ContactQuery sphere_contact(const vec3 &center, const float radius)
{
  return [center, radius](const vec3 &p, Contact &r_contact) {
    const vec3 d = p - center;
    const float dist = glm::length(d);
    if (dist >= radius || dist <= 0.0f) {
      return false;
    }
    r_contact.normal_wo = d / dist;
    r_contact.depth = radius - dist;
    r_contact.surface_point_wo = center + r_contact.normal_wo * radius;
    return true;
  };
}

/* Issue 11's violent shake: keys every 4 frames alternate the head's yaw between +170° and
 * −170° and its pitch between +45° and −45° (key 0 at rest), eased between keys with
 * smoothstep (as Blender's default Bézier keys are); yaw about world Z, pitch about the head's
 * X, about `pivot`. The yaw turns up to 127° in one frame (53 rad/s at 24 frames/s). */
inline mat4 violent_shake(const int frame, const vec3 &pivot = vec3(0.0f))
{
  const auto key = [](const int k, const float amplitude) {
    return k == 0 ? 0.0f : (k % 2 == 1 ? amplitude : -amplitude);
  };
  const int k = frame / 4;
  const float t = float(frame % 4) / 4.0f;
  const float ease = t * t * (3.0f - 2.0f * t);
  const float yaw_max = 170.0f * pi_f / 180.0f, pitch_max = 45.0f * pi_f / 180.0f;
  const float yaw = key(k, yaw_max) + ease * (key(k + 1, yaw_max) - key(k, yaw_max));
  const float pitch = key(k, pitch_max) + ease * (key(k + 1, pitch_max) - key(k, pitch_max));
  return glm::translate(mat4(1.0f), pivot) * glm::rotate(mat4(1.0f), yaw, vec3(0, 0, 1)) *
         glm::rotate(mat4(1.0f), pitch, vec3(1, 0, 0)) * glm::translate(mat4(1.0f), -pivot);
}

/* m/s, the fastest particle. */
inline float max_speed(const LcpSolver &solver)
{
  float result = 0.0f;
  for (const vec3 &v : solver.velocities()) {
    result = std::max(result, glm::length(v));
  }
  return result;
}

inline vec3 centroid_of_free(const LcpSolver &solver)
{
  vec3 sum(0.0f);
  int64_t count = 0;
  for (int64_t i = 0; i < solver.particles_num(); i++) {
    if (!solver.is_root()[i]) {
      sum += solver.positions()[i];
      count++;
    }
  }
  return sum / float(std::max<int64_t>(count, 1));
}

}  // namespace hairdyn::lcp_scenes
