#pragma once
/* The cylindrical representation of a collider part (Kurihara 1993 §3.1): in map space
 * (r, θ, y), an m × n table of the radius and normal of the part's surface at azimuth θ_i and
 * height y_j, made by casting a ray from the axis outwards and keeping the OUTERMOST hit. A
 * ray that misses leaves its cell empty, and no query near it reports a collision.
 *
 * Samples: θ_i = 2π i / m (i = 0 .. m-1, wrapping), y_j = y_min + (j + ½) h with
 * h = (y_max - y_min) / n, where [y_min, y_max] is the part's extent along the axis. Points
 * outside that height range are never inside. */
#include "collision/radial_map.hh"

namespace hairdyn {

class CylinderMap {
 public:
  CylinderMap() = default;
  /* Builds the table for the triangles (object space) around `frame`'s axis. The BVH holds
   * exactly these triangles. */
  CylinderMap(const TriangleBVH &bvh, Span<vec3> vertices, Span<ivec3> triangles,
              const MapFrame &frame, int32_t azimuth_num, int32_t height_num);

  const MapFrame &frame() const { return frame_; }
  const RadialTable &table() const { return table_; }
  float height_min() const { return y_min_; }
  float height_max() const { return y_max_; }
  bool is_empty() const { return table_.u_num() == 0; }

  /* Signed depth at p (map space) wherever the map is defined (within the height range, next
   * to filled cells); false elsewhere. */
  bool evaluate_map(const vec3 &p_cyl, MapSample &r_sample) const
  {
    return sample_map(p_cyl, false, r_sample);
  }

  /* Inside test and contact (Kurihara 1993 §3.1): true when P is inside, with eq. 11's
   * nearest surface point T, depth |PT| along N and N. */
  bool find_contact_map(const vec3 &p_cyl, MapSample &r_sample) const
  {
    /* Cheap rejections first: most hair nodes are far outside. */
    if (p_cyl.x * p_cyl.x + p_cyl.z * p_cyl.z >= max_radius_sq_) {
      return false;
    }
    return sample_map(p_cyl, true, r_sample);
  }

  /* Object-space conveniences (not for the per-step path). */
  bool evaluate(const vec3 &p_object, MapSample &r_sample) const;

 private:
  /* With inside_only, returns false for points outside before computing the normal. */
  bool sample_map(const vec3 &p_cyl, const bool inside_only, MapSample &r_sample) const
  {
    if (!(p_cyl.y >= y_min_ && p_cyl.y <= y_max_)) {
      return false;
    }
    /* (r_p, θ_p, y_p) of P. */
    const float r_p = std::sqrt(p_cyl.x * p_cyl.x + p_cyl.z * p_cyl.z);
    const float theta = fast_atan2(p_cyl.z, p_cyl.x);
    float u = theta * u_per_radian_;
    u = u < 0.0f ? u + float(table_.u_num()) : u;
    const float v = std::min(std::max((p_cyl.y - y_min_) * v_per_unit_ - 0.5f, 0.0f),
                             float(table_.v_num() - 1));
    float r_q;
    RadialTable::Stencil stencil;
    if (!table_.lookup_radius(u, v, r_q, stencil) || (inside_only && !(r_p < r_q))) {
      return false;
    }
    const vec3 normal = RadialTable::normal(stencil);
    /* Q: same azimuth and height as P, at radius r_q. */
    const vec3 radial = r_p > 0.0f ? vec3(p_cyl.x, 0.0f, p_cyl.z) * (1.0f / r_p) :
                                     vec3(1.0f, 0.0f, 0.0f);
    const vec3 q(radial.x * r_q, p_cyl.y, radial.z * r_q);
    finish_sample(p_cyl, q, normal, r_p < r_q, r_sample);
    return true;
  }

  MapFrame frame_;
  mat4 object_to_map_{1.0f};
  RadialTable table_;
  float y_min_ = 0.0f, y_max_ = -1.0f;
  float u_per_radian_ = 0.0f;
  float v_per_unit_ = 0.0f;
  float max_radius_sq_ = 0.0f;
};

}  // namespace hairdyn
