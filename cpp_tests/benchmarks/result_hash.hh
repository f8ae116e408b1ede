#pragma once
/* A fingerprint of a benchmark's result: FNV-1a over the bytes of its arrays. Equal across
 * versions of the code that change the speed but not the result (reported as the counter
 * result_hash). */
#include <cstdint>
#include <initializer_list>

#include "core/math.hh"
#include "core/span.hh"

namespace hairdyn {

inline uint32_t result_hash(const std::initializer_list<Span<vec3>> arrays)
{
  uint32_t hash = 2166136261u;
  for (const Span<vec3> values : arrays) {
    const auto *bytes = reinterpret_cast<const unsigned char *>(values.data());
    for (size_t i = 0; i < size_t(values.size()) * sizeof(vec3); i++) {
      hash = (hash ^ bytes[i]) * 16777619u;
    }
  }
  return hash;
}

}  // namespace hairdyn
