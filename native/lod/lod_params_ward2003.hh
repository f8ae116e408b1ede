#pragma once
/* Parameters of the level of detail of Ward & Lin 2003: the hair hierarchy (§4), its run-time
 * selection (§6.1) and the smooth splits and merges (§6.2, §6.3). Lengths in meters. */
#include <cstdint>

#include "core/params.hh"

namespace hairdyn {

struct LodParams {
  /* Level of detail on; off simulates the finest level everywhere. */
  bool enabled = true;
  /* Top-level strips: the coarsest representation (§4.1; Ward's scene has 110 for 9,350
   * strands). Built over the scalp's root UVs where the groom has no strips of its own. */
  int32_t strips_num = 16;
  /* Binary splits of a strip before it turns into clusters (§4.1): a top strip is
   * 2^strip_splits clusters wide. */
  int32_t strip_splits = 1;
  /* m, clusters whose cross-section radius is below this stop splitting; strand groups take
   * over (§4.1). */
  float cluster_min_radius = 0.01f;
  /* Strand groups stop splitting at this many strands (§4.2, §7.2: some hierarchies end at
   * four or five strands); 1 goes down to single strands. */
  int32_t min_group_strands = 1;
  /* Control points of every skeleton (§3, §4: each skeleton has its parent's count); 0, or
   * more than the groom's largest strand point count, takes that count. */
  int32_t skeleton_points = 0;
  /* Deepest level the selection may use (§6.1); -1 means the deepest the hierarchy has. */
  int32_t finest_level = -1;
  /* Coarsest level the selection may use, and the one hidden hair falls back to (§6.1). */
  int32_t coarsest_level = 0;
  /* m, camera distances at which the finest and the coarsest levels are chosen; the levels
   * between get linearly interpolated thresholds (§6.1). */
  float distance_near = 1.0f;
  float distance_far = 8.0f;
  /* m/s, hair speeds (relative to its root) at which the coarsest and the finest levels are
   * chosen, interpolated between (§6.1). */
  float velocity_slow = 0.2f;
  float velocity_fast = 2.0f;
  /* Hair hidden behind the colliders (a ray from the camera to the group's centre hits them)
   * or outside the camera's frustum falls to the coarsest level (§6.1). */
  bool use_occlusion = true;
  /* m, children merge only if each control point is within this of where the merged parent
   * puts it (§6.3). */
  float merge_threshold = 0.01f;
  /* s, time constant of the spring that pulls the output into place after a split or merge
   * (§6.3), so no strand jumps; 0 switches at once. */
  float transition_time = 0.1f;

  template<typename Fn> static void for_each_field(Fn &&fn)
  {
    fn(&LodParams::enabled,
       ParamInfo{"enabled", "", "", 0.0, 1.0,
                 "Level of detail (Ward & Lin 2003, §6); off simulates the finest level "
                 "everywhere"}
           .labeled("Level of Detail"));
    fn(&LodParams::strips_num,
       ParamInfo{"strips_num", "", "", 1.0, 100000.0,
                 "Top-level hair strips, the coarsest representation (Ward & Lin 2003, §4.1)"}
           .soft(1.0, 500.0)
           .labeled("Strips"));
    fn(&LodParams::strip_splits,
       ParamInfo{"strip_splits", "", "", 0.0, 8.0,
                 "Binary splits of a strip before it becomes clusters (Ward & Lin 2003, §4.1)"});
    fn(&LodParams::cluster_min_radius,
       ParamInfo{"cluster_min_radius", "", "m", 0.0, 10.0,
                 "Clusters narrower than this stop splitting and strand groups take over (Ward "
                 "& Lin 2003, §4.1)"}
           .shown_as(1000.0, "mm")
           .soft(0.0, 0.05)
           .labeled("Cluster Radius"));
    fn(&LodParams::min_group_strands,
       ParamInfo{"min_group_strands", "", "", 1.0, 1000000.0,
                 "Strand groups stop splitting at this many strands; 1 goes down to single "
                 "strands (Ward & Lin 2003, §4.2, §7.2)"}
           .soft(1.0, 20.0)
           .labeled("Group Strands"));
    fn(&LodParams::skeleton_points,
       ParamInfo{"skeleton_points", "n", "", 0.0, 1000.0,
                 "Control points of every skeleton, the same at every level (Ward & Lin 2003, "
                 "§3, §4); 0, or more than the groom's longest strand has, takes that strand's "
                 "count"}
           .soft(0.0, 64.0));
    fn(&LodParams::finest_level,
       ParamInfo{"finest_level", "", "", -1.0, 64.0,
                 "Deepest hierarchy level used (Ward & Lin 2003, §6.1); -1 is the deepest"});
    fn(&LodParams::coarsest_level,
       ParamInfo{"coarsest_level", "", "", 0.0, 64.0,
                 "Coarsest hierarchy level used, and where hidden hair goes (Ward & Lin 2003, "
                 "§6.1); 0 is the top strips. A deeper level keeps hidden hair closer to a full "
                 "simulation, at more cost"});
    fn(&LodParams::distance_near,
       ParamInfo{"distance_near", "", "m", 0.0, 1e6,
                 "Camera distance at or below which the finest level is chosen (Ward & Lin "
                 "2003, §6.1)"}
           .soft(0.0, 20.0));
    fn(&LodParams::distance_far,
       ParamInfo{"distance_far", "", "m", 0.0, 1e6,
                 "Camera distance at or beyond which the coarsest level is chosen; levels "
                 "between are interpolated (Ward & Lin 2003, §6.1)"}
           .soft(0.0, 100.0));
    fn(&LodParams::velocity_slow,
       ParamInfo{"velocity_slow", "", "m/s", 0.0, 1e4,
                 "Hair speed at or below which motion asks only for the coarsest level (Ward & "
                 "Lin 2003, §6.1)"}
           .soft(0.0, 5.0));
    fn(&LodParams::velocity_fast,
       ParamInfo{"velocity_fast", "", "m/s", 0.0, 1e4,
                 "Hair speed at or above which motion asks for the finest level (Ward & Lin "
                 "2003, §6.1)"}
           .soft(0.0, 10.0));
    fn(&LodParams::use_occlusion,
       ParamInfo{"use_occlusion", "", "", 0.0, 1.0,
                 "Hair outside the camera's view or behind the colliders falls to the coarsest "
                 "level (Ward & Lin 2003, §6.1)"});
    fn(&LodParams::merge_threshold,
       ParamInfo{"merge_threshold", "", "m", 0.0, 10.0,
                 "Children merge only when every control point is this close to its place on "
                 "the merged parent (Ward & Lin 2003, §6.3)"}
           .shown_as(1000.0, "mm")
           .soft(0.0, 0.05));
    fn(&LodParams::transition_time,
       ParamInfo{"transition_time", "", "s", 0.0, 10.0,
                 "Time constant of the spring that pulls strands into place after a split or "
                 "merge (Ward & Lin 2003, §6.3); 0 switches at once"}
           .soft(0.0, 1.0));
  }
};

/* Empty when the parameters make sense together, else one sentence (near < far, slow < fast,
 * coarsest <= finest). */
inline const char *find_lod_params_error(const LodParams &params)
{
  if (!(params.distance_near < params.distance_far)) {
    return "distance_near must be smaller than distance_far";
  }
  if (!(params.velocity_slow < params.velocity_fast)) {
    return "velocity_slow must be smaller than velocity_fast";
  }
  if (params.finest_level >= 0 && params.finest_level < params.coarsest_level) {
    return "finest_level must be -1 or at least coarsest_level";
  }
  return "";
}

}  // namespace hairdyn
