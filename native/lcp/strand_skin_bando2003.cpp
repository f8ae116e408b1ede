#include "lcp/strand_skin_bando2003.hh"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/parallel.hh"
#include "core/spatial_grid.hh"
#include "groom/groom.hh"
#include "groom/pins.hh"

namespace hairdyn {

void find_k_nearest(const Span<vec3> points, const Span<float> points_w, const Span<vec3> queries,
                    const Span<float> queries_w, int k, std::vector<int32_t> &r_indices,
                    std::vector<float> &r_distances)
{
  const int64_t n = points.size();
  k = int(std::min<int64_t>(k, n));
  r_indices.assign(size_t(queries.size() * k), -1);
  r_distances.assign(size_t(queries.size() * k), 0.0f);
  if (k <= 0) {
    return;
  }
  vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
  for (const vec3 &p : points) {
    lo = glm::min(lo, p);
    hi = glm::max(hi, p);
  }
  const float extent = std::max(std::max(hi.x - lo.x, hi.y - lo.y), hi.z - lo.z);
  /* First guess: the spacing of n points spread through the points' box, times k. */
  float radius = std::max(extent * std::cbrt(float(k) / float(n)), 1e-6f);
  std::vector<int64_t> pending(size_t(queries.size()));
  std::iota(pending.begin(), pending.end(), 0);
  std::vector<uint8_t> done;
  SpatialGrid grid;
  while (!pending.empty()) {
    grid.build(points, radius);
    done.assign(pending.size(), 0);
    parallel_for(int64_t(pending.size()), 256, [&](const IndexRange range) {
      std::vector<std::pair<float, int32_t>> found;
      for (int64_t a = range.start; a < range.one_after_last(); a++) {
        const int64_t q = pending[size_t(a)];
        found.clear();
        grid.for_each_in_radius(queries[q], radius, [&](const int32_t j) {
          const vec3 d = points[j] - queries[q];
          const float dw = points_w[j] - queries_w[q];
          const float distance = std::sqrt(glm::dot(d, d) + dw * dw);
          if (distance < radius) {
            found.emplace_back(distance, j);
          }
        });
        /* Any point nearer than `radius` in 4D is nearer in 3D, so was visited: with k of
         * them found (or every point), the k nearest are certain. */
        if (int64_t(found.size()) < k && int64_t(found.size()) < n) {
          continue;
        }
        std::partial_sort(found.begin(), found.begin() + k, found.end());
        for (int c = 0; c < k; c++) {
          r_indices[size_t(q * k + c)] = found[size_t(c)].second;
          r_distances[size_t(q * k + c)] = found[size_t(c)].first;
        }
        done[size_t(a)] = 1;
      }
    });
    size_t kept = 0;
    for (size_t a = 0; a < pending.size(); a++) {
      if (!done[a]) {
        pending[kept++] = pending[a];
      }
    }
    pending.resize(kept);
    radius *= 2.0f;
  }
}

/* Inverse-distance weights over each row of k, summing to 1. */
static void blend_weights(const std::vector<float> &distances, const int k,
                          std::vector<double> &r_weights)
{
  r_weights.resize(distances.size());
  for (size_t row = 0; row + size_t(k) <= distances.size(); row += size_t(k)) {
    double sum = 0.0;
    for (int c = 0; c < k; c++) {
      r_weights[row + size_t(c)] = 1.0 / std::max(double(distances[row + size_t(c)]), 1e-6);
      sum += r_weights[row + size_t(c)];
    }
    for (int c = 0; c < k; c++) {
      r_weights[row + size_t(c)] /= sum;
    }
  }
}

static glm::dvec3 transform_point(const glm::dmat4 &m, const vec3 &p)
{
  return glm::dvec3(m * glm::dvec4(glm::dvec3(p), 1.0));
}

ParticleSkin::ParticleSkin(const Span<int32_t> curve_offsets, const Span<vec3> points_wo,
                           const Span<vec3> particles_wo, const Span<vec3> directions_wo,
                           const Span<float> u, const Span<float> v, const Span<float> s,
                           const mat4 &head_to_world, const int neighbours_num,
                           const bool shape_from_particles) :
    curve_offsets_(curve_offsets.begin(), curve_offsets.end()),
    shape_from_particles_(shape_from_particles), neighbours_num_(neighbours_num)
{
  const int64_t points_num = points_wo.size(), particles_num = particles_wo.size();
  const int64_t curves_num = curve_offsets.size() - 1;
  /* Each strand point as (its root, its arc length). */
  rest_lengths_.assign(size_t(points_num), 0.0);
  std::vector<vec3> strand_roots(static_cast<size_t>(points_num));
  std::vector<float> arc(static_cast<size_t>(points_num));
  for (int64_t c = 0; c < curves_num; c++) {
    const IndexRange points = curve_points(curve_offsets, c);
    double length = 0.0;
    for (int64_t i = points.start; i < points.one_after_last(); i++) {
      if (i > points.start) {
        rest_lengths_[size_t(i)] = glm::length(glm::dvec3(points_wo[i]) - glm::dvec3(points_wo[i - 1]));
      }
      length += rest_lengths_[size_t(i)];
      strand_roots[size_t(i)] = points_wo[points.start];
      arc[size_t(i)] = float(length);
    }
  }
  /* Each particle as (where its hair leaves the scalp, s). */
  std::vector<vec3> scalp(static_cast<size_t>(particles_num));
  std::vector<int32_t> roots, free;
  for (int64_t j = 0; j < particles_num; j++) {
    scalp[size_t(j)] = particles_wo[j] - s[j] * directions_wo[j];
    (s[j] < 0.0f ? roots : free).push_back(int32_t(j));
  }
  if (!roots.empty() && !free.empty()) {
    std::vector<vec3> root_uv, free_uv;
    for (const int32_t j : roots) {
      root_uv.emplace_back(u[j], v[j], 0.0f);
    }
    for (const int32_t j : free) {
      free_uv.emplace_back(u[j], v[j], 0.0f);
    }
    const std::vector<float> no_w(std::max(roots.size(), free.size()), 0.0f);
    std::vector<int32_t> near;
    std::vector<float> distances;
    std::vector<double> weights;
    find_k_nearest(root_uv, Span<float>(no_w.data(), int64_t(roots.size())), free_uv,
                   Span<float>(no_w.data(), int64_t(free.size())), 3, near, distances);
    const int k = int(distances.size() / free.size());
    blend_weights(distances, k, weights);
    std::vector<vec3> root_scalp(roots.size());
    for (size_t a = 0; a < roots.size(); a++) {
      root_scalp[a] = scalp[size_t(roots[a])];
    }
    for (size_t a = 0; a < free.size(); a++) {
      glm::dvec3 sum(0.0);
      for (int c = 0; c < k; c++) {
        sum += weights[a * size_t(k) + size_t(c)] * glm::dvec3(root_scalp[size_t(near[a * size_t(k) + size_t(c)])]);
      }
      scalp[size_t(free[a])] = vec3(sum);
    }
  }
  std::vector<float> distances;
  find_k_nearest(scalp, s, strand_roots, arc, neighbours_num, neighbours_, distances);
  neighbours_num_ = int(std::min<int64_t>(neighbours_num, particles_num));
  blend_weights(distances, neighbours_num_, weights_);

  const glm::dmat4 to_head = glm::inverse(glm::dmat4(head_to_world));
  rest_head_.resize(size_t(points_num));
  particles_rest_head_.resize(size_t(particles_num));
  for (int64_t i = 0; i < points_num; i++) {
    rest_head_[size_t(i)] = transform_point(to_head, points_wo[i]);
  }
  for (int64_t j = 0; j < particles_num; j++) {
    particles_rest_head_[size_t(j)] = transform_point(to_head, particles_wo[j]);
  }
  if (shape_from_particles) {
    arc_.assign(arc.begin(), arc.end());
    particle_s_.assign(s.begin(), s.end());
  }
}

void ParticleSkin::set_pinned(const Span<uint8_t> pinned)
{
  assert(pinned.is_empty() || pinned.size() == points_num());
  pinned_.assign(pinned.begin(), pinned.end());
  for (size_t c = 0; c + 1 < curve_offsets_.size() && !pinned_.empty(); c++) {
    pinned_[size_t(curve_offsets_[c])] = 0; /* the root is held anyway */
  }
  if (std::none_of(pinned_.begin(), pinned_.end(), [](const uint8_t p) { return p != 0; })) {
    pinned_.clear();
  }
}

glm::dvec3 ParticleSkin::carried(const int64_t i, const Span<vec3> particles_wo,
                                 const Span<vec3> directions_wo, const glm::dmat4 &to_world) const
{
  const int k = neighbours_num_;
  glm::dvec3 target(0.0);
  if (shape_from_particles_) {
    /* The blend of its particles, each taken along its direction to the point's arc length
     * (a tip beyond the last particles is not pulled back among them). */
    for (int a = 0; a < k; a++) {
      const size_t entry = size_t(i) * size_t(k) + size_t(a);
      const int32_t j = neighbours_[entry];
      target += weights_[entry] *
                (glm::dvec3(particles_wo[j]) + (arc_[size_t(i)] - double(particle_s_[size_t(j)])) *
                                                   glm::dvec3(directions_wo[j]));
    }
    return target;
  }
  /* Carried by its particles' displacements, in the head's space. */
  target = rest_head_[size_t(i)];
  for (int a = 0; a < k; a++) {
    const size_t entry = size_t(i) * size_t(k) + size_t(a);
    target += weights_[entry] * moved_[size_t(neighbours_[entry])];
  }
  return glm::dvec3(to_world * glm::dvec4(target, 1.0));
}

void ParticleSkin::apply(const Span<vec3> particles_wo, const mat4 &head_to_world,
                         const ColliderSet *colliders, const MutableSpan<vec3> r_points_wo,
                         const Span<vec3> directions_wo)
{
  assert(!shape_from_particles_ || directions_wo.size() == particles_wo.size());
  const glm::dmat4 to_world(head_to_world);
  const glm::dmat4 to_head = glm::inverse(to_world);
  moved_.resize(shape_from_particles_ ? 0 : particles_rest_head_.size());
  parallel_for(int64_t(moved_.size()), 4096, [&](const IndexRange range) {
    for (int64_t j = range.start; j < range.one_after_last(); j++) {
      moved_[size_t(j)] = transform_point(to_head, particles_wo[j]) - particles_rest_head_[size_t(j)];
    }
  });
  const int64_t curves_num = int64_t(curve_offsets_.size()) - 1;
  parallel_for(curves_num, 64, [&](const IndexRange range) {
    std::vector<glm::dvec3> strand; /* a strand's points while pins move them */
    for (int64_t c = range.start; c < range.one_after_last(); c++) {
      const IndexRange points = curve_points(curve_offsets_, c);
      glm::dvec3 previous = glm::dvec3(to_world * glm::dvec4(rest_head_[size_t(points.start)], 1.0));
      r_points_wo[points.start] = vec3(previous);
      strand.assign(size_t(points.size), previous);
      int64_t held = points.start; /* the root, then the last pin */
      for (int64_t i = points.start + 1; i < points.one_after_last(); i++) {
        const double rest_length = rest_lengths_[size_t(i)];
        const auto toward = [&](const glm::dvec3 &goal) {
          const glm::dvec3 step = goal - previous;
          return previous + step * (rest_length / std::max(glm::length(step), 1e-12));
        };
        glm::dvec3 point = toward(carried(i, particles_wo, directions_wo, to_world));
        /* Swung out of the body where it went inside (twice at most). */
        for (int attempt = 0; colliders != nullptr && attempt < 2; attempt++) {
          Contact contact;
          if (!colliders->find_contact(vec3(point), contact) || !(contact.depth > 0.0f)) {
            break;
          }
          point = toward(glm::dvec3(contact.surface_point_wo + 1e-4f * contact.normal_wo));
        }
        strand[size_t(i - points.start)] = point;
        if (!pinned_.empty() && pinned_[size_t(i)]) {
          /* Carried by the head; the points since the last held one reach it. */
          const int64_t n = i - held + 1;
          double length = 0.0;
          for (int64_t m = held + 1; m <= i; m++) {
            length += rest_lengths_[size_t(m)];
          }
          reach_pin(MutableSpan<glm::dvec3>(strand).slice(held - points.start, n),
                    Span<double>(rest_lengths_).slice(held, n),
                    glm::dvec3(to_world * glm::dvec4(rest_head_[size_t(i)], 1.0)),
                    1e-9 * length);
          held = i;
          point = strand[size_t(i - points.start)];
        }
        previous = point;
      }
      for (int64_t i = points.start + 1; i < points.one_after_last(); i++) {
        r_points_wo[i] = vec3(strand[size_t(i - points.start)]);
      }
    }
  });
}

}  // namespace hairdyn
