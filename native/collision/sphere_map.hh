#pragma once
/* The spherical representation Kurihara 1993 §5 suggests for parts a cylinder describes badly,
 * such as the top of the head: r as a function of the azimuth θ around the map's y axis and
 * the polar angle φ from it, with the same m × n table, bilinear look-up (eq. 8–10) and
 * nearest-point approximation (eq. 11) as the cylindrical map. Rays start at the centre and
 * keep the outermost hit; a missed ray leaves its cell empty.
 *
 * Samples: θ_i = 2π i / m (wrapping), φ_j = (j + ½) π / n, plus one ray along each pole
 * (φ = 0 and φ = π): within half a row of a pole the first or last row is blended linearly
 * into the pole's sample, so the normal there does not inherit the row's tilt. */
#include "collision/radial_map.hh"

namespace hairdyn {

class SphereMap {
 public:
  SphereMap() = default;
  /* Builds the table around frame.origin. The BVH holds exactly these triangles. */
  SphereMap(const TriangleBVH &bvh, Span<vec3> vertices, Span<ivec3> triangles,
            const MapFrame &frame, int32_t azimuth_num, int32_t polar_num);

  const MapFrame &frame() const { return frame_; }
  const RadialTable &table() const { return table_; }
  bool is_empty() const { return table_.u_num() == 0; }

  /* Signed depth at p (map space, relative to the centre) next to filled cells. */
  bool evaluate_map(const vec3 &p_sph, MapSample &r_sample) const
  {
    MapBatch<1> b = single_point_batch(p_sph);
    sample<false>(b);
    return read_sample(b, 0, r_sample);
  }

  /* Inside test and eq. 11 contact, as CylinderMap::find_contact_map. */
  bool find_contact_map(const vec3 &p_sph, MapSample &r_sample) const
  {
    MapBatch<1> b = single_point_batch(p_sph);
    sample<true>(b);
    return read_sample(b, 0, r_sample);
  }

  bool evaluate(const vec3 &p_object, MapSample &r_sample) const;

  /* The batched look-up (see MapBatch): with inside_only, valid only where P is inside. */
  template<bool inside_only, int64_t N> HAIRDYN_BATCH_INLINE void sample(MapBatch<N> &b) const
  {
    const float max_radius_sq = max_radius_sq_;
    const RadialTable::Shape shape = table_.shape();
    const float u_per_radian = u_per_radian_, v_per_radian = v_per_radian_;
    const float v_last = float(table_.v_num() - 1);
    /* Whether any point is within half a row of a pole (few are: the pole blend below is
     * skipped for batches with none). */
    int32_t any_near_pole = 0;
    /* Short loops, one step each (see MapBatch). Beyond the largest radius P is never
     * inside: compared squared, the square roots are taken only for the points looked up. */
    for (int64_t k = 0; k < b.size; k++) {
      const float x = b.x[k], y = b.y[k], z = b.z[k];
      const float r_sq = (x * x + z * z) + y * y;
      b.defined[k] = inside_only ? (r_sq < max_radius_sq ? 1 : 0) : 1;
    }
    bool compacted = false;
    if constexpr (inside_only && N > 1) {
      compacted = compact_defined(b);
    }
    /* r_p = |P| and, in v for now, P's distance from the pole axis. */
    for (int64_t k = 0; k < b.size; k++) {
      const float x = b.x[k], y = b.y[k], z = b.z[k];
      const float rho_xz_sq = x * x + z * z;
      b.r_p[k] = std::sqrt(rho_xz_sq + y * y);
      b.v[k] = std::sqrt(rho_xz_sq);
    }
    /* φ from the pole axis and θ around it, in one loop. */
    for (int64_t k = 0; k < b.size; k++) {
      const float v = fast_atan2(b.v[k], b.y[k]) * v_per_radian - 0.5f;
      b.v[k] = v;
      any_near_pole |= (v < 0.0f ? 1 : 0) | (v > v_last ? 1 : 0);
      b.u[k] = fast_atan2(b.z[k], b.x[k]) * u_per_radian;
    }
    for (int64_t k = 0; k < b.size; k++) {
      RadialTable::locate(shape, b, k, b.u[k], b.v[k]);
    }
    if constexpr (N == 1) {
      /* A single point (the per-point calls) stops here when it cannot be inside. */
      if (!b.defined[0]) {
        b.valid[0] = 0;
        return;
      }
    }
    table_.blend(b);
    if (any_near_pole) {
      blend_poles(b);
    }
    normalise_normals<inside_only>(b);
    for (int64_t k = 0; k < b.size; k++) {
      /* Q: same direction from the centre as P, at radius r_q. */
      const float r_p = b.r_p[k];
      const bool off_centre = r_p > 0.0f;
      const float inv_r = 1.0f / (off_centre ? r_p : 1.0f);
      const float ux = b.x[k] * inv_r, uy = b.y[k] * inv_r, uz = b.z[k] * inv_r;
      const float dx = off_centre ? ux : 0.0f;
      const float dy = off_centre ? uy : 1.0f;
      const float dz = off_centre ? uz : 0.0f;
      set_depth(b, k, dx * b.r_q[k], dy * b.r_q[k], dz * b.r_q[k]);
    }
    if (compacted) {
      expand_defined(b);
    }
  }

 private:
  /* Within half a row of a pole, r_q and N of the first (last) row blended linearly into the
   * pole's sample. */
  template<int64_t N> HAIRDYN_BATCH_INLINE void blend_poles(MapBatch<N> &b) const
  {
    const float v_last = float(table_.v_num() - 1);
    const MapCell north = north_, south = south_;
    for (int64_t k = 0; k < b.size; k++) {
      /* Between the first (last) row and the pole: w = 1 at the pole. */
      const float v = b.v[k];
      const bool is_north = v < 0.0f;
      const bool near_pole = is_north | (v > v_last);
      const float w_north = -2.0f * v, w_south = 2.0f * (v - v_last);
      const float w = is_north ? w_north : w_south;
      const float pole_radius = is_north ? north.radius : south.radius;
      b.defined[k] &= (!near_pole | (pole_radius >= 0.0f)) ? 1 : 0;
      const float r_q = b.r_q[k];
      const float r_q_pole = r_q + w * (pole_radius - r_q);
      b.r_q[k] = near_pole ? r_q_pole : r_q;
      /* Near a pole, the row's normal (normalised) blended toward the pole's;
       * normalise_normals normalises. */
      const float nx = b.nx[k], ny = b.ny[k], nz = b.nz[k];
      const float inv = 1.0f / std::sqrt(nx * nx + ny * ny + nz * nz);
      const float mx = nx * inv, my = ny * inv, mz = nz * inv;
      const float px = is_north ? north.normal.x : south.normal.x;
      const float py = is_north ? north.normal.y : south.normal.y;
      const float pz = is_north ? north.normal.z : south.normal.z;
      const float bx = mx + w * (px - mx), by = my + w * (py - my), bz = mz + w * (pz - mz);
      b.nx[k] = near_pole ? bx : nx;
      b.ny[k] = near_pole ? by : ny;
      b.nz[k] = near_pole ? bz : nz;
    }
  }

  MapFrame frame_;
  mat4 object_to_map_{ 1.0f };
  RadialTable table_;
  MapCell north_, south_; /* The rays along +y and -y. */
  float u_per_radian_ = 0.0f;
  float v_per_radian_ = 0.0f;
  float max_radius_sq_ = 0.0f;
};

}  // namespace hairdyn
