/* Strand dynamics (Kurihara 1993 §2, Ward & Lin 2003 appendix A) against analytic references:
 * rest shape, pendulum periods, spring frequency, energy, stability, inextensibility, inertia. */
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/parallel.hh"
#include "groom/groom.hh"
#include "groom/metrics.hh"
#include "oscillation.hh"
#include "strands/strand_solver.hh"

using namespace hairdyn;

namespace {

constexpr float pi = float(M_PI);

struct Groom {
  std::vector<int32_t> offsets{0};
  std::vector<vec3> positions;
  std::vector<vec3> normals;

  void add(const std::vector<vec3> &strand, const vec3 &normal = vec3(0.0f))
  {
    positions.insert(positions.end(), strand.begin(), strand.end());
    offsets.push_back(int32_t(positions.size()));
    normals.push_back(normal);
  }
};

/* A straight strand from `root` along `direction`. */
std::vector<vec3> straight(const vec3 &root, const vec3 &direction, const float length,
                           const int segments)
{
  std::vector<vec3> points;
  for (int i = 0; i <= segments; i++) {
    points.push_back(root + glm::normalize(direction) * (length * float(i) / float(segments)));
  }
  return points;
}

/* A helix hanging from `root`: a curl of radius 1 cm, 1.5 cm pitch. */
std::vector<vec3> curl(const vec3 &root, const int segments)
{
  std::vector<vec3> points;
  for (int i = 0; i <= segments; i++) {
    const float t = float(i) * 0.5f;
    points.push_back(root + vec3(0.01f * (std::cos(t) - 1.0f), 0.01f * std::sin(t),
                                 -0.015f * t / (2.0f * pi)));
  }
  return points;
}

/* A wave in the x-z plane, combed sideways and down. */
std::vector<vec3> wave(const vec3 &root, const int segments)
{
  std::vector<vec3> points;
  for (int i = 0; i <= segments; i++) {
    const float s = 0.02f * float(i);
    points.push_back(root + vec3(0.5f * s, 0.01f * std::sin(s * 40.0f), -s));
  }
  return points;
}

/* Straight, curly and wavy strands, one growing back into the head (the chart's worst case). */
Groom mixed_groom()
{
  Groom groom;
  groom.add(straight(vec3(0.0f, 0.0f, 0.1f), vec3(0.2f, 0.1f, 1.0f), 0.3f, 16),
            vec3(0.3f, 0.1f, 1.0f));
  groom.add(curl(vec3(0.05f, 0.0f, 0.1f), 24), vec3(0.0f, 0.0f, 1.0f));
  groom.add(wave(vec3(-0.05f, 0.02f, 0.1f), 12), vec3(-1.0f, 0.0f, 0.2f));
  groom.add(straight(vec3(0.0f, 0.05f, 0.1f), vec3(0.0f, 0.0f, -1.0f), 0.2f, 8),
            vec3(0.0f, 0.0f, 1.0f));
  return groom;
}

/* These tests are of the kurihara1993 model (Kurihara 1993 §2), which keeps today's behaviour;
 * the articulated model has its own (test_strands_articulated.cpp). */
StrandParams kurihara_params()
{
  StrandParams params;
  params.model = StrandModel::Kurihara1993;
  return params;
}

StrandParams quiet_params()
{
  StrandParams params = kurihara_params();
  params.gravity = vec3(0.0f);
  params.air_drag = 0.0f;
  params.form_drag = 0.0f;
  params.damping = 0.0f;
  params.k_theta = 0.0f;
  params.k_phi = 0.0f;
  return params;
}

float max_distance(const Span<vec3> a, const Span<vec3> b)
{
  float result = 0.0f;
  for (int64_t i = 0; i < a.size(); i++) {
    result = std::max(result, glm::length(a[i] - b[i]));
  }
  return result;
}

/* Period of a single segment of length L, released at rest `amplitude` from hanging, measured
 * on the tip's x. `explicit_normal` decides which angle of the chart carries the swing: the
 * default normal (the segment itself) puts the swing on φ, a vertical normal on θ. */
double pendulum_period(const float amplitude, const bool explicit_normal)
{
  const float length = 0.1f;
  Groom groom;
  groom.add({vec3(0.0f), length * vec3(std::sin(amplitude), 0.0f, -std::cos(amplitude))},
            vec3(0.0f, 0.0f, -1.0f));
  StrandParams params = quiet_params();
  params.gravity = vec3(0.0f, 0.0f, -9.81f);
  params.integrator = Integrator::Explicit;
  params.substeps = 4;
  StrandSolver solver(groom.offsets, groom.positions, mat4(1.0f),
                      explicit_normal ? Span<vec3>(groom.normals) : Span<vec3>(), params);
  const float frame_dt = 1.0f / 240.0f;
  std::vector<double> x;
  for (int frame = 0; frame < 240 * 3; frame++) {
    solver.step(frame_dt, mat4(1.0f));
    x.push_back(double(solver.positions()[1].x));
  }
  return test::period_from_crossings(test::zero_crossings(x, frame_dt));
}

/* Model energy of every segment: ½ I (ω_θ² + ω_φ²) + ½ (k_θ θ² + k_φ φ²) + c d g z_centre.
 * Kurihara's equations of motion dissipate exactly this at rate γ (ω_θ² + ω_φ²). */
double model_energy(const StrandSolver &solver)
{
  const StrandParams &p = solver.params();
  double energy = 0.0;
  for (int64_t curve = 0; curve < solver.curves_num(); curve++) {
    const IndexRange points = curve_points(solver.curve_offsets(), curve);
    for (int64_t i = points.start + 1; i < points.one_after_last(); i++) {
      const vec2 q = solver.angles()[i];
      const vec2 w = solver.angular_velocities()[i];
      const double d = solver.segment_length(i);
      const double z = 0.5 * double(solver.positions()[i - 1].z + solver.positions()[i].z);
      energy += 0.5 * double(solver.moment_of_inertia(i)) * double(w.x * w.x + w.y * w.y) +
                0.5 * double(p.k_theta * q.x * q.x + p.k_phi * q.y * q.y) +
                double(p.line_density) * d * double(-p.gravity.z) * z;
    }
  }
  return energy;
}

}  // namespace

TEST(Strands, RestShapeHoldsWithoutGravity)
{
  /* Straight, wavy and curly strands on a head that is rotated, moved and scaled at rest and
   * stays there: nothing may drift, curls included, for ten seconds at 24 fps. */
  const Groom groom = mixed_groom();
  const mat4 head = glm::scale(glm::rotate(glm::translate(mat4(1.0f), vec3(0.3f, -1.0f, 1.5f)),
                                           0.8f, glm::normalize(vec3(1.0f, 2.0f, 0.5f))),
                               vec3(1.2f));
  std::vector<vec3> rest_wo;
  for (const vec3 &p : groom.positions) {
    rest_wo.push_back(transform_point(head, p));
  }
  std::vector<vec3> normals_wo;
  for (const vec3 &n : groom.normals) {
    normals_wo.push_back(glm::normalize(mat3(head) * n));
  }
  for (const Integrator integrator : {Integrator::Explicit, Integrator::Implicit}) {
    StrandParams params = kurihara_params();
    params.gravity = vec3(0.0f);
    params.integrator = integrator;
    StrandSolver solver(groom.offsets, rest_wo, head, normals_wo, params);
    for (int frame = 0; frame < 240; frame++) {
      solver.step(1.0f / 24.0f, head);
    }
    EXPECT_LE(max_distance(solver.positions(), rest_wo), 1e-5f) << int(integrator);
    /* The same shape rebuilt from angles after a reset to the head's pose. */
    solver.reset(head);
    EXPECT_LE(max_distance(solver.positions(), rest_wo), 1e-5f) << int(integrator);

    /* The counterpart: the same setup with gravity does move, by centimetres in a second. */
    params.gravity = vec3(0.0f, 0.0f, -9.81f);
    solver.set_params(params);
    for (int frame = 0; frame < 24; frame++) {
      solver.step(1.0f / 24.0f, head);
    }
    EXPECT_GE(max_distance(solver.positions(), rest_wo), 0.01f) << int(integrator);
  }
}

TEST(Strands, SmallPendulumPeriod)
{
  /* A rigid rod swinging about its end: T = 2π √(2L / 3g) (I = c L³/3, load c L g at L/2),
   * times 1 + A²/16 for amplitude A. Both angles of the chart must give it. */
  const double length = 0.1;
  const double amplitude = 5.0 * M_PI / 180.0;
  const double expected = 2.0 * M_PI * std::sqrt(2.0 * length / (3.0 * 9.81)) *
                          (1.0 + amplitude * amplitude / 16.0);
  EXPECT_NEAR(pendulum_period(float(amplitude), false) / expected, 1.0, 0.01);
  EXPECT_NEAR(pendulum_period(float(amplitude), true) / expected, 1.0, 0.01);
}

TEST(Strands, LargePendulumPeriodRatio)
{
  /* Released horizontal (90°): T / T0 = 2 K(sin 45°) / π = 1.18034. With the vertical normal
   * the swing passes through the chart's pole, where φ is undefined: θ must carry it. */
  const double small = pendulum_period(float(2.0 * M_PI / 180.0), false);
  EXPECT_NEAR(pendulum_period(0.5f * pi, false) / small, 1.18034, 0.01 * 1.18034);
  EXPECT_NEAR(pendulum_period(0.5f * pi, true) / small, 1.18034, 0.01 * 1.18034);
}

TEST(Strands, SpringFrequency)
{
  /* No gravity, a hinge spring: θ and φ oscillate at √(k/I), each with its own constant. */
  Groom groom;
  groom.add(straight(vec3(0.0f), vec3(0.3f, 0.2f, -1.0f), 0.1f, 1));
  for (const Integrator integrator : {Integrator::Explicit, Integrator::Implicit}) {
    StrandParams params = quiet_params();
    params.k_theta = 4e-7f;
    params.k_phi = 1.6e-6f;
    params.integrator = integrator;
    params.substeps = 8;
    StrandSolver solver(groom.offsets, groom.positions, mat4(1.0f), {}, params);
    solver.angles_for_write()[1] = vec2(0.1f, -0.05f);
    const float frame_dt = 1.0f / 240.0f;
    std::vector<double> theta, phi;
    for (int frame = 0; frame < 480; frame++) {
      solver.step(frame_dt, mat4(1.0f));
      theta.push_back(double(solver.angles()[1].x));
      phi.push_back(double(solver.angles()[1].y));
    }
    const double inertia = double(solver.moment_of_inertia(1));
    const double omega_theta = 2.0 * M_PI /
                               test::period_from_crossings(test::zero_crossings(theta, frame_dt));
    const double omega_phi = 2.0 * M_PI /
                             test::period_from_crossings(test::zero_crossings(phi, frame_dt));
    EXPECT_NEAR(omega_theta / std::sqrt(double(params.k_theta) / inertia), 1.0, 0.01);
    EXPECT_NEAR(omega_phi / std::sqrt(double(params.k_phi) / inertia), 1.0, 0.01);
  }
}

TEST(Strands, DampingNeverAddsEnergy)
{
  /* Gravity, springs and damping (30% of critical) on segments thrown out of rest: the model
   * energy may only go down, step after step, with either integrator, over 1,000 steps at
   * 240 Hz. A single swinging segment (nonlinear gravity) and a wavy chain without gravity
   * (independent hinges) are both checked. Damping must outweigh the integrators' O(h) energy
   * error for this to hold: with γ = 0 the explicit energy oscillates and this test fails. */
  Groom pendulum;
  pendulum.add(straight(vec3(0.0f), vec3(1.0f, 0.0f, -1.0f), 0.05f, 1));
  Groom chain;
  chain.add(wave(vec3(0.0f), 8));
  for (const Integrator integrator : {Integrator::Explicit, Integrator::Implicit}) {
    for (const bool with_gravity : {true, false}) {
      const Groom &groom = with_gravity ? pendulum : chain;
      StrandParams params = quiet_params();
      params.gravity = vec3(0.0f, 0.0f, with_gravity ? -9.81f : 0.0f);
      params.k_theta = 6e-8f;
      params.k_phi = 9e-8f;
      params.integrator = integrator;
      params.substeps = 1;
      StrandSolver solver(groom.offsets, groom.positions, mat4(1.0f), {}, params);
      params.damping = 0.6f * std::sqrt(params.k_phi * solver.moment_of_inertia(1));
      solver.set_params(params);
      const double energy_rest = model_energy(solver);
      for (int64_t i = 1; i < int64_t(groom.positions.size()); i++) {
        solver.angles_for_write()[i] = vec2(0.6f, -0.8f);
        solver.angular_velocities_for_write()[i] = vec2(3.0f, 2.0f);
      }
      solver.step(1.0f / 240.0f, mat4(1.0f)); /* Positions catch up with the new angles. */
      const double energy_start = model_energy(solver);
      const double tolerance = 1e-6 * (energy_start - energy_rest); /* float rounding */
      double energy = energy_start;
      int increases = 0;
      for (int step = 0; step < 1000; step++) {
        solver.step(1.0f / 240.0f, mat4(1.0f));
        const double next = model_energy(solver);
        increases += next > energy + tolerance ? 1 : 0;
        energy = next;
      }
      EXPECT_EQ(increases, 0) << "integrator " << int(integrator) << " gravity " << with_gravity;
      /* And damping did work: little is left of the energy above rest. */
      EXPECT_LT(energy - energy_rest, 0.01 * (energy_start - energy_rest));
    }
  }
}

TEST(Strands, ImplicitIsStableWhereExplicitExplodes)
{
  /* h √(k/I) = 4 at 24 fps with one substep: beyond the explicit limit of 2. */
  Groom groom;
  groom.add(straight(vec3(0.0f), vec3(0.0f, 0.0f, -1.0f), 0.02f, 1));
  const float h = 1.0f / 24.0f;
  StrandParams params = quiet_params();
  params.substeps = 1;
  StrandSolver probe(groom.offsets, groom.positions, mat4(1.0f), {}, params);
  params.k_theta = params.k_phi = 16.0f / (h * h) * probe.moment_of_inertia(1);

  params.integrator = Integrator::Explicit;
  StrandSolver explicit_solver(groom.offsets, groom.positions, mat4(1.0f), {}, params);
  params.integrator = Integrator::Implicit;
  StrandSolver implicit_solver(groom.offsets, groom.positions, mat4(1.0f), {}, params);
  int64_t explicit_diverged = 0;
  for (StrandSolver *solver : {&explicit_solver, &implicit_solver}) {
    solver->angles_for_write()[1] = vec2(0.1f, 0.1f);
    for (int frame = 0; frame < 48; frame++) {
      solver->step(h, mat4(1.0f));
      explicit_diverged += solver == &explicit_solver ? solver->diverged_num() : 0;
      EXPECT_EQ(count_nonfinite(solver->positions()), 0);
    }
  }
  /* The explicit solver runs away; the solver reports it and puts the strand back at rest
   * rather than handing out non-finite positions. */
  EXPECT_GT(explicit_diverged, 0);
  EXPECT_EQ(implicit_solver.diverged_num(), 0);
  const vec2 q_implicit = implicit_solver.angles()[1];
  EXPECT_LT(std::abs(q_implicit.x), 0.1f);
  EXPECT_LT(std::abs(q_implicit.y), 0.1f);
  EXPECT_LE(max_relative_stretch(groom.offsets, groom.positions, implicit_solver.positions()),
            1e-5f);
}

TEST(Strands, IntegratorsAgreeAtSmallSteps)
{
  /* A wavy strand under gravity with springs and damping, h = 1/9600 s: explicit and implicit
   * trajectories stay within 1% of the strand's length of each other for a second. */
  Groom groom;
  groom.add(wave(vec3(0.0f), 8));
  StrandParams params = kurihara_params();
  params.substeps = 40;
  params.integrator = Integrator::Explicit;
  StrandSolver explicit_solver(groom.offsets, groom.positions, mat4(1.0f), {}, params);
  params.integrator = Integrator::Implicit;
  StrandSolver implicit_solver(groom.offsets, groom.positions, mat4(1.0f), {}, params);
  float difference_max = 0.0f;
  float motion_max = 0.0f;
  for (int frame = 0; frame < 240; frame++) {
    explicit_solver.step(1.0f / 240.0f, mat4(1.0f));
    implicit_solver.step(1.0f / 240.0f, mat4(1.0f));
    difference_max = std::max(difference_max, max_distance(explicit_solver.positions(),
                                                           implicit_solver.positions()));
    motion_max = std::max(motion_max, max_distance(explicit_solver.positions(), groom.positions));
  }
  const float length = 8.0f * glm::length(groom.positions[1] - groom.positions[0]);
  EXPECT_GT(motion_max, 0.05f * length); /* It did swing. */
  EXPECT_LT(difference_max, 0.01f * length);
}

TEST(Strands, NoStretchUnderViolentMotion)
{
  /* 1,000 steps of a head shaken and spun hard in a gusty gale: segment lengths hold to float
   * precision because positions are rebuilt from angles. */
  Groom groom;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int s = 0; s < 30; s++) {
    const vec3 root = 0.1f * glm::normalize(vec3(u(rng), u(rng), 0.5f + 0.5f * u(rng) + 0.6f));
    if (s % 3 == 0) {
      groom.add(curl(root, 16));
    }
    else if (s % 3 == 1) {
      groom.add(wave(root, 16));
    }
    else {
      groom.add(straight(root, root + vec3(u(rng), u(rng), u(rng)) * 0.05f, 0.3f, 16));
    }
  }
  StrandParams params = kurihara_params();
  WindParams wind;
  wind.speed = 20.0f;
  wind.turbulence = 1.0f;
  wind.frequency = 3.0f;
  params.substeps = 1;
  StrandSolver solver(groom.offsets, groom.positions, mat4(1.0f), {}, params, wind);
  float moved = 0.0f;
  for (int frame = 0; frame < 1000; frame++) {
    const float t = float(frame) / 24.0f;
    const mat4 head = glm::rotate(glm::translate(mat4(1.0f), vec3(0.2f * std::sin(18.0f * t),
                                                                  0.0f, 0.1f * std::cos(11.0f * t))),
                                  1.0f * std::sin(13.0f * t), glm::normalize(vec3(0.2f, 0.3f, 1.0f)));
    solver.step(1.0f / 24.0f, head);
    moved = std::max(moved, max_distance(solver.positions(), groom.positions));
  }
  EXPECT_EQ(count_nonfinite(solver.positions()), 0);
  EXPECT_GT(moved, 0.1f);
  EXPECT_LE(max_relative_stretch(groom.offsets, groom.positions, solver.positions()), 1e-5f);
}

TEST(Strands, HeadMovingRightLeavesStrandsBehind)
{
  /* Strands hang still under gravity; the head then moves toward +X (right, seen from the
   * front) for a quarter second: the tips trail to the left of their roots. When it stops,
   * they swing and settle back to hanging straight down. */
  Groom groom;
  for (int s = 0; s < 8; s++) {
    groom.add(straight(vec3(0.02f * float(s), 0.0f, 0.0f), vec3(0.0f, 0.0f, -1.0f), 0.2f, 10));
  }
  StrandParams params = kurihara_params();
  StrandSolver solver(groom.offsets, groom.positions, mat4(1.0f), {}, params);
  const float frame_dt = 1.0f / 24.0f;
  const auto tip_offset_x = [&]() {
    double sum = 0.0;
    for (int64_t curve = 0; curve < solver.curves_num(); curve++) {
      const IndexRange points = curve_points(solver.curve_offsets(), curve);
      sum += double(solver.positions()[points.one_after_last() - 1].x -
                    solver.positions()[points.start].x);
    }
    return sum / double(solver.curves_num());
  };
  float x = 0.0f;
  double lag_min = 0.0;
  for (int frame = 0; frame < 6; frame++) {
    x += 1.0f * frame_dt; /* 1 m/s to the right. */
    solver.step(frame_dt, glm::translate(mat4(1.0f), vec3(x, 0.0f, 0.0f)));
    lag_min = std::min(lag_min, tip_offset_x());
    EXPECT_LT(tip_offset_x(), 0.0) << "frame " << frame;
  }
  EXPECT_LT(lag_min, -0.005);
  for (int frame = 0; frame < 24 * 8; frame++) {
    solver.step(frame_dt, glm::translate(mat4(1.0f), vec3(x, 0.0f, 0.0f)));
  }
  EXPECT_NEAR(tip_offset_x(), 0.0, 1e-3);
  float speed_max = 0.0f;
  for (const vec3 &v : solver.velocities()) {
    speed_max = std::max(speed_max, glm::length(v));
  }
  EXPECT_LT(speed_max, 1e-3f);
}

/* The positions after `frames` frames in a 3 m/s wind, the head turning by `turn` rad a frame,
 * on `threads` threads. */
static std::vector<vec3> positions_on_threads(const Groom &groom, const StrandParams &params,
                                              const int threads, const int frames,
                                              const float turn)
{
  WindParams wind;
  wind.speed = 3.0f;
  set_thread_num(threads);
  StrandSolver solver(groom.offsets, groom.positions, mat4(1.0f), {}, params, wind);
  for (int frame = 0; frame < frames; frame++) {
    solver.step(1.0f / 24.0f, glm::rotate(mat4(1.0f), turn * float(frame), vec3(0, 0, 1)));
  }
  set_thread_num(0);
  return {solver.positions().begin(), solver.positions().end()};
}

TEST(Strands, SameResultOnAnyThreadCount)
{
  Groom groom;
  for (int s = 0; s < 300; s++) {
    groom.add(curl(vec3(0.01f * float(s), 0.0f, 0.0f), 12));
  }
  const std::vector<vec3> one = positions_on_threads(groom, kurihara_params(), 1, 10, 0.05f);
  const std::vector<vec3> two = positions_on_threads(groom, kurihara_params(), 2, 10, 0.05f);
  EXPECT_EQ(std::memcmp(one.data(), two.data(), one.size() * sizeof(vec3)), 0);
}

TEST(Strands, ArticulatedSameResultOnAnyThreadCount)
{
  /* 2,100 strands: groups of 128 on one thread, 65 on two and 32 on eight (16 groups a
   * thread), each strand's bits the same. */
  Groom groom;
  for (int s = 0; s < 2100; s++) {
    groom.add(curl(vec3(0.01f * float(s % 50), 0.01f * float(s / 50), 0.0f), 8));
  }
  const std::vector<vec3> one = positions_on_threads(groom, StrandParams(), 1, 6, 0.2f);
  for (const int threads : {2, 8}) {
    const std::vector<vec3> other = positions_on_threads(groom, StrandParams(), threads, 6, 0.2f);
    EXPECT_EQ(std::memcmp(one.data(), other.data(), one.size() * sizeof(vec3)), 0);
  }
}

TEST(Strands, BadGroomIsRejected)
{
  /* The solver's constructor requires find_groom_error to pass; the bindings turn its
   * sentence into a ValueError. The three inputs the strand solver cannot take: */
  Groom groom;
  groom.add(straight(vec3(0.0f), vec3(0.0f, 0.0f, -1.0f), 0.1f, 4));
  EXPECT_EQ(find_groom_error(groom.offsets, groom.positions), "");

  Groom zero_length = groom;
  zero_length.positions[2] = zero_length.positions[1];
  EXPECT_NE(find_groom_error(zero_length.offsets, zero_length.positions).find("zero-length"),
            std::string::npos);

  Groom one_point = groom;
  one_point.add({vec3(1.0f)});
  EXPECT_NE(find_groom_error(one_point.offsets, one_point.positions).find("1 point"),
            std::string::npos);

  Groom nan = groom;
  nan.positions[3].y = NAN;
  EXPECT_NE(find_groom_error(nan.offsets, nan.positions).find("not a finite number"),
            std::string::npos);
}
