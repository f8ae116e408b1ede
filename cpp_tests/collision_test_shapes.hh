#pragma once
/* Meshes for the collision tests and benchmarks: analytic shapes built in code, and a tiny OBJ
 * reader for the Sintel head, which is read from the shared data folder at test time. */
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "collision/mesh.hh"

namespace hairdyn::test {

struct TestMesh {
  std::vector<vec3> vertices;
  std::vector<ivec3> triangles;
};

/* UV sphere around the origin, outward winding: 2 · segments · (rings - 1) triangles. */
inline TestMesh uv_sphere(const float radius, const int segments, const int rings)
{
  TestMesh mesh;
  mesh.vertices.emplace_back(0.0f, radius, 0.0f);
  for (int r = 1; r < rings; r++) {
    const double phi = M_PI * r / rings;
    for (int s = 0; s < segments; s++) {
      const double theta = 2.0 * M_PI * s / segments;
      mesh.vertices.emplace_back(float(radius * std::sin(phi) * std::cos(theta)),
                                 float(radius * std::cos(phi)),
                                 float(radius * std::sin(phi) * std::sin(theta)));
    }
  }
  mesh.vertices.emplace_back(0.0f, -radius, 0.0f);
  const int south = int(mesh.vertices.size()) - 1;
  const auto ring_vertex = [&](int r, int s) { return 1 + (r - 1) * segments + (s % segments); };
  for (int s = 0; s < segments; s++) {
    mesh.triangles.emplace_back(0, ring_vertex(1, s + 1), ring_vertex(1, s));
    mesh.triangles.emplace_back(south, ring_vertex(rings - 1, s), ring_vertex(rings - 1, s + 1));
  }
  for (int r = 1; r < rings - 1; r++) {
    for (int s = 0; s < segments; s++) {
      const int a = ring_vertex(r, s), b = ring_vertex(r, s + 1);
      const int c = ring_vertex(r + 1, s), d = ring_vertex(r + 1, s + 1);
      mesh.triangles.emplace_back(a, b, d);
      mesh.triangles.emplace_back(a, d, c);
    }
  }
  return mesh;
}

/* Closed cylinder along y, centred on the origin, with fan caps; outward winding. When
 * `azimuth_fraction` < 1 only that share of the side wall is made (an open shell, no caps). */
inline TestMesh closed_cylinder(const float radius, const float height, const int segments,
                                const int stacks, const double azimuth_fraction = 1.0)
{
  TestMesh mesh;
  const bool closed = azimuth_fraction >= 1.0;
  const int columns = closed ? segments : int(segments * azimuth_fraction) + 1;
  for (int k = 0; k <= stacks; k++) {
    const float y = -0.5f * height + height * float(k) / float(stacks);
    for (int s = 0; s < columns; s++) {
      const double theta = 2.0 * M_PI * s / segments;
      mesh.vertices.emplace_back(float(radius * std::cos(theta)), y, float(radius * std::sin(theta)));
    }
  }
  const auto vertex = [&](int k, int s) { return k * columns + (closed ? s % segments : s); };
  for (int k = 0; k < stacks; k++) {
    for (int s = 0; s < (closed ? segments : columns - 1); s++) {
      const int a = vertex(k, s), b = vertex(k, s + 1), c = vertex(k + 1, s), d = vertex(k + 1, s + 1);
      mesh.triangles.emplace_back(a, c, d);
      mesh.triangles.emplace_back(a, d, b);
    }
  }
  if (closed) {
    const int bottom = int(mesh.vertices.size());
    mesh.vertices.emplace_back(0.0f, -0.5f * height, 0.0f);
    const int top = bottom + 1;
    mesh.vertices.emplace_back(0.0f, 0.5f * height, 0.0f);
    for (int s = 0; s < segments; s++) {
      mesh.triangles.emplace_back(bottom, vertex(0, s), vertex(0, s + 1));
      mesh.triangles.emplace_back(top, vertex(stacks, s + 1), vertex(stacks, s));
    }
  }
  return mesh;
}

/* Axis-aligned box [-h, h]^3 with 12 outward triangles. */
inline TestMesh box(const vec3 &h)
{
  TestMesh mesh;
  for (int i = 0; i < 8; i++) {
    mesh.vertices.emplace_back(i & 1 ? h.x : -h.x, i & 2 ? h.y : -h.y, i & 4 ? h.z : -h.z);
  }
  mesh.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                    {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  return mesh;
}

/* Appends b's vertices and triangles to a. */
inline void append(TestMesh &a, const TestMesh &b)
{
  const int offset = int(a.vertices.size());
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (const ivec3 &t : b.triangles) {
    a.triangles.push_back(t + ivec3(offset));
  }
}

/* v and f lines of an OBJ file (f entries "i", "i/t", "i//n", "i/t/n"; polygons fanned into
 * triangles). False when the file cannot be opened. */
inline bool read_obj(const std::string &path, TestMesh &r_mesh)
{
  std::ifstream file(path);
  if (!file) {
    return false;
  }
  std::string line;
  while (std::getline(file, line)) {
    std::istringstream in(line);
    std::string tag;
    in >> tag;
    if (tag == "v") {
      vec3 v;
      in >> v.x >> v.y >> v.z;
      r_mesh.vertices.push_back(v);
    }
    else if (tag == "f") {
      std::vector<int> corners;
      std::string token;
      while (in >> token) {
        corners.push_back(std::stoi(token.substr(0, token.find('/'))) - 1);
      }
      for (size_t k = 2; k < corners.size(); k++) {
        r_mesh.triangles.emplace_back(corners[0], corners[k - 1], corners[k]);
      }
    }
  }
  return true;
}

inline const char *sintel_folder = HAIRDYN_SHARED_DATA "/sintel";
inline const char *sintel_bust_path = HAIRDYN_SHARED_DATA "/sintel/sintel_bust.obj";

}  // namespace hairdyn::test
