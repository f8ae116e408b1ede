#include "lod/hierarchy_ward2003.hh"

#include <algorithm>
#include <cmath>

#include "core/parallel.hh"
#include "groom/frames.hh"
#include "groom/groom.hh"

namespace hairdyn {

namespace {

/* Deepest tree a hierarchy may grow (a guard: quadrant splits halve the cross-section). */
constexpr int32_t max_tree_depth = 48;

}  // namespace

void resample_strands(const Span<int32_t> curve_offsets, const Span<vec3> positions,
                      const int32_t points_num, const MutableSpan<vec3> r_resampled,
                      const MutableSpan<int32_t> r_point_segments,
                      const MutableSpan<float> r_point_weights)
{
  const int64_t curves = curve_offsets.size() - 1;
  const float last = float(points_num - 1);
  parallel_for(curves, 256, [&](const IndexRange range) {
    std::vector<float> arc;
    for (int64_t curve = range.start; curve < range.one_after_last(); curve++) {
      const IndexRange points = curve_points(curve_offsets, curve);
      arc.assign(size_t(points.size), 0.0f);
      for (int64_t i = 1; i < points.size; i++) {
        arc[size_t(i)] = arc[size_t(i - 1)] +
                         glm::length(positions[points.start + i] - positions[points.start + i - 1]);
      }
      const float length = arc.back();
      /* Each strand point: where it lies along an n-point curve of the same arc length. */
      for (int64_t i = 0; i < points.size; i++) {
        const float x = arc[size_t(i)] / length * last;
        const int32_t segment = std::min(int32_t(x), points_num - 2);
        r_point_segments[points.start + i] = segment;
        r_point_weights[points.start + i] = std::min(x - float(segment), 1.0f);
      }
      /* n points evenly spaced in arc length. */
      int64_t i = 0;
      for (int32_t k = 0; k < points_num; k++) {
        const float s = length * float(k) / last;
        while (i + 2 < points.size && arc[size_t(i + 1)] < s) {
          i++;
        }
        const float span = arc[size_t(i + 1)] - arc[size_t(i)];
        const float t = glm::clamp((s - arc[size_t(i)]) / span, 0.0f, 1.0f);
        r_resampled[curve * points_num + k] = glm::mix(positions[points.start + i],
                                                        positions[points.start + i + 1], t);
      }
      r_resampled[curve * points_num] = positions[points.start];
      r_resampled[curve * points_num + points_num - 1] = positions[points.start + points.size - 1];
    }
  });
}

void project_roots(const Span<vec3> roots, const Span<vec3> root_normals,
                   const MutableSpan<vec2> r_uvs)
{
  vec3 centroid(0.0f), normal_sum(0.0f);
  for (int64_t i = 0; i < roots.size(); i++) {
    centroid += roots[i];
    normal_sum += root_normals[i];
  }
  centroid /= float(roots.size());
  const vec3 axis = glm::length(normal_sum) > 1e-6f ? glm::normalize(normal_sum) : vec3(0, 0, 1);
  const mat3 basis = root_frame_from_normal(axis);
  double radius_sum = 0.0;
  for (const vec3 &root : roots) {
    radius_sum += double(glm::length(root - centroid));
  }
  const float radius = float(radius_sum / double(roots.size()));
  /* Azimuthal equidistant projection about the scalp's mean normal, seen from the roots'
   * centroid: (u, v) = ρ α (cos β, sin β), α the angle from the axis, β the azimuth. */
  for (int64_t i = 0; i < roots.size(); i++) {
    const vec3 d = roots[i] - centroid;
    const float d_length = glm::length(d);
    if (d_length < 1e-12f) {
      r_uvs[i] = vec2(0.0f);
      continue;
    }
    const vec3 w = d / d_length;
    const float alpha = std::acos(glm::clamp(glm::dot(w, axis), -1.0f, 1.0f));
    const float beta = std::atan2(glm::dot(w, basis[1]), glm::dot(w, basis[0]));
    r_uvs[i] = radius * alpha * vec2(std::cos(beta), std::sin(beta));
  }
}

void skeleton_frames(const Span<vec3> skeleton, const mat3 &root_frame,
                     const MutableSpan<mat3> r_frames)
{
  mat3 frame = root_frame;
  r_frames[0] = frame;
  for (int64_t i = 1; i < skeleton.size(); i++) {
    frame = parallel_transport(frame, glm::normalize(skeleton[i] - skeleton[i - 1]));
    r_frames[i] = frame;
  }
}

Span<vec3> LodHierarchy::rest_skeleton(const int64_t node) const
{
  return Span<vec3>(rest_skeletons_).slice(node * skeleton_points_num_, skeleton_points_num_);
}

Span<mat3> LodHierarchy::rest_frames(const int64_t node) const
{
  return Span<mat3>(rest_frames_).slice(node * skeleton_points_num_, skeleton_points_num_);
}

Span<vec3> LodHierarchy::offsets(const int64_t node) const
{
  return Span<vec3>(offsets_).slice(node * skeleton_points_num_, skeleton_points_num_);
}

Span<float> LodHierarchy::spread(const int64_t node) const
{
  return Span<float>(spread_).slice(node * skeleton_points_num_, skeleton_points_num_);
}

Span<vec3> LodHierarchy::half_width(const int64_t node) const
{
  return Span<vec3>(half_width_).slice(node * skeleton_points_num_, skeleton_points_num_);
}

int32_t LodHierarchy::add_node(const int32_t parent, const LodKind kind, const Range strands)
{
  const int32_t node = int32_t(depth_.size());
  depth_.push_back(parent < 0 ? 0 : depth_[size_t(parent)] + 1);
  parent_.push_back(parent);
  top_.push_back(parent < 0 ? node : top_[size_t(parent)]);
  children_start_.push_back(0);
  children_num_.push_back(0);
  strands_start_.push_back(strands.start);
  strands_num_.push_back(strands.size);
  kind_.push_back(kind);
  max_depth_ = std::max(max_depth_, depth_.back());
  return node;
}

void LodHierarchy::split(const int32_t node, const int32_t strip_depth, const Span<vec2> uvs,
                         const Span<vec3> roots, const LodParams &params)
{
  const int32_t start = strands_start_[size_t(node)];
  const int32_t size = strands_num_[size_t(node)];
  if (size <= std::max(params.min_group_strands, 1) || depth_[size_t(node)] >= max_tree_depth) {
    return; /* A leaf (§4.2: a group of one strand has no children). */
  }
  int32_t *begin = strand_order_.data() + start;
  int32_t *end = begin + size;
  vec2 lo(INFINITY), hi(-INFINITY);
  for (const int32_t *s = begin; s != end; s++) {
    lo = glm::min(lo, uvs[*s]);
    hi = glm::max(hi, uvs[*s]);
  }
  std::vector<Range> parts;
  LodKind child_kind = kind_[size_t(node)];
  if (child_kind == LodKind::Strip && strip_depth < params.strip_splits) {
    /* §4.1: a strip splits only into two equal parts, across its width. */
    const int axis = (hi.x - lo.x) >= (hi.y - lo.y) ? 0 : 1;
    std::sort(begin, end, [&](const int32_t a, const int32_t b) {
      return uvs[a][axis] < uvs[b][axis] || (uvs[a][axis] == uvs[b][axis] && a < b);
    });
    parts = {{start, size / 2}, {start + size / 2, size - size / 2}};
  }
  else {
    /* §4.1, §4.2, Fig. 5: the four quadrants of the cross-section; empty ones are null. */
    if (child_kind == LodKind::Strip) {
      child_kind = LodKind::Cluster; /* The finest strip becomes clusters (Fig. 4). */
    }
    else if (child_kind == LodKind::Cluster) {
      vec3 mean(0.0f);
      for (const int32_t *s = begin; s != end; s++) {
        mean += roots[*s];
      }
      mean /= float(size);
      float radius = 0.0f;
      for (const int32_t *s = begin; s != end; s++) {
        radius = std::max(radius, glm::length(roots[*s] - mean));
      }
      if (radius < params.cluster_min_radius) {
        child_kind = LodKind::StrandGroup;
      }
    }
    const vec2 centre = 0.5f * (lo + hi);
    const auto quadrant = [&](const int32_t s) {
      return int(uvs[s].x >= centre.x) + 2 * int(uvs[s].y >= centre.y);
    };
    std::sort(begin, end, [&](const int32_t a, const int32_t b) {
      const int qa = quadrant(a), qb = quadrant(b);
      return qa < qb || (qa == qb && a < b);
    });
    int32_t part_start = start;
    for (int32_t i = start + 1; i <= start + size; i++) {
      if (i == start + size || quadrant(strand_order_[size_t(i)]) !=
                                   quadrant(strand_order_[size_t(i - 1)]))
      {
        parts.push_back({part_start, i - part_start});
        part_start = i;
      }
    }
    if (parts.size() == 1) {
      /* Roots that share one (u, v) cannot be told apart by quadrant: split them evenly. */
      parts.clear();
      const int32_t chunks = std::min(size, 4);
      for (int32_t c = 0; c < chunks; c++) {
        const int32_t a = start + int32_t(int64_t(size) * c / chunks);
        const int32_t b = start + int32_t(int64_t(size) * (c + 1) / chunks);
        parts.push_back({a, b - a});
      }
    }
  }
  /* Children are consecutive: add them all, then split each. */
  const int32_t first_child = int32_t(depth_.size());
  for (const Range &part : parts) {
    add_node(node, child_kind, part);
  }
  children_start_[size_t(node)] = first_child;
  children_num_[size_t(node)] = int32_t(parts.size());
  const int32_t next_strip_depth = child_kind == LodKind::Strip ? strip_depth + 1 : strip_depth;
  for (int32_t child = first_child; child < first_child + int32_t(parts.size()); child++) {
    split(child, next_strip_depth, uvs, roots, params);
  }
}

void LodHierarchy::finish_node(const int32_t node, const Span<vec3> resampled,
                               const Span<vec3> root_normals)
{
  const int32_t n = skeleton_points_num_;
  const Span<int32_t> members = strands(node);
  const MutableSpan<vec3> skeleton(rest_skeletons_.data() + int64_t(node) * n, n);
  /* §4.2: one skeleton per group; the mean of its strands resampled to n points. */
  vec3 normal(0.0f);
  for (int32_t k = 0; k < n; k++) {
    skeleton[k] = vec3(0.0f);
  }
  for (const int32_t s : members) {
    for (int32_t k = 0; k < n; k++) {
      skeleton[k] += resampled[int64_t(s) * n + k];
    }
    normal += root_normals[s];
  }
  for (int32_t k = 0; k < n; k++) {
    skeleton[k] /= float(members.size());
  }
  /* Strands that part ways (a strip combed both sides) can average to a curve with vanishing
   * segments: then the member nearest the mean is the skeleton. */
  bool degenerate = false;
  for (int32_t k = 1; k < n; k++) {
    double member_length = 0.0;
    for (const int32_t s : members) {
      member_length += double(glm::length(resampled[int64_t(s) * n + k] -
                                          resampled[int64_t(s) * n + k - 1]));
    }
    const float mean_length = float(member_length / double(members.size()));
    degenerate |= glm::length(skeleton[k] - skeleton[k - 1]) < 0.25f * mean_length;
  }
  if (degenerate) {
    int32_t best = members[0];
    double best_distance = INFINITY;
    for (const int32_t s : members) {
      double distance = 0.0;
      for (int32_t k = 0; k < n; k++) {
        distance += double(glm::length(resampled[int64_t(s) * n + k] - skeleton[k]));
      }
      if (distance < best_distance) {
        best_distance = distance;
        best = s;
      }
    }
    for (int32_t k = 0; k < n; k++) {
      skeleton[k] = resampled[int64_t(best) * n + k];
    }
  }
  float radius = 0.0f;
  for (const int32_t s : members) {
    for (int32_t k = 0; k < n; k++) {
      radius = std::max(radius, glm::length(resampled[int64_t(s) * n + k] - skeleton[k]));
    }
  }
  radius_[size_t(node)] = radius;
  /* §5.2: the spread of the strands around each control point. */
  for (int32_t k = 0; k < n; k++) {
    const vec3 chord = skeleton[std::min(k + 1, n - 1)] - skeleton[std::max(k - 1, 0)];
    const float chord_length = glm::length(chord);
    const vec3 tangent = chord_length > 0.0f ? chord / chord_length : vec3(0.0f);
    const auto across = [&](const int32_t strand) {
      const vec3 d = resampled[int64_t(strand) * n + k] - skeleton[k];
      return d - glm::dot(d, tangent) * tangent;
    };
    double sum2 = 0.0;
    glm::dmat3 covariance(0.0);
    vec3 widest(0.0f);
    for (const int32_t strand : members) {
      const vec3 d = across(strand);
      sum2 += double(glm::dot(d, d));
      covariance += glm::outerProduct(glm::dvec3(d), glm::dvec3(d));
      widest = glm::dot(d, d) > glm::dot(widest, widest) ? d : widest;
    }
    const double count = double(members.size());
    vec3 half_width(0.0f);
    double along2 = 0.0;
    if (kind_[size_t(node)] == LodKind::Strip && glm::dot(widest, widest) > 0.0f) {
      /* The principal axis: power iteration from the widest offset. */
      glm::dvec3 axis = glm::normalize(glm::dvec3(widest));
      for (int iteration = 0; iteration < 32; iteration++) {
        const glm::dvec3 next = covariance * axis;
        const double length = glm::length(next);
        if (!(length > 0.0)) {
          break;
        }
        axis = next / length;
      }
      along2 = glm::dot(axis, covariance * axis) / count;
      half_width = vec3(std::sqrt(3.0 * along2) * axis);
    }
    const size_t i = size_t(int64_t(node) * n + k);
    spread_[i] = float(std::sqrt(std::max(sum2 / count - along2, 0.0)));
    half_width_[i] = half_width;
  }
  root_normals_[size_t(node)] = glm::length(normal) > 1e-6f ?
                                    glm::normalize(normal) :
                                    glm::normalize(skeleton[1] - skeleton[0]);
  const MutableSpan<mat3> frames(rest_frames_.data() + int64_t(node) * n, n);
  skeleton_frames(skeleton, root_frame_from_normal(root_normals_[size_t(node)]), frames);
  /* §6.2: "the offset of each child from the parent is stored", in the parent's frames. */
  const int32_t parent = parent_[size_t(node)];
  for (int32_t k = 0; k < n; k++) {
    offsets_[size_t(int64_t(node) * n + k)] =
        parent < 0 ? vec3(0.0f) :
                     glm::transpose(rest_frames_[size_t(int64_t(parent) * n + k)]) *
                         (skeleton[k] - rest_skeletons_[size_t(int64_t(parent) * n + k)]);
  }
}

LodHierarchy::LodHierarchy(const Span<int32_t> curve_offsets, const Span<vec3> rest_positions_wo,
                           const Span<vec2> root_uvs, const Span<vec3> root_normals_wo,
                           const LodParams &params)
    : curve_offsets_(curve_offsets.begin(), curve_offsets.end()),
      rest_positions_wo_(rest_positions_wo.begin(), rest_positions_wo.end())
{
  assert(find_groom_error(curve_offsets, rest_positions_wo).empty());
  const int64_t curves = strands_num();
  const int64_t points = rest_positions_wo.size();
  int32_t longest = 2;
  for (int64_t c = 0; c < curves; c++) {
    longest = std::max(longest, int32_t(curve_points(curve_offsets, c).size));
  }
  /* No more than the longest strand has: more control points add no shape the strands have,
   * and the hair–hair pass's pairs grow with their square (a group's swept sphere is
   * centimetres thick: 1,000 points on a 9-point groom took minutes a frame). */
  skeleton_points_num_ = params.skeleton_points >= 2 ? std::min(params.skeleton_points, longest) :
                                                       longest;
  const int32_t n = skeleton_points_num_;

  std::vector<vec3> resampled(static_cast<size_t>(curves * n));
  point_segments_.resize(size_t(points));
  point_weights_.resize(size_t(points));
  resample_strands(curve_offsets, rest_positions_wo, n, resampled, point_segments_,
                   point_weights_);

  std::vector<mat3> strand_root_frames(static_cast<size_t>(curves));
  compute_root_frames(curve_offsets, rest_positions_wo, root_normals_wo, strand_root_frames);
  std::vector<vec3> roots(static_cast<size_t>(curves)), normals(static_cast<size_t>(curves));
  for (int64_t c = 0; c < curves; c++) {
    roots[size_t(c)] = rest_positions_wo[curve_offsets[c]];
    normals[size_t(c)] = strand_root_frames[size_t(c)][2];
  }
  std::vector<vec2> uvs(root_uvs.begin(), root_uvs.end());
  if (uvs.empty()) {
    uvs.resize(size_t(curves));
    project_roots(roots, normals, uvs);
  }

  /* Top strips (§4.1): equal-count bands along v, each cut into equal-count strips along u,
   * so that a strip is about 2^strip_splits times wider than high. */
  strand_order_.resize(size_t(curves));
  for (int64_t c = 0; c < curves; c++) {
    strand_order_[size_t(c)] = int32_t(c);
  }
  const auto by_axis = [&](const int axis) {
    return [&, axis](const int32_t a, const int32_t b) {
      return uvs[size_t(a)][axis] < uvs[size_t(b)][axis] ||
             (uvs[size_t(a)][axis] == uvs[size_t(b)][axis] && a < b);
    };
  };
  const int64_t strips = std::min<int64_t>(params.strips_num, curves);
  const double aspect = std::ldexp(1.0, std::min(params.strip_splits, 8));
  const int64_t rows = std::clamp<int64_t>(int64_t(std::lround(std::sqrt(double(strips) / aspect))),
                                           1, strips);
  std::sort(strand_order_.begin(), strand_order_.end(), by_axis(1));
  for (int64_t row = 0; row < rows; row++) {
    const int64_t row_start = curves * row / rows, row_end = curves * (row + 1) / rows;
    std::sort(strand_order_.begin() + row_start, strand_order_.begin() + row_end, by_axis(0));
    const int64_t cols = strips * (row + 1) / rows - strips * row / rows;
    for (int64_t col = 0; col < cols; col++) {
      const int64_t a = row_start + (row_end - row_start) * col / cols;
      const int64_t b = row_start + (row_end - row_start) * (col + 1) / cols;
      if (b > a) {
        add_node(-1, LodKind::Strip, {int32_t(a), int32_t(b - a)});
      }
    }
  }
  top_nodes_num_ = nodes_num();
  for (int32_t top = 0; top < int32_t(top_nodes_num_); top++) {
    split(top, 0, uvs, roots, params);
  }

  const size_t nodes = size_t(nodes_num());
  radius_.resize(nodes);
  root_normals_.resize(nodes);
  rest_skeletons_.resize(nodes * size_t(n));
  rest_frames_.resize(nodes * size_t(n));
  offsets_.resize(nodes * size_t(n));
  spread_.resize(nodes * size_t(n));
  half_width_.resize(nodes * size_t(n));
  /* Parents come before their children, so their frames are ready for the offsets. */
  for (int32_t depth = 0; depth <= max_depth_; depth++) {
    parallel_for(int64_t(nodes), 64, [&](const IndexRange range) {
      for (int64_t node = range.start; node < range.one_after_last(); node++) {
        if (depth_[size_t(node)] == depth) {
          finish_node(int32_t(node), resampled, normals);
        }
      }
    });
  }
}

std::vector<float> LodHierarchy::at_control_points(const Span<float> point_values) const
{
  const int32_t n = skeleton_points_num_;
  const Span<int32_t> offsets = curve_offsets();
  std::vector<float> values(size_t(strands_num()) * size_t(n));
  parallel_for(strands_num(), 256, [&](const IndexRange range) {
    for (int64_t strand = range.start; strand < range.one_after_last(); strand++) {
      const IndexRange points = curve_points(offsets, strand);
      const auto place = [&](const int64_t i) {
        return float(point_segments_[size_t(i)]) + point_weights_[size_t(i)];
      };
      int64_t i = points.start;
      for (int32_t k = 0; k < n; k++) {
        while (i + 2 < points.one_after_last() && place(i + 1) < float(k)) {
          i++;
        }
        const float span = place(i + 1) - place(i);
        const float t = span > 0.0f ? glm::clamp((float(k) - place(i)) / span, 0.0f, 1.0f) : 0.0f;
        values[size_t(strand * n + k)] = glm::mix(point_values[i], point_values[i + 1], t);
      }
    }
  });
  return values;
}

std::vector<int32_t> LodHierarchy::level_nodes(const int32_t level) const
{
  std::vector<int32_t> result;
  std::vector<int32_t> stack;
  for (int64_t top = top_nodes_num_ - 1; top >= 0; top--) {
    stack.push_back(int32_t(top));
  }
  while (!stack.empty()) {
    const int32_t node = stack.back();
    stack.pop_back();
    if (depth_[size_t(node)] >= level || is_leaf(node)) {
      result.push_back(node);
      continue;
    }
    const IndexRange kids = children(node);
    for (int64_t child = kids.one_after_last() - 1; child >= kids.start; child--) {
      stack.push_back(int32_t(child));
    }
  }
  return result;
}

}  // namespace hairdyn
