#pragma once
/* What the cylindrical and the spherical collision maps share (Kurihara 1993 §3.1, §5): an
 * orthonormal map frame, an m × n table of radii and normals looked up bilinearly (eq. 8–10),
 * and the nearest-point approximation of eq. 11. The two maps differ only in how a point maps
 * to table coordinates (cylinder_map_kurihara1993.hh, sphere_map.hh). */
#include <cmath>
#include <vector>

#include "collision/bvh.hh"
#include "core/math.hh"
#include "core/span.hh"

namespace hairdyn {

/* Map space: origin on the axis (cylinder) or at the centre (sphere); y along the axis / pole,
 * x along the reference direction (θ = 0), z = x × y. Rigid: distances are the same in object
 * and map space. */
struct MapFrame {
  vec3 origin{0.0f};
  vec3 axis{0.0f, 1.0f, 0.0f};
  vec3 reference{1.0f, 0.0f, 0.0f}; /* Made perpendicular to axis by make_frame. */

  /* p_map = object_to_map * p_object. */
  mat4 object_to_map() const;
  mat4 map_to_object() const;
};

/* A frame from an origin and two directions; `reference` is orthogonalised against `axis`
 * (a reference parallel to the axis is replaced by any perpendicular direction). */
MapFrame make_frame(const vec3 &origin, const vec3 &axis, const vec3 &reference);

/* Principal axes of a triangle set (area-weighted PCA of the triangle centroids): origin at
 * the area centroid, axis the direction of largest spread, reference the second. */
MapFrame fit_frame(Span<vec3> vertices, Span<ivec3> triangles);

/* A contact or signed-depth sample in map space. */
struct MapSample {
  float depth = 0.0f;     /* (Q - P) · N: > 0 inside (Kurihara 1993, eq. 11). */
  vec3 normal{0.0f};      /* N, unit, outward. */
  vec3 surface_point{0.0f}; /* T = P + depth N (eq. 11). */
  bool inside = false;    /* r_p < r_q (the comparison after eq. 10). */
};

/* atan2 to within 1e-6 rad, several times faster than std::atan2 (the query path's only
 * transcendental function). Result in (-π, π]. */
inline float fast_atan2(const float y, const float x)
{
  const float ax = std::abs(x), ay = std::abs(y);
  const float big = std::max(ax, ay);
  if (big == 0.0f) {
    return 0.0f;
  }
  const float a = std::min(ax, ay) / big;
  const float s = a * a;
  /* Minimax polynomial for atan on [0, 1]. */
  float r = ((((((-0.0040540580f * s + 0.0218612288f) * s - 0.0559098861f) * s +
               0.0964200441f) * s - 0.1390853351f) * s + 0.1994653599f) * s -
             0.3332985605f) * s * a + a;
  if (ay > ax) {
    r = 1.57079637f - r;
  }
  if (x < 0.0f) {
    r = 3.14159274f - r;
  }
  return y < 0.0f ? -r : r;
}

/* One table cell: the outward unit normal and the radius of the outermost hit; radius < 0
 * marks an empty cell (the ray missed the part). */
struct MapCell {
  vec3 normal{0.0f};
  float radius = -1.0f;
};
static_assert(sizeof(MapCell) == 16, "one cell is 16 bytes: four cells per cache line");

/* The m × n table. u (azimuth, 0 <= u < m) wraps around; v (0 <= v <= n - 1) is clamped by
 * the caller. */
class RadialTable {
 public:
  RadialTable() = default;
  RadialTable(int32_t u_num, int32_t v_num)
      : u_num_(u_num), v_num_(v_num), cells_(size_t(u_num) * size_t(v_num))
  {
  }

  int32_t u_num() const { return u_num_; }
  int32_t v_num() const { return v_num_; }
  MapCell &cell_for_write(const int32_t u, const int32_t v) { return cells_[size_t(v * u_num_ + u)]; }
  const MapCell &cell(const int32_t u, const int32_t v) const { return cells_[size_t(v * u_num_ + u)]; }
  int64_t empty_cells_num() const;
  /* Largest radius of a filled cell (0 when all are empty). */
  float max_radius() const { return max_radius_; }
  void update_max_radius();

  /* The four cells around table coordinates (u, v) and their bilinear weights. */
  struct Stencil {
    const MapCell *c00, *c10, *c01, *c11;
    float w00, w10, w01, w11;
  };

  /* Bilinear look-up of the radius r_q at table coordinates (u, v) (Kurihara 1993, eq. 8–10).
   * False when any of the four cells is empty: a query never reports a collision next to a
   * missed ray. r_stencil is for normal(). */
  bool lookup_radius(const float u, const float v, float &r_radius, Stencil &r_stencil) const
  {
    /* eq. 8: i <= u < i + 1, j <= v < j + 1. */
    const float u_floor = std::floor(u);
    const float v_floor = std::floor(v);
    int32_t i0 = int32_t(u_floor);
    int32_t j0 = int32_t(v_floor);
    i0 = i0 >= u_num_ ? i0 - u_num_ : (i0 < 0 ? i0 + u_num_ : i0);
    j0 = std::min(std::max(j0, 0), v_num_ - 1);
    const int32_t i1 = i0 + 1 == u_num_ ? 0 : i0 + 1;
    const int32_t j1 = std::min(j0 + 1, v_num_ - 1);
    /* eq. 10 */
    const float s = u - u_floor;
    const float t = v - v_floor;
    Stencil &st = r_stencil;
    st.c00 = &cells_[size_t(j0 * u_num_ + i0)];
    st.c10 = &cells_[size_t(j0 * u_num_ + i1)];
    st.c01 = &cells_[size_t(j1 * u_num_ + i0)];
    st.c11 = &cells_[size_t(j1 * u_num_ + i1)];
    if (std::min(std::min(st.c00->radius, st.c10->radius), std::min(st.c01->radius, st.c11->radius)) <
        0.0f)
    {
      return false;
    }
    st.w00 = (1.0f - s) * (1.0f - t);
    st.w10 = s * (1.0f - t);
    st.w01 = (1.0f - s) * t;
    st.w11 = s * t;
    /* eq. 9 */
    r_radius = st.c00->radius * st.w00 + st.c10->radius * st.w10 + st.c01->radius * st.w01 +
               st.c11->radius * st.w11;
    return true;
  }

  /* §3.1, step 1: N at Q by bilinear interpolation of the cells' normals, normalised. */
  static vec3 normal(const Stencil &st)
  {
    const vec3 n = st.c00->normal * st.w00 + st.c10->normal * st.w10 + st.c01->normal * st.w01 +
                   st.c11->normal * st.w11;
    const float len_sq = glm::dot(n, n);
    /* Opposite normals cancelling out (a thin sheet seen from both sides): any unit vector
     * is as good, keep the first cell's. */
    return len_sq > 1e-12f ? n * (1.0f / std::sqrt(len_sq)) : st.c00->normal;
  }

 private:
  int32_t u_num_ = 0;
  int32_t v_num_ = 0;
  std::vector<MapCell> cells_;
  float max_radius_ = 0.0f;
};

/* Fills one cell from the outermost hit of the ray origin + t direction (map space; the BVH is
 * in object space, hence the frame). The normal is the hit triangle's, turned to face along
 * the ray: the outermost surface faces outwards whatever the mesh's winding. */
void fill_cell_from_ray(const TriangleBVH &bvh, Span<vec3> vertices, Span<ivec3> triangles,
                        const mat4 &map_to_object, const vec3 &origin_map,
                        const vec3 &direction_map, MapCell &r_cell);

/* Eq. 11 and the inside test, once the map has found Q (on the ray from `base` through P, at
 * radius r_q) and N: fills r_sample for the point p (map space). */
inline void finish_sample(const vec3 &p, const vec3 &q, const vec3 &normal, const bool inside,
                          MapSample &r_sample)
{
  /* Kurihara 1993, eq. 11: PT = (PQ · N) N. */
  const float depth = glm::dot(q - p, normal);
  r_sample.depth = depth;
  r_sample.normal = normal;
  r_sample.surface_point = p + depth * normal;
  r_sample.inside = inside;
}

}  // namespace hairdyn
