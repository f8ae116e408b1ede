#pragma once
/* Four float lanes for the inner loops of the volume grids (splat, blur, read-back): one SSE
 * register on x86-64, four scalars elsewhere. Every operation is the IEEE operation of each lane
 * on its own (no fused multiply-add, no reordering), so a loop written with Lanes4 gives the
 * same bits as the same loop on glm::vec4 (or on the x, y, z of a vec3). */
#include <cstring>

#if defined(__SSE2__) || defined(_M_X64)
#include <emmintrin.h>
#define HAIRDYN_LANES4_SSE 1
#endif

#include "core/math.hh"

namespace hairdyn {

struct Lanes4 {
#ifdef HAIRDYN_LANES4_SSE
  __m128 v;

  static Lanes4 load(const float *p)
  {
    return { _mm_loadu_ps(p) };
  }
  void store(float *p) const
  {
    _mm_storeu_ps(p, v);
  }
  static Lanes4 splat(const float s)
  {
    return { _mm_set1_ps(s) };
  }
  static Lanes4 set(const float x, const float y, const float z, const float w)
  {
    return { _mm_setr_ps(x, y, z, w) };
  }
  static Lanes4 zero()
  {
    return { _mm_setzero_ps() };
  }
  friend Lanes4 operator+(const Lanes4 a, const Lanes4 b)
  {
    return { _mm_add_ps(a.v, b.v) };
  }
  friend Lanes4 operator-(const Lanes4 a, const Lanes4 b)
  {
    return { _mm_sub_ps(a.v, b.v) };
  }
  friend Lanes4 operator*(const Lanes4 a, const Lanes4 b)
  {
    return { _mm_mul_ps(a.v, b.v) };
  }
  friend Lanes4 operator/(const Lanes4 a, const Lanes4 b)
  {
    return { _mm_div_ps(a.v, b.v) };
  }
  /* Lane i in all four lanes. */
  template<int i> Lanes4 broadcast() const
  {
    return { _mm_shuffle_ps(v, v, _MM_SHUFFLE(i, i, i, i)) };
  }
#else
  float v[4];

  static Lanes4 load(const float *p)
  {
    Lanes4 r;
    std::memcpy(r.v, p, sizeof(r.v));
    return r;
  }
  void store(float *p) const
  {
    std::memcpy(p, v, sizeof(v));
  }
  static Lanes4 splat(const float s)
  {
    return { { s, s, s, s } };
  }
  static Lanes4 set(const float x, const float y, const float z, const float w)
  {
    return { { x, y, z, w } };
  }
  static Lanes4 zero()
  {
    return splat(0.0f);
  }
  friend Lanes4 operator+(const Lanes4 a, const Lanes4 b)
  {
    return { { a.v[0] + b.v[0], a.v[1] + b.v[1], a.v[2] + b.v[2], a.v[3] + b.v[3] } };
  }
  friend Lanes4 operator-(const Lanes4 a, const Lanes4 b)
  {
    return { { a.v[0] - b.v[0], a.v[1] - b.v[1], a.v[2] - b.v[2], a.v[3] - b.v[3] } };
  }
  friend Lanes4 operator*(const Lanes4 a, const Lanes4 b)
  {
    return { { a.v[0] * b.v[0], a.v[1] * b.v[1], a.v[2] * b.v[2], a.v[3] * b.v[3] } };
  }
  friend Lanes4 operator/(const Lanes4 a, const Lanes4 b)
  {
    return { { a.v[0] / b.v[0], a.v[1] / b.v[1], a.v[2] / b.v[2], a.v[3] / b.v[3] } };
  }
  template<int i> Lanes4 broadcast() const
  {
    return splat(v[i]);
  }
#endif
  static Lanes4 load(const vec4 &p)
  {
    return load(&p.x);
  }
  void store(vec4 &p) const
  {
    store(&p.x);
  }
  vec4 to_vec4() const
  {
    vec4 r;
    store(r);
    return r;
  }
};

}  // namespace hairdyn
