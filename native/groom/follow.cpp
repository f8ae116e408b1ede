#include "groom/follow.hh"

#include "core/parallel.hh"

namespace hairdyn {

void transform_points(const mat4 &m, const Span<vec3> src, const MutableSpan<vec3> r_dst)
{
  assert(src.size() == r_dst.size());
  parallel_for(src.size(), 4096, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      r_dst[i] = transform_point(m, src[i]);
    }
  });
}

FollowSolver::FollowSolver(const Span<int32_t> curve_offsets, const Span<vec3> rest_positions_wo,
                           const mat4 &head_to_world_rest)
    : curve_offsets_(curve_offsets.begin(), curve_offsets.end()),
      rest_positions_wo_(rest_positions_wo.begin(), rest_positions_wo.end()),
      world_to_head_rest_(glm::inverse(glm::dmat4(head_to_world_rest))),
      positions_wo_(rest_positions_wo_)
{
}

void FollowSolver::step(const mat4 &head_to_world)
{
  /* p(t) = M(t) M(rest)^-1 p(rest). The product is formed in double precision so that an
   * unmoved head returns the rest shape to float precision. */
  const mat4 rest_to_now = mat4(glm::dmat4(head_to_world) * world_to_head_rest_);
  transform_points(rest_to_now, rest_positions_wo_, positions_wo_);
}

void FollowSolver::reset()
{
  positions_wo_ = rest_positions_wo_;
}

}  // namespace hairdyn
