#pragma once
/* Hair–hair collision of Ward & Lin 2003 §5.3 as a substep pass.
 *
 * Every strand segment is a line swept sphere (LSS) whose radius is the strand's thickness
 * (§5.2); under level of detail a cluster's or strand group's segment is an LSS as thick as
 * the group, and a strip's a rectangle swept sphere (RSS) as wide as the strip
 * (SubstepState::strip_half_widths_hs), tested exactly (segment–rectangle,
 * rectangle–rectangle) at the end of the substep. The SSVs are inserted into a uniform grid (§5.3; here its cells are columns along
 * the axis of the thinnest boxes, as wide as the largest box across them, up to twice the mean
 * segment length), each once, in the column of its box's lower corner, sorted along the
 * column; only segments in the same or neighbouring columns whose boxes overlap are tested
 * (sweep and prune along the columns, each pair once): the distance d between their cores minus
 * their radii,
 *
 *   overlap = d − (r1 + r2),                                   (§5.3)
 *
 * and a pair intersects when it is negative. Nearly parallel intersecting segments (the angle
 * between them, from |s1 × s2|, below near_parallel_angle) get the average of their
 * velocities; the others are pushed apart by half the overlap each, in opposite directions
 * along the vector between their closest points.
 *
 * Beyond the paper: a pair that crossed during the substep (the closest-point vector turned
 * around since the substep's start, x − h v) is pushed back to the side it came from, by the
 * whole crossing plus the radii; the approaching normal velocity of a pushed pair is removed
 * (inelastic, like the push), so that the next substep does not undo it. A strand's segment is
 * not tested against its neighbours (they share a node). Each node's corrections are averaged
 * over its contacts, summed in the fixed order of the pairs: the result does not depend on
 * the thread count. */
#include <vector>

#include "collision/ssv_ward2003.hh"
#include "core/math.hh"
#include "core/span.hh"
#include "strands/substep_pass.hh"

namespace hairdyn {

/* Two segments in contact, each named by its first point (the segment runs to the next), and
 * the response §5.3 gives them (applied by resolve_hair_hair, averaged per node). */
struct SegmentContact {
  int32_t first = 0;  /* the smaller point index */
  int32_t second = 0;
  CoreDistance core;    /* at the end of the substep: point_a on `first`, point_b on `second` */
  float overlap = 0.0f; /* core.distance − r1 − r2 (< 0); for a pair that passed through each
                         * other during the substep, minus the distance they must move apart */
  bool crossed = false; /* they passed through each other during the substep */
  bool parallel = false; /* near parallel: velocities averaged, not pushed */
  vec3 move{0.0f};      /* `second`'s closest point moves by this, `first`'s by minus it */
  vec3 dv_first{0.0f}, dv_second{0.0f}; /* the closest points' velocity changes */
};

/* Reusable buffers of the segment grid (no allocation once they have grown). */
struct SegmentGridScratch {
  std::vector<int32_t> point_curve; /* per point: its strand */
  /* Per segment (segment k of strand c starts at point k + c). */
  std::vector<int32_t> segment_curve;
  /* m, the farthest one of its nodes moved in the substep, less the nodes' mean move (the
   * frame its box is swept in: build_grid) */
  std::vector<float> segment_sweep;
  std::vector<vec3> box_min, box_max; /* its swept LSS's bounding box, start and end (in `axes`) */
  std::vector<uint32_t> segment_cell; /* the column of its box's lower corner (linear index) */
  /* The grid: one entry per segment but the big ones, column by column (in linear order),
   * within a column by the lower end of the box along it (ties by segment). Boxes and cells in
   * the axes `axes` (x: the sweep axis along the columns, y and z across them). */
  std::vector<float> lo_x, hi_x; /* its box along the sweep axis */
  /* And across it, the upper ends negated (every test one ≤), each array apart so that four
   * entries load at once, or eight with AVX2 (all five padded by seven at the end). */
  std::vector<float> lo_y, lo_z, neg_hi_y, neg_hi_z;
  struct Segment {
    vec4 origin;       /* its first node at the end of the substep, and its LSS radius */
    vec4 tip;          /* its second node there, and its length² */
    vec4 start_origin; /* its first node at the substep's start */
    vec4 start_tip;    /* its second node there */
  };
  std::vector<Segment> entry_segments; /* its copy (in the original axes) */
  std::vector<int32_t> entry_point;    /* its first point */
  std::vector<int32_t> entry_curve;    /* its strand */
  std::vector<float> entry_sweep;      /* its segment_sweep */
  std::vector<int32_t> entry_segment;  /* its segment */
  std::vector<uint8_t> entry_strip;    /* it is a strip's (with half widths; else empty) */
  /* resolve_hair_hair: per point, the strips' half widths and the rest positions turned with
   * the head (GroupVolumes). */
  std::vector<vec3> half_widths_wo, rest_positions_wo;
  std::vector<uint32_t> cell_offsets;  /* per column: its first entry */
  std::vector<uint32_t> fill;          /* counting sort: per column, the next entry */
  std::vector<int32_t> big_segments;   /* segments whose box is wider than a column */
  std::vector<float> sort_scratch;
  std::vector<uint64_t> column_keys; /* build_grid's sort of each column */
  std::vector<std::vector<SegmentContact>> chunk_contacts;
  /* Sorting the contacts: per bucket of first points and chunk, the first contact; per contact
   * its pair (first << 32 | second) and where it is. */
  std::vector<uint32_t> contact_offsets;
  struct ContactKey {
    uint64_t pair;
    uint32_t chunk, index;
  };
  std::vector<ContactKey> contact_keys;
  std::vector<uint8_t> keep;             /* per contact: still in contact when re-tested */
  std::vector<SegmentContact> retested;  /* per contact: re-tested */
  /* The response's per-node sums of corrections and of their weights. */
  std::vector<vec4> dx, dv; /* xyz: the sum, w: the weight */
  vec3 cell_size{0.0f}; /* across the columns (along the sweep axis: 0) */
  ivec3 dims{0};
  ivec3 axes{0, 1, 2}; /* the boxes' (and the grid's) axes: the sweep axis first */
  vec3 grid_lo{0.0f};
  glm::dvec3 inv_cell{0.0};
  int64_t candidate_pairs_num = 0; /* pairs whose boxes overlap, tested */
};

/* What the segments of level-of-detail skeletons stand for (SubstepState), per point, in one
 * frame turned with the head: a strip's half width (empty, or zero: not a strip), and where
 * the point lies at rest (empty: no rest allowance). Two segments closer at rest than their
 * radii (the groups of a dense groom overlap where their strands interleave) may stay as
 * close as they were at rest: the pass keeps groups from moving into each other, it does not
 * pull the groom apart. */
struct GroupVolumes {
  Span<vec3> half_widths;
  Span<vec3> rest_positions;
};

/* Every pair of segments whose LSSs intersect at `positions` (overlap < 0), but a strand's
 * neighbouring segments, in the order of their first, then second points (so independent of
 * the thread count and of the grid). Radii per point (a segment takes the mean of its two
 * nodes'), or empty for default_radius everywhere.
 * With `different_strands_only`, pairs of one strand are left out too. With
 * `start_positions` (the nodes at the substep's start), also the pairs that passed through
 * each other on the way (continuous detection: each segment sweeps linearly from its start;
 * without them but with `params`, from x − h v).
 * The contacts carry §5.3's response computed from `velocities` (may be empty when `params`
 * is null; then no response is computed). With `groups`, a segment whose nodes have a
 * non-zero half width is a strip's, a rectangle swept sphere (§5.2). */
void find_segment_contacts(Span<int32_t> curve_offsets, Span<vec3> positions, Span<float> radii,
                           float default_radius, bool different_strands_only,
                           SegmentGridScratch &scratch, std::vector<SegmentContact> &r_contacts,
                           Span<vec3> start_positions = {}, Span<vec3> velocities = {},
                           const SweptSphereParams *params = nullptr, float h = 0.0f,
                           const GroupVolumes &groups = {});

/* Segment pairs of different strands closer than the sum of their radii: the `crossings`
 * report of a frame. */
int64_t count_crossings(Span<int32_t> curve_offsets, Span<vec3> positions, Span<float> radii,
                        float default_radius);

struct HairHairStats {
  int64_t pairs_num = 0;       /* intersecting pairs found (hair_hair_pairs) */
  int64_t pushed_num = 0;      /* pairs pushed apart */
  int64_t averaged_num = 0;    /* near-parallel pairs whose velocities were averaged */
  int64_t crossed_num = 0;     /* pairs that had passed through each other in the substep */
  int64_t candidates_num = 0;  /* pairs sharing a grid cell */
  double ms = 0.0;             /* time spent in apply() */
};

/* §5.3's response over the node state: positions and velocities corrected in place (roots
 * untouched). The state's start_positions_wo, when given, let it catch segments that passed
 * through each other within the substep; without them the previous positions are taken as
 * x − h v. Returns the statistics of this call. */
HairHairStats resolve_hair_hair(const SweptSphereParams &params, const SubstepState &state,
                                SegmentGridScratch &scratch,
                                std::vector<SegmentContact> &contacts_scratch);

class HairHairPass : public SubstepPass {
 public:
  explicit HairHairPass(const SweptSphereParams &params = {}) : params_(params) {}
  const char *name() const override { return "hair_hair"; }
  void apply(const SubstepState &state) override;

  const SweptSphereParams &params() const { return params_; }
  void set_params(const SweptSphereParams &params) { params_ = params; }
  /* Summed over the calls since the last reset_stats() (a frame's substeps, say). */
  const HairHairStats &stats() const { return stats_; }
  void reset_stats() { stats_ = {}; }

 private:
  SweptSphereParams params_;
  SegmentGridScratch scratch_;
  std::vector<SegmentContact> contacts_;
  HairHairStats stats_;
};

}  // namespace hairdyn
