#pragma once
/* What the processor can run, for the code that has a wider form beside its baseline one
 * (collision look-ups, the articulated strands' recursion). */

namespace hairdyn {

/* The vector code a function has clones for, narrowest first. */
enum class VectorCode { Baseline, Avx2, Avx512 };

/* Whether the CPU runs AVX2 (x86-64 with GCC or Clang; false elsewhere). */
bool cpu_has_avx2();

/* The widest of VectorCode the CPU runs: Avx512 needs AVX-512F (512-bit vectors, 32
 * registers) and VL (its instructions on 256-bit vectors too) beside AVX2. */
VectorCode cpu_vector_code();

}  // namespace hairdyn
