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

}  // namespace hairdyn
