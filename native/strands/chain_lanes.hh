#pragma once
/* The articulated chain's algebra in lanes: Lanes, lane_width doubles in one GCC/Clang
 * vector, and Floats, the same lanes in single precision, for lane_width strands of the same
 * number of segments stepped together (strand_dynamics_articulated.cpp). V2, V3, M2 and M3
 * take either as their lane type R.
 *
 * Every operation is written as glm evaluates it on vec3, mat3, dvec3, dmat3, dvec2 and dmat2
 * (the same products, summed in the same order), each lane on its own, and none is fused
 * (the core builds with -ffp-contract=off). So a strand's step gives the same bits in any
 * lane of a vector as alone, whatever the instruction set the vector code was compiled for
 * (test StrandsCollision.LanesGiveEachStrandItsOwnBits). */
#include <cmath>

#include "core/math.hh"

/* Functions on Lanes are always inlined, so no vector crosses a call: the warning that one
 * would pass differently with and without AVX does not apply. */
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"

namespace hairdyn::chain {

constexpr int lane_width = 4;
typedef double Lanes __attribute__((vector_size(lane_width * sizeof(double))));
/* The same lanes in single precision (what pass 1 computes, widened exactly to Lanes). */
typedef float Floats __attribute__((vector_size(lane_width * sizeof(float))));
/* What memory the vector code reads must be aligned to: GCC gives a vector only 16-byte
 * alignment where AVX is off (and drops an alignment attribute on a template argument),
 * while the AVX code it calls loads it assuming its full size. */
constexpr size_t lane_alignment = sizeof(Lanes);

#define HAIRDYN_CHAIN_INLINE [[gnu::always_inline]] inline
/* The same for a lambda (after its parameters): inlined into each clone of its caller, it
 * runs the clone's vector code (a lambda called apart would run the baseline's). */
#define HAIRDYN_CHAIN_INLINE_LAMBDA __attribute__((always_inline))

template<class R> struct V2 {
  R x, y;
};
template<class R> struct V3 {
  R x, y, z;
};
/* Column-major, as glm: c[column]. */
template<class R> struct M2 {
  V2<R> c[2];
};
template<class R> struct M3 {
  V3<R> c[3];
};

/* One lane: writing it (pass 1's single-precision lanes) and reading it. */
HAIRDYN_CHAIN_INLINE void put(V2<Floats> &v, const int lane, const glm::vec2 &value)
{
  v.x[lane] = value.x;
  v.y[lane] = value.y;
}
HAIRDYN_CHAIN_INLINE void put(V3<Floats> &v, const int lane, const glm::vec3 &value)
{
  v.x[lane] = value.x;
  v.y[lane] = value.y;
  v.z[lane] = value.z;
}
HAIRDYN_CHAIN_INLINE float get(const Floats &x, const int lane)
{
  return x[lane];
}
HAIRDYN_CHAIN_INLINE glm::vec3 get(const V3<Floats> &v, const int lane)
{
  return glm::vec3(v.x[lane], v.y[lane], v.z[lane]);
}
HAIRDYN_CHAIN_INLINE double get(const Lanes &x, const int lane)
{
  return x[lane];
}
HAIRDYN_CHAIN_INLINE glm::dvec2 get(const V2<Lanes> &v, const int lane)
{
  return glm::dvec2(get(v.x, lane), get(v.y, lane));
}
HAIRDYN_CHAIN_INLINE glm::dvec3 get(const V3<Lanes> &v, const int lane)
{
  return glm::dvec3(get(v.x, lane), get(v.y, lane), get(v.z, lane));
}
HAIRDYN_CHAIN_INLINE glm::dmat2 get(const M2<Lanes> &m, const int lane)
{
  return glm::dmat2(get(m.c[0], lane), get(m.c[1], lane));
}

/* Single-precision lanes with one value for every lane (a glm scalar, vector or matrix):
 * the same operations as glm's on each lane. */
HAIRDYN_CHAIN_INLINE V3<Floats> operator*(const float s, const V3<Floats> &v)
{
  return { s * v.x, s * v.y, s * v.z };
}
HAIRDYN_CHAIN_INLINE V3<Floats> operator-(const V3<Floats> &a, const glm::vec3 &b)
{
  return { a.x - b.x, a.y - b.y, a.z - b.z };
}
HAIRDYN_CHAIN_INLINE V3<Floats> operator+(const glm::vec3 &a, const V3<Floats> &b)
{
  return { a.x + b.x, a.y + b.y, a.z + b.z };
}
HAIRDYN_CHAIN_INLINE V3<Floats> operator*(const glm::mat3 &m, const V3<Floats> &v)
{
  return { m[0][0] * v.x + m[1][0] * v.y + m[2][0] * v.z,
           m[0][1] * v.x + m[1][1] * v.y + m[2][1] * v.z,
           m[0][2] * v.x + m[1][2] * v.y + m[2][2] * v.z };
}
HAIRDYN_CHAIN_INLINE V3<Floats> cross(const glm::vec3 &x, const V3<Floats> &y)
{
  return { x.y * y.z - y.y * x.z, x.z * y.x - y.z * x.x, x.x * y.y - y.x * x.y };
}
/* Each lane's square root (correctly rounded, as std::sqrt). */
HAIRDYN_CHAIN_INLINE Floats sqrt(const Floats &x)
{
  Floats r;
  for (int lane = 0; lane < lane_width; lane++) {
    r[lane] = std::sqrt(x[lane]);
  }
  return r;
}
/* std::max(a, b) in each lane: (a < b) ? b : a. */
HAIRDYN_CHAIN_INLINE Floats max(const Floats &a, const Floats &b)
{
  return a < b ? b : a;
}

/* Single-precision lanes in double precision (exact). */
HAIRDYN_CHAIN_INLINE Lanes widen(const Floats &x)
{
  return __builtin_convertvector(x, Lanes);
}
HAIRDYN_CHAIN_INLINE V2<Lanes> widen(const V2<Floats> &v)
{
  return { widen(v.x), widen(v.y) };
}
HAIRDYN_CHAIN_INLINE V3<Lanes> widen(const V3<Floats> &v)
{
  return { widen(v.x), widen(v.y), widen(v.z) };
}
template<class R> HAIRDYN_CHAIN_INLINE V2<R> operator+(const V2<R> &a, const V2<R> &b)
{
  return { a.x + b.x, a.y + b.y };
}
template<class R> HAIRDYN_CHAIN_INLINE V2<R> operator-(const V2<R> &a, const V2<R> &b)
{
  return { a.x - b.x, a.y - b.y };
}
template<class R> HAIRDYN_CHAIN_INLINE V3<R> operator+(const V3<R> &a, const V3<R> &b)
{
  return { a.x + b.x, a.y + b.y, a.z + b.z };
}
template<class R> HAIRDYN_CHAIN_INLINE V3<R> operator-(const V3<R> &a, const V3<R> &b)
{
  return { a.x - b.x, a.y - b.y, a.z - b.z };
}
template<class R> HAIRDYN_CHAIN_INLINE V3<R> operator-(const V3<R> &v)
{
  return { -v.x, -v.y, -v.z };
}
template<class R> HAIRDYN_CHAIN_INLINE V3<R> operator*(const R &s, const V3<R> &v)
{
  return { s * v.x, s * v.y, s * v.z };
}
template<class R> HAIRDYN_CHAIN_INLINE V2<R> operator*(const R &s, const V2<R> &v)
{
  return { s * v.x, s * v.y };
}
template<class R> HAIRDYN_CHAIN_INLINE R dot(const V3<R> &a, const V3<R> &b)
{
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
template<class R> HAIRDYN_CHAIN_INLINE V3<R> cross(const V3<R> &x, const V3<R> &y)
{
  return { x.y * y.z - y.y * x.z, x.z * y.x - y.z * x.x, x.x * y.y - y.x * x.y };
}
template<class R> HAIRDYN_CHAIN_INLINE R length(const V3<R> &v)
{
  return sqrt(dot(v, v));
}
template<class R> HAIRDYN_CHAIN_INLINE M3<R> operator+(const M3<R> &a, const M3<R> &b)
{
  return { { a.c[0] + b.c[0], a.c[1] + b.c[1], a.c[2] + b.c[2] } };
}
template<class R> HAIRDYN_CHAIN_INLINE M3<R> operator-(const M3<R> &a, const M3<R> &b)
{
  return { { a.c[0] - b.c[0], a.c[1] - b.c[1], a.c[2] - b.c[2] } };
}
template<class R> HAIRDYN_CHAIN_INLINE M3<R> operator-(const M3<R> &m)
{
  return { { -m.c[0], -m.c[1], -m.c[2] } };
}
template<class R> HAIRDYN_CHAIN_INLINE M3<R> operator*(const R &s, const M3<R> &m)
{
  return { { s * m.c[0], s * m.c[1], s * m.c[2] } };
}
/* m v */
template<class R> HAIRDYN_CHAIN_INLINE V3<R> operator*(const M3<R> &m, const V3<R> &v)
{
  return { m.c[0].x * v.x + m.c[1].x * v.y + m.c[2].x * v.z,
           m.c[0].y * v.x + m.c[1].y * v.y + m.c[2].y * v.z,
           m.c[0].z * v.x + m.c[1].z * v.y + m.c[2].z * v.z };
}
/* mᵀ v */
template<class R> HAIRDYN_CHAIN_INLINE V3<R> transpose_times(const M3<R> &m, const V3<R> &v)
{
  return { dot(m.c[0], v), dot(m.c[1], v), dot(m.c[2], v) };
}
/* mᵀ */
template<class R> HAIRDYN_CHAIN_INLINE M3<R> transpose(const M3<R> &m)
{
  return { { { m.c[0].x, m.c[1].x, m.c[2].x },
             { m.c[0].y, m.c[1].y, m.c[2].y },
             { m.c[0].z, m.c[1].z, m.c[2].z } } };
}
/* x yᵀ */
template<class R> HAIRDYN_CHAIN_INLINE M3<R> outer(const V3<R> &x, const V3<R> &y)
{
  return { { y.x * x, y.y * x, y.z * x } };
}
/* [v]× m and m [v]×, column by column (the products with cross_matrix(v) less its
 * multiplications by zero). */
template<class R> HAIRDYN_CHAIN_INLINE M3<R> cross_times(const V3<R> &v, const M3<R> &m)
{
  return { { cross(v, m.c[0]), cross(v, m.c[1]), cross(v, m.c[2]) } };
}
template<class R> HAIRDYN_CHAIN_INLINE M3<R> times_cross(const M3<R> &m, const V3<R> &v)
{
  return { { v.z * m.c[1] - v.y * m.c[2], v.x * m.c[2] - v.z * m.c[0],
             v.y * m.c[0] - v.x * m.c[1] } };
}
/* m v */
template<class R> HAIRDYN_CHAIN_INLINE V2<R> operator*(const M2<R> &m, const V2<R> &v)
{
  return { m.c[0].x * v.x + m.c[1].x * v.y, m.c[0].y * v.x + m.c[1].y * v.y };
}
template<class R> HAIRDYN_CHAIN_INLINE M2<R> inverse(const M2<R> &m)
{
  const R one_over_determinant = 1.0 / (m.c[0].x * m.c[1].y - m.c[1].x * m.c[0].y);
  return { { { m.c[1].y * one_over_determinant, -m.c[0].y * one_over_determinant },
             { -m.c[1].x * one_over_determinant, m.c[0].x * one_over_determinant } } };
}

}  // namespace hairdyn::chain

#pragma GCC diagnostic pop
