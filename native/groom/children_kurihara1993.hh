#pragma once
/* Render hairs that follow simulated guides.
 *
 * Kurihara 1993, §4 (cluster model): "we simulate the movement of typical strands and generate
 * other strands by adding random numbers to the origin of the typical strands". Each child
 * takes root at a seeded random offset within a disc around its guide's root on the scalp
 * plane (the root frame's tangent plane) and keeps that offset in the guide's frame all along
 * it: the offset is carried by twist-free frames transported from the root frame along the
 * guide's current shape, so a child stays beside its guide through curls and follows it
 * rigidly when the guide moves rigidly.
 *
 * For render hairs rooted anywhere on the scalp, a child instead blends the guides whose roots
 * are nearest to its own, weighted by inverse root distance (the keyhair interpolation of
 * Ward & Lin 2003, §3 and Petrovic 2006; Kurihara has only the cluster model). Both kinds are
 * the same data: per child, a few (guide, weight, offset) influences. */
#include <vector>

#include "core/math.hh"
#include "core/span.hh"

namespace hairdyn {

class ChildHairs {
 public:
  /* `children_per_guide` children around each guide of the groom described by
   * `guide_offsets`, rooted uniformly within `spread` meters of the guide's root. The same
   * seed gives the same children. */
  static ChildHairs around_guides(Span<int32_t> guide_offsets, int children_per_guide,
                                  float spread, uint32_t seed);
  /* One child per root in `roots_wo`, blending the `neighbours_num` guides whose rest roots are
   * nearest, with weights ∝ 1 / distance. A child has the point count of its nearest guide. */
  static ChildHairs between_guides(Span<int32_t> guide_offsets, Span<vec3> guide_rest_positions_wo,
                                   Span<mat3> guide_rest_root_frames_wo, Span<vec3> roots_wo,
                                   int neighbours_num = 3);

  /* Places every child on the guides' current shapes: `guide_positions_wo` in the layout of
   * `guide_offsets`, one root frame per guide (columns tangent, bitangent, normal), e.g. from
   * StrandSolver::root_frames(). */
  void update(Span<vec3> guide_positions_wo, Span<mat3> guide_root_frames_wo);
  /* A value per guide point (e.g. a shading normal) carried to every child point as the
   * positions are, without the root offset: the influencing guides' values at the child
   * point's place along them, blended by weight. */
  void blend(Span<vec3> guide_values, MutableSpan<vec3> r_child_values) const;

  int64_t curves_num() const { return int64_t(curve_offsets_.size()) - 1; }
  int64_t guides_num() const { return int64_t(guide_offsets_.size()) - 1; }
  int64_t guide_points_num() const { return guide_offsets_.back(); }
  Span<int32_t> curve_offsets() const { return curve_offsets_; }
  Span<vec3> positions() const { return positions_wo_; }

 private:
  struct Influence {
    int32_t guide;
    float weight;
    vec3 offset_root; /* the child's root relative to the guide's, in the guide's root frame */
  };

  /* Every child point gets Σ weight · term(influence, i, f) over its influencing guides, with
   * i and i + 1 the guide's points around the child point's place and f the fraction between. */
  template<typename Fn>
  void blend_over_guides(MutableSpan<vec3> r_child_values, const Fn &term) const;

  ChildHairs(Span<int32_t> guide_offsets, std::vector<int32_t> influence_offsets,
             std::vector<Influence> influences, Span<int32_t> child_points_nums);

  std::vector<int32_t> guide_offsets_;
  /* Child c's influences are influences_[influence_offsets_[c] .. influence_offsets_[c + 1]). */
  std::vector<int32_t> influence_offsets_;
  std::vector<Influence> influences_;
  std::vector<int32_t> curve_offsets_;
  std::vector<vec3> positions_wo_;
  /* Scratch: the transported frame at every guide point, rebuilt by update(). */
  std::vector<mat3> guide_frames_wo_;
};

}  // namespace hairdyn
