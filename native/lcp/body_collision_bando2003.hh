#pragma once
/* Collisions between hair particles and the body (head, torso), Bando 2003, §3.5: after
 * integration, a particle inside a collider goes back to the surface, loses the part of its
 * velocity (relative to the collider) that points into the body, and its sliding velocity is
 * reduced by Coulomb friction (Bridson et al. 2002).
 *
 * The seam: the solver asks a ContactQuery per particle, in world space, for the one contact
 * type of collision/contact.hh. LcpSolver::set_colliders() plugs in a ColliderSet (its
 * find_contact); tests plug in analytic shapes with set_body_contact().
 *
 * The query is called from several threads at once: it must be safe to call concurrently
 * (const look-ups are). */
#include <functional>

#include "collision/contact.hh"
#include "core/math.hh"

namespace hairdyn {

/* True and r_contact filled when p_wo touches or is inside a collider. */
using ContactQuery = std::function<bool(const vec3 &p_wo, Contact &r_contact)>;

/* Response to one contact: r_position_wo onto the surface; of the velocity relative to the
 * collider (r_relative_velocity_wo), the inward normal part is removed and the tangential
 * part is reduced by μ times the removed normal speed (Coulomb), stopping at zero. */
inline void respond_to_contact(const Contact &contact, const float friction,
                               vec3 &r_position_wo, vec3 &r_relative_velocity_wo)
{
  if (contact.depth > 0.0f) {
    r_position_wo = contact.surface_point_wo;
  }
  const float v_n = glm::dot(r_relative_velocity_wo, contact.normal_wo);
  if (v_n >= 0.0f) {
    return; /* Leaving the surface. */
  }
  const vec3 v_t = r_relative_velocity_wo - v_n * contact.normal_wo;
  const float v_t_len = glm::length(v_t);
  const float scale = v_t_len > 0.0f ? std::max(0.0f, 1.0f + friction * v_n / v_t_len) : 0.0f;
  r_relative_velocity_wo = scale * v_t;
}

}  // namespace hairdyn
