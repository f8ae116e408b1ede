#include "core/wind.hh"

#include <algorithm>
#include <cmath>

#include "core/random.hh"

namespace hairdyn {

WindField::WindField(const WindParams &params)
{
  const float direction_length = glm::length(params.direction);
  if (direction_length < 1e-6f || params.speed <= 0.0f) {
    return; /* No wind. */
  }
  const vec3 direction = params.direction / direction_length;
  mean_ = params.speed * direction;
  turbulence_ = params.turbulence * params.speed;
  /* Frozen turbulence: each wave travels with the mean wind (wave number f / U along the
   * wind) and varies across it on a similar scale, so neighbouring strands sway together and
   * distant ones independently. Frequencies spread over [0.6, 1.4] of the nominal one. */
  RandomNumberGenerator rng(uint64_t(params.seed) * 0x2545f4914f6cdd1dull + 1);
  const float speed = std::max(params.speed, 0.1f);
  for (int component = 0; component < 3; component++) {
    for (int wave = 0; wave < waves_num; wave++) {
      const float omega = 2.0f * float(M_PI) * params.frequency * rng.next_float(0.6f, 1.4f);
      const vec3 across(rng.next_float(-1.0f, 1.0f), rng.next_float(-1.0f, 1.0f),
                        rng.next_float(-1.0f, 1.0f));
      angular_frequencies_[component][wave] = omega;
      wave_vectors_[component][wave] = (omega / speed) * (direction + 0.5f * across);
      phases_[component][wave] = rng.next_float(0.0f, 2.0f * float(M_PI));
    }
  }
}

vec3 WindField::velocity_at(const vec3 &p, const float time) const
{
  if (turbulence_ == 0.0f) {
    return mean_;
  }
  vec3 noise(0.0f);
  for (int component = 0; component < 3; component++) {
    for (int wave = 0; wave < waves_num; wave++) {
      noise[component] += std::sin(angular_frequencies_[component][wave] * time -
                                   glm::dot(wave_vectors_[component][wave], p) +
                                   phases_[component][wave]);
    }
  }
  return mean_ + (turbulence_ / float(waves_num)) * noise;
}

}  // namespace hairdyn
