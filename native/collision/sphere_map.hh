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
    return sample_map(p_sph, false, r_sample);
  }

  /* Inside test and eq. 11 contact, as CylinderMap::find_contact_map. */
  bool find_contact_map(const vec3 &p_sph, MapSample &r_sample) const
  {
    if (glm::dot(p_sph, p_sph) >= max_radius_sq_) {
      return false;
    }
    return sample_map(p_sph, true, r_sample);
  }

  bool evaluate(const vec3 &p_object, MapSample &r_sample) const;

 private:
  bool sample_map(const vec3 &p_sph, const bool inside_only, MapSample &r_sample) const
  {
    const float rho_xz_sq = p_sph.x * p_sph.x + p_sph.z * p_sph.z;
    const float rho_xz = std::sqrt(rho_xz_sq);
    const float r_p = std::sqrt(rho_xz_sq + p_sph.y * p_sph.y);
    float u = fast_atan2(p_sph.z, p_sph.x) * u_per_radian_;
    u = u < 0.0f ? u + float(table_.u_num()) : u;
    const float phi = fast_atan2(rho_xz, p_sph.y);
    const float v_last = float(table_.v_num() - 1);
    const float v = phi * v_per_radian_ - 0.5f;
    float r_q;
    RadialTable::Stencil stencil;
    if (!table_.lookup_radius(u, std::min(std::max(v, 0.0f), v_last), r_q, stencil)) {
      return false;
    }
    /* Between the first (last) row and the pole: w = 1 at the pole. */
    const bool near_pole = v < 0.0f || v > v_last;
    const MapCell &pole = v < 0.0f ? north_ : south_;
    const float w = v < 0.0f ? -2.0f * v : 2.0f * (v - v_last);
    if (near_pole) {
      if (pole.radius < 0.0f) {
        return false;
      }
      r_q += w * (pole.radius - r_q);
    }
    if (inside_only && !(r_p < r_q)) {
      return false;
    }
    vec3 normal = RadialTable::normal(stencil);
    if (near_pole) {
      normal = glm::normalize(normal + w * (pole.normal - normal));
    }
    /* Q: same direction from the centre as P, at radius r_q. */
    const vec3 direction = r_p > 0.0f ? p_sph * (1.0f / r_p) : vec3(0.0f, 1.0f, 0.0f);
    finish_sample(p_sph, direction * r_q, normal, r_p < r_q, r_sample);
    return true;
  }

  MapFrame frame_;
  mat4 object_to_map_{1.0f};
  RadialTable table_;
  MapCell north_, south_; /* The rays along +y and -y. */
  float u_per_radian_ = 0.0f;
  float v_per_radian_ = 0.0f;
  float max_radius_sq_ = 0.0f;
};

}  // namespace hairdyn
