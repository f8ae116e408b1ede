#pragma once
/* Level-of-detail strand dynamics of Ward & Lin 2003 (§4, §6): the groom's hierarchy of
 * strips, clusters and strand groups (lod/hierarchy_ward2003.hh), a cut through it chosen
 * every frame by visibility, distance and velocity (§6.1), split (§6.2) and merged (§6.3) one
 * level per frame, and every artist strand placed on the skeleton that drives it.
 *
 * Dynamics. One StrandSolver holds every node's skeleton (curve i is node i), and each frame
 * steps only the skeletons of the current cut (the active ones)
 * and, on the frame of a switch, the ones that drove strands at the last frame (so the jump
 * between the old and the new skeleton's placement is measured at the same instant):
 * StrandSolver::set_stepped. The cost of a frame is that of the active skeletons (Ward's
 * Tables 1-2), not of the whole hierarchy. An inactive skeleton is held: its angles and rates
 * stay as they were and nothing integrates them; no output reads it. At a split the children
 * take the parent's dynamic state (§6.2), at a merge the parent takes the average of its
 * children's (§6.3): the angles are offsets from each skeleton's own rest shape, measured in
 * charts that every skeleton of a tree orients from the same root normal, so a child
 * inheriting its parent's angles turns as its parent did and keeps its stored offset from
 * it. The angles and rates are the whole of a skeleton's dynamic state; what a held skeleton
 * lacks is where the head has gone meanwhile, so a skeleton that takes a state is placed
 * (StrandSolver::set_curve_state) with the head where the last step left it: its root and
 * frames carried by the head, its nodes at the taken angles, its velocities from the taken
 * rates. Its first step then starts from that state whatever it did before it was held. (A
 * skeleton stepped by the last step that takes back its own state bit for bit keeps its
 * nodes, so a split undone at once changes nothing.)
 *
 * Output. Every strand follows the skeleton that drives it with its rest offset
 * (lod/skinning_ward2003.hh), so the output keeps the groom's topology. At a switch, the jump
 * between the old and the new skeleton's placement is kept as a residual that a spring pulls
 * to zero with time constant transition_time (§6.3: "a spring force is used to subtly pull
 * the children into place"). */
#include <memory>
#include <string>
#include <vector>

#include "collision/collider.hh"
#include "core/math.hh"
#include "core/span.hh"
#include "lod/hierarchy_ward2003.hh"
#include "lod/lod_params_ward2003.hh"
#include "lod/selection_ward2003.hh"
#include "core/head_motion.hh"
#include "core/wind.hh"
#include "strands/strand_solver.hh"
#include "strands/strand_params.hh"

namespace hairdyn {

class LodSolver {
 public:
  /* `root_uvs`: one scalp (u, v) per strand or empty; `root_normals_wo`: one unit normal per
   * strand or empty (see LodHierarchy). `head_to_world_rest` is the head's transform when the
   * groom had `rest_positions_wo`. The groom must pass find_groom_error, the parameters
   * find_lod_params_error. */
  LodSolver(Span<int32_t> curve_offsets, Span<vec3> rest_positions_wo, Span<vec2> root_uvs,
            Span<vec3> root_normals_wo, const mat4 &head_to_world_rest,
            const StrandParams &strand_params, const WindParams &wind,
            const LodParams &lod_params);

  /* Hair-object collision of every skeleton (see StrandSolver::set_colliders), the bodies
   * that occlude hair (§6.1), and the bodies the placed strands stay out of (set_bodies).
   * nullptr: none of them. */
  void set_colliders(const ColliderSet *colliders, const CollisionParams &params);
  /* Only the bodies the placed strands stay out of, as deep as at rest at most (by their
   * collision maps, after each placement), when the skeletons collide by a pass instead; the
   * bodies where they are now are the groom's rest pose. nullptr: none. */
  void set_bodies(const ColliderSet *bodies);
  /* Only the bodies that occlude hair (when the skeletons collide by a pass instead); they
   * also give the passes' rest clearances. */
  void set_occluders(const ColliderSet *occluders)
  {
    colliders_ = occluders;
    occluders_.clear();
    if (!solver_->passes().is_empty()) {
      update_pass_volumes();
    }
  }
  /* Runs `pass` after every substep over the active skeletons (not over one kept a frame
   * longer to measure a switch: it would meet the skeleton that replaced it), each seen as
   * its group's swept-sphere volume (Ward & Lin 2003 §5.2): a strip segment a rectangle swept
   * sphere as wide as the strip, a cluster or strand group segment a line swept sphere; the
   * radius `strand_radius` (m, a single strand's) plus the group's spread
   * (LodHierarchy::spread). Groups closer at rest than that (their strands interleave) may
   * stay as close as at rest (GroupVolumes), and as near the colliders as at rest
   * (SubstepState::rest_clearances). The pass must outlive the solver. */
  void add_pass(SubstepPass *pass, float strand_radius);
  /* The strands' own radius per point (m, one per point of the groom: a Curves radius
   * attribute) in place of add_pass's strand_radius: at each control point a group's swept
   * sphere is its widest strand's radius there (each strand's radii interpolated along it to
   * the control point, where its points lie along the skeleton) plus the group's spread.
   * Empty: add_pass's strand_radius everywhere. */
  void set_radii(Span<float> point_radii);
  /* Milliseconds the pass named `name` took during the last step. */
  double pass_ms(const std::string &name) const { return solver_->pass_ms(name); }
  /* One frame: select and switch (§6.1-6.3) from the state at the end of the last frame and
   * this frame's camera, step every level, place the strands. Levels change by one per frame
   * except for occlusion, and on the first frame after a reset, which starts at the levels
   * the camera asks for. */
  void step(float frame_dt, const mat4 &head_to_world, const mat4 &view_projection);
  /* The rest shape carried by the head, at rest, at the coarsest level (the finest when the
   * level of detail is off). */
  void reset(const mat4 &head_to_world);

  const LodHierarchy &hierarchy() const { return hierarchy_; }
  const LodParams &lod_params() const { return lod_params_; }
  int32_t coarsest_level() const { return coarsest_; }
  int32_t finest_level() const { return finest_; }

  /* The output, in the groom's layout: world positions and, per point, the level (depth) of
   * the skeleton that drives its strand. */
  Span<vec3> positions() const { return positions_wo_; }
  Span<int32_t> point_levels() const { return point_levels_; }
  /* Per strand, the node that drives it; per node, 1 while it is active. */
  Span<int32_t> strand_nodes() const { return strand_nodes_; }
  Span<uint8_t> active() const { return active_; }
  /* Active skeletons per level (depth 0 .. max_depth). */
  std::vector<int64_t> active_per_level() const;
  int64_t active_num() const;
  /* Splits, merges and occlusion collapses made by the last step. */
  int64_t splits_num() const { return splits_num_; }
  int64_t merges_num() const { return merges_num_; }
  int64_t collapses_num() const { return collapses_num_; }
  /* Per node: visible and wanted level as the last selection saw them (active nodes only). */
  Span<uint8_t> visible() const { return visible_; }
  Span<int32_t> wanted_levels() const { return wanted_; }

  /* A node's current skeleton and frames: where the last step, or a split or merge since,
   * put it; for a node that is neither active nor was stepped by the last step, where it was
   * when it was last stepped or placed (frames: last stepped). */
  Span<vec3> skeleton(int64_t node) const;
  Span<mat3> frames(int64_t node) const;
  /* A node's segment angles and rates (points 1 .. n-1 of its curve; slot 0 is the root). */
  Span<vec2> angles(int64_t node) const;
  Span<vec2> angular_velocities(int64_t node) const;

  /* The strips as ribbons (Ward & Lin 2003 §3: a strip is a flat surface along its skeleton),
   * for display: every strip node of the hierarchy (strip_nodes(), in node order), per
   * control point k two vertices, 2k the skeleton point less its half width and 2k + 1 plus
   * it, the half width turned from the rest frames into the skeleton's current ones (the
   * strip's plane bends and twists with it). A strip that is not active lies at the root of
   * its first strand, all its vertices there: a ribbon of no area, nothing shows. */
  Span<int32_t> strip_nodes() const { return strip_nodes_; }
  void strip_ribbons(MutableSpan<vec3> r_vertices_wo) const;

  /* Skeletons the last step advanced (the active ones, plus those of the last frame that a
   * switch made inactive), and per level. */
  int64_t stepped_num() const { return solver_->stepped_num(); }
  std::vector<int64_t> stepped_per_level() const;
  /* Skeleton nodes inside a collider during the last step (the reaction constraint, Kurihara
   * 1993 eq. 12–15), over every substep: StrandSolver::contacts_num. */
  int64_t contacts_num() const { return solver_->contacts_num(); }

  /* The transitions step() makes, for tests: split an active node into its children (§6.2);
   * merge the active children of `parent` into it (§6.3). The output is updated at the next
   * step. */
  void split(int32_t node);
  void merge(int32_t parent);
  /* m, the largest distance of a child's control point from where the merged parent would put
   * it (§6.3's positional test). */
  float merge_deviation(int32_t parent) const;

 private:
  /* Makes `node` active with the strand-weighted average state of `sources` (§6.3), which
   * become inactive. */
  void absorb(int32_t node, Span<int32_t> sources);
  void select(const LodCamera &camera);
  void update_frames();
  void place_strands(float frame_dt);
  /* Gives the placed `strands` (a range) their segment lengths back, root to tip, moving
   * each point that lies deeper inside bodies_ (if any) than at rest back out on the way. */
  void keep_lengths(IndexRange strands);
  /* find_contacts of `points` against bodies_: depths into r_depths, the rest into the
   * contact_ buffers. */
  void find_body_contacts(Span<vec3> points, MutableSpan<float> r_depths);
  void set_active(int32_t node, bool active);
  /* `node` takes the dynamic state (angles, rates; slot 0 ignored) and is placed with the
   * head where the last step left it; a node whose nodes are current and whose state this
   * leaves unchanged bit for bit is left alone. */
  void take_state(int32_t node, Span<vec2> angles, Span<vec2> rates);
  /* The volumes the passes see (add_pass), from node_radii_ (else strand_radius_) and the
   * colliders. */
  void update_pass_volumes();

  LodHierarchy hierarchy_;
  LodParams lod_params_;
  int32_t coarsest_ = 0, finest_ = 0;
  HeadPose rest_pose_;
  mat3 head_rotation_{1.0f}; /* since rest, at the end of the last step */
  const ColliderSet *colliders_ = nullptr;
  const ColliderSet *bodies_ = nullptr; /* set_bodies' */
  float strand_radius_ = 0.0f; /* m, add_pass's */
  std::vector<float> node_radii_; /* m, per node and control point: set_radii's, or empty */

  std::unique_ptr<StrandSolver> solver_;
  /* Per node: stepped by the next step. */
  std::vector<uint8_t> stepped_;

  /* Per node. shown_: active at the end of the last step (drove strands at the last
   * placement); current_: its solver nodes agree with its state and the head's last pose
   * (stepped by the last step, or placed since). */
  std::vector<uint8_t> active_, visible_, shown_, current_;
  std::vector<int32_t> wanted_;
  std::vector<int32_t> strip_nodes_; /* the nodes of kind Strip, in node order */
  /* Per node, select()'s memory of the last frame (the same answers, found sooner): per
   * sampled control point the triangle that hid it (hidden_by_colliders' r_occluder), and
   * the sample that showed the node (tested first). */
  static constexpr int occlusion_samples = 4;
  std::vector<int64_t> occluders_;
  std::vector<uint8_t> seen_sample_;
  /* Per node and control point: current frames. */
  std::vector<mat3> frames_;

  /* Per strand: driving node now and at the last placement. */
  std::vector<int32_t> strand_nodes_, placed_nodes_;
  /* Per point. */
  std::vector<vec3> positions_wo_;
  std::vector<vec3> residuals_wo_;
  /* Per point, its strand's strand_offsets on the node offset_nodes_ names (per strand; −1:
   * none yet). */
  std::vector<vec3> offsets_;
  std::vector<int32_t> offset_nodes_;
  std::vector<float> rest_lengths_; /* m, from the previous point at rest (0 at roots) */
  std::vector<int32_t> point_levels_;
  /* find_body_contacts' contacts. */
  std::vector<uint8_t> contact_hit_;
  /* m, per point: how deep inside bodies_ it lies at rest (the groom near the scalp lies
   * within the collision maps' surface: it may stay as deep as that). */
  std::vector<float> rest_depths_;
  std::vector<vec3> contact_normal_, contact_surface_;

  int64_t splits_num_ = 0, merges_num_ = 0, collapses_num_ = 0;
  /* True until the first step after a reset. */
  bool starting_ = true;
};

/* Mean distance between two point sets of equal size (the report's lod_error against a fine
 * simulation of the same frames). */
double mean_distance(Span<vec3> a, Span<vec3> b);

}  // namespace hairdyn
