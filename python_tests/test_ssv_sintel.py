"""Sintel's groom through the head turn of test_sintel with the swept-sphere body collision
(Ward & Lin 2003 section 5.4): the share of segment-frames that cut the bust (a point of the
segment deeper than the report's tolerance, 1% of the bust's size) stays at or below 0.1%."""
import bpy
import numpy as np
import pytest

from hairdyn import native, simulation
from test_sintel import sintel_scene


def segment_shares(tmp_path, mode):
    """Per-frame segment penetration shares of the head turn with body collision `mode`
    ('maps', 'swept_spheres' or 'both')."""
    n = native.load()
    hair, _ = sintel_scene()
    hair.hairdyn.use_collision = True
    hair.hairdyn.cache_directory = str(tmp_path)
    runner = simulation.Runner(bpy.context, hair, 1, 24)
    solver, colliders = runner.simulation.solver, runner.simulation.colliders
    choices = n.SweptSphereParams.fields()[4]["choices"].split(",")
    params = n.SweptSphereParams(body_collision=choices.index(mode))
    if mode == "swept_spheres":
        solver.set_colliders(None)
    body = n.SsvObjectPass(colliders.set, params)
    solver.add_pass(body)
    offsets = np.asarray(solver.curve_offsets)
    shares = []
    while not runner.done:
        runner.advance()
        shares.append(n.segment_penetration_share(offsets, np.asarray(solver.positions),
                                                  colliders.set, colliders.tolerance_wo()))
    report = runner.report()
    assert report["nan_frames"] == 0 and report["stretch_max"] < 1e-4
    return float(np.mean(shares)), body.stats


@pytest.mark.parametrize("mode", ["swept_spheres", "both"])
def test_sintel_head_turn_segments_stay_out_of_the_bust(mode, tmp_path):
    share, stats = segment_shares(tmp_path, mode)
    print(f"segment_penetration_share ({mode}): {share:.6f}, pass: {stats}")
    assert share <= 0.001
    assert stats["near_num"] > 0  # the pass met the bust
