#pragma once
/* Deterministic random numbers: the same seed gives the same sequence on every platform and
 * thread count (std:: distributions are implementation-defined, so they are not used). */
#include <cstdint>

namespace hairdyn {

/* SplitMix64 (Steele, Lea, Flood 2014): small state, good statistics, trivially seeded. */
class RandomNumberGenerator {
 public:
  explicit RandomNumberGenerator(const uint64_t seed) : state_(seed) {}

  uint64_t next_uint64()
  {
    uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  /* Uniform in [0, 1). */
  float next_float() { return float(next_uint64() >> 40) * (1.0f / 16777216.0f); }
  /* Uniform in [low, high). */
  float next_float(const float low, const float high) { return low + (high - low) * next_float(); }

 private:
  uint64_t state_;
};

}  // namespace hairdyn
