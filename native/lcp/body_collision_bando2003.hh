#pragma once
/* Collisions between hair particles and the body (head, torso), Bando 2003, §3.5: after
 * integration, a particle inside a collider goes back to the surface, loses the part of its
 * velocity (relative to the collider) that points into the body, and its sliding velocity is
 * reduced by Coulomb friction (Bridson et al. 2002).
 *
 * The seam: the solver asks an LcpContactQuery per particle, in world space. To plug in
 * native/collision's ColliderSet (collision/contact.hh `Contact`), wrap it:
 *
 *   solver.set_body_contact([&colliders](const vec3 &p_wo, LcpContact &r_contact) {
 *     Contact contact;
 *     if (!colliders.find_contact(p_wo, contact)) { return false; }
 *     r_contact.depth = contact.depth;
 *     r_contact.normal_wo = contact.normal_wo;
 *     r_contact.surface_point_wo = contact.surface_point_wo;
 *     return true;  // moves_with_head stays true: the body moves with the head's frame
 *   });
 *
 * The query is called from several threads at once: it must be safe to call concurrently
 * (const look-ups are). */
#include <functional>

#include "core/math.hh"

namespace hairdyn {

struct LcpContact {
  float depth = 0.0f;          /* > 0: the point is inside, this far from the surface. */
  vec3 normal_wo{0.0f};        /* Outward unit normal at the surface point. */
  vec3 surface_point_wo{0.0f}; /* Nearest point on the surface. */
  /* The collider is carried by the head's frame (the body). If false, it moves on its own
   * with `velocity_wo` (an obstacle). */
  bool moves_with_head = true;
  vec3 velocity_wo{0.0f};
};

/* True and r_contact filled when p_wo touches or is inside a collider. */
using LcpContactQuery = std::function<bool(const vec3 &p_wo, LcpContact &r_contact)>;

/* Response to one contact: r_position_wo onto the surface; of the velocity relative to the
 * collider (r_relative_velocity_wo), the inward normal part is removed and the tangential
 * part is reduced by μ times the removed normal speed (Coulomb), stopping at zero. */
inline void respond_to_contact(const LcpContact &contact, const float friction,
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
