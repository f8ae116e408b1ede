#include "lcp/wind_bando2003.hh"

#include <algorithm>
#include <cmath>

#include "core/parallel.hh"
#include "core/sph_kernels.hh"

namespace hairdyn {

WindBox wind_box_around(const Span<vec3> hair_positions_wo, const vec3 &direction,
                        const float margin)
{
  WindBox box;
  const vec3 along = glm::normalize(direction);
  /* Across: horizontal when the wind is not vertical. */
  vec3 across = glm::cross(vec3(0.0f, 0.0f, 1.0f), along);
  if (glm::length(across) < 1e-3f) {
    across = glm::cross(vec3(0.0f, 1.0f, 0.0f), along);
  }
  across = glm::normalize(across);
  box.axes_wo = mat3(along, across, glm::cross(along, across));
  const mat3 to_box = glm::transpose(box.axes_wo);
  box.lo = vec3(std::numeric_limits<float>::max());
  box.hi = -box.lo;
  for (const vec3 &p : hair_positions_wo) {
    const vec3 q = to_box * p;
    box.lo = glm::min(box.lo, q);
    box.hi = glm::max(box.hi, q);
  }
  box.lo -= vec3(margin);
  box.hi += vec3(margin);
  return box;
}

static glm::ivec3 wind_box_counts(const WindBox &box, const float spacing)
{
  /* Clamped before the conversion, so that a huge box does not overflow. */
  const vec3 counts = glm::clamp((box.hi - box.lo) / spacing, vec3(1.0f), vec3(1e6f));
  return glm::ivec3(counts);
}

int64_t wind_box_count(const WindBox &box, const float spacing)
{
  const glm::ivec3 counts = wind_box_counts(box, spacing);
  return int64_t(counts.x) * int64_t(counts.y) * int64_t(counts.z);
}

void fill_wind_box(const WindBox &box, const float spacing, const WindField &wind,
                   const float time, const uint64_t seed, std::vector<vec3> &r_positions,
                   std::vector<vec3> &r_velocities)
{
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> jitter(-0.2f * spacing, 0.2f * spacing);
  r_positions.clear();
  r_velocities.clear();
  const glm::ivec3 counts = wind_box_counts(box, spacing);
  for (int z = 0; z < counts.z; z++) {
    for (int y = 0; y < counts.y; y++) {
      for (int x = 0; x < counts.x; x++) {
        const vec3 q = box.lo + (vec3(float(x), float(y), float(z)) + 0.5f) * spacing +
                       vec3(jitter(rng), jitter(rng), jitter(rng));
        r_positions.push_back(box.axes_wo * q);
        r_velocities.push_back(wind.velocity_at(r_positions.back(), time));
      }
    }
  }
}

void wrap_air_particles(const WindBox &box, const WindField &wind, const float time,
                        const MutableSpan<vec3> r_positions, const MutableSpan<vec3> r_velocities)
{
  const mat3 to_box = glm::transpose(box.axes_wo);
  const vec3 extent = box.hi - box.lo;
  parallel_for(r_positions.size(), 4096, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      vec3 q = to_box * r_positions[i];
      bool fresh = false;
      for (int a = 0; a < 3; a++) {
        if (q[a] < box.lo[a] || q[a] > box.hi[a]) {
          q[a] =
              box.lo[a] + std::fmod(std::fmod(q[a] - box.lo[a], extent[a]) + extent[a], extent[a]);
          fresh |= a == 0;
        }
      }
      r_positions[i] = box.axes_wo * q;
      if (fresh) {
        r_velocities[i] = wind.velocity_at(r_positions[i], time);
      }
    }
  });
}

void accumulate_air_pressure(const Span<vec3> positions, const float mass,
                             const float rest_density, const float sound_speed, const float h,
                             const NeighborList &neighbors, const MutableSpan<float> r_density,
                             const MutableSpan<vec3> r_forces)
{
  parallel_for(positions.size(), 1024, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      float rho = mass * sph_kernel(0.0f, h); /* Eq. 1. */
      for (const int32_t j : neighbors.neighbors_of(i)) {
        rho += mass * sph_kernel(glm::length(positions[j] - positions[i]), h);
      }
      r_density[i] = rho;
    }
  });
  const float c2 = sound_speed * sound_speed;
  parallel_for(positions.size(), 1024, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      const float p_i = std::max(0.0f, c2 * (r_density[i] - rest_density));
      vec3 force(0.0f);
      for (const int32_t j : neighbors.neighbors_of(i)) {
        const float p_j = std::max(0.0f, c2 * (r_density[j] - rest_density));
        /* SPH pressure force, the same form as eq. 16. */
        force -= mass * mass *
                 (p_i / (r_density[i] * r_density[i]) + p_j / (r_density[j] * r_density[j])) *
                 sph_kernel_gradient_i(positions[j] - positions[i], h);
      }
      r_forces[i] += force;
    }
  });
}

void accumulate_drag(const Span<vec3> target_positions, const Span<vec3> target_velocities,
                     const Span<float> target_factors, const Span<vec3> source_positions,
                     const Span<vec3> source_velocities, const Span<float> source_factors,
                     const NeighborList &target_to_sources, const float h, const float k_d,
                     const MutableSpan<vec3> r_forces, const MutableSpan<float> r_damping)
{
  parallel_for(target_positions.size(), 1024, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      vec3 force(0.0f);
      float damping = 0.0f;
      for (const int32_t j : target_to_sources.neighbors_of(i)) {
        const float coefficient =
            k_d * target_factors[i] * source_factors[j] *
            sph_kernel(glm::length(source_positions[j] - target_positions[i]), h);
        force += coefficient * (source_velocities[j] - target_velocities[i]);
        damping += coefficient;
      }
      r_forces[i] += force;
      r_damping[i] += damping;
    }
  });
}

}  // namespace hairdyn
