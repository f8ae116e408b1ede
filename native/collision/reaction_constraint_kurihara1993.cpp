#include "collision/reaction_constraint_kurihara1993.hh"

#include <algorithm>
#include <numeric>
#include <vector>

#include "core/parallel.hh"

namespace hairdyn {

ReactionConstants ReactionConstants::from(const CollisionParams &params, const float dt,
                                          const float rest_depth)
{
  return {params.stiffness, params.damping_or_critical(), params.friction, dt, rest_depth};
}

vec3 reaction_constraint_force(const vec3 &force, const vec3 &velocity, const Contact &contact,
                               const ReactionConstants &constants)
{
  const vec3 &n = contact.normal_wo;
  const float force_n = glm::dot(force, n);
  /* Inelastic: only when the input force does not lift P off the surface (§3.2, last line). */
  if (force_n >= 0.0f) {
    return force;
  }
  /* Kurihara 1993, eq. 12 */
  const vec3 unconstrained = force - force_n * n;
  /* eq. 13, with N outward and PT·N = depth (see the header), taken at the end of the step
   * (backward Euler, as Ward & Lin 2003 appendix A takes the hinge springs): the depth then is
   * d − h V'·N and V'·N = V·N + h F_n, so F_n = (k d − (c + h k) V·N) / (1 + h c + h² k).
   * Taken at the step's start, the penalty overshoots once h² k or h c nears 1 (the defaults
   * at 96 substeps a second: 1.1 and 1.5) and a node resting on a body chatters in and out.
   * The spring acts beyond rest_depth only. Within it the surface gives what keeps the node
   * from moving further in at the step's end and no more, max(F·N, −V·N / h): a node comes to
   * rest there instead of being pushed onto the surface, out of contact, to fall back in by
   * g h² at the next step. The surface never pulls. */
  const float h = constants.dt, k = constants.stiffness, c = constants.damping;
  const float v_n = glm::dot(velocity, n);
  const float spring_depth = contact.depth - constants.rest_depth;
  const float constrained_n =
      spring_depth > 0.0f ?
          std::max((k * spring_depth - (c + h * k) * v_n) / (1.0f + h * c + h * h * k), 0.0f) :
          std::max(force_n, -v_n / h);
  /* eq. 14 / 15 */
  vec3 output = unconstrained + constrained_n * n;
  if (constants.friction > 0.0f) {
    /* Extension: Coulomb friction. The surface pushes with normal_load = the change of the
     * normal force; friction opposes the tangential velocity after the step. */
    const float normal_load = std::max(constrained_n - force_n, 0.0f);
    const vec3 v_t = velocity - glm::dot(velocity, n) * n;
    const vec3 slide = v_t + unconstrained * constants.dt;
    const float slide_len = glm::length(slide);
    if (slide_len > 0.0f) {
      const float stop = slide_len / constants.dt;
      const float magnitude = std::min(constants.friction * normal_load, stop);
      output -= slide * (magnitude / slide_len);
    }
  }
  return output;
}

int64_t apply_reaction_constraint(const ColliderSet &colliders, const Span<vec3> positions_wo,
                                  const Span<vec3> velocities_wo, const Span<vec3> forces,
                                  const ReactionConstants &constants,
                                  const MutableSpan<vec3> r_forces)
{
  assert(positions_wo.size() == velocities_wo.size() && forces.size() == positions_wo.size() &&
         r_forces.size() == positions_wo.size());
  const int64_t grain = 4096;
  std::vector<int64_t> chunk_counts(size_t((positions_wo.size() + grain - 1) / grain), 0);
  parallel_for(positions_wo.size(), grain, [&](const IndexRange range) {
    int64_t count = 0;
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      Contact contact;
      if (colliders.find_contact(positions_wo[i], contact)) {
        r_forces[i] = reaction_constraint_force(forces[i], velocities_wo[i], contact, constants);
        count++;
      }
      else {
        r_forces[i] = forces[i];
      }
    }
    chunk_counts[size_t(range.start / grain)] = count;
  });
  return std::accumulate(chunk_counts.begin(), chunk_counts.end(), int64_t(0));
}

int64_t project_out_of_colliders(const ColliderSet &colliders, const float tolerance_wo,
                                 const MutableSpan<vec3> r_positions_wo,
                                 const MutableSpan<vec3> r_velocities_wo)
{
  assert(r_positions_wo.size() == r_velocities_wo.size());
  const int64_t grain = 4096;
  std::vector<int64_t> chunk_counts(size_t((r_positions_wo.size() + grain - 1) / grain), 0);
  parallel_for(r_positions_wo.size(), grain, [&](const IndexRange range) {
    int64_t count = 0;
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      Contact contact;
      if (!colliders.find_contact(r_positions_wo[i], contact) || contact.depth <= tolerance_wo) {
        continue;
      }
      r_positions_wo[i] = contact.surface_point_wo;
      const float v_n = glm::dot(r_velocities_wo[i], contact.normal_wo);
      if (v_n < 0.0f) {
        r_velocities_wo[i] -= v_n * contact.normal_wo;
      }
      count++;
    }
    chunk_counts[size_t(range.start / grain)] = count;
  });
  return std::accumulate(chunk_counts.begin(), chunk_counts.end(), int64_t(0));
}

}  // namespace hairdyn
