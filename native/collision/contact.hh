#pragma once
/* A contact between a point and a collider, as the solvers see it (world space). The one
 * contact type of every method: the strands' reaction constraint and LCP's body collision. */
#include "core/math.hh"

namespace hairdyn {

struct Contact {
  float depth = 0.0f;          /* > 0 inside: distance from the point to surface_point_wo. */
  vec3 normal_wo{0.0f};        /* Outward unit normal N of the surface at the contact. */
  vec3 surface_point_wo{0.0f}; /* T, the nearest surface point (Kurihara 1993, eq. 11). */
  /* How the collider moves: with the head's frame (the body, as every ColliderSet collider
   * is), or on its own at `velocity_wo` (an obstacle). LCP's friction acts on the velocity
   * relative to it. */
  bool moves_with_head = true;
  vec3 velocity_wo{0.0f};
};

}  // namespace hairdyn
