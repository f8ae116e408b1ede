#pragma once
/* LCP's motion on real strands (Bando 2003, §4): every strand point moves with the particles
 * near its (u, v, s), in the distance of eq. 3 (scalp points apart, and arc length). A strand
 * point's scalp point is its root and s its arc length; a particle's scalp point is where its
 * hair leaves the scalp: x − s t for the fixed root particles, and for the others the
 * inverse-distance blend of those of the 3 root particles nearest in (u, v). In the head's
 * frame, a point is displaced by the inverse-distance blend of the displacements since rest of
 * its `neighbours_num` nearest particles, so the groom keeps its shape at rest, takes the
 * particles' motion, and the head's own motion is carried exactly. With `shape_from_particles`
 * a point is carried to the blend of its particles' positions instead (each taken along its
 * direction to the point's arc length), so that the strands lie in the volume the billboards
 * of §4 show, in its shape, with their own lengths. That is for
 * particles that do not come from the groom (sampled over the scalp in the cantilever shape of
 * §3.2): their rest shape is not the groom's, and carried by their displacements alone the
 * strands would keep the groom's shape outside the volume. Roots follow the head rigidly;
 * then, root to tip, each point is put at its rest distance from the previous one
 * toward where it was carried, or toward the body's surface (up to twice) when that is inside
 * a collider, so strands never stretch nor go through the body. Pinned points (set_pinned,
 * groom/pins.hh) are carried rigidly by the head like the roots: the chain before each one
 * reaches it with its lengths kept, and the points after it go on from it.
 *
 * Nearest neighbours come from the spatial grid (core/spatial_grid.hh): exact k nearest, the
 * search radius doubled for the points whose k nearest are not yet certain. */
#include <vector>

#include "collision/collider.hh"
#include "core/math.hh"
#include "core/span.hh"

namespace hairdyn {

class ParticleSkin {
 public:
  /* The groom (offsets, world positions) and the particles (world positions, directions,
   * u, v, s; s < 0 the roots) at rest, with the head at `head_to_world` (any affine matrix:
   * points go to the head's space by its inverse). */
  ParticleSkin(Span<int32_t> curve_offsets, Span<vec3> points_wo, Span<vec3> particles_wo,
               Span<vec3> directions_wo, Span<float> u, Span<float> v, Span<float> s,
               const mat4 &head_to_world, int neighbours_num = 4,
               bool shape_from_particles = false);

  /* The strand points for the particles at `particles_wo` and the head at `head_to_world`;
   * `colliders` (or nullptr) keeps the points out of the body. With shape_from_particles the
   * particles' directions now are needed too. */
  void apply(Span<vec3> particles_wo, const mat4 &head_to_world, const ColliderSet *colliders,
             MutableSpan<vec3> r_points_wo, Span<vec3> directions_wo = {});
  bool shape_from_particles() const { return shape_from_particles_; }
  /* Per groom point, non-zero where it is pinned (roots are whatever the mask says); empty:
   * only the roots. */
  void set_pinned(Span<uint8_t> pinned);

  int64_t points_num() const { return int64_t(rest_head_.size()); }
  int64_t particles_num() const { return int64_t(particles_rest_head_.size()); }
  int neighbours_num() const { return neighbours_num_; }
  /* Point i's particles and weights: neighbours_num() entries from i * neighbours_num(). */
  Span<int32_t> neighbours() const { return neighbours_; }
  Span<double> weights() const { return weights_; }

 private:
  std::vector<int32_t> curve_offsets_;
  std::vector<double> rest_lengths_; /* Of the segment ending at each point (0 at roots). */
  std::vector<glm::dvec3> rest_head_, particles_rest_head_;
  bool shape_from_particles_ = false;
  /* With shape_from_particles: each point's arc length and each particle's s. */
  std::vector<double> arc_;
  std::vector<float> particle_s_;
  /* Where point i is carried (world space), before its length is put back. */
  glm::dvec3 carried(int64_t i, Span<vec3> particles_wo, Span<vec3> directions_wo,
                     const glm::dmat4 &to_world) const;
  int neighbours_num_ = 4;
  std::vector<int32_t> neighbours_;
  std::vector<double> weights_;
  std::vector<glm::dvec3> moved_; /* apply()'s particle displacements (head's space). */
  std::vector<uint8_t> pinned_;   /* per point after the roots, or empty */
};

/* The k nearest of `points` (with a fourth coordinate `points_w`) to each query (with
 * `queries_w`), in the 4D distance: r_indices and r_distances, k per query, nearest first
 * (ties by index). k is capped at the point count. Exact; deterministic on any thread count. */
void find_k_nearest(Span<vec3> points, Span<float> points_w, Span<vec3> queries,
                    Span<float> queries_w, int k, std::vector<int32_t> &r_indices,
                    std::vector<float> &r_distances);

}  // namespace hairdyn
