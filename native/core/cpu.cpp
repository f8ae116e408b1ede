#include "core/cpu.hh"

namespace hairdyn {

bool cpu_has_avx2()
{
#if defined(__GNUC__) && defined(__x86_64__)
  __builtin_cpu_init(); /* needed where this runs before the constructors (static init) */
  return __builtin_cpu_supports("avx2");
#else
  return false;
#endif
}

VectorCode cpu_vector_code()
{
  if (!cpu_has_avx2()) {
    return VectorCode::Baseline;
  }
#if defined(__GNUC__) && defined(__x86_64__)
  if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl")) {
    return VectorCode::Avx512;
  }
#endif
  return VectorCode::Avx2;
}

}  // namespace hairdyn
