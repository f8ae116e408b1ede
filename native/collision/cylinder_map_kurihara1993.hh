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
    MapBatch<1> b = single_point_batch(p_cyl);
    sample<false>(b);
    return read_sample(b, 0, r_sample);
  }

  /* Inside test and contact (Kurihara 1993 §3.1): true when P is inside, with eq. 11's
   * nearest surface point T, depth |PT| along N and N. */
  bool find_contact_map(const vec3 &p_cyl, MapSample &r_sample) const
  {
    MapBatch<1> b = single_point_batch(p_cyl);
    sample<true>(b);
    return read_sample(b, 0, r_sample);
  }

  /* Object-space conveniences (not for the per-step path). */
  bool evaluate(const vec3 &p_object, MapSample &r_sample) const;

  /* The batched look-up (see MapBatch): with inside_only, valid only where P is inside. */
  template<bool inside_only, int64_t N> HAIRDYN_BATCH_INLINE void sample(MapBatch<N> &b) const
  {
    const float y_min = y_min_, y_max = y_max_, max_radius_sq = max_radius_sq_;
    const RadialTable::Shape shape = table_.shape();
    const float u_per_radian = u_per_radian_, v_per_unit = v_per_unit_;
    /* Short loops, one step each (see MapBatch). */
    for (int64_t k = 0; k < b.size; k++) {
      /* Outside the height range or beyond the largest radius P is never inside (compared
       * squared: the square root is taken only for the points looked up). */
      const float x = b.x[k], y = b.y[k], z = b.z[k];
      const float r_sq = x * x + z * z;
      b.defined[k] = (y >= y_min ? 1 : 0) & (y <= y_max ? 1 : 0) &
                     (inside_only ? (r_sq < max_radius_sq ? 1 : 0) : 1);
    }
    bool compacted = false;
    if constexpr (inside_only && N > 1) {
      compacted = compact_defined(b);
    }
    /* (r_p, θ_p, y_p) of P. */
    for (int64_t k = 0; k < b.size; k++) {
      b.r_p[k] = std::sqrt(b.x[k] * b.x[k] + b.z[k] * b.z[k]);
    }
    for (int64_t k = 0; k < b.size; k++) {
      b.u[k] = fast_atan2(b.z[k], b.x[k]) * u_per_radian;
    }
    for (int64_t k = 0; k < b.size; k++) {
      RadialTable::locate(shape, b, k, b.u[k], (b.y[k] - y_min) * v_per_unit - 0.5f);
    }
    if constexpr (N == 1) {
      /* A single point (the per-point calls) stops here when it cannot be inside. */
      if (!b.defined[0]) {
        b.valid[0] = 0;
        return;
      }
    }
    table_.blend(b);
    normalise_normals<inside_only>(b);
    for (int64_t k = 0; k < b.size; k++) {
      /* Q: same azimuth and height as P, at radius r_q. */
      const float r_p = b.r_p[k], r_q = b.r_q[k];
      const bool off_axis = r_p > 0.0f;
      const float inv_r = 1.0f / (off_axis ? r_p : 1.0f);
      const float rx = b.x[k] * inv_r, rz = b.z[k] * inv_r;
      const float radial_x = off_axis ? rx : 1.0f;
      const float radial_z = off_axis ? rz : 0.0f;
      set_depth(b, k, radial_x * r_q, b.y[k], radial_z * r_q);
    }
    if (compacted) {
      expand_defined(b);
    }
  }

 private:
  MapFrame frame_;
  mat4 object_to_map_{ 1.0f };
  RadialTable table_;
  float y_min_ = 0.0f, y_max_ = -1.0f;
  float u_per_radian_ = 0.0f;
  float v_per_unit_ = 0.0f;
  float max_radius_sq_ = 0.0f;
};

}  // namespace hairdyn
