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
#include <cstdint>
#include <cstring>

#include "core/math.hh"

/* Functions on Lanes are always inlined, so no vector crosses a call: the warning that one
 * would pass differently with and without AVX does not apply. */
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"

namespace hairdyn::chain {

/* W doubles in one GCC/Clang vector (Lanes), and the same lanes in single precision (Floats,
 * what pass 1 computes, widened exactly to Lanes). Each vector code steps the width its
 * registers hold best (strand_dynamics_articulated.cpp): 8 with AVX-512, 4 otherwise. */
template<int W> struct LaneTypes {
  typedef double Lanes __attribute__((vector_size(W * sizeof(double))));
  typedef float Floats __attribute__((vector_size(W * sizeof(float))));
  typedef int32_t Ints __attribute__((vector_size(W * sizeof(int32_t))));
};
template<int W> using Lanes = typename LaneTypes<W>::Lanes;
template<int W> using Floats = typename LaneTypes<W>::Floats;
template<int W> using Ints = typename LaneTypes<W>::Ints; /* as many int32_t lanes */
constexpr int max_lane_width = 8;
/* What memory the vector code reads must be aligned to: GCC gives a vector only 16-byte
 * alignment where AVX is off (and drops an alignment attribute on a template argument),
 * while the AVX code it calls loads it assuming its full size. */
constexpr size_t lane_alignment = sizeof(Lanes<max_lane_width>);

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
/* A symmetric 3×3 matrix: its diagonal and the entries above it. */
template<class R> struct S3 {
  R xx, yy, zz, xy, xz, yz;
};

/* One lane: writing it (pass 1's single-precision lanes) and reading it (as glm's float or
 * double values). The vector type R of a lane's scalar is any of Lanes and Floats. */
template<class R> HAIRDYN_CHAIN_INLINE void put(V2<R> &v, const int lane, const glm::vec2 &value)
{
  v.x[lane] = value.x;
  v.y[lane] = value.y;
}
template<class R> HAIRDYN_CHAIN_INLINE void put(V3<R> &v, const int lane, const glm::vec3 &value)
{
  v.x[lane] = value.x;
  v.y[lane] = value.y;
  v.z[lane] = value.z;
}
template<class R> HAIRDYN_CHAIN_INLINE auto get(const R &x, const int lane) -> decltype(+x[lane])
{
  return x[lane];
}
template<class R> HAIRDYN_CHAIN_INLINE auto get(const V2<R> &v, const int lane)
{
  return glm::vec<2, decltype(get(v.x, lane))>(get(v.x, lane), get(v.y, lane));
}
template<class R> HAIRDYN_CHAIN_INLINE auto get(const V3<R> &v, const int lane)
{
  return glm::vec<3, decltype(get(v.x, lane))>(get(v.x, lane), get(v.y, lane), get(v.z, lane));
}
template<class R> HAIRDYN_CHAIN_INLINE auto get(const M2<R> &m, const int lane)
{
  return glm::mat<2, 2, decltype(get(m.c[0].x, lane))>(get(m.c[0], lane), get(m.c[1], lane));
}
template<class R> HAIRDYN_CHAIN_INLINE auto get(const M3<R> &m, const int lane)
{
  return glm::mat<3, 3, decltype(get(m.c[0].x, lane))>(get(m.c[0], lane), get(m.c[1], lane),
                                                       get(m.c[2], lane));
}

/* Records of W lanes, one pointer per lane, as lane vectors: out[j][lane] = records[lane][j]
 * (what putting them lane by lane gives, bit for bit), loaded four or two floats at a time
 * and transposed, for records of four floats (a vec4, or four consecutive floats of a larger
 * record) and of two (a vec2). W is 4 or 8. */
HAIRDYN_CHAIN_INLINE void gather4(const float *const *records, Floats<4> *out)
{
  using F4 = Floats<4>;
  F4 r[4];
  for (int lane = 0; lane < 4; lane++) {
    std::memcpy(&r[lane], records[lane], sizeof(F4));
  }
  const F4 t0 = __builtin_shufflevector(r[0], r[1], 0, 4, 1, 5);
  const F4 t1 = __builtin_shufflevector(r[0], r[1], 2, 6, 3, 7);
  const F4 t2 = __builtin_shufflevector(r[2], r[3], 0, 4, 1, 5);
  const F4 t3 = __builtin_shufflevector(r[2], r[3], 2, 6, 3, 7);
  out[0] = __builtin_shufflevector(t0, t2, 0, 1, 4, 5);
  out[1] = __builtin_shufflevector(t0, t2, 2, 3, 6, 7);
  out[2] = __builtin_shufflevector(t1, t3, 0, 1, 4, 5);
  out[3] = __builtin_shufflevector(t1, t3, 2, 3, 6, 7);
}
HAIRDYN_CHAIN_INLINE void gather4(const float *const *records, Floats<8> *out)
{
  Floats<4> low[4], high[4];
  gather4(records, low);
  gather4(records + 4, high);
  for (int j = 0; j < 4; j++) {
    out[j] = __builtin_shufflevector(low[j], high[j], 0, 1, 2, 3, 4, 5, 6, 7);
  }
}
HAIRDYN_CHAIN_INLINE void gather2(const float *const *records, V2<Floats<4>> &out)
{
  using F4 = Floats<4>;
  F4 r[2];
  for (int pair = 0; pair < 2; pair++) {
    float both[4];
    std::memcpy(both, records[2 * pair], 2 * sizeof(float));
    std::memcpy(both + 2, records[2 * pair + 1], 2 * sizeof(float));
    std::memcpy(&r[pair], both, sizeof(F4));
  }
  out.x = __builtin_shufflevector(r[0], r[1], 0, 2, 4, 6);
  out.y = __builtin_shufflevector(r[0], r[1], 1, 3, 5, 7);
}
HAIRDYN_CHAIN_INLINE void gather2(const float *const *records, V2<Floats<8>> &out)
{
  V2<Floats<4>> low, high;
  gather2(records, low);
  gather2(records + 4, high);
  out.x = __builtin_shufflevector(low.x, high.x, 0, 1, 2, 3, 4, 5, 6, 7);
  out.y = __builtin_shufflevector(low.y, high.y, 0, 1, 2, 3, 4, 5, 6, 7);
}

/* Single-precision lanes F with one value for every lane (a glm scalar, vector or matrix):
 * the same operations as glm's on each lane. */
template<class F> HAIRDYN_CHAIN_INLINE V3<F> operator*(const float s, const V3<F> &v)
{
  return { s * v.x, s * v.y, s * v.z };
}
template<class F> HAIRDYN_CHAIN_INLINE V3<F> operator-(const V3<F> &a, const glm::vec3 &b)
{
  return { a.x - b.x, a.y - b.y, a.z - b.z };
}
template<class F> HAIRDYN_CHAIN_INLINE V3<F> operator+(const glm::vec3 &a, const V3<F> &b)
{
  return { a.x + b.x, a.y + b.y, a.z + b.z };
}
template<class F> HAIRDYN_CHAIN_INLINE V3<F> operator*(const glm::mat3 &m, const V3<F> &v)
{
  return { m[0][0] * v.x + m[1][0] * v.y + m[2][0] * v.z,
           m[0][1] * v.x + m[1][1] * v.y + m[2][1] * v.z,
           m[0][2] * v.x + m[1][2] * v.y + m[2][2] * v.z };
}
template<class F> HAIRDYN_CHAIN_INLINE V3<F> cross(const glm::vec3 &x, const V3<F> &y)
{
  return { x.y * y.z - y.y * x.z, x.z * y.x - y.z * x.x, x.x * y.y - y.x * x.y };
}
/* Each lane's square root (correctly rounded, as std::sqrt). */
template<class F> HAIRDYN_CHAIN_INLINE auto sqrt(const F &x) -> decltype(x[0], F())
{
  F r;
  for (int lane = 0; lane < int(sizeof(F) / sizeof(x[0])); lane++) {
    r[lane] = std::sqrt(x[lane]);
  }
  return r;
}
/* std::max(a, b) in each lane: (a < b) ? b : a. */
template<class F> HAIRDYN_CHAIN_INLINE auto max(const F &a, const F &b) -> decltype(a[0], F())
{
  return a < b ? b : a;
}

/* Single-precision lanes in double precision (exact), for each width a vector code steps. */
HAIRDYN_CHAIN_INLINE Lanes<4> widen(const Floats<4> &x)
{
  return __builtin_convertvector(x, Lanes<4>);
}
HAIRDYN_CHAIN_INLINE Lanes<8> widen(const Floats<8> &x)
{
  return __builtin_convertvector(x, Lanes<8>);
}
template<class F> HAIRDYN_CHAIN_INLINE auto widen(const V2<F> &v)
{
  return V2<decltype(widen(v.x))>{ widen(v.x), widen(v.y) };
}
template<class F> HAIRDYN_CHAIN_INLINE auto widen(const V3<F> &v)
{
  return V3<decltype(widen(v.x))>{ widen(v.x), widen(v.y), widen(v.z) };
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
/* m v, m symmetric */
template<class R> HAIRDYN_CHAIN_INLINE V3<R> operator*(const S3<R> &m, const V3<R> &v)
{
  return { m.xx * v.x + m.xy * v.y + m.xz * v.z, m.xy * v.x + m.yy * v.y + m.yz * v.z,
           m.xz * v.x + m.yz * v.y + m.zz * v.z };
}
/* x yᵀ + z wᵀ, known to be symmetric: the entries of S3. */
template<class R> HAIRDYN_CHAIN_INLINE S3<R> symmetric_outer_sum(const V3<R> &x, const V3<R> &y,
                                                                 const V3<R> &z, const V3<R> &w)
{
  return { x.x * y.x + z.x * w.x, x.y * y.y + z.y * w.y, x.z * y.z + z.z * w.z,
           x.x * y.y + z.x * w.y, x.x * y.z + z.x * w.z, x.y * y.z + z.y * w.z };
}
template<class R> HAIRDYN_CHAIN_INLINE S3<R> operator-(const S3<R> &a, const S3<R> &b)
{
  return { a.xx - b.xx, a.yy - b.yy, a.zz - b.zz, a.xy - b.xy, a.xz - b.xz, a.yz - b.yz };
}
/* mᵀ v */
template<class R> HAIRDYN_CHAIN_INLINE V3<R> transpose_times(const M3<R> &m, const V3<R> &v)
{
  return { dot(m.c[0], v), dot(m.c[1], v), dot(m.c[2], v) };
}
/* x yᵀ */
template<class R> HAIRDYN_CHAIN_INLINE M3<R> outer(const V3<R> &x, const V3<R> &y)
{
  return { { y.x * x, y.y * x, y.z * x } };
}
/* [v]× m (m symmetric) and m [v]×, column by column (the products with cross_matrix(v) less
 * its multiplications by zero). */
template<class R> HAIRDYN_CHAIN_INLINE M3<R> cross_times(const V3<R> &v, const S3<R> &m)
{
  return { { cross(v, V3<R>{ m.xx, m.xy, m.xz }), cross(v, V3<R>{ m.xy, m.yy, m.yz }),
             cross(v, V3<R>{ m.xz, m.yz, m.zz }) } };
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

}  // namespace hairdyn::chain

#pragma GCC diagnostic pop
