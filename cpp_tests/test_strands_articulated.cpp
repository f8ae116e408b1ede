/* The articulated strand model (strand_dynamics_articulated.cpp) against references computed
 * here: the large-deflection elastica (shooting, checked first against Bisshopp & Drucker's
 * tip-load value), the hanging chain's lowest mode, the compound double pendulum's normal
 * modes; convergence in the segment count, stability at one substep per frame, dissipation. */
#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "groom/groom.hh"
#include "groom/metrics.hh"
#include "strands/strand_solver.hh"

using namespace hairdyn;

namespace {

constexpr double pi = M_PI;

/* ---- references --------------------------------------------------------------------------- */

/* A clamped cantilever, horizontal at its root, in arc length σ ∈ [0, 1] (units of L), θ its
 * angle below the horizontal. Bending moment balance EI θ' = M and M' = −(load beyond σ)·cos θ
 * give θ'' = −q(σ) cos θ with θ(0) = 0 and θ'(1) = 0 (free end), where
 *   own weight, Γ = c g L³ / EI:      q(σ) = Γ (1 − σ)
 *   tip load,  α = P L² / EI:          q(σ) = α.
 * Shooting: integrate from the root with θ'(0) = κ (RK4, 2000 steps), bisect κ until
 * θ'(1) = 0. Returns the tip's drop over L, ∫ sin θ dσ. */
double elastica_tip_drop(const std::function<double(double)> &load)
{
  const auto end_slope = [&](const double kappa, double *r_drop) {
    const int steps = 2000;
    const double ds = 1.0 / steps;
    double theta = 0.0, slope = kappa, drop = 0.0;
    /* State (θ, θ', y). */
    const auto f = [&](const double s, const double th, const double sl, double &dth,
                       double &dsl, double &dy) {
      dth = sl;
      dsl = -load(s) * std::cos(th);
      dy = std::sin(th);
    };
    for (int i = 0; i < steps; i++) {
      const double s = i * ds;
      double k1[3], k2[3], k3[3], k4[3];
      f(s, theta, slope, k1[0], k1[1], k1[2]);
      f(s + 0.5 * ds, theta + 0.5 * ds * k1[0], slope + 0.5 * ds * k1[1], k2[0], k2[1], k2[2]);
      f(s + 0.5 * ds, theta + 0.5 * ds * k2[0], slope + 0.5 * ds * k2[1], k3[0], k3[1], k3[2]);
      f(s + ds, theta + ds * k3[0], slope + ds * k3[1], k4[0], k4[1], k4[2]);
      theta += ds / 6.0 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0]);
      slope += ds / 6.0 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1]);
      drop += ds / 6.0 * (k1[2] + 2 * k2[2] + 2 * k3[2] + k4[2]);
    }
    if (r_drop) {
      *r_drop = drop;
    }
    return slope;
  };
  /* θ'(1) grows with κ; the root curvature lies between 0 and the total load's moment. */
  double lo = 0.0, hi = 0.0;
  for (double s = 0.0; s <= 1.0; s += 1e-3) {
    hi += load(s) * 1e-3;
  }
  hi += 1.0;
  for (int i = 0; i < 100; i++) {
    const double mid = 0.5 * (lo + hi);
    (end_slope(mid, nullptr) < 0.0 ? lo : hi) = mid;
  }
  double drop = 0.0;
  end_slope(0.5 * (lo + hi), &drop);
  return drop;
}

double self_weight_drop(const double gamma)
{
  return elastica_tip_drop([gamma](const double s) { return gamma * (1.0 - s); });
}

/* Small oscillations of two uniform rods (length l, mass m each) hanging from a pivot, angles
 * φ₁, φ₂ from vertical: M φ̈ + K φ = 0 with
 *   M = m l² [4/3 1/2; 1/2 1/3],   K = m g l [3/2 0; 0 1/2]
 * (Lagrangian of the compound double pendulum, linearised). Returns the two ω² and the
 * mode shapes (φ₂ / φ₁). */
void double_pendulum_modes(const double g, const double l, double r_omega2[2], double r_shape[2])
{
  const double m11 = 4.0 / 3.0, m12 = 0.5, m22 = 1.0 / 3.0;
  const double k11 = 1.5 * g / l, k22 = 0.5 * g / l;
  /* det(K − λ M) = 0: a λ² + b λ + c = 0. */
  const double a = m11 * m22 - m12 * m12;
  const double b = -(k11 * m22 + k22 * m11);
  const double c = k11 * k22;
  const double root = std::sqrt(b * b - 4 * a * c);
  r_omega2[0] = (-b - root) / (2 * a);
  r_omega2[1] = (-b + root) / (2 * a);
  for (int i = 0; i < 2; i++) {
    /* (k11 − λ m11) φ₁ − λ m12 φ₂ = 0. */
    r_shape[i] = (k11 - r_omega2[i] * m11) / (r_omega2[i] * m12);
  }
}

/* ---- scenes ------------------------------------------------------------------------------- */

struct Strand {
  std::vector<int32_t> offsets{0};
  std::vector<vec3> positions;
  std::vector<vec3> normals;
};

Strand polyline(const std::vector<vec3> &points, const vec3 &root_normal)
{
  Strand strand;
  strand.positions = points;
  strand.offsets.push_back(int32_t(points.size()));
  strand.normals.push_back(root_normal);
  return strand;
}

Strand straight(const vec3 &root, const vec3 &direction, const float length, const int segments)
{
  std::vector<vec3> points;
  for (int i = 0; i <= segments; i++) {
    points.push_back(root + direction * (length * float(i) / float(segments)));
  }
  return polyline(points, direction);
}

/* Material with Γ = c g L³ / EI = `gamma` for a strand of `length`, human-hair radius and
 * density: E = 4 ρ g L³ / (Γ r²). */
StrandParams material_for_gamma(const double gamma, const double length)
{
  StrandParams params;
  params.youngs_modulus = float(4.0 * params.hair_density * 9.81 * length * length * length /
                                (gamma * double(params.strand_radius) * params.strand_radius));
  return params;
}

/* Times at which x(t) crosses zero (linear interpolation between samples). */
std::vector<double> zero_crossings(const std::vector<double> &x, const double dt)
{
  std::vector<double> times;
  for (size_t i = 1; i < x.size(); i++) {
    if ((x[i - 1] < 0.0) != (x[i] < 0.0)) {
      times.push_back(dt * (double(i - 1) + x[i - 1] / (x[i - 1] - x[i])));
    }
  }
  return times;
}

double angular_frequency(const std::vector<double> &x, const double dt)
{
  const std::vector<double> crossings = zero_crossings(x, dt);
  EXPECT_GE(crossings.size(), 3u);
  if (crossings.size() < 3) {
    return 0.0;
  }
  const double period = 2.0 * (crossings.back() - crossings.front()) /
                        double(crossings.size() - 1);
  return 2.0 * pi / period;
}

/* The clamped horizontal strand's settled tip drop over L. */
double settled_drop(const double gamma, const int segments, const int substeps)
{
  const float length = 0.3f;
  const Strand strand = straight(vec3(0.0f), vec3(1.0f, 0.0f, 0.0f), length, segments);
  StrandParams params = material_for_gamma(gamma, length);
  params.substeps = substeps;
  params.air_drag = 2e-4f; /* settles within the run; drag is no force at rest */
  StrandSolver solver(strand.offsets, strand.positions, mat4(1.0f), strand.normals, params);
  for (int frame = 0; frame < 24 * 8; frame++) {
    solver.step(1.0f / 24.0f, mat4(1.0f));
  }
  return double(-solver.positions().last().z) / length;
}

}  // namespace

TEST(StrandsArticulated, ElasticaReferenceMatchesBisshoppDrucker)
{
  /* Bisshopp & Drucker (1945), cantilever with an end load: PL²/EI = 1 gives a vertical tip
   * deflection of 0.30172 L (linear theory: 1/3). And the small-load limits of the two
   * loadings: α/3 and Γ/8. */
  EXPECT_NEAR(elastica_tip_drop([](double) { return 1.0; }), 0.30172, 2e-4);
  EXPECT_NEAR(elastica_tip_drop([](double) { return 1e-3; }) / 1e-3, 1.0 / 3.0, 1e-3);
  EXPECT_NEAR(self_weight_drop(1e-3) / 1e-3, 1.0 / 8.0, 1e-3);
}

TEST(StrandsArticulated, StaticSagMatchesTheElasticaAtAnyResolution)
{
  for (const double gamma : {1.0, 4.0, 16.0, 32.0}) {
    const double reference = self_weight_drop(gamma);
    for (const int segments : {8, 16, 32}) {
      const double drop = settled_drop(gamma, segments, 4);
      EXPECT_NEAR(drop, reference, 0.05 * reference)
          << "Γ " << gamma << ", " << segments << " segments";
    }
  }
}
