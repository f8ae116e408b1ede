#pragma once
/* Parameters of the volumetric hair methods of Petrovic, Henne and Anderson 2006: the density
 * grid (eq. 1), velocity smoothing as hair–hair interaction (§5.1), directing hair toward a
 * target density (§5.2, eq. 3) and the hair-shell normals (§4.1, eq. 2). Lengths in meters. */
#include <cstdint>

#include "core/params.hh"

namespace hairdyn {

struct VolumeParams {
  /* m, h: the grid's spacing (eq. 1's "grid unit"). 0 picks the groom's mean segment length. */
  float cell_size = 0.0f;
  /* s ∈ [0, 1] (§5.1): each substep every node's velocity moves this share of the way toward
   * the smoothed grid velocity at its position; 0 is off, 1 makes neighbours move as one. */
  float smoothing = 0.2f;
  /* Cells, radius of the binomial filter that smooths the grid velocities (§5.1). */
  int32_t filter_radius = 1;
  /* m/s², κ (§5.2): acceleration per unit of the relative density force F / D̄_t (F the
   * force that follows eq. 3 in grid units, D̄_t the target's mean density where it has
   * hair), so a sparse and a dense groom, and every level, feel the same; 0 turns targeting
   * off even when a target is set. */
  float target_strength = 20.0f;
  /* Coarse-to-fine levels of the targeting grid (§5.2, last paragraph): level l has cells
   * 2^l · h; targeting starts on the coarsest and refines as the error drops. */
  int32_t target_levels = 3;
  /* Refine to the next finer level once eq. 3's error on the current level is below this
   * share of its value when the level began (or stops falling). */
  float target_refine = 0.5f;
  /* m: the spacing of the shell's grid (§4.1). 0 picks 4 × the mean segment length, which
   * closes the shell over a groom of guide strands a few segment lengths apart. */
  float shell_cell_size = 0.0f;
  /* Density (nodes per grid vertex, eq. 1) of the iso-surface that is the hair shell (§4.1). */
  float shell_threshold = 0.5f;
  /* Cells, radius of the binomial filter applied to the density before the shell is built. */
  int32_t shell_blur = 2;

  template<typename Fn> static void for_each_field(Fn &&fn)
  {
    fn(&VolumeParams::cell_size,
       ParamInfo{"cell_size", "h", "m", 0.0, 1.0,
                 "Spacing of the density grid (Petrovic 2006, eq. 1); 0 uses the mean segment "
                 "length"}
           .shown_as(100.0, "cm")
           .soft(0.0, 0.1));
    fn(&VolumeParams::smoothing,
       ParamInfo{"smoothing", "s", "", 0.0, 1.0,
                 "Velocity smoothing per substep: share of the way each node moves toward the "
                 "grid's smoothed velocity (Petrovic 2006, §5.1); 0 is off"});
    fn(&VolumeParams::filter_radius,
       ParamInfo{"filter_radius", "", "cells", 0.0, 4.0,
                 "Radius of the filter that smooths the grid velocities (Petrovic 2006, §5.1)"});
    fn(&VolumeParams::target_strength,
       ParamInfo{"target_strength", "κ", "m/s²", 0.0, 1e4,
                 "Acceleration per unit of the density force toward the target, relative to "
                 "the target's mean density (Petrovic 2006, eq. 3 and the force after it)"}
           .soft(0.0, 100.0));
    fn(&VolumeParams::target_levels,
       ParamInfo{"target_levels", "", "", 1.0, 6.0,
                 "Coarse-to-fine grid levels of targeting; each coarser level doubles the cell "
                 "(Petrovic 2006, §5.2)"});
    fn(&VolumeParams::target_refine,
       ParamInfo{"target_refine", "", "", 0.0, 1.0,
                 "Refine the targeting grid when the error of eq. 3 falls below this share of "
                 "its value at the level's start (Petrovic 2006, §5.2)"});
    fn(&VolumeParams::shell_cell_size,
       ParamInfo{"shell_cell_size", "", "m", 0.0, 1.0,
                 "Spacing of the hair shell's grid (Petrovic 2006, §4.1); 0 uses 4 × the mean "
                 "segment length"}
           .shown_as(100.0, "cm")
           .soft(0.0, 0.2));
    fn(&VolumeParams::shell_threshold,
       ParamInfo{"shell_threshold", "", "", 1e-3, 1e4,
                 "Density (nodes per grid vertex, eq. 1) of the hair shell's iso-surface "
                 "(Petrovic 2006, §4.1)"}
           .soft(0.05, 10.0));
    fn(&VolumeParams::shell_blur,
       ParamInfo{"shell_blur", "", "cells", 0.0, 4.0,
                 "Radius of the filter applied to the density before the hair shell is built"});
  }
};

}  // namespace hairdyn
