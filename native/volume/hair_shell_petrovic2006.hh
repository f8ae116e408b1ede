#pragma once
/* Illumination normals from the hair volume (Petrovic, Henne and Anderson 2006, §4.1).
 *
 * The hair shell is the iso-surface of the density (eq. 1) at a threshold. Its signed distance
 * field S solves |∇S| = 1 with S = 0 on the shell, negative inside the hair; it is computed by
 * fast sweeping of closest points (Tsai 2002, "Rapid and accurate computation of the distance
 * function using grids"): the vertices next to the shell find their nearest shell point by a
 * Newton step on the density, sweeps in the 8 alternating grid orderings hand the nearest
 * point on to the rest, and each vertex refines the point it received onto the shell (tangent
 * plane, then Newton steps on the trilinear density); S = ±|x − closest point| is a distance
 * function, |∇S| = 1. The shading normal is
 *
 *   N = ∇S                                                                  (eq. 2)
 *
 * normalised, at every point of the rest groom. The normals are computed once, at rest, and
 * carried to every frame in frames that follow each strand: the root's frame is fixed to the
 * head, and parallel transport (Bishop 1975) carries it from segment to segment (§4.1, last
 * paragraph). A point's frame is that of its outgoing segment (the tip: its incoming one); the
 * rest normal's coordinates in it are kept, and re-expressed in the moving frame. */
#include <vector>

#include "core/math.hh"
#include "core/span.hh"
#include "volume/density_grid_petrovic2006.hh"
#include "volume/volume_params.hh"

namespace hairdyn {

/* S on a grid of `size` vertices and spacing h (m): the signed distance to the iso-surface
 * density = threshold, negative where the density exceeds the threshold. Vertices farther than
 * the sweeps reach (none, on a connected grid) keep the largest float. */
void signed_distance_fast_sweeping(const ivec3 &size, float cell_size, Span<float> density,
                                   float threshold, MutableSpan<float> r_distance);

/* eq. 2 at each point: the unit gradient of S (central differences at the vertices,
 * interpolated with the tent weights), in world space. Where the gradient vanishes (a point
 * on the shell's medial axis) or the point is off the grid, the direction from `center_wo`. */
void shell_normals_at(const GridFrame &grid, Span<float> distance, Span<vec3> positions_wo,
                      const vec3 &center_wo, MutableSpan<vec3> r_normals_wo);

/* Per point, the frame (columns x, y, z; z along the point's segment) obtained by carrying each
 * strand's root frame by parallel transport from segment to segment. */
void transport_frames(Span<int32_t> curve_offsets, Span<vec3> positions_wo,
                      Span<mat3> root_frames_wo, MutableSpan<mat3> r_frames_wo);

/* The hair shell of a rest groom and its normals, carried along the strands as they move. */
class HairShell {
 public:
  /* The groom must pass find_groom_error. `head_to_world_rest` is the head when the groom had
   * `rest_positions_wo`. */
  HairShell(Span<int32_t> curve_offsets, Span<vec3> rest_positions_wo,
            const mat4 &head_to_world_rest, const VolumeParams &params);

  const GridFrame &grid() const { return grid_; }
  Span<float> density() const { return density_; }
  Span<float> signed_distance() const { return distance_; }
  /* eq. 2 at the rest points, world space at the rest head. */
  Span<vec3> rest_normals() const { return rest_normals_; }

  /* The rest normals carried to `positions_wo` (same strands) with the head at
   * `head_to_world`. */
  void transport(Span<vec3> positions_wo, const mat4 &head_to_world,
                 MutableSpan<vec3> r_normals_wo) const;

 private:
  std::vector<int32_t> curve_offsets_;
  GridFrame grid_;
  std::vector<float> density_;
  std::vector<float> distance_;
  std::vector<vec3> rest_normals_;
  std::vector<mat3> root_frames_head_; /* per strand, fixed to the head */
  std::vector<vec3> local_normals_;    /* per point, in its transported rest frame */
};

}  // namespace hairdyn
