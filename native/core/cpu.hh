#pragma once
/* What the processor can run, for the code that has a wider form beside its baseline one
 * (collision look-ups, the articulated strands' recursion). */

namespace hairdyn {

/* Whether the CPU runs AVX2 (x86-64 with GCC or Clang; false elsewhere). */
bool cpu_has_avx2();

}  // namespace hairdyn
