#pragma once
/* The scalp of Bando 2003, §3.2: a triangle patch of the head embedded in the unit square
 * D = [0,1]² by a piecewise-linear harmonic map φ (Eck et al. 1995). The boundary loop goes
 * onto the square's edges by arc length; interior vertices solve the cotangent Laplace
 * equation. φ⁻¹(u, v) is found by locating (u, v) among the mapped triangles. */
#include <string>
#include <vector>

#include "core/math.hh"
#include "core/span.hh"

namespace hairdyn {

using glm::vec2;

/* Empty when the patch can be mapped; otherwise one sentence: no faces, bad indices, a
 * vertex no triangle uses, a non-manifold patch, no boundary (a closed surface), several
 * boundary loops, or a handle (not a disc). */
std::string find_scalp_error(Span<vec3> vertices, Span<ivec3> triangles);

/* Harmonic map of a disc-like patch (which must pass find_scalp_error) to the unit square:
 * r_uv[v] for each vertex. Returns false if the sparse solve failed. */
bool compute_harmonic_map(Span<vec3> vertices, Span<ivec3> triangles, MutableSpan<vec2> r_uv);

/* A point of the scalp: φ⁻¹(u, v), its unit normal and the interpolated per-vertex weight. */
struct ScalpPoint {
  vec3 position{0.0f};
  vec3 normal{0.0f, 0.0f, 1.0f};
  float weight = 0.0f;
};

class ScalpMap {
 public:
  /* `weights`: one value per vertex (the length map), or empty for all 1. The patch must pass
   * find_scalp_error. Normals follow the triangles' winding (counter-clockwise = outward). */
  ScalpMap(Span<vec3> vertices, Span<ivec3> triangles, Span<float> weights);

  bool is_valid() const { return valid_; }
  Span<vec2> uv() const { return uv_; }
  Span<vec3> vertices() const { return vertices_; }
  Span<ivec3> triangles() const { return triangles_; }
  float area() const { return area_; }

  /* φ⁻¹(u, v) (§3.2), for (u, v) in the unit square. */
  ScalpPoint locate(const vec2 &uv) const;
  /* The point with barycentric coordinates `bary` in triangle `tri`, and its (u, v). */
  ScalpPoint point_in_triangle(int64_t tri, const vec3 &bary, vec2 &r_uv) const;
  /* Area of each triangle in the world (for area-uniform sampling). */
  Span<float> triangle_areas() const { return triangle_areas_; }

 private:
  std::vector<vec3> vertices_;
  std::vector<ivec3> triangles_;
  std::vector<float> weights_;
  std::vector<vec3> vertex_normals_;
  std::vector<vec2> uv_;
  std::vector<float> triangle_areas_;
  float area_ = 0.0f;
  bool valid_ = false;
  /* Triangles overlapping each cell of a grid_res_² grid over D. */
  int32_t grid_res_ = 1;
  std::vector<int32_t> cell_offsets_;
  std::vector<int32_t> cell_triangles_;
};

}  // namespace hairdyn
