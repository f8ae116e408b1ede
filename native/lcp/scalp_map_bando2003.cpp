#include "lcp/scalp_map_bando2003.hh"

/* OpenMesh grows its vertex property arrays with default-constructed (deliberately
 * uninitialised) VectorT values that add_vertex then overwrites; GCC 12 flags that inlined
 * copy as maybe-uninitialised (the same note as in main's collision/mesh.cpp). */
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "collision/mesh.hh"

namespace hairdyn {

static void build_trimesh(const Span<vec3> vertices, const Span<ivec3> triangles,
                          TriMesh &r_mesh, int64_t &r_rejected_num)
{
  r_rejected_num = 0;
  for (const vec3 &v : vertices) {
    r_mesh.add_vertex(TriMesh::Point(v.x, v.y, v.z));
  }
  for (const ivec3 &tri : triangles) {
    if (tri.x == tri.y || tri.y == tri.z || tri.z == tri.x) {
      r_rejected_num++;
      continue;
    }
    const auto face = r_mesh.add_face(TriMesh::VertexHandle(tri.x), TriMesh::VertexHandle(tri.y),
                                      TriMesh::VertexHandle(tri.z));
    r_rejected_num += face.is_valid() ? 0 : 1;
  }
}

/* The boundary loops of the mesh, each as its vertex indices in walking order. */
static std::vector<std::vector<int32_t>> boundary_loops(const TriMesh &mesh)
{
  std::vector<std::vector<int32_t>> loops;
  std::vector<bool> visited(mesh.n_halfedges(), false);
  for (const auto heh : mesh.halfedges()) {
    if (!mesh.is_boundary(heh) || visited[size_t(heh.idx())]) {
      continue;
    }
    std::vector<int32_t> loop;
    auto h = heh;
    do {
      visited[size_t(h.idx())] = true;
      loop.push_back(int32_t(mesh.from_vertex_handle(h).idx()));
      h = mesh.next_halfedge_handle(h);
    } while (h != heh && loop.size() <= mesh.n_halfedges());
    loops.push_back(std::move(loop));
  }
  return loops;
}

std::string find_scalp_error(const Span<vec3> vertices, const Span<ivec3> triangles)
{
  if (triangles.is_empty()) {
    return "the scalp patch has no faces (mark part of the head as scalp)";
  }
  std::string error = find_mesh_error(vertices, triangles);
  if (!error.empty()) {
    return "the scalp patch is invalid: " + error;
  }
  std::vector<bool> used(size_t(vertices.size()), false);
  for (const ivec3 &tri : triangles) {
    used[size_t(tri.x)] = used[size_t(tri.y)] = used[size_t(tri.z)] = true;
  }
  std::ostringstream msg;
  for (size_t v = 0; v < used.size(); v++) {
    if (!used[v]) {
      msg << "scalp vertex " << v << " is not used by any triangle";
      return msg.str();
    }
  }
  TriMesh mesh;
  int64_t rejected_num = 0;
  build_trimesh(vertices, triangles, mesh, rejected_num);
  if (rejected_num > 0) {
    msg << "the scalp patch is not a manifold surface (" << rejected_num
        << " triangles are degenerate or share an edge with two others)";
    return msg.str();
  }
  const std::vector<std::vector<int32_t>> loops = boundary_loops(mesh);
  if (loops.empty()) {
    return "the scalp patch has no boundary: mark only the part of the head that grows hair, "
           "not a closed surface";
  }
  if (loops.size() > 1) {
    msg << "the scalp patch has " << loops.size()
        << " boundary loops; it must be one piece without holes";
    return msg.str();
  }
  const int64_t euler = int64_t(mesh.n_vertices()) - int64_t(mesh.n_edges()) +
                        int64_t(mesh.n_faces());
  if (euler != 1) {
    return "the scalp patch is not a disc (it is in several pieces or has handles)";
  }
  return {};
}

/* cot of the angle at `apex` in the triangle (apex, a, b), clamped to stay positive so that
 * the weights are positive and the map is an embedding (Tutte / Floater). */
static double clamped_cotangent(const vec3 &apex, const vec3 &a, const vec3 &b)
{
  const glm::dvec3 e1 = glm::dvec3(a - apex);
  const glm::dvec3 e2 = glm::dvec3(b - apex);
  const double cross = glm::length(glm::cross(e1, e2));
  const double cot = glm::dot(e1, e2) / std::max(cross, 1e-30);
  return std::max(cot, 1e-2);
}

bool compute_harmonic_map(const Span<vec3> vertices, const Span<ivec3> triangles,
                          const MutableSpan<vec2> r_uv)
{
  TriMesh mesh;
  int64_t rejected_num = 0;
  build_trimesh(vertices, triangles, mesh, rejected_num);
  const std::vector<std::vector<int32_t>> loops = boundary_loops(mesh);
  assert(loops.size() == 1 && rejected_num == 0);
  std::vector<int32_t> loop = loops[0];
  /* Start at the boundary vertex with the smallest index, so the result does not depend on
   * the half-edge order. */
  std::rotate(loop.begin(), std::min_element(loop.begin(), loop.end()), loop.end());

  /* Boundary onto the square's edges by arc length (§3.2, Figure 2b). */
  const int64_t n = int64_t(loop.size());
  std::vector<double> arc(size_t(n) + 1, 0.0);
  for (int64_t k = 0; k < n; k++) {
    arc[size_t(k) + 1] = arc[size_t(k)] + double(glm::length(vertices[loop[size_t(k)]] -
                                                            vertices[loop[size_t((k + 1) % n)]]));
  }
  std::vector<int32_t> interior_index(size_t(vertices.size()), -1);
  for (int64_t k = 0; k < n; k++) {
    const double t = 4.0 * arc[size_t(k)] / arc[size_t(n)];
    vec2 uv;
    if (t < 1.0) {
      uv = vec2(float(t), 0.0f);
    }
    else if (t < 2.0) {
      uv = vec2(1.0f, float(t - 1.0));
    }
    else if (t < 3.0) {
      uv = vec2(float(3.0 - t), 1.0f);
    }
    else {
      uv = vec2(0.0f, float(4.0 - t));
    }
    r_uv[loop[size_t(k)]] = uv;
    interior_index[size_t(loop[size_t(k)])] = -2;
  }
  int32_t interior_num = 0;
  for (int32_t &index : interior_index) {
    if (index == -1) {
      index = interior_num++;
    }
  }

  if (interior_num > 0) {
    /* Interior: Σ_j w_ij (φ_j − φ_i) = 0, w_ij = (cot α_ij + cot β_ij) / 2. */
    std::vector<Eigen::Triplet<double>> entries;
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(interior_num, 2);
    for (const ivec3 &tri : triangles) {
      for (int k = 0; k < 3; k++) {
        const int32_t apex = tri[k], a = tri[(k + 1) % 3], b = tri[(k + 2) % 3];
        const double w = 0.5 * clamped_cotangent(vertices[apex], vertices[a], vertices[b]);
        const int32_t ia = interior_index[size_t(a)], ib = interior_index[size_t(b)];
        /* Edge (a, b) with weight w. */
        for (const auto &[row, other, irow, iother] :
             {std::tuple{a, b, ia, ib}, std::tuple{b, a, ib, ia}})
        {
          if (irow < 0) {
            continue;
          }
          entries.emplace_back(irow, irow, w);
          if (iother >= 0) {
            entries.emplace_back(irow, iother, -w);
          }
          else {
            rhs(irow, 0) += w * double(r_uv[other].x);
            rhs(irow, 1) += w * double(r_uv[other].y);
          }
          (void)row;
        }
      }
    }
    Eigen::SparseMatrix<double> laplacian(interior_num, interior_num);
    laplacian.setFromTriplets(entries.begin(), entries.end());
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(laplacian);
    if (solver.info() != Eigen::Success) {
      return false;
    }
    const Eigen::MatrixXd solution = solver.solve(rhs);
    if (solver.info() != Eigen::Success) {
      return false;
    }
    for (int64_t v = 0; v < vertices.size(); v++) {
      const int32_t i = interior_index[size_t(v)];
      if (i >= 0) {
        r_uv[v] = vec2(float(solution(i, 0)), float(solution(i, 1)));
      }
    }
  }

  /* The loop may run clockwise on the square: mirror (u ↔ v) so every triangle keeps the
   * patch's orientation. The boundary stays on the square. */
  double signed_area = 0.0;
  for (const ivec3 &tri : triangles) {
    const vec2 e1 = r_uv[tri.y] - r_uv[tri.x], e2 = r_uv[tri.z] - r_uv[tri.x];
    signed_area += double(e1.x * e2.y - e1.y * e2.x);
  }
  if (signed_area < 0.0) {
    for (vec2 &uv : r_uv) {
      uv = vec2(uv.y, uv.x);
    }
  }
  return true;
}

ScalpMap::ScalpMap(const Span<vec3> vertices, const Span<ivec3> triangles,
                   const Span<float> weights)
    : vertices_(vertices.begin(), vertices.end()),
      triangles_(triangles.begin(), triangles.end()),
      weights_(weights.is_empty() ? std::vector<float>(size_t(vertices.size()), 1.0f) :
                                    std::vector<float>(weights.begin(), weights.end())),
      vertex_normals_(size_t(vertices.size()), vec3(0.0f)),
      uv_(size_t(vertices.size()), vec2(0.0f)),
      triangle_areas_(size_t(triangles.size()), 0.0f)
{
  assert(find_scalp_error(vertices, triangles).empty());
  valid_ = compute_harmonic_map(vertices, triangles, uv_);
  for (size_t t = 0; t < triangles_.size(); t++) {
    const ivec3 &tri = triangles_[t];
    const vec3 n = glm::cross(vertices_[size_t(tri.y)] - vertices_[size_t(tri.x)],
                              vertices_[size_t(tri.z)] - vertices_[size_t(tri.x)]);
    triangle_areas_[t] = 0.5f * glm::length(n);
    area_ += triangle_areas_[t];
    for (int k = 0; k < 3; k++) {
      vertex_normals_[size_t(tri[k])] += n; /* Area-weighted. */
    }
  }
  for (vec3 &n : vertex_normals_) {
    const float len = glm::length(n);
    n = len > 0.0f ? n / len : vec3(0.0f, 0.0f, 1.0f);
  }

  /* Grid over D for φ⁻¹. */
  grid_res_ = std::max(1, int32_t(std::sqrt(double(triangles_.size()))));
  const auto cell_range = [&](const size_t t, int32_t r_lo[2], int32_t r_hi[2]) {
    const ivec3 &tri = triangles_[t];
    const vec2 lo = glm::min(uv_[size_t(tri.x)], glm::min(uv_[size_t(tri.y)], uv_[size_t(tri.z)]));
    const vec2 hi = glm::max(uv_[size_t(tri.x)], glm::max(uv_[size_t(tri.y)], uv_[size_t(tri.z)]));
    for (int a = 0; a < 2; a++) {
      r_lo[a] = std::clamp(int32_t(std::floor(lo[a] * float(grid_res_) - 1e-4f)), 0, grid_res_ - 1);
      r_hi[a] = std::clamp(int32_t(std::floor(hi[a] * float(grid_res_) + 1e-4f)), 0, grid_res_ - 1);
    }
  };
  cell_offsets_.assign(size_t(grid_res_ * grid_res_) + 1, 0);
  for (int pass = 0; pass < 2; pass++) {
    std::vector<int32_t> cursor(cell_offsets_.begin(), cell_offsets_.end() - 1);
    for (size_t t = 0; t < triangles_.size(); t++) {
      int32_t lo[2], hi[2];
      cell_range(t, lo, hi);
      for (int32_t y = lo[1]; y <= hi[1]; y++) {
        for (int32_t x = lo[0]; x <= hi[0]; x++) {
          const size_t cell = size_t(y * grid_res_ + x);
          if (pass == 0) {
            cell_offsets_[cell + 1]++;
          }
          else {
            cell_triangles_[size_t(cursor[cell]++)] = int32_t(t);
          }
        }
      }
    }
    if (pass == 0) {
      for (size_t c = 0; c + 1 < cell_offsets_.size(); c++) {
        cell_offsets_[c + 1] += cell_offsets_[c];
      }
      cell_triangles_.resize(size_t(cell_offsets_.back()));
    }
  }
}

ScalpPoint ScalpMap::point_in_triangle(const int64_t tri_index, const vec3 &bary,
                                       vec2 &r_uv) const
{
  const ivec3 &tri = triangles_[size_t(tri_index)];
  ScalpPoint point;
  point.position = bary.x * vertices_[size_t(tri.x)] + bary.y * vertices_[size_t(tri.y)] +
                   bary.z * vertices_[size_t(tri.z)];
  point.normal = glm::normalize(bary.x * vertex_normals_[size_t(tri.x)] +
                                bary.y * vertex_normals_[size_t(tri.y)] +
                                bary.z * vertex_normals_[size_t(tri.z)] + vec3(1e-12f));
  point.weight = bary.x * weights_[size_t(tri.x)] + bary.y * weights_[size_t(tri.y)] +
                 bary.z * weights_[size_t(tri.z)];
  r_uv = bary.x * uv_[size_t(tri.x)] + bary.y * uv_[size_t(tri.y)] + bary.z * uv_[size_t(tri.z)];
  return point;
}

/* Barycentric coordinates of p in the 2D triangle (a, b, c). */
static vec3 barycentric(const vec2 &p, const vec2 &a, const vec2 &b, const vec2 &c)
{
  const vec2 e1 = b - a, e2 = c - a, d = p - a;
  const float det = e1.x * e2.y - e1.y * e2.x;
  if (std::abs(det) < 1e-20f) {
    return vec3(-1.0f);
  }
  const float l1 = (d.x * e2.y - d.y * e2.x) / det;
  const float l2 = (e1.x * d.y - e1.y * d.x) / det;
  return vec3(1.0f - l1 - l2, l1, l2);
}

ScalpPoint ScalpMap::locate(const vec2 &uv) const
{
  const int32_t x = std::clamp(int32_t(uv.x * float(grid_res_)), 0, grid_res_ - 1);
  const int32_t y = std::clamp(int32_t(uv.y * float(grid_res_)), 0, grid_res_ - 1);
  const size_t cell = size_t(y * grid_res_ + x);
  /* The containing triangle, or (at the edge of the square, within rounding) the one the
   * point is least outside of, with clamped coordinates. */
  float best_score = -std::numeric_limits<float>::infinity();
  int32_t best_tri = cell_triangles_.empty() ? 0 : cell_triangles_[size_t(cell_offsets_[cell])];
  vec3 best_bary(1.0f / 3.0f);
  const auto consider = [&](const int32_t t) {
    const ivec3 &tri = triangles_[size_t(t)];
    const vec3 b = barycentric(uv, uv_[size_t(tri.x)], uv_[size_t(tri.y)], uv_[size_t(tri.z)]);
    const float score = std::min(b.x, std::min(b.y, b.z));
    if (score > best_score) {
      best_score = score;
      best_tri = t;
      best_bary = b;
    }
  };
  for (int32_t k = cell_offsets_[cell]; k < cell_offsets_[cell + 1]; k++) {
    consider(cell_triangles_[size_t(k)]);
  }
  if (best_score < -1e-3f) {
    for (size_t t = 0; t < triangles_.size(); t++) {
      consider(int32_t(t));
    }
  }
  best_bary = glm::max(best_bary, vec3(0.0f));
  best_bary /= std::max(best_bary.x + best_bary.y + best_bary.z, 1e-12f);
  vec2 unused;
  return point_in_triangle(best_tri, best_bary, unused);
}

}  // namespace hairdyn
