#pragma once
/* Parameters of hair–object collision: the maps (Kurihara 1993 §3.1, §5), the reaction
 * constraint (Kurihara 1993 §3.2, eq. 12–15) and its extensions (friction, the hard
 * no-penetration projection of Ward & Lin 2003 §5.5, the penetration report).
 *
 * Forces in the reaction constraint are per unit mass (accelerations), so k is in 1/s² and
 * c in 1/s; a solver that works with forces multiplies the result by the node's mass. */
#include <cmath>
#include <cstdint>

#include "core/params.hh"

namespace hairdyn {

/* Which radial map describes a collider part. */
enum class MapKind : int32_t {
  Auto = 0,     /* Build both, keep the one with the smaller error against the exact mesh. */
  Cylinder = 1, /* (r, θ, y), Kurihara 1993 §3.1. */
  Sphere = 2,   /* (r, θ, φ), Kurihara 1993 §5's suggestion for the top of the head. */
};

/* Where a part's map axis comes from. */
enum class AxisMode : int32_t {
  Fitted = 0,  /* Principal axis of the part's surface (area-weighted PCA). */
  ObjectX = 1, /* The collider object's local X axis through the part's centroid. */
  ObjectY = 2,
  ObjectZ = 3,
};

struct CollisionParams {
  int32_t azimuth_num = 40;   /* m: samples of the azimuth θ per map. */
  int32_t height_num = 40;    /* n: samples of the height y (cylinder) or polar angle φ (sphere). */
  MapKind map_kind = MapKind::Auto;
  AxisMode axis_mode = AxisMode::Fitted;
  float stiffness = 1.0e4f;   /* k: constraint strength, 1/s² (force per unit mass per unit depth). */
  float damping = 0.0f;       /* c: 1/s; 0 means the paper's c = √(2k). */
  float friction = 0.0f;      /* μ: Coulomb friction coefficient; 0 reproduces the paper. */
  float projection_tolerance = 0.001f; /* Depth beyond which a node is projected out, × collider size. */
  float penetration_tolerance = 0.01f; /* Depth counted as penetration in the report, × collider size. */

  /* c actually used: the paper's critical value c = √(2k) when damping is 0 (Kurihara 1993,
   * eq. 13). (For a unit mass, the textbook critical value of x'' = -k x - c x' is 2√k; we keep
   * the paper's value, a damping ratio of 1/√2.) */
  float damping_or_critical() const
  {
    return damping > 0.0f ? damping : std::sqrt(2.0f * stiffness);
  }

  template<typename Fn> static void for_each_field(Fn &&fn)
  {
    fn(&CollisionParams::azimuth_num,
       ParamInfo{"azimuth_num", "m", "", 4, 4096,
                 "Azimuth samples of each collision map (Kurihara 1993, eq. 8; the paper uses 40)"}
           .labeled("Map Columns"));
    fn(&CollisionParams::height_num,
       ParamInfo{"height_num", "n", "", 4, 4096,
                 "Height (cylinder) or polar (sphere) samples of each collision map (Kurihara 1993, eq. 8; the paper uses 40)"}
           .labeled("Map Rows"));
    fn(&CollisionParams::map_kind,
       ParamInfo{"map_kind", "", "", 0, 2,
                 "Map per collider part: automatic (smaller error against the mesh), cylindrical (Kurihara 1993 §3.1) or spherical (§5)",
                 "auto,cylinder,sphere"}
           .labeled("Map"));
    fn(&CollisionParams::axis_mode,
       ParamInfo{"axis_mode", "", "", 0, 3,
                 "Map axis: fitted principal axis of the part, or a local axis of the collider object",
                 "fitted,object_x,object_y,object_z"}
           .labeled("Axis"));
    fn(&CollisionParams::stiffness,
       ParamInfo{"stiffness", "k", "1/s²", 0.0, 1.0e9,
                 "Strength of the reaction constraint pulling a node to the surface (Kurihara 1993, eq. 13)"}
           .soft(0.0, 1.0e6));
    fn(&CollisionParams::damping,
       ParamInfo{"damping", "c", "1/s", 0.0, 1.0e6,
                 "Damping of the normal velocity in the reaction constraint; 0 uses the paper's c = √(2k) (Kurihara 1993, eq. 13)"}
           .soft(0.0, 1000.0));
    fn(&CollisionParams::friction,
       ParamInfo{"friction", "μ", "", 0.0, 10.0,
                 "Coulomb friction against colliders; 0 reproduces Kurihara 1993 (an extension of eq. 14)"}
           .soft(0.0, 2.0));
    fn(&CollisionParams::projection_tolerance,
       ParamInfo{"projection_tolerance", "", "", 0.0, 1.0,
                 "Nodes deeper than this share of the collider's size (bounding-box diagonal) are put back on the surface (Ward & Lin 2003 §5.5)"}.labeled("Projection"));
    fn(&CollisionParams::penetration_tolerance,
       ParamInfo{"penetration_tolerance", "", "", 0.0, 1.0,
                 "Depth, as a share of the collider's size (bounding-box diagonal), counted as penetration in the report"}
           .labeled("Report Tolerance"));
  }
};

}  // namespace hairdyn
