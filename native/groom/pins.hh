#pragma once
/* Pinned points. TressFX marks vertices immovable (inverse mass 0, `w == 0` in a .tfx file;
 * AMD's ponytail pins both ends of its back strands) and the importer keeps them as the
 * BOOLEAN point attribute `hairdyn_fixed`. A pinned point is kinematic, as the root is in
 * every paper (Kurihara 1993 §2: the root segment is fixed to the head): it is carried rigidly
 * by the head on its rest position. A strand with pins is then a chain held at both ends
 * between each kinematic point (the root, or the pin before) and the next pin.
 *
 * Reaching a pin keeps every segment's length: the chain's segments turn, each about its own
 * start, by the least total turn that moves the pin onto its target. With d_i the unit
 * directions and l_i the lengths, turning segment i by a small ω_i moves the pin by
 * Σ l_i ω_i × d_i; the least-norm turns that move it by Δ are ω_i = l_i d_i × λ with
 * (Σ l_i² (1 − d_i d_iᵀ)) λ = Δ (the pseudo-inverse of the chain's Jacobian: Buss 2004,
 * "Introduction to inverse kinematics with Jacobian transpose, pseudoinverse and damped least
 * squares methods"; a little damping keeps the 3×3 system regular when the chain is nearly
 * straight). Each segment then turns by exactly its ω_i (Rodrigues), so lengths are exact,
 * and a few such Newton steps reach the target (quadratically: a pin moved a few millimetres
 * by a substep's dynamics is back within a micrometre in two or three). The turns are spread
 * over the whole chain, most where a segment lies across the move, so the shape changes as
 * little as the pin needs. */
#include <algorithm>
#include <cmath>

#include "core/math.hh"
#include "core/span.hh"

namespace hairdyn {

/* At most this many Newton steps per pin and substep. */
constexpr int pin_iterations = 16;

/* Moves chain[1], ..., chain[n - 1] so that chain[n - 1] reaches `target` with chain[0] held:
 * `lengths[i]` is the distance from chain[i - 1] to chain[i] (lengths[0] is not read). Stops
 * once the last point is within `tolerance` of the target, or after `iterations`; returns that
 * distance. A target beyond the chain's reach gets the chain straight toward it. Works for
 * vec3 and dvec3 (with float and double lengths). */
template<typename Vec, typename Scalar> Scalar reach_pin(const MutableSpan<Vec> chain,
                                                         const Span<Scalar> lengths,
                                                         const Vec &target, const Scalar tolerance,
                                                         const int iterations = pin_iterations)
{
  using Mat = glm::mat<3, 3, Scalar>;
  const int64_t n = chain.size();
  const int64_t last = n - 1;
  const Vec base = chain[0];
  Scalar total = Scalar(0), total_squared = Scalar(0);
  for (int64_t i = 1; i < n; i++) {
    total += lengths[i];
    total_squared += lengths[i] * lengths[i];
  }
  const Scalar reach = glm::length(target - base);
  if (n >= 2 && reach >= total - tolerance) {
    /* Out of reach, or just within it: the chain straight toward the target. */
    const Vec direction = reach > Scalar(0) ? (target - base) / reach : Vec(0, 0, 1);
    Scalar s = Scalar(0);
    for (int64_t i = 1; i < n; i++) {
      s += lengths[i];
      chain[i] = base + s * direction;
    }
    return glm::length(target - chain[last]);
  }
  /* Regularises the system along a straight chain (where no turn lengthens it). */
  const Scalar damping = Scalar(1e-6) * total_squared;
  Scalar error = glm::length(target - chain[last]);
  for (int iteration = 0; iteration < iterations && n >= 2 && error > tolerance; iteration++) {
    Mat system = Mat(damping);
    for (int64_t i = 1; i < n; i++) {
      const Vec d = glm::normalize(chain[i] - chain[i - 1]);
      system += (lengths[i] * lengths[i]) * (Mat(Scalar(1)) - glm::outerProduct(d, d));
    }
    const Vec lambda = glm::inverse(system) * (target - chain[last]);
    /* No segment turns more than half a radian a step (a far target takes a few). */
    Scalar largest = Scalar(0);
    for (int64_t i = 1; i < n; i++) {
      largest = std::max(
          largest,
          lengths[i] * glm::length(glm::cross(glm::normalize(chain[i] - chain[i - 1]), lambda)));
    }
    const Scalar scale = largest > Scalar(0.5) ? Scalar(0.5) / largest : Scalar(1);
    Vec start = base, old_start = base; /* segment i's start, after and before the step */
    for (int64_t i = 1; i < n; i++) {
      const Vec old = chain[i];
      const Vec d = glm::normalize(old - old_start);
      const Vec omega = (scale * lengths[i]) * glm::cross(d, lambda);
      const Scalar angle = glm::length(omega);
      Vec turned = d;
      if (angle > Scalar(0)) {
        const Vec axis = omega / angle;
        turned = std::cos(angle) * d + std::sin(angle) * glm::cross(axis, d) +
                 (Scalar(1) - std::cos(angle)) * glm::dot(axis, d) * axis;
      }
      chain[i] = start + lengths[i] * glm::normalize(turned);
      start = chain[i];
      old_start = old;
    }
    error = glm::length(target - chain[last]);
  }
  return error;
}

}  // namespace hairdyn
