#pragma once
/* A contact between a point and a collider, as the solvers see it (world space). */
#include "core/math.hh"

namespace hairdyn {

struct Contact {
  float depth = 0.0f;          /* > 0 inside: distance from the point to surface_point_wo. */
  vec3 normal_wo{0.0f};        /* Outward unit normal N of the surface at the contact. */
  vec3 surface_point_wo{0.0f}; /* T, the nearest surface point (Kurihara 1993, eq. 11). */
};

}  // namespace hairdyn
