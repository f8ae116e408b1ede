#include "collision/sphere_map.hh"

#include <algorithm>

#include "core/parallel.hh"

namespace hairdyn {

SphereMap::SphereMap(const TriangleBVH &bvh, const Span<vec3> vertices,
                     const Span<ivec3> triangles, const MapFrame &frame,
                     const int32_t azimuth_num, const int32_t polar_num)
    : frame_(frame), object_to_map_(frame.object_to_map()), table_(azimuth_num, polar_num)
{
  assert(azimuth_num > 0 && polar_num > 0 && !triangles.is_empty());
  u_per_radian_ = float(azimuth_num) / float(2.0 * M_PI);
  v_per_radian_ = float(polar_num) / float(M_PI);
  const mat4 map_to_object = frame.map_to_object();
  parallel_for(polar_num, 1, [&](const IndexRange rows) {
    for (int32_t j = int32_t(rows.start); j < int32_t(rows.one_after_last()); j++) {
      const double phi = M_PI * (double(j) + 0.5) / double(polar_num);
      for (int32_t i = 0; i < azimuth_num; i++) {
        const double theta = 2.0 * M_PI * double(i) / double(azimuth_num);
        const vec3 direction(float(std::sin(phi) * std::cos(theta)), float(std::cos(phi)),
                             float(std::sin(phi) * std::sin(theta)));
        fill_cell_from_ray(bvh, vertices, triangles, map_to_object, vec3(0.0f), direction,
                           table_.cell_for_write(i, j));
      }
    }
  });
  fill_cell_from_ray(bvh, vertices, triangles, map_to_object, vec3(0.0f), vec3(0, 1, 0), north_);
  fill_cell_from_ray(bvh, vertices, triangles, map_to_object, vec3(0.0f), vec3(0, -1, 0), south_);
  table_.finish_build();
  const float max_radius = std::max(table_.max_radius(), std::max(north_.radius, south_.radius));
  max_radius_sq_ = max_radius * max_radius;
}

bool SphereMap::evaluate(const vec3 &p_object, MapSample &r_sample) const
{
  return evaluate_map(transform_point(object_to_map_, p_object), r_sample);
}

}  // namespace hairdyn
