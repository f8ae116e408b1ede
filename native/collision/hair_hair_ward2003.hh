#pragma once
/* Hair–hair collision of Ward & Lin 2003 §5.3 as a substep pass.
 *
 * Every strand segment is a line swept sphere (LSS) whose radius is the strand's thickness
 * (§5.2). The SSVs are inserted into a uniform grid whose cell edge is the mean segment length,
 * each into every cell its bounding box touches; only segments sharing a cell are tested: the
 * distance d between their cores minus their radii,
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

/* Two intersecting segments, each named by its first point (the segment runs to the next). */
struct SegmentContact {
  int32_t first = 0;  /* the smaller point index */
  int32_t second = 0;
  CoreDistance core;  /* point_a on `first`, point_b on `second` */
  float overlap = 0.0f; /* core.distance − r1 − r2 (< 0) */
};

/* Reusable buffers of the segment grid. */
struct SegmentGridScratch {
  std::vector<int32_t> point_curve;      /* per point: its strand */
  /* Per segment, together for the pair loop's memory accesses. */
  struct Segment {
    vec3 box_min, box_max; /* its LSS's bounding box (relative to the groom's lower corner) */
    ivec3 cell_min;        /* the first cell it touches */
    int32_t point;         /* its first point */
    int32_t curve;
    float radius;
  };
  std::vector<Segment> segments;
  std::vector<int64_t> entry_offsets;    /* per segment: its first grid entry */
  std::vector<ivec3> entry_cells;        /* per entry: the cell */
  std::vector<uint32_t> bucket_offsets;  /* counting sort by hashed cell */
  std::vector<int32_t> sorted_entries;   /* segment index per entry, bucket by bucket */
  std::vector<ivec3> sorted_cells;
  std::vector<float> sorted_min_x, sorted_max_x; /* per entry: its box's x range */
  std::vector<uint32_t> fill;
  std::vector<std::vector<SegmentContact>> chunk_contacts;
  /* The response's per-node sums of corrections and of their weights. */
  std::vector<vec3> dx, dv;
  std::vector<float> wx, wv;
  float cell_size = 0.0f;
  int64_t candidate_pairs_num = 0; /* pairs sharing a cell whose boxes overlap along x */
};

/* Every pair of segments whose LSSs intersect (overlap < 0), but a strand's neighbouring
 * segments, sorted by (first, second). Radii per point (a segment takes the mean of its two
 * nodes'), or empty for default_radius everywhere. With `different_strands_only`, pairs of
 * one strand are left out too. */
void find_segment_contacts(Span<int32_t> curve_offsets, Span<vec3> positions, Span<float> radii,
                           float default_radius, bool different_strands_only,
                           SegmentGridScratch &scratch, std::vector<SegmentContact> &r_contacts);

/* Segment pairs of different strands closer than the sum of their radii: the `crossings`
 * report of a frame. */
int64_t count_crossings(Span<int32_t> curve_offsets, Span<vec3> positions, Span<float> radii,
                        float default_radius);

struct HairHairStats {
  int64_t pairs_num = 0;       /* intersecting pairs found (hair_hair_pairs) */
  int64_t pushed_num = 0;      /* pairs pushed apart */
  int64_t averaged_num = 0;    /* near-parallel pairs whose velocities were averaged */
  int64_t candidates_num = 0;  /* pairs sharing a grid cell */
  double ms = 0.0;             /* time spent in apply() */
};

/* §5.3's response over the node state: positions and velocities corrected in place (roots
 * untouched). Velocities at the substep's start are taken as the state's (x − h v for the
 * previous positions). Returns the statistics of this call. */
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
