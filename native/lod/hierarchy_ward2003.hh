#pragma once
/* The hair hierarchy of Ward & Lin 2003, §4, precomputed once from the groom.
 *
 * One hierarchy per top-level strip (Fig. 4): a strip splits into two equal halves (a binary
 * tree, §4.1) `strip_splits` times; a finest strip turns into the clusters of the four
 * quadrants of its cross-section; a cluster splits into its four quadrants (a quad-tree,
 * §4.1) until its radius is below `cluster_min_radius`; then strand groups split the same way
 * (§4.2, Fig. 5) down to single strands or `min_group_strands`. Empty quadrants are null
 * (Fig. 5e). The cross-sections are taken at the roots, over the scalp's (u, v): the Curves
 * surface UVs when the groom has them, otherwise an azimuthal projection of the roots about
 * the scalp's mean normal. Top strips are equal-count bands of the scalp, 2^strip_splits
 * times wider than high.
 *
 * Every node has a base skeleton of the same n control points (§3, §4: "each skeleton contains
 * the same number of control points as its parent"): the mean of its strands resampled to n
 * points evenly in arc length. Each node stores its offset from its parent's skeleton, per
 * control point, in the parent's rest frames (§6.2), and every artist strand point stores
 * where it sits along a skeleton (segment and weight), so any node of the strand's path can
 * drive it (skinning in lod/skinning_ward2003.hh).
 *
 * Nodes are numbered so that the top strips come first and the children of a node are
 * consecutive; a node's strands are a consecutive range of strand_order(). */
#include <vector>

#include "core/math.hh"
#include "core/span.hh"
#include "lod/lod_params_ward2003.hh"

namespace hairdyn {

using glm::vec2;

enum class LodKind : int8_t { Strip = 0, Cluster = 1, StrandGroup = 2 };

class LodHierarchy {
 public:
  LodHierarchy() = default;
  /* `root_uvs` holds one scalp (u, v) per strand, or is empty (then a projection of the roots
   * is used). `root_normals_wo` holds one unit normal per strand, or is empty (then each
   * strand's first segment is its normal). The groom must pass find_groom_error. */
  LodHierarchy(Span<int32_t> curve_offsets, Span<vec3> rest_positions_wo, Span<vec2> root_uvs,
               Span<vec3> root_normals_wo, const LodParams &params);

  int64_t nodes_num() const { return int64_t(depth_.size()); }
  int64_t strands_num() const { return int64_t(curve_offsets_.size()) - 1; }
  /* Top strips are nodes [0, top_nodes_num()). */
  int64_t top_nodes_num() const { return top_nodes_num_; }
  /* n, the control points of every skeleton. */
  int32_t skeleton_points_num() const { return skeleton_points_num_; }
  int32_t max_depth() const { return max_depth_; }

  int32_t depth(int64_t node) const { return depth_[size_t(node)]; }
  int32_t parent(int64_t node) const { return parent_[size_t(node)]; }
  LodKind kind(int64_t node) const { return kind_[size_t(node)]; }
  IndexRange children(int64_t node) const
  {
    return {children_start_[size_t(node)], children_num_[size_t(node)]};
  }
  bool is_leaf(int64_t node) const { return children_num_[size_t(node)] == 0; }
  /* The top strip whose tree holds `node`. */
  int32_t top_node(int64_t node) const { return top_[size_t(node)]; }
  /* The strands a node covers. */
  Span<int32_t> strands(int64_t node) const
  {
    return Span<int32_t>(strand_order_.data() + strands_start_[size_t(node)],
                         strands_num_[size_t(node)]);
  }
  /* m, the largest distance of a covered strand's resampled points from the skeleton's. */
  float radius(int64_t node) const { return radius_[size_t(node)]; }
  /* Per control point of a node's rest skeleton, how far its strands spread around it (§5.2:
   * the group's swept-sphere volume): `spread`, in m, the root mean square distance of its
   * strands' resampled points from the control point (for a strip, across its plane only);
   * and for a strip, `half_width`, half its width: the principal axis of those points in the
   * plane normal to the skeleton, √3 times their root mean square along it (a band's half
   * width); zero for clusters and strand groups. */
  Span<float> spread(int64_t node) const;
  Span<vec3> half_width(int64_t node) const;
  /* The n control points of a node's rest skeleton, and their rest frames (columns tangent,
   * bitangent, normal; frame 0 is the root frame, frame i > 0 the frame of the segment that
   * ends at point i, transported without twist). */
  Span<vec3> rest_skeleton(int64_t node) const;
  Span<mat3> rest_frames(int64_t node) const;
  /* The node's offset from its parent's skeleton, per control point, in the parent's rest
   * frames (§6.2); zeros for a top strip. */
  Span<vec3> offsets(int64_t node) const;
  /* The unit root normal of the node's skeleton (mean of its strands'). */
  vec3 root_normal(int64_t node) const { return root_normals_[size_t(node)]; }

  /* The groom, and per strand point the skeleton segment it lies on (the segment from control
   * point `point_segment` to the next) and its weight along it. */
  Span<int32_t> curve_offsets() const { return curve_offsets_; }
  Span<vec3> rest_positions() const { return rest_positions_wo_; }
  Span<int32_t> point_segments() const { return point_segments_; }
  Span<float> point_weights() const { return point_weights_; }

  /* A value per strand point (N, the groom's points) at each strand's n control points:
   * strand s's value at k is interpolated linearly between the two of its points whose places
   * along a skeleton (point_segments + point_weights: 0 at the root, n − 1 at the tip) bracket
   * k. strands_num() × n values, strand by strand. */
  std::vector<float> at_control_points(Span<float> point_values) const;

  /* Nodes of level `level`: those at that depth plus the leaves above it. Every level covers
   * each strand exactly once. */
  std::vector<int32_t> level_nodes(int32_t level) const;

 private:
  struct Range {
    int32_t start, size;
  };
  void split(int32_t node, int32_t strip_depth, Span<vec2> uvs, Span<vec3> roots,
             const LodParams &params);
  int32_t add_node(int32_t parent, LodKind kind, Range strands);
  void finish_node(int32_t node, Span<vec3> resampled, Span<vec3> root_normals);

  std::vector<int32_t> curve_offsets_;
  std::vector<vec3> rest_positions_wo_;
  std::vector<int32_t> point_segments_;
  std::vector<float> point_weights_;

  int32_t skeleton_points_num_ = 0;
  int32_t max_depth_ = 0;
  int64_t top_nodes_num_ = 0;
  std::vector<int32_t> strand_order_;

  /* Per node. */
  std::vector<int32_t> depth_, parent_, top_, children_start_, children_num_;
  std::vector<int32_t> strands_start_, strands_num_;
  std::vector<LodKind> kind_;
  std::vector<float> radius_;
  std::vector<vec3> root_normals_;
  /* Per node and control point. */
  std::vector<vec3> rest_skeletons_;
  std::vector<mat3> rest_frames_;
  std::vector<vec3> offsets_;
  std::vector<float> spread_;
  std::vector<vec3> half_width_;
};

/* Per strand, n points evenly spaced in arc length along it (r_resampled holds n per strand),
 * and per strand point the segment of such an n-point curve it lies on and its weight. */
void resample_strands(Span<int32_t> curve_offsets, Span<vec3> positions, int32_t points_num,
                      MutableSpan<vec3> r_resampled, MutableSpan<int32_t> r_point_segments,
                      MutableSpan<float> r_point_weights);

/* The scalp (u, v) of each strand's root when the groom gives none: the azimuthal equidistant
 * projection about the roots' mean normal, in meters. */
void project_roots(Span<vec3> roots, Span<vec3> root_normals, MutableSpan<vec2> r_uvs);

/* Frames along a skeleton of n points: r_frames[0] = root_frame, r_frames[i] the frame of the
 * segment ending at point i, transported without twist (groom/frames.hh). */
void skeleton_frames(Span<vec3> skeleton, const mat3 &root_frame, MutableSpan<mat3> r_frames);

}  // namespace hairdyn
