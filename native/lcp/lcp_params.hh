#pragma once
/* Parameters of loosely connected particles (Bando, Chen, Nishita 2003). Defaults suit a
 * human head in metres (head radius ~0.1 m, hair 0.1-0.3 m, ~2,000 particles). Each field's
 * comment gives the unit and the paper's symbol. */
#include "core/params.hh"

namespace hairdyn {

struct LcpParams {
  /* ---- initialisation (§3.2) ---- */
  float particle_spacing = 0.012f; /* m, r: Poisson-disc radius in the distance of eq. 3. */
  /* N: target particle count; 0 = as many as `r` allows. Bando 2003 (§5) used about 2,000. */
  int32_t particle_num = 2000;
  float root_depth = 0.01f;        /* m, s_r: depth of the hair roots beneath the scalp. */
  float max_length = 0.25f;        /* m, L_max: scales the length map L(u, v). */
  float root_tangent_weight = 0.3f; /* w_t of eq. 4: tilts roots away from the whorl. */
  float root_normal_weight = 1.0f;  /* w_n of eq. 4: weight of the scalp normal. */
  float whorl_u = 0.5f;             /* u of the whorl centre on the scalp (eq. 4's n_w). */
  float whorl_v = 0.5f;             /* v of the whorl centre. */
  /* m, b = (EI / (λg))^(1/3): bending length of Anjyo's cantilever. 3 cm starts 12 cm hair
   * near its hanging shape; a stiffer start falls over the head in the first frames and tears
   * the loose connections. */
  float beam_length = 0.03f;
  int32_t seed = 0;          /* Random seed of the Poisson-disc sampling. */

  /* ---- connections and hair dynamics (§3.2-3.3) ---- */
  float h1 = 0.016f;       /* m, h₁: smoothing length of the connections (pairs within 2h₁). */
  float a0 = 0.5f;         /* a₀: pairs less aligned than this (eq. 6) are not connected. */
  int32_t neighbor_num = 12; /* N_n: connections kept per particle. */
  float young_modulus = 1.0e4f; /* Pa, E: tensile modulus kept constant (eq. 10-11). */
  float material_density = 1300.0f; /* kg/m³, δ: density of the hair material (eq. 9). */
  float spring_damping = 0.005f; /* s, γ: spring damping, force γ·αk·(v_ij·x̂_ij). */
  /* Backward Euler for the springs (lcp/implicit_springs.hh): stable at any time step. Off:
   * explicit springs, with as many substeps as their stiffness needs. */
  bool implicit_springs = true;
  float hair_density = 10.0f; /* kg/m³, ρ_h: mass of hair per volume of hair; sets m_i. */

  /* ---- hair-hair interactions (§3.4) ---- */
  float h2 = 0.011f;              /* m, h₂: smoothing length of the interactions. */
  bool attraction_repulsion = true; /* Apply eq. 16. */
  /* m²/s², k_a: P = k_a (ρ − ρ₀) of eq. 16; c = √k_a is the hair's sound speed. 0.2 keeps
   * two locks from passing into each other when they meet (Fig. 6 test); it also sets the
   * substeps through the CFL bound. */
  float pressure_stiffness = 0.2f;
  /* The stiffness of eq. 16 joins the implicit springs' backward-Euler step
   * (lcp/implicit_springs.hh): stable at any time step, so its CFL bound no longer sets the
   * substeps; backward Euler also damps fast hair-hair motion (Fig. 6's bar parts the hair
   * less cleanly at 1-5 substeps). Off (the default), or with explicit springs: eq. 16 is
   * explicit, with as many substeps as its CFL bound needs. */
  bool implicit_pressure = false;
  float rest_density = 8.0f;      /* kg/m³, ρ₀: small = repulsive, large = cohesive. */
  bool hair_collision = true;     /* Apply eq. 17. */
  float collision_damping = 60.0f; /* 1/s, d_c: damping of approaching hair (eq. 17). */
  bool hair_friction = true;      /* Apply eq. 18. */
  float friction_damping = 10.0f; /* 1/s, d_f: damping of sliding hair (eq. 18). */

  /* ---- other forces (§3.5) ---- */
  /* m/s², g: world acceleration of gravity; the add-on fills it from the scene. */
  vec3 gravity = vec3(0.0f, 0.0f, -9.81f);
  float air_friction = 2.0f;  /* 1/s: damping force −(this)·m·v against still air. */
  /* The wind itself (speed, direction, turbulence) is core/wind.hh's WindParams, shared by
   * every method, given to the solver apart: it is the free stream of the air particles. */
  float wind_particle_spacing = 0.03f; /* m: spacing of the SPH air particles. */
  float wind_drag = 20.0f;    /* 1/s, k_d: hair-air drag rate, both ways. */
  float air_density = 1.2f;   /* kg/m³: density of the air particles. */
  float body_friction = 0.3f; /* μ: Coulomb friction of hair on the body. */
  /* Fewest time steps per frame: more are taken when the explicit pressure of eq. 16 (CFL),
   * the wind or explicit springs need them. */
  int32_t substeps = 1;
  /* Most time steps per frame: a frame whose stability bounds (the pressure's CFL, explicit
   * springs) ask for more is refused with the reason, rather than running for minutes. */
  int32_t max_substeps = 200;
  /* Share of h₂: the implicit step's conjugate gradients stop when what they leave would move
   * no particle by more than solver_tolerance h₂ over the step. 5·10⁻⁴ leaves 1-3% of the
   * time step's own error (what twice the substeps change) in swaying back hair, and the
   * lag behind a turning head within 1% (tests DefaultSolverTolerance*); 10⁻⁴ until stop 47,
   * for 40-70% more matrix products. */
  float solver_tolerance = 5e-4f;

  template<typename Fn> static void for_each_field(Fn &&fn)
  {
    fn(&LcpParams::particle_spacing,
       ParamInfo{"particle_spacing", "r", "m", 1e-4, 1.0,
                 "Poisson-disc radius of the particles in the (u, v, s) distance of eq. 3"}
           .labeled("Particle Spacing"));
    fn(&LcpParams::particle_num,
       ParamInfo{"particle_num", "N", "", 0, 2000000,
                 "Target particle count (0: as many as the spacing allows)"}
           .labeled("Particle Count"));
    fn(&LcpParams::root_depth,
       ParamInfo{"root_depth", "s_r", "m", 0.0, 1.0,
                 "Depth of the fixed root particles beneath the scalp (§3.2)"});
    fn(&LcpParams::max_length,
       ParamInfo{"max_length", "L_max", "m", 1e-4, 10.0,
                 "Hair length where the length map is 1 (§3.2)"});
    fn(&LcpParams::root_tangent_weight,
       ParamInfo{"root_tangent_weight", "w_t", "", 0.0, 100.0,
                 "Tangent weight of the root direction, eq. 4 (large: hair lies down)"}.labeled("Root Tangent"));
    fn(&LcpParams::root_normal_weight,
       ParamInfo{"root_normal_weight", "w_n", "", 0.0, 100.0,
                 "Normal weight of the root direction, eq. 4"}.labeled("Root Normal"));
    fn(&LcpParams::whorl_u, ParamInfo{"whorl_u", "u_w", "", 0.0, 1.0,
                                      "u of the hair whorl centre on the scalp (eq. 4)"}
           .labeled("Whorl U"));
    fn(&LcpParams::whorl_v, ParamInfo{"whorl_v", "v_w", "", 0.0, 1.0,
                                      "v of the hair whorl centre on the scalp (eq. 4)"}
           .labeled("Whorl V"));
    fn(&LcpParams::beam_length,
       ParamInfo{"beam_length", "b", "m", 1e-3, 100.0,
                 "Bending length (EI/λg)^(1/3) of the cantilever-beam initial shape (Anjyo 1992)"});
    fn(&LcpParams::seed, ParamInfo{"seed", "", "", 0, 2147483647,
                                   "Random seed of the Poisson-disc sampling"});
    fn(&LcpParams::h1,
       ParamInfo{"h1", "h₁", "m", 1e-5, 1.0,
                 "Smoothing length of the connections: pairs within 2h₁ at rest (eq. 7)"}
           .labeled("Link Radius"));
    fn(&LcpParams::a0, ParamInfo{"a0", "a₀", "", 0.0, 1.0,
                                 "Alignment threshold: pairs with a_ij < a₀ are dropped (eq. 6)"}
           .labeled("Alignment"));
    fn(&LcpParams::neighbor_num,
       ParamInfo{"neighbor_num", "N_n", "", 1, 1000,
                 "Connections kept per particle, strongest c_ij W(l_ij, h₁) first (§3.2)"}
           .labeled("Connections"));
    /* Above ~1e10 Pa the springs' linear system is beyond single precision (measured: a
     * head cap tears apart at 1e11 Pa, holds at 1e10 Pa). */
    fn(&LcpParams::young_modulus,
       ParamInfo{"young_modulus", "E", "Pa", 0.0, 1e9,
                 "Tensile Young's modulus kept constant per particle (eq. 10-14)"}
           .labeled("Young's Modulus"));
    fn(&LcpParams::material_density,
       ParamInfo{"material_density", "δ", "kg/m³", 1.0, 1e5,
                 "Density of the hair material, giving the cross-section A_i (eq. 9)"});
    fn(&LcpParams::spring_damping,
       ParamInfo{"spring_damping", "γ", "s", 0.0, 10.0,
                 "Damping of the springs: force γ·α_ij k_ij·(v_ij·x̂_ij) (§3.3)"});
    fn(&LcpParams::implicit_springs,
       ParamInfo{"implicit_springs", "", "", 0, 1,
                 "Integrate the springs implicitly (backward Euler): few substeps at any "
                 "stiffness. Off: explicit springs, substeps added as their stiffness needs"});
    fn(&LcpParams::hair_density,
       ParamInfo{"hair_density", "ρ_h", "kg/m³", 1e-3, 1e4,
                 "Mass of hair per volume of the hair region; sets the particle mass m_i"});
    fn(&LcpParams::h2, ParamInfo{"h2", "h₂", "m", 1e-5, 1.0,
                                 "Smoothing length of hair-hair interactions (eq. 1, 16-18)"}
           .labeled("SPH Radius"));
    fn(&LcpParams::attraction_repulsion,
       ParamInfo{"attraction_repulsion", "", "", 0, 1, "Apply attraction/repulsion (eq. 16)"}
           .labeled("Attract/Repel"));
    fn(&LcpParams::pressure_stiffness,
       ParamInfo{"pressure_stiffness", "k_a", "m²/s²", 0.0, 1e4,
                 "Magnitude of the attraction/repulsion, P = k_a(ρ − ρ₀) (eq. 16)"}
           .labeled("Attraction"));
    fn(&LcpParams::implicit_pressure,
       ParamInfo{"implicit_pressure", "", "", 0, 1,
                 "Integrate the attraction/repulsion (eq. 16) implicitly with the springs: its "
                 "sound speed √k_a no longer adds substeps. Off (or with explicit springs): "
                 "explicit, substeps added as its CFL bound needs"});
    fn(&LcpParams::rest_density,
       ParamInfo{"rest_density", "ρ₀", "kg/m³", 0.0, 1e5,
                 "Average hair density kept by eq. 16: small is repulsive, large cohesive"});
    fn(&LcpParams::hair_collision,
       ParamInfo{"hair_collision", "", "", 0, 1, "Apply inelastic hair-hair collision (eq. 17)"});
    fn(&LcpParams::collision_damping,
       ParamInfo{"collision_damping", "d_c", "1/s", 0.0, 1e6,
                 "Collision damping constant of eq. 17 (per unit SPH volume)"}.labeled("Impact Damping"));
    fn(&LcpParams::hair_friction,
       ParamInfo{"hair_friction", "", "", 0, 1, "Apply hair-hair friction (eq. 18)"});
    fn(&LcpParams::friction_damping,
       ParamInfo{"friction_damping", "d_f", "1/s", 0.0, 1e6,
                 "Frictional damping constant of eq. 18 (per unit SPH volume)"});
    fn(&LcpParams::gravity, ParamInfo{"gravity", "g", "m/s²", -1000.0, 1000.0,
                                      "Acceleration of gravity, world space (§3.5)"});
    fn(&LcpParams::air_friction,
       ParamInfo{"air_friction", "", "1/s", 0.0, 1e4,
                 "Air friction: damping force proportional to velocity (§3.5)"});
    fn(&LcpParams::wind_particle_spacing,
       ParamInfo{"wind_particle_spacing", "", "m", 1e-3, 1.0,
                 "Spacing (and smoothing length) of the air particles"}.labeled("Wind Spacing"));
    fn(&LcpParams::wind_drag,
       ParamInfo{"wind_drag", "k_d", "1/s", 0.0, 1e5,
                 "Drag between hair and air particles, acting on both (§3.5)"});
    fn(&LcpParams::air_density, ParamInfo{"air_density", "", "kg/m³", 1e-3, 1e3,
                                          "Density of the air particles"});
    fn(&LcpParams::body_friction,
       ParamInfo{"body_friction", "μ", "", 0.0, 10.0,
                 "Coulomb friction coefficient of hair sliding on the body (§3.5)"});
    fn(&LcpParams::substeps,
       ParamInfo{"substeps", "", "", 1, 1000,
                 "Fewest time steps per frame; more are taken as an explicit hair-hair "
                 "pressure (eq. 16), the wind or explicit springs need"});
    fn(&LcpParams::max_substeps,
       ParamInfo{"max_substeps", "", "", 1, 100000,
                 "Most time steps per frame: a frame whose stability bounds (hair-hair pressure "
                 "CFL, wind, explicit springs) need more is refused with the reason"});
    fn(&LcpParams::solver_tolerance,
       ParamInfo{ "solver_tolerance", "", "", 1e-7, 0.1,
                  "Implicit springs: the solve stops when what it leaves would move no particle "
                  "by more than this share of the SPH radius h₂ over a step" }
           .shown_as(100.0, "% of h₂"));
  }
};

}  // namespace hairdyn
