#pragma once
/* The seam through which methods that act on the whole groom plug into strand dynamics
 * (Petrovic 2006's volume, Ward & Lin 2003's swept spheres and level of detail; DESIGN.md:
 * "all strands advance one substep, then grid and collision passes").
 *
 * Each substep the strand solver advances every strand, then runs its passes in order over
 * the node state, then takes the corrected positions and velocities back into its own
 * coordinates (segment lengths kept, roots carried by the head). A pass owns its scratch
 * buffers and calls kernels that are free functions over spans; it must be deterministic for
 * any thread count. */
#include <cstdint>
#include <vector>

#include "core/math.hh"
#include "core/span.hh"

namespace hairdyn {

/* Per point, what the nodes stand for in the passes beyond a strand's own thickness (level of
 * detail's groups; SubstepState's fields of the same names). Each empty when not given. */
struct PassVolumes {
  std::vector<float> radii;
  std::vector<vec3> strip_half_widths_hs;
  std::vector<vec3> rest_positions_hs;
  std::vector<float> rest_clearances;
};

/* Segment p's (from point p to p + 1) swept-sphere radius: the mean of its nodes' radii, or
 * `default_radius` when there are none. */
inline float segment_radius(const Span<float> radii, const float default_radius, const int64_t p)
{
  return radii.is_empty() ? default_radius : 0.5f * (radii[p] + radii[p + 1]);
}
/* Segment p's half width across its strip, the mean of its nodes' (zero: not a strip). */
inline vec3 segment_half_width(const Span<vec3> half_widths, const int64_t p)
{
  return half_widths.is_empty() ? vec3(0.0f) : 0.5f * (half_widths[p] + half_widths[p + 1]);
}
/* How far segment p's swept sphere reaches from its core segment: its radius, plus a strip's
 * half width (the line swept sphere around its rectangle swept sphere). */
inline float segment_reach(const Span<float> radii, const float default_radius,
                           const Span<vec3> half_widths, const int64_t p)
{
  return segment_radius(radii, default_radius, p) +
         glm::length(segment_half_width(half_widths, p));
}

struct SubstepState {
  float h = 0.0f;    /* s, the substep's length */
  float time = 0.0f; /* s, simulated time at its end */
  Span<int32_t> curve_offsets;
  /* World-space node positions (m) and velocities (m/s) at the end of the substep. A pass
   * may change any node but the roots (the first point of each strand). */
  MutableSpan<vec3> positions_wo;
  MutableSpan<vec3> velocities_wo;
  /* World-space node positions at the substep's start (as the last substep's passes and
   * take-back left them), or empty when the caller has none: a collision pass sweeps each
   * segment from there to positions_wo (continuous detection). */
  Span<vec3> start_positions_wo;
  /* m, per point: the strand's radius (swept-sphere thickness); empty when unknown. */
  Span<float> radii;
  /* m, per point: half the width of a strip across its segments, in the head's frame
   * (head_to_world turns it): a segment whose two nodes give a non-zero one is a rectangle
   * swept sphere (Ward & Lin 2003 §5.2), its rectangle the segment widened by it both ways.
   * Empty, or zero: a line swept sphere. */
  Span<vec3> strip_half_widths_hs;
  /* m, per point: where it lies at rest, in the frame of strip_half_widths_hs (the head's,
   * unscaled): segments closer at rest than their radii may stay that close (hair–hair's
   * GroupVolumes). Empty: none. */
  Span<vec3> rest_positions_hs;
  /* m, per point: how far it lay outside the colliders at rest; a body collision pass keeps a
   * segment no farther out than its nodes were then, up to its radius (a group's skeleton
   * lies closer to the body than its radius where its strands rest on it). Empty: none. */
  Span<float> rest_clearances;
  /* The head at the end of the substep (grids that move with the head use it). */
  mat4 head_to_world{ 1.0f };

  void set_volumes(const PassVolumes &volumes)
  {
    radii = volumes.radii;
    strip_half_widths_hs = volumes.strip_half_widths_hs;
    rest_positions_hs = volumes.rest_positions_hs;
    rest_clearances = volumes.rest_clearances;
  }
};

class SubstepPass {
 public:
  virtual ~SubstepPass() = default;
  /* Report name ("volume", "hair_hair"): the solver times each pass under it. */
  virtual const char *name() const = 0;
  virtual void apply(const SubstepState &state) = 0;
};

}  // namespace hairdyn
