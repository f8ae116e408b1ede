#pragma once
/* Parameters of the angular strand solver (Kurihara, Anjyo, Thalmann 1993, §2; implicit
 * integration from Ward & Lin 2003, §5.6 and appendix A) and of its child hairs (Kurihara
 * 1993, §4). Lengths in meters, Blender's Z is up.
 *
 * The defaults describe a single human hair (~70 µm thick, 5·10⁻⁶ kg/m) cut into segments of
 * about 2 cm (a 0.3 m strand in 16 segments): the hinge springs hold a style against gravity
 * with a sag of roughly 0.1 rad per hinge when the strand is horizontal, and the damping is
 * about a fifth of critical for the hinge spring. The hinge constants are per hinge, so they
 * are tuned for that segment length: halving the segment length asks for roughly half the
 * stiffness for the same look. */
#include <cstdint>

#include "core/math.hh"
#include "core/params.hh"

namespace hairdyn {

enum class Integrator : int32_t {
  /* Kurihara 1993, eq. 7: central differences with a backward-difference damping term
   * (symplectic Euler). Stable while h·√(k/I) < 2. */
  Explicit = 0,
  /* Ward & Lin 2003, appendix A: backward Euler on the hinge spring and damping, explicit
   * external torques. Stable for any stiffness. */
  Implicit = 1,
};

/* Where child hairs take root (Kurihara 1993, §4). */
enum class ChildMode : int32_t {
  Cluster = 0,     /* Around each guide, within child_spread of its root. */
  Interpolate = 1, /* Anywhere on the scalp, blending the nearest guides. */
};

struct StrandParams {
  /* N·m/rad, k_θ (Kurihara 1993, eq. 4): hinge spring toward the rest zenith angle. */
  float k_theta = 1e-7f;
  /* N·m/rad, k_φ (eq. 4): hinge spring toward the rest azimuth. */
  float k_phi = 1e-7f;
  /* N·m·s/rad, γ (eq. 1): damping of the angular velocities relative to the parent segment. */
  float damping = 4e-10f;
  /* kg/m, c (eq. 2): mass per length; moment of inertia I = c d³ / 3 of a segment of length d
   * about its hinge. */
  float line_density = 5e-6f;
  /* m/s², g (eq. 6): gravitational acceleration in world space; the add-on fills it from the
   * scene's gravity. The wind is core/wind.hh's WindParams, shared by every method. */
  vec3 gravity = vec3(0.0f, 0.0f, -9.81f);
  /* N·s/m², c_air (eq. 6, f = c_air (v_wind − v)): air drag per length and relative speed.
   * It carries the wind and damps every motion through the air. */
  float air_drag = 5e-5f;
  Integrator integrator = Integrator::Implicit;
  /* Solver steps per frame; the head's transform is interpolated over them. */
  int32_t substeps = 4;
  /* Child hairs per simulated guide (Kurihara 1993, §4 cluster model). */
  int32_t children_per_guide = 10;
  /* Clusters around each guide, or hairs spread over the scalp between the guides. */
  ChildMode child_mode = ChildMode::Cluster;
  /* m, radius around a guide's root within which its children take root. */
  float child_spread = 0.01f;
  /* Seed of the child roots: equal seeds give equal bakes. */
  int32_t seed = 0;

  template<typename Fn> static void for_each_field(Fn &&fn)
  {
    fn(&StrandParams::k_theta,
       ParamInfo{"k_theta", "k_θ", "N·m/rad", 0.0, 1.0,
                 "Hinge spring toward the rest zenith angle (Kurihara 1993, eq. 4)"});
    fn(&StrandParams::k_phi,
       ParamInfo{"k_phi", "k_φ", "N·m/rad", 0.0, 1.0,
                 "Hinge spring toward the rest azimuth (Kurihara 1993, eq. 4)"});
    fn(&StrandParams::damping,
       ParamInfo{"damping", "γ", "N·m·s/rad", 0.0, 1.0,
                 "Damping of each segment's angular velocity (Kurihara 1993, eq. 1)"});
    fn(&StrandParams::line_density,
       ParamInfo{"line_density", "c", "kg/m", 1e-9, 1.0,
                 "Mass per length of a strand; sets the moment of inertia (Kurihara 1993, eq. 2)"});
    fn(&StrandParams::gravity,
       ParamInfo{"gravity", "g", "m/s²", -100.0, 100.0,
                 "Gravitational acceleration in world space, from the scene (Kurihara 1993, "
                 "eq. 6)"});
    fn(&StrandParams::air_drag,
       ParamInfo{"air_drag", "c_air", "N·s/m²", 0.0, 1.0,
                 "Air drag per length and relative speed; carries the wind (Kurihara 1993, eq. 6)"});
    fn(&StrandParams::integrator,
       ParamInfo{"integrator", "", "", 0.0, 1.0,
                 "Explicit (Kurihara 1993, eq. 7) or implicit backward Euler (Ward & Lin 2003, "
                 "appendix A)",
                 "explicit,implicit"});
    fn(&StrandParams::substeps,
       ParamInfo{"substeps", "", "", 1.0, 1000.0, "Solver steps per frame"});
    fn(&StrandParams::children_per_guide,
       ParamInfo{"children_per_guide", "", "", 0.0, 1000.0,
                 "Render hairs generated around each simulated guide (Kurihara 1993, §4)"});
    fn(&StrandParams::child_mode,
       ParamInfo{"child_mode", "", "", 0.0, 1.0,
                 "Children around each guide (Kurihara 1993, §4 clusters) or spread over the "
                 "scalp, blending the nearest guides",
                 "cluster,interpolate"});
    fn(&StrandParams::child_spread,
       ParamInfo{"child_spread", "", "m", 0.0, 1.0,
                 "Radius around a guide's root within which its children take root"});
    fn(&StrandParams::seed,
       ParamInfo{"seed", "", "", 0.0, 2147483647.0,
                 "Seed of the child hairs' roots"});
  }
};

}  // namespace hairdyn
