#include "collision/cylinder_map_kurihara1993.hh"

#include <algorithm>
#include <limits>

#include "core/parallel.hh"

namespace hairdyn {

CylinderMap::CylinderMap(const TriangleBVH &bvh, const Span<vec3> vertices,
                         const Span<ivec3> triangles, const MapFrame &frame,
                         const int32_t azimuth_num, const int32_t height_num)
    : frame_(frame), object_to_map_(frame.object_to_map()), table_(azimuth_num, height_num)
{
  assert(azimuth_num > 0 && height_num > 0 && !triangles.is_empty());
  /* Height range: the part's extent along the axis. */
  y_min_ = std::numeric_limits<float>::max();
  y_max_ = -std::numeric_limits<float>::max();
  for (const ivec3 &tri : triangles) {
    for (int k = 0; k < 3; k++) {
      const float y = transform_point(object_to_map_, vertices[tri[k]]).y;
      y_min_ = std::min(y_min_, y);
      y_max_ = std::max(y_max_, y);
    }
  }
  const float h = (y_max_ - y_min_) / float(height_num);
  u_per_radian_ = float(azimuth_num) / float(2.0 * M_PI);
  v_per_unit_ = h > 0.0f ? 1.0f / h : 0.0f;

  const mat4 map_to_object = frame.map_to_object();
  /* One ray per cell: from the axis at height y_j, outwards at azimuth θ_i (Kurihara 1993,
   * Figure 5), keeping the outermost hit. */
  parallel_for(height_num, 1, [&](const IndexRange rows) {
    for (int32_t j = int32_t(rows.start); j < int32_t(rows.one_after_last()); j++) {
      const float y = y_min_ + (float(j) + 0.5f) * h;
      for (int32_t i = 0; i < azimuth_num; i++) {
        const double theta = 2.0 * M_PI * double(i) / double(azimuth_num);
        const vec3 direction(float(std::cos(theta)), 0.0f, float(std::sin(theta)));
        fill_cell_from_ray(bvh, vertices, triangles, map_to_object, vec3(0.0f, y, 0.0f),
                           direction, table_.cell_for_write(i, j));
      }
    }
  });
  table_.finish_build();
  max_radius_sq_ = table_.max_radius() * table_.max_radius();
}

bool CylinderMap::evaluate(const vec3 &p_object, MapSample &r_sample) const
{
  return evaluate_map(transform_point(object_to_map_, p_object), r_sample);
}

}  // namespace hairdyn
