#pragma once
/* Scenes for the level-of-detail tests and benchmark (Ward & Lin 2003): a head sphere with a
 * cap of strands, and cameras around it. */
#include <cmath>
#include <memory>
#include <vector>

#include "collision/collider.hh"
#include "collision_test_shapes.hh"
#include "core/math.hh"

namespace hairdyn::test {

/* `strands_num` strands of `points_num` points rooted on a Fibonacci spiral over the cap of a
 * sphere of radius `head_radius` at the origin (polar angle up to `cap` rad): each leaves the
 * scalp along its normal, leans outward and bends down. Segments are `segment` m long. */
struct CapGroom {
  std::vector<int32_t> offsets{0};
  std::vector<vec3> positions;
  std::vector<vec3> normals;

  CapGroom(const int strands_num, const int points_num, const float head_radius = 0.1f,
           const float segment = 0.02f, const float cap = 1.3f)
  {
    const float golden = float(M_PI) * (3.0f - std::sqrt(5.0f));
    for (int s = 0; s < strands_num; s++) {
      const float z = 1.0f - (1.0f - std::cos(cap)) * (float(s) + 0.5f) / float(strands_num);
      const float ring = std::sqrt(std::max(1.0f - z * z, 0.0f));
      const float azimuth = golden * float(s);
      const vec3 n(ring * std::cos(azimuth), ring * std::sin(azimuth), z);
      const vec3 out = glm::normalize(vec3(std::cos(azimuth), std::sin(azimuth), 0.0f));
      vec3 p = head_radius * n;
      positions.push_back(p);
      for (int i = 1; i < points_num; i++) {
        const float e = std::exp(-float(i) / 3.0f);
        p += segment * glm::normalize(e * n + 0.5f * out + (1.0f - e) * vec3(0.0f, 0.0f, -1.0f));
        positions.push_back(p);
      }
      offsets.push_back(int32_t(positions.size()));
      normals.push_back(n);
    }
  }
  int64_t strands_num() const { return int64_t(offsets.size()) - 1; }
  /* The root's unit normal of strand s. */
  vec3 normal(const int64_t s) const { return normals[size_t(s)]; }
};

/* The head as one collider: a sphere slightly inside the scalp. */
inline std::shared_ptr<ColliderSet> head_colliders(const float radius = 0.095f)
{
  const TestMesh sphere = uv_sphere(radius, 32, 16);
  const ColliderMesh mesh(sphere.vertices, sphere.triangles);
  auto colliders = std::make_shared<ColliderSet>();
  colliders->add(std::make_shared<Collider>(mesh, Span<int32_t>(), Span<int32_t>(),
                                            CollisionParams()));
  return colliders;
}

/* A perspective camera at `eye` looking at `target` (60° field of view, Z up), as Blender's
 * projection @ view matrix. */
inline mat4 camera_view_projection(const vec3 &eye, const vec3 &target = vec3(0.0f))
{
  const vec3 forward = glm::normalize(target - eye);
  const vec3 up = std::abs(forward.z) > 0.99f ? vec3(0.0f, 1.0f, 0.0f) : vec3(0.0f, 0.0f, 1.0f);
  return glm::perspective(glm::radians(60.0f), 1.0f, 0.01f, 1000.0f) * glm::lookAt(eye, target, up);
}

}  // namespace hairdyn::test
