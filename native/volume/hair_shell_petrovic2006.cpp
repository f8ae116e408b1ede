#include "volume/hair_shell_petrovic2006.hh"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/parallel.hh"
#include "groom/frames.hh"
#include "groom/groom.hh"

namespace hairdyn {

namespace {

constexpr float far_away = std::numeric_limits<float>::max();

}  // namespace

void signed_distance_fast_sweeping(const ivec3 &size, const float cell_size,
                                   const Span<float> density, const float threshold,
                                   const MutableSpan<float> r_distance)
{
  const int64_t strides[3] = {1, int64_t(size.x), int64_t(size.x) * size.y};
  const auto index = [&](const ivec3 &v) { return v.x + v.y * strides[1] + v.z * strides[2]; };
  const int64_t vertices_num = int64_t(size.x) * size.y * size.z;
  const auto phi = [&](const int64_t v) { return density[v] - threshold; };
  /* Per vertex, the nearest point of the shell found so far (grid units); NaN for none. */
  const vec3 none(std::numeric_limits<float>::quiet_NaN());
  std::vector<vec3> closest(static_cast<size_t>(vertices_num), none);

  /* Vertices next to the shell (an edge to a neighbour crosses phi = 0): one Newton step of
   * phi = density − threshold onto its zero set, with phi's central-difference gradient. */
  parallel_for(size.z, slab_grain(size), [&](const IndexRange slices) {
    for (int k = int(slices.start); k < int(slices.one_after_last()); k++) {
      for (int j = 0; j < size.y; j++) {
        for (int i = 0; i < size.x; i++) {
          const ivec3 v(i, j, k);
          const int64_t vi = index(v);
          bool on_shell = false;
          vec3 gradient;
          for (int axis = 0; axis < 3; axis++) {
            const int lo = std::max(v[axis] - 1, 0), hi = std::min(v[axis] + 1, size[axis] - 1);
            const float lo_phi = phi(vi + (lo - v[axis]) * strides[axis]);
            const float hi_phi = phi(vi + (hi - v[axis]) * strides[axis]);
            on_shell |= (lo_phi > 0.0f) != (phi(vi) > 0.0f) || (hi_phi > 0.0f) != (phi(vi) > 0.0f);
            gradient[axis] = hi > lo ? (hi_phi - lo_phi) / float(hi - lo) : 0.0f;
          }
          const float g2 = glm::dot(gradient, gradient);
          if (on_shell && g2 > 0.0f) {
            const vec3 step = -phi(vi) * gradient / g2;
            /* The shell is within a cell of a vertex next to it. */
            closest[size_t(vi)] = vec3(v) + (glm::length(step) < 1.0f ? step :
                                                                       glm::normalize(step));
          }
        }
      }
    }
  });

  /* Fast sweeping of the closest points (Tsai 2002): in the 8 alternating orderings, a vertex
   * takes a neighbour's closest point when it is nearer than its own. Two rounds. */
  for (int round = 0; round < 2; round++) {
    for (int ordering = 0; ordering < 8; ordering++) {
      const ivec3 step((ordering & 1) ? -1 : 1, (ordering & 2) ? -1 : 1, (ordering & 4) ? -1 : 1);
      const ivec3 first((step.x > 0) ? 0 : size.x - 1, (step.y > 0) ? 0 : size.y - 1,
                        (step.z > 0) ? 0 : size.z - 1);
      for (int k = first.z; k >= 0 && k < size.z; k += step.z) {
        for (int j = first.y; j >= 0 && j < size.y; j += step.y) {
          for (int i = first.x; i >= 0 && i < size.x; i += step.x) {
            const vec3 x = vec3(float(i), float(j), float(k));
            const int64_t vi = index(ivec3(i, j, k));
            vec3 &own = closest[size_t(vi)];
            float own_distance = std::isnan(own.x) ? far_away : glm::length(own - x);
            for (int axis = 0; axis < 3; axis++) {
              const int at = int(x[axis]) - step[axis]; /* the upwind neighbour */
              if (at < 0 || at >= size[axis]) {
                continue;
              }
              const vec3 &candidate = closest[size_t(vi - step[axis] * strides[axis])];
              if (!std::isnan(candidate.x) && glm::length(candidate - x) < own_distance) {
                own = candidate;
                own_distance = glm::length(candidate - x);
              }
            }
          }
        }
      }
    }
  }

  /* The handed-on point is the nearest shell point of a neighbour, not quite this vertex's own:
   * refine it by stepping onto the neighbour point's tangent plane toward the vertex and then
   * back onto the shell with Newton steps on the trilinear phi. */
  const auto sample = [&](const vec3 &p, vec3 &r_gradient) {
    const ivec3 cell = glm::clamp(ivec3(glm::floor(p)), ivec3(0), size - 2);
    const vec3 f = glm::clamp(p - vec3(cell), vec3(0.0f), vec3(1.0f));
    float value = 0.0f;
    r_gradient = vec3(0.0f);
    for (int c = 0; c < 8; c++) {
      const ivec3 corner(c & 1, (c >> 1) & 1, (c >> 2) & 1);
      const vec3 w(corner.x ? f.x : 1.0f - f.x, corner.y ? f.y : 1.0f - f.y,
                   corner.z ? f.z : 1.0f - f.z);
      const vec3 dw(corner.x ? 1.0f : -1.0f, corner.y ? 1.0f : -1.0f, corner.z ? 1.0f : -1.0f);
      const float value_c = phi(index(cell + corner));
      value += w.x * w.y * w.z * value_c;
      r_gradient += value_c * dw * vec3(w.y * w.z, w.x * w.z, w.x * w.y);
    }
    return value;
  };
  parallel_for(vertices_num, grid_grain, [&](const IndexRange range) {
    for (int64_t v = range.start; v < range.one_after_last(); v++) {
      vec3 &c = closest[size_t(v)];
      if (std::isnan(c.x)) {
        continue;
      }
      const vec3 x = vec3(float(v % size.x), float((v / size.x) % size.y), float(v / strides[2]));
      vec3 gradient;
      sample(c, gradient);
      if (glm::dot(gradient, gradient) == 0.0f) {
        continue;
      }
      const vec3 n = glm::normalize(gradient);
      vec3 y = x - glm::dot(x - c, n) * n;
      for (int iteration = 0; iteration < 3; iteration++) {
        const float value = sample(y, gradient);
        const float g2 = glm::dot(gradient, gradient);
        if (g2 == 0.0f) {
          break;
        }
        y -= value * gradient / g2;
      }
      if (glm::all(glm::greaterThanEqual(y, vec3(0.0f))) &&
          glm::all(glm::lessThanEqual(y, vec3(size - 1))) && glm::length(y - x) < glm::length(c - x))
      {
        c = y;
      }
    }
  });

  /* S in meters, negative inside the hair (§4.1). */
  parallel_for(vertices_num, grid_grain, [&](const IndexRange range) {
    for (int64_t v = range.start; v < range.one_after_last(); v++) {
      const vec3 x(float(v % size.x), float((v / size.x) % size.y), float(v / strides[2]));
      const vec3 &c = closest[size_t(v)];
      const float distance = std::isnan(c.x) ? far_away : cell_size * glm::length(c - x);
      r_distance[v] = phi(v) > 0.0f ? -distance : distance;
    }
  });
}

void shell_normals_at(const GridFrame &grid, const Span<float> distance,
                      const Span<vec3> positions_wo, const vec3 &center_wo,
                      const MutableSpan<vec3> r_normals_wo)
{
  const ivec3 n = grid.size;
  /* ∇S at the vertices by central differences (one-sided on the border), per grid unit. */
  std::vector<vec3> gradient(static_cast<size_t>(grid.vertices_num()));
  parallel_for(n.z, slab_grain(n), [&](const IndexRange slices) {
    for (int k = int(slices.start); k < int(slices.one_after_last()); k++) {
      for (int j = 0; j < n.y; j++) {
        for (int i = 0; i < n.x; i++) {
          const ivec3 v(i, j, k);
          vec3 g;
          for (int axis = 0; axis < 3; axis++) {
            ivec3 lo = v, hi = v;
            lo[axis] = std::max(v[axis] - 1, 0);
            hi[axis] = std::min(v[axis] + 1, n[axis] - 1);
            const float span = float(hi[axis] - lo[axis]);
            g[axis] = span > 0.0f ? (distance[grid.vertex_index(hi.x, hi.y, hi.z)] -
                                     distance[grid.vertex_index(lo.x, lo.y, lo.z)]) /
                                        span :
                                    0.0f;
          }
          gradient[size_t(grid.vertex_index(i, j, k))] = g;
        }
      }
    }
  });
  const mat3 rotation(grid.head_to_world);
  parallel_for(positions_wo.size(), point_grain, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      const vec3 g = rotation * sample_grid(grid, Span<vec3>(gradient), grid.to_grid(positions_wo[i]));
      const float length = glm::length(g);
      if (length > 1e-6f && std::isfinite(length)) {
        r_normals_wo[i] = g / length; /* eq. 2 */
        continue;
      }
      const vec3 outward = positions_wo[i] - center_wo;
      r_normals_wo[i] = glm::length(outward) > 0.0f ? glm::normalize(outward) : vec3(0, 0, 1);
    }
  });
}

void transport_frames(const Span<int32_t> curve_offsets, const Span<vec3> positions_wo,
                      const Span<mat3> root_frames_wo, const MutableSpan<mat3> r_frames_wo)
{
  parallel_for(curve_offsets.size() - 1, 512, [&](const IndexRange range) {
    for (int64_t curve = range.start; curve < range.one_after_last(); curve++) {
      const IndexRange points = curve_points(curve_offsets, curve);
      mat3 frame = root_frames_wo[curve];
      for (int64_t p = points.start; p < points.one_after_last() - 1; p++) {
        frame = parallel_transport(frame, glm::normalize(positions_wo[p + 1] - positions_wo[p]));
        r_frames_wo[p] = frame;
      }
      r_frames_wo[points.one_after_last() - 1] = frame;
    }
  });
}

HairShell::HairShell(const Span<int32_t> curve_offsets, const Span<vec3> rest_positions_wo,
                     const mat4 &head_to_world_rest, const VolumeParams &params)
    : curve_offsets_(curve_offsets.begin(), curve_offsets.end())
{
  const mat4 head_to_world = rigid_head_to_world(head_to_world_rest);
  const mat4 world_to_head = glm::inverse(head_to_world);
  const float cell_size = params.shell_cell_size > 0.0f ?
                              params.shell_cell_size :
                              4.0f * std::max(mean_segment_length(curve_offsets, rest_positions_wo),
                                              min_segment_length(rest_positions_wo));
  /* Room outside the hair for the blurred density to fall below the threshold. */
  grid_ = grid_around(head_box(rest_positions_wo, world_to_head), cell_size,
                      params.shell_blur + 2, head_to_world);

  PointBins bins;
  bin_points(grid_, rest_positions_wo, bins);
  density_.resize(size_t(grid_.vertices_num()));
  std::vector<float> scratch;
  splat_density(grid_, bins, density_, scratch);
  blur_binomial(grid_.size, params.shell_blur, density_, scratch);
  distance_.resize(density_.size());
  signed_distance_fast_sweeping(grid_.size, grid_.cell_size, density_, params.shell_threshold,
                                distance_);

  const int64_t points_num = rest_positions_wo.size();
  const vec3 center = transform_point(grid_.grid_to_world(), 0.5f * vec3(grid_.size - 1));
  rest_normals_.resize(size_t(points_num));
  shell_normals_at(grid_, distance_, rest_positions_wo, center, rest_normals_);

  /* The root frames, fixed to the head, and the normals' coordinates in the rest frames. */
  const int64_t curves_num = curve_offsets.size() - 1;
  const mat3 rotation_rest(head_to_world);
  root_frames_head_.resize(size_t(curves_num));
  std::vector<mat3> root_frames_wo(static_cast<size_t>(curves_num));
  compute_root_frames(curve_offsets, rest_positions_wo, {}, root_frames_wo);
  std::vector<mat3> frames(static_cast<size_t>(points_num));
  transport_frames(curve_offsets, rest_positions_wo, root_frames_wo, frames);
  local_normals_.resize(size_t(points_num));
  parallel_for(points_num, point_grain, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      local_normals_[size_t(i)] = glm::transpose(frames[size_t(i)]) * rest_normals_[size_t(i)];
    }
  });
  for (int64_t curve = 0; curve < curves_num; curve++) {
    root_frames_head_[size_t(curve)] = glm::transpose(rotation_rest) * root_frames_wo[size_t(curve)];
  }
}

void HairShell::transport(const Span<vec3> positions_wo, const mat4 &head_to_world,
                          const MutableSpan<vec3> r_normals_wo) const
{
  const mat3 rotation(rigid_head_to_world(head_to_world));
  const int64_t curves_num = int64_t(curve_offsets_.size()) - 1;
  std::vector<mat3> root_frames_wo(static_cast<size_t>(curves_num));
  for (int64_t curve = 0; curve < curves_num; curve++) {
    root_frames_wo[size_t(curve)] = rotation * root_frames_head_[size_t(curve)];
  }
  std::vector<mat3> frames(static_cast<size_t>(positions_wo.size()));
  transport_frames(curve_offsets_, positions_wo, root_frames_wo, frames);
  parallel_for(positions_wo.size(), point_grain, [&](const IndexRange range) {
    for (int64_t i = range.start; i < range.one_after_last(); i++) {
      r_normals_wo[i] = frames[size_t(i)] * local_normals_[size_t(i)];
    }
  });
}

}  // namespace hairdyn
