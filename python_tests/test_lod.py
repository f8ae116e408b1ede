"""Level of detail (Ward & Lin 2003) through the native module: a cap of strands on a head,
cameras far and close, the report's figures, and bad input refused with a sentence."""

import numpy as np
import pytest

from hairdyn import native


def cap_groom(strands_num=120, points_num=8, radius=0.1, segment=0.02):
    """Strands rooted on a Fibonacci spiral over the top of a sphere, leaning out and down."""
    golden = np.pi * (3.0 - np.sqrt(5.0))
    positions = []
    for s in range(strands_num):
        z = 1.0 - (1.0 - np.cos(1.3)) * (s + 0.5) / strands_num
        ring = np.sqrt(max(1.0 - z * z, 0.0))
        azimuth = golden * s
        n = np.array([ring * np.cos(azimuth), ring * np.sin(azimuth), z])
        out = np.array([np.cos(azimuth), np.sin(azimuth), 0.0])
        p = radius * n
        positions.append(p)
        for i in range(1, points_num):
            e = np.exp(-i / 3.0)
            d = e * n + 0.5 * out + (1.0 - e) * np.array([0.0, 0.0, -1.0])
            p = p + segment * d / np.linalg.norm(d)
            positions.append(p)
    offsets = np.arange(strands_num + 1, dtype=np.int32) * points_num
    return offsets, np.array(positions, dtype=np.float32)


def view_projection(eye, target=(0.0, 0.0, 0.0), fov=np.radians(60.0), near=0.01, far=1000.0):
    """Blender-style row-major projection @ view for a camera at eye looking at target, Z up."""
    eye, target = np.asarray(eye, float), np.asarray(target, float)
    forward = target - eye
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    view = np.eye(4)
    view[0, :3], view[1, :3], view[2, :3] = right, up, -forward
    view[:3, 3] = -view[:3, :3] @ eye
    f = 1.0 / np.tan(fov / 2.0)
    projection = np.array(
        [
            [f, 0, 0, 0],
            [0, f, 0, 0],
            [0, 0, (far + near) / (near - far), 2 * far * near / (near - far)],
            [0, 0, -1, 0],
        ]
    )
    return projection @ view


def make_solver(nm, **lod):
    offsets, positions = cap_groom()
    params = nm.LodParams(
        strips_num=6,
        cluster_min_radius=0.02,
        distance_near=0.35,
        distance_far=1.5,
        velocity_slow=50.0,
        velocity_fast=100.0,
        **lod,
    )
    return nm.LodSolver(offsets, positions, np.eye(4), lod_params=params), offsets, positions


def test_params_cite_the_paper_and_refuse_nonsense():
    nm = native.load()
    fields = nm.LodParams.fields()
    names = [f["name"] for f in fields]
    for name in (
        "enabled",
        "strips_num",
        "distance_near",
        "distance_far",
        "velocity_slow",
        "velocity_fast",
        "finest_level",
        "coarsest_level",
        "merge_threshold",
        "min_group_strands",
        "transition_time",
    ):
        assert name in names
    assert all("Ward & Lin 2003" in f["description"] for f in fields)
    with pytest.raises(ValueError, match="strips_num"):
        nm.LodParams(strips_num=0)
    offsets, positions = cap_groom()
    with pytest.raises(ValueError, match="distance_near must be smaller than distance_far"):
        nm.LodSolver(
            offsets,
            positions,
            np.eye(4),
            lod_params=nm.LodParams(distance_near=5.0, distance_far=2.0),
        )


def test_far_camera_keeps_the_coarsest_strips_and_a_close_one_refines():
    nm = native.load()
    solver, offsets, positions = make_solver(nm)
    assert solver.positions.shape == positions.shape
    np.testing.assert_allclose(solver.positions, positions, atol=1e-5)  # at rest: the groom
    far = view_projection((0.0, -30.0, 0.0))
    for _ in range(4):
        solver.step(1.0 / 24.0, np.eye(4), far)
    assert solver.lod_level.shape == (len(positions),)
    assert (solver.lod_level == 0).all()
    assert solver.skeletons_per_level[0] == solver.top_nodes_num
    assert sum(solver.skeletons_per_level) == solver.active_num
    assert solver.stepped_num == solver.active_num  # no switch: only the active ones step
    close = view_projection((0.0, -0.2, 0.3))
    switches = 0
    for _ in range(solver.max_depth + 2):
        solver.step(1.0 / 24.0, np.eye(4), close)
        switches += solver.lod_switches
    assert switches > 0
    assert solver.lod_level.max() == solver.max_depth
    assert np.isfinite(solver.positions).all()
    # Every strand of the groom is still there, in the groom's layout.
    lengths = np.linalg.norm(
        np.diff(solver.positions.reshape(len(offsets) - 1, -1, 3), axis=1), axis=2
    ).sum(axis=1)
    rest = np.linalg.norm(np.diff(positions.reshape(len(offsets) - 1, -1, 3), axis=1), axis=2).sum(
        axis=1
    )
    assert np.abs(lengths / rest - 1.0).max() < 0.2


def test_off_simulates_the_finest_level():
    nm = native.load()
    solver, _, _ = make_solver(nm, enabled=False)
    solver.step(1.0 / 24.0, np.eye(4), view_projection((0.0, -30.0, 0.0)))
    assert solver.lod_switches == 0
    assert solver.lod_level.min() > 0


def test_mean_distance_is_the_mean_of_row_distances():
    nm = native.load()
    rng = np.random.default_rng(3)
    a = rng.normal(size=(500, 3)).astype(np.float32)
    b = rng.normal(size=(500, 3)).astype(np.float32)
    assert nm.mean_distance(a, b) == pytest.approx(np.linalg.norm(a - b, axis=1).mean(), rel=1e-5)
    with pytest.raises(ValueError, match="same number of rows"):
        nm.mean_distance(a, b[:10])


def test_bad_input_is_refused_with_a_sentence():
    nm = native.load()
    offsets, positions = cap_groom()
    with pytest.raises(ValueError, match="root_uvs must have one row per strand"):
        nm.LodSolver(offsets, positions, np.eye(4), root_uvs=np.zeros((3, 2), np.float32))
    uvs = np.zeros((len(offsets) - 1, 2), np.float32)
    uvs[5, 1] = np.nan
    with pytest.raises(ValueError, match="root_uvs has a value that is not a finite number"):
        nm.LodSolver(offsets, positions, np.eye(4), root_uvs=uvs)
    with pytest.raises(ValueError):
        nm.LodSolver(offsets[:-1], positions, np.eye(4))
    solver, _, _ = make_solver(nm)
    with pytest.raises(ValueError, match="frame_dt"):
        solver.step(0.0, np.eye(4), np.eye(4))
    with pytest.raises(ValueError, match="view_projection"):
        solver.step(1.0 / 24.0, np.eye(4), np.eye(3))
