#pragma once
/* Parameters of the angular strand solver (Kurihara, Anjyo, Thalmann 1993, §2; implicit
 * integration from Ward & Lin 2003, §5.6 and appendix A; the articulated model after
 * Featherstone's articulated-body algorithm and Hadap 2006) and of its child hairs (Kurihara
 * 1993, §4). Lengths in meters, Blender's Z is up.
 *
 * The articulated model reads the material: Young's modulus E, the strand's
 * radius r and the hair's density ρ give the bending stiffness EI = E π r⁴ / 4 and the line
 * density c = ρ π r²; each hinge's spring is EI over the length of strand it stands for, so
 * the look does not depend on how finely a strand is cut. How much a strand of length L
 * droops is set by the one number Γ = c g L³ / EI (gamma()).
 *
 * The kurihara1993 model (the paper's own, its preset's; the articulated model is the default)
 * reads k_θ, k_φ, γ and c per hinge. Its defaults describe a single human hair (~70 µm
 * thick, 5·10⁻⁶ kg/m) cut into segments of about 2 cm (a 0.3 m strand in 16 segments): the
 * hinge springs hold a style against gravity with a sag of roughly 0.1 rad per hinge when
 * the strand is horizontal, and the damping is about a fifth of critical for the hinge
 * spring. The hinge constants are per hinge, so they are tuned for that segment length:
 * halving the segment length asks for roughly half the stiffness for the same look. */
#include <algorithm>
#include <cmath>
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

/* The per-strand dynamics. */
enum class StrandModel : int32_t {
  /* Full coupled chain: every hinge feels the inertia and the forces of everything distal to
   * it (articulated-body algorithm), implicit in the hinge springs and damping. */
  Articulated = 0,
  /* Kurihara 1993, §2: each hinge moves with its own segment's inertia and load only. */
  Kurihara1993 = 1,
};

struct StrandParams {
  StrandModel model = StrandModel::Articulated;
  /* Pa, E: Young's modulus of the hair (human hair 3–4 GPa; articulated model). */
  float youngs_modulus = 3.5e9f;
  /* m, r: radius of one strand's cross-section (human hair 35–50 µm; articulated model). */
  float strand_radius = 40e-6f;
  /* kg/m³, ρ: density of the hair (keratin ≈ 1300; articulated model). */
  float hair_density = 1300.0f;
  /* s, τ: Kelvin–Voigt damping of bending, the hinge damping over its stiffness (γ = τ k);
   * damps fast bending waves, leaves slow swings to the air (articulated model). */
  float bending_damping = 0.002f;
  /* ×, the bending stiffness at the root relative to the rest of the strand (gel, a short
   * cut, a stiff root: > 1); it returns to 1 linearly over root_length. */
  float root_stiffness = 1.0f;
  /* Fraction of each strand's length over which root_stiffness fades to 1. */
  float root_length = 0.3f;
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
  /* C_d: form (pressure) drag coefficient of a strand in air, beside the linear drag: the
   * force per length ½ ρ_air C_d (2 r) |v_wind − v| (v_wind − v), r = strand_radius. A
   * cylinder in cross-flow has C_d ≈ 1–1.5 at Reynolds numbers 10–1000 (a hair of 80 µm
   * from about 2 m/s); the linear term c_air is its viscous part at low speed. Without it a
   * whipped strand's tip, which weighs next to nothing, reached hundreds of m/s. */
  float form_drag = 1.2f;
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

  /* N·m², EI = E π r⁴ / 4 away from the root. */
  double bending_stiffness() const
  {
    const double r = strand_radius;
    return double(youngs_modulus) * M_PI * r * r * r * r / 4.0;
  }
  /* kg/m, c = ρ π r² (articulated model). */
  double material_line_density() const
  {
    return double(hair_density) * M_PI * double(strand_radius) * double(strand_radius);
  }
  /* The bending stiffness at arc length s of a strand of length L (root profile applied). */
  double bending_stiffness_at(const double s, const double length) const
  {
    const double fade = root_length > 0.0f ? 1.0 - s / (double(root_length) * length) : 0.0;
    return bending_stiffness() * (1.0 + (double(root_stiffness) - 1.0) * std::max(fade, 0.0));
  }
  /* Γ = c g L³ / EI: a strand of length L stands nearly straight well below 1 and hangs like
   * a chain well above 100 (a horizontal cantilever's tip drops ≈ Γ/8 of L for small Γ). */
  double gamma(const double length) const
  {
    return material_line_density() * double(glm::length(gravity)) * length * length * length /
           bending_stiffness();
  }

  template<typename Fn> static void for_each_field(Fn &&fn)
  {
    fn(&StrandParams::model,
       ParamInfo{"model", "", "", 0.0, 1.0,
                 "Articulated: the full coupled chain, sag and swing independent of the "
                 "segment count (Featherstone's articulated-body algorithm, Hadap 2006). "
                 "Kurihara 1993: each hinge alone, with its own k, γ and c (eq. 1-7), as the "
                 "paper has it (its preset keeps it)",
                 "articulated,kurihara1993"});
    fn(&StrandParams::youngs_modulus,
       ParamInfo{"youngs_modulus", "E", "Pa", 1e3, 1e12,
                 "Young's modulus of the hair; bending stiffness EI = E π r^4 / 4 "
                 "(articulated model; human hair 3-4 GPa)"}
           .shown_as(1e-9, "GPa")
           .soft(1e6, 1e10));
    fn(&StrandParams::strand_radius,
       ParamInfo{"strand_radius", "r", "m", 1e-7, 0.01,
                 "Radius of a strand's cross-section; sets EI and the line density "
                 "(articulated model; human hair 35-50 µm)"}
           .shown_as(1e6, "µm")
           .soft(10e-6, 500e-6));
    fn(&StrandParams::hair_density,
       ParamInfo{"hair_density", "ρ", "kg/m³", 1.0, 1e5,
                 "Density of the hair; line density c = ρ π r^2 (articulated model)"}
           .soft(500.0, 2000.0));
    fn(&StrandParams::bending_damping,
       ParamInfo{"bending_damping", "τ", "s", 0.0, 10.0,
                 "Internal damping of bending, as a relaxation time: hinge damping = τ × hinge "
                 "stiffness (articulated model)"}
           .shown_as(1e3, "ms")
           .soft(0.0, 0.05).labeled("Bend Damping"));
    fn(&StrandParams::root_stiffness,
       ParamInfo{"root_stiffness", "", "", 0.01, 1e4,
                 "Bending stiffness at the root relative to the rest of the strand: > 1 holds "
                 "a style up (gel, short cut); fades to 1 over root_length (articulated model)"}
           .soft(1.0, 100.0));
    fn(&StrandParams::root_length,
       ParamInfo{"root_length", "", "", 0.0, 1.0,
                 "Fraction of each strand's length over which root_stiffness fades to 1"});
    fn(&StrandParams::k_theta,
       ParamInfo{"k_theta", "k_θ", "N·m/rad", 0.0, 1.0,
                 "Hinge spring toward the rest zenith angle (Kurihara 1993, eq. 4)"}
           .shown_as(1e6, "µN·m/rad").soft(0.0, 1e-5).labeled("Stiffness θ"));
    fn(&StrandParams::k_phi,
       ParamInfo{"k_phi", "k_φ", "N·m/rad", 0.0, 1.0,
                 "Hinge spring toward the rest azimuth (Kurihara 1993, eq. 4)"}
           .shown_as(1e6, "µN·m/rad").soft(0.0, 1e-5).labeled("Stiffness φ"));
    fn(&StrandParams::damping,
       ParamInfo{"damping", "γ", "N·m·s/rad", 0.0, 1.0,
                 "Damping of each segment's angular velocity (Kurihara 1993, eq. 1)"}
           .shown_as(1e9, "nN·m·s/rad").soft(0.0, 1e-7));
    fn(&StrandParams::line_density,
       ParamInfo{"line_density", "c", "kg/m", 1e-9, 1.0,
                 "Mass per length of a strand; sets the moment of inertia (Kurihara 1993, eq. 2)"}
           .shown_as(1e6, "mg/m").soft(1e-9, 1e-4));
    fn(&StrandParams::gravity,
       ParamInfo{"gravity", "g", "m/s²", -100.0, 100.0,
                 "Gravitational acceleration in world space, from the scene (Kurihara 1993, "
                 "eq. 6)"});
    fn(&StrandParams::air_drag,
       ParamInfo{"air_drag", "c_air", "N·s/m²", 0.0, 1.0,
                 "Air drag per length and relative speed; carries the wind (Kurihara 1993, eq. 6)"}
           .shown_as(1e6, "µN·s/m²").soft(0.0, 1e-3));
    fn(&StrandParams::form_drag,
       ParamInfo{"form_drag", "C_d", "", 0.0, 10.0,
                 "Form drag coefficient of a strand in air: ½ ρ_air C_d 2r |v|² per length on top "
                 "of the linear drag, r the strand radius; it matters from about 1 m/s and keeps "
                 "whipped tips from flying off (a cylinder: 1–1.5; 0: linear drag only, as "
                 "Kurihara 1993, eq. 6)"}
           .soft(0.0, 2.0));
    fn(&StrandParams::integrator,
       ParamInfo{"integrator", "", "", 0.0, 1.0,
                 "Explicit (Kurihara 1993, eq. 7) or implicit backward Euler (Ward & Lin 2003, "
                 "appendix A)",
                 "explicit,implicit"});
    fn(&StrandParams::substeps,
       ParamInfo{"substeps", "", "", 1.0, 1000.0, "Solver steps per frame"}.soft(1.0, 32.0));
    fn(&StrandParams::children_per_guide,
       ParamInfo{"children_per_guide", "", "", 0.0, 1000.0,
                 "Render hairs generated around each simulated guide (Kurihara 1993, §4)"}.labeled("Children"));
    fn(&StrandParams::child_mode,
       ParamInfo{"child_mode", "", "", 0.0, 1.0,
                 "Children around each guide (Kurihara 1993, §4 clusters) or spread over the "
                 "scalp, blending the nearest guides",
                 "cluster,interpolate"});
    fn(&StrandParams::child_spread,
       ParamInfo{"child_spread", "", "m", 0.0, 1.0,
                 "Radius around a guide's root within which its children take root"}
           .soft(0.0, 0.05));
    fn(&StrandParams::seed,
       ParamInfo{"seed", "", "", 0.0, 2147483647.0,
                 "Seed of the child hairs' roots"});
  }
};

}  // namespace hairdyn
