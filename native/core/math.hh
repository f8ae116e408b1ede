#pragma once
/* GLM types used across the core. Points are packed 12-byte vec3 so that an (N, 3) float32
 * numpy array or Blender's position attribute is a vec3 array without conversion. */
#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

namespace hairdyn {

using glm::ivec3;
using glm::mat3;
using glm::mat4;
using glm::vec3;
using glm::vec4;

static_assert(sizeof(vec3) == 12, "vec3 must be packed: it maps onto (N, 3) float32 arrays");
static_assert(sizeof(mat4) == 64, "mat4 must be 16 packed floats");

/* Affine transform of a point (w = 1). */
inline vec3 transform_point(const mat4 &m, const vec3 &p)
{
  return vec3(m * vec4(p, 1.0f));
}

inline bool is_finite(const vec3 &v)
{
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

}  // namespace hairdyn
