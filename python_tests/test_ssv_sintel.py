"""Sintel's groom through a head turn (the turn of test_sintel: 0.6 rad about the bust's
vertical axis over frames 1-12, then held to frame 24) with the swept-sphere body collision
(Ward & Lin 2003 section 5.4), natively: the share of segment-frames that cut the bust (a point
of the segment deeper than 1% of the bust's size, the report's tolerance) stays at or below
0.1%. Everything stays in the files' Y-up axes, scaled by 0.015 as the import does."""

import math

import numpy as np
import pytest

from conftest import ROOT
from hairdyn import hair_formats, native

SINTEL = ROOT.parent / "shared" / "data" / "sintel"
SCALE = 0.015


def read_obj(path):
    vertices, triangles = [], []
    with open(path) as file:
        for line in file:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                vertices.append([float(v) for v in parts[1:4]])
            elif parts[0] == "f":
                corners = [int(p.split("/")[0]) - 1 for p in parts[1:]]
                triangles += [
                    [corners[0], corners[k - 1], corners[k]] for k in range(2, len(corners))
                ]
    return np.array(vertices, dtype=np.float32) * np.float32(SCALE), np.array(
        triangles, dtype=np.int32
    )


def turn(frame):
    """The bust's transform at `frame`: a smooth turn about +Y (the files' up axis)."""
    t = min(max((frame - 1) / 11.0, 0.0), 1.0)
    angle = 0.6 * t * t * (3.0 - 2.0 * t)
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0, s, 0], [0, 1, 0, 0], [-s, 0, c, 0], [0, 0, 0, 1]], dtype=np.float64)


def segment_share(mode):
    """Mean segment penetration share of the head turn with body collision `mode` ('none':
    no body collision at all)."""
    if not SINTEL.is_dir():
        pytest.skip(f"needs the Sintel assets in {SINTEL}")
    n = native.load()
    hair = hair_formats.read_tfx(SINTEL / "sintel_hair.tfx")
    positions = np.ascontiguousarray(hair.positions * np.float32(SCALE), dtype=np.float32)
    offsets = np.ascontiguousarray(hair.curve_offsets, dtype=np.int32)
    vertices, triangles = read_obj(SINTEL / "sintel_bust.obj")
    bust = n.Collider(vertices, triangles)
    bust.set_transform(turn(1))
    colliders = n.ColliderSet([bust])
    params = n.StrandParams(gravity=(0.0, -9.81, 0.0), children_per_guide=0)
    solver = n.StrandSolver(offsets, positions, turn(1), None, params)
    choices = n.SweptSphereParams.fields()[4]["choices"].split(",")
    ssv = n.SweptSphereParams(body_collision=choices.index(mode) if mode != "none" else 0)
    if mode in ("maps", "both"):
        solver.set_colliders(colliders, n.CollisionParams())
    body = n.SsvObjectPass(colliders, ssv)
    solver.add_pass(body)
    tolerance = 0.01 * colliders.size_wo
    shares = []
    for frame in range(2, 25):
        bust.set_transform(turn(frame))
        solver.step(1.0 / 24.0, turn(frame))
        shares.append(
            n.segment_penetration_share(offsets, np.asarray(solver.positions), colliders, tolerance)
        )
    return float(np.mean(shares)), body.stats


@pytest.mark.parametrize("mode", ["swept_spheres", "both"])
def test_sintel_head_turn_segments_stay_out_of_the_bust(mode):
    share, stats = segment_share(mode)
    print(f"segment_penetration_share ({mode}): {share:.6f}, pass: {stats}")
    assert share <= 0.001
    assert stats["near_num"] > 0  # the pass met the bust


def test_sintel_head_turn_without_body_collision_cuts_the_bust():
    """The measure sees the turn: without body collision the segments do cut the bust."""
    share, _ = segment_share("none")
    maps, _ = segment_share("maps")
    print(f"segment_penetration_share: none {share:.6f}, maps only {maps:.6f}")
    assert share > 0.001
