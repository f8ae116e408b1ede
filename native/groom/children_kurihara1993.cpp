#include "groom/children_kurihara1993.hh"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/parallel.hh"
#include "core/random.hh"
#include "groom/frames.hh"
#include "groom/groom.hh"

namespace hairdyn {

ChildHairs::ChildHairs(const Span<int32_t> guide_offsets, std::vector<int32_t> influence_offsets,
                       std::vector<Influence> influences, const Span<int32_t> child_points_nums)
    : guide_offsets_(guide_offsets.begin(), guide_offsets.end()),
      influence_offsets_(std::move(influence_offsets)),
      influences_(std::move(influences))
{
  curve_offsets_.assign(size_t(child_points_nums.size()) + 1, 0);
  for (int64_t c = 0; c < child_points_nums.size(); c++) {
    curve_offsets_[size_t(c + 1)] = curve_offsets_[size_t(c)] + child_points_nums[c];
  }
  positions_wo_.assign(size_t(curve_offsets_.back()), vec3(0.0f));
  guide_frames_wo_.assign(size_t(guide_offsets_.back()), mat3(1.0f));
}

ChildHairs ChildHairs::around_guides(const Span<int32_t> guide_offsets,
                                     const int children_per_guide, const float spread,
                                     const uint32_t seed)
{
  const int64_t guides = guide_offsets.size() - 1;
  const int64_t children = guides * children_per_guide;
  std::vector<int32_t> influence_offsets(size_t(children) + 1);
  std::iota(influence_offsets.begin(), influence_offsets.end(), 0);
  std::vector<Influence> influences(static_cast<size_t>(children));
  std::vector<int32_t> points_nums(static_cast<size_t>(children));
  parallel_for(guides, 256, [&](const IndexRange range) {
    for (int64_t guide = range.start; guide < range.one_after_last(); guide++) {
      /* One generator per guide: a child's root depends on the seed and its guide only. */
      RandomNumberGenerator rng((uint64_t(seed) << 32) ^ uint64_t(guide) * 0x9e3779b97f4a7c15ull);
      for (int64_t k = 0; k < children_per_guide; k++) {
        const size_t child = size_t(guide * children_per_guide + k);
        /* Uniform in the disc of radius `spread` on the root's tangent plane. */
        const float radius = spread * std::sqrt(rng.next_float());
        const float angle = rng.next_float(0.0f, 2.0f * float(M_PI));
        influences[child] = {int32_t(guide), 1.0f,
                             vec3(radius * std::cos(angle), radius * std::sin(angle), 0.0f)};
        points_nums[child] = int32_t(curve_points(guide_offsets, guide).size);
      }
    }
  });
  return ChildHairs(guide_offsets, std::move(influence_offsets), std::move(influences),
                    points_nums);
}

ChildHairs ChildHairs::between_guides(const Span<int32_t> guide_offsets,
                                      const Span<vec3> guide_rest_positions_wo,
                                      const Span<mat3> guide_rest_root_frames_wo,
                                      const Span<vec3> roots_wo, const int neighbours_num)
{
  const int64_t guides = guide_offsets.size() - 1;
  const int64_t influences_per_child = std::min<int64_t>(std::max(neighbours_num, 1), guides);
  const int64_t children = roots_wo.size();
  std::vector<Influence> influences(static_cast<size_t>(children * influences_per_child));
  std::vector<int32_t> counts(static_cast<size_t>(children));
  std::vector<int32_t> points_nums(static_cast<size_t>(children));
  /* Brute-force nearest roots: once per groom, guides are few (thousands). */
  parallel_for(children, 64, [&](const IndexRange range) {
    std::vector<std::pair<float, int32_t>> nearest(static_cast<size_t>(guides));
    for (int64_t child = range.start; child < range.one_after_last(); child++) {
      const vec3 root = roots_wo[child];
      for (int64_t guide = 0; guide < guides; guide++) {
        const vec3 guide_root = guide_rest_positions_wo[guide_offsets[guide]];
        nearest[size_t(guide)] = {glm::length(root - guide_root), int32_t(guide)};
      }
      std::partial_sort(nearest.begin(), nearest.begin() + influences_per_child, nearest.end());
      Influence *out = &influences[size_t(child * influences_per_child)];
      points_nums[size_t(child)] = int32_t(curve_points(guide_offsets, nearest[0].second).size);
      if (nearest[0].first < 1e-7f) {
        /* On a guide's root: that guide alone (inverse distance weight → 1). */
        counts[size_t(child)] = 1;
        out[0] = {nearest[0].second, 1.0f, vec3(0.0f)};
        continue;
      }
      float weight_sum = 0.0f;
      for (int64_t k = 0; k < influences_per_child; k++) {
        const auto [distance, guide] = nearest[size_t(k)];
        const vec3 guide_root = guide_rest_positions_wo[guide_offsets[guide]];
        out[k] = {guide, 1.0f / distance,
                  glm::transpose(guide_rest_root_frames_wo[guide]) * (root - guide_root)};
        weight_sum += out[k].weight;
      }
      for (int64_t k = 0; k < influences_per_child; k++) {
        out[k].weight /= weight_sum;
      }
      counts[size_t(child)] = int32_t(influences_per_child);
    }
  });
  /* Compact to offsets + influences. */
  std::vector<int32_t> influence_offsets(size_t(children) + 1, 0);
  std::vector<Influence> compact;
  compact.reserve(influences.size());
  for (int64_t child = 0; child < children; child++) {
    const Influence *in = &influences[size_t(child * influences_per_child)];
    compact.insert(compact.end(), in, in + counts[size_t(child)]);
    influence_offsets[size_t(child + 1)] = int32_t(compact.size());
  }
  return ChildHairs(guide_offsets, std::move(influence_offsets), std::move(compact), points_nums);
}

template<typename Fn>
void ChildHairs::blend_over_guides(const MutableSpan<vec3> r_child_values, const Fn &term) const
{
  parallel_for(curves_num(), 256, [&](const IndexRange range) {
    for (int64_t child = range.start; child < range.one_after_last(); child++) {
      const IndexRange points = curve_points(curve_offsets_, child);
      for (int64_t j = 0; j < points.size; j++) {
        /* Child point j sits at parameter u = j / (n − 1) along each influencing guide. */
        const float u = float(j) / float(points.size - 1);
        vec3 value(0.0f);
        for (int32_t k = influence_offsets_[size_t(child)];
             k < influence_offsets_[size_t(child + 1)]; k++)
        {
          const Influence &influence = influences_[size_t(k)];
          const IndexRange guide = curve_points(guide_offsets_, influence.guide);
          const float s = u * float(guide.size - 1);
          const int64_t i0 = std::min<int64_t>(int64_t(s), guide.size - 2);
          value += influence.weight * term(influence, guide.start + i0, s - float(i0));
        }
        r_child_values[points.start + j] = value;
      }
    }
  });
}

void ChildHairs::update(const Span<vec3> guide_positions_wo, const Span<mat3> guide_root_frames_wo)
{
  assert(guide_positions_wo.size() == guide_points_num());
  assert(guide_root_frames_wo.size() == guides_num());
  /* The frame at every guide point: the root frame, then transported along each segment. */
  parallel_for(guides_num(), 256, [&](const IndexRange range) {
    for (int64_t guide = range.start; guide < range.one_after_last(); guide++) {
      const IndexRange points = curve_points(guide_offsets_, guide);
      mat3 frame = guide_root_frames_wo[guide];
      guide_frames_wo_[size_t(points.start)] = frame;
      for (int64_t i = points.start + 1; i < points.one_after_last(); i++) {
        frame = parallel_transport(
            frame, glm::normalize(guide_positions_wo[i] - guide_positions_wo[i - 1]));
        guide_frames_wo_[size_t(i)] = frame;
      }
    }
  });
  /* The guide's point at the child point's place plus the root offset carried by the guide's
   * frame, blended by weight. */
  blend_over_guides(positions_wo_, [&](const Influence &influence, const int64_t i, const float f) {
    const mat3 &frame = guide_frames_wo_[size_t(f < 0.5f ? i : i + 1)];
    return glm::mix(guide_positions_wo[i], guide_positions_wo[i + 1], f) +
           frame * influence.offset_root;
  });
}

void ChildHairs::blend(const Span<vec3> guide_values, const MutableSpan<vec3> r_child_values) const
{
  assert(guide_values.size() == guide_points_num());
  assert(r_child_values.size() == curve_offsets_.back());
  blend_over_guides(r_child_values, [&](const Influence &, const int64_t i, const float f) {
    return glm::mix(guide_values[i], guide_values[i + 1], f);
  });
}

}  // namespace hairdyn
