#pragma once
/* Particle initialisation of Bando 2003, §3.2: Poisson-disc samples of the (u, v, s) volume
 * between s = −s_r and the length map L(u, v), with the distance of eq. 3; root particles
 * (s < 0) inside the scalp, the others placed by Anjyo's cantilever beam. Or: samples along
 * an existing groom's strands. */
#include <functional>
#include <string>
#include <vector>

#include "core/math.hh"
#include "core/span.hh"
#include "lcp/lcp_params.hh"
#include "lcp/scalp_map_bando2003.hh"

namespace hairdyn {

/* The particles of an LCP hair volume, one array per attribute. s < 0: root particle. */
struct LcpParticles {
  std::vector<vec3> positions;
  std::vector<vec3> directions; /* Unit hair direction t. */
  std::vector<float> u, v, s;
  /* Empty, or one per particle: 1 for a particle held by the head like a root (it stands for
   * hair the groom pins, groom/pins.hh). */
  std::vector<uint8_t> fixed;

  int64_t size() const { return int64_t(positions.size()); }
};

/* The length map L(u, v) / L_max in [0, 1]: the scalp's per-vertex weights, or a grey image
 * (rows from v = 0 upward, columns from u = 0) sampled bilinearly. */
struct LengthMap {
  Span<float> image; /* image_height × image_width values, or empty to use the weights. */
  int64_t image_width = 0;
  int64_t image_height = 0;

  float sample(const ScalpPoint &point, const vec2 &uv) const;
};

/* Empty when sampling can run; otherwise a sentence (empty length map, bad image size...). */
std::string find_length_map_error(const ScalpMap &scalp, const LengthMap &length);

/* Root direction t_r of eq. 4 from the scalp normal n and the whorl normal n_w. */
vec3 root_direction(const vec3 &normal, const vec3 &whorl_normal, float w_t, float w_n);

/* Position and direction at arc length `s` of a cantilever beam of total length `length`
 * (Anjyo, Usami, Kurihara 1992) rooted at `root` along `root_dir`, bent by gravity along
 * `gravity_dir` (unit) with bending length b. */
void cantilever_beam(const vec3 &root, const vec3 &root_dir, const vec3 &gravity_dir,
                     float length, float s, float bending_length, vec3 &r_position,
                     vec3 &r_direction);

/* What sample_scalp_particles will place, known before it throws a dart: the (u, v, s)
 * volume V (m³, Monte Carlo), the Poisson-disc radius and about how many particles. */
struct ScalpSampling {
  double volume = 0.0;
  float radius = 0.0f;
  int64_t count = 0;
};
ScalpSampling plan_scalp_sampling(const ScalpMap &scalp, const LengthMap &length,
                                  const LcpParams &params);

/* The most particles an LCP simulation holds, and the most neighbour entries (particles times
 * the neighbours each has within 2 max(h₁, h₂)) its lists may hold: 8 GB for the lists'
 * indices alone. (300,000 particles on the fixtures' head with the default h₁ and h₂ have
 * about 3,400 each, 1e9 in all: they take minutes to set up, and run.) */
constexpr int64_t max_lcp_particles = 2000000;
constexpr int64_t max_lcp_neighbor_entries = 2000000000;

/* A sentence why a plan is too large to simulate, or empty: more than max_lcp_particles, or
 * h₁ and h₂ so large against the spacing that the neighbour lists would outgrow
 * max_lcp_neighbor_entries (the plan's density times the volume of a ball of radius
 * 2 max(h₁, h₂)). Refused before sampling, which would take hours there. */
std::string find_sampling_size_error(const ScalpSampling &plan, const LcpParams &params);

/* About how many candidates sample_groom_particles places along the strands (one every r/4,
 * the root's continuation beneath the scalp included), counted without placing them, and the
 * most the bindings let it place (36 bytes each: 3.6 GB). */
int64_t groom_candidates_num(Span<int32_t> curve_offsets, Span<vec3> positions,
                             const LcpParams &params);
constexpr int64_t max_groom_candidates = 100000000;

/* Poisson-disc sampling of the scalp volume (§3.2) in the scalp's space; gravity_dir is the
 * unit gravity direction in that space (world −Z for a world-space scalp). Both samplers hand
 * out their particles in space order (Morton order of cells of h₂), neighbours near each other
 * in memory. */
LcpParticles sample_scalp_particles(const ScalpMap &scalp, const LengthMap &length,
                                    const LcpParams &params, const vec3 &gravity_dir);

/* Even spacing of the rest state. §3.2 wants the particles to sample the hair volume evenly,
 * but eq. 3 measures distance on the scalp: where strands converge as they bend, or where
 * particles were put back onto the body, two samples can nearly coincide. Pushes apart every
 * pair closer than `min_distance` in Jacobi sweeps (a free particle moves by half of each
 * overlap, or all of it against a fixed one; fixed ones stay), calling `constrain` on each
 * moved particle after a sweep (e.g. back out of the body), for at most `iterations` sweeps.
 * Returns the pairs still closer than 0.99 min_distance. */
int64_t separate_close_particles(MutableSpan<vec3> positions, Span<uint8_t> is_fixed,
                                 float min_distance, int iterations,
                                 const std::function<void(vec3 &)> &constrain);

/* Particles along an existing groom (curves): (u, v) from the strand's root (root_uv, two
 * floats per strand, or empty: the roots' bounding box projected on its two widest axes),
 * s from arc length, t from the tangents; roots continue s_r beneath the first point.
 * `pinned` (one per groom point, or empty): a particle stands for the hair around it, so it is
 * fixed (LcpParticles::fixed) where the groom point nearest to it along its strand is pinned
 * (a strand's first point is its root: the root particles stand for it already). */
LcpParticles sample_groom_particles(Span<int32_t> curve_offsets, Span<vec3> positions,
                                    Span<vec2> root_uv, const LcpParams &params,
                                    Span<uint8_t> pinned = {});

}  // namespace hairdyn
