"""Volumetric hair (Petrovic, Henne & Anderson 2006) through the Python API: parameters, the
density grid against a numpy reference of eq. 1, the substep pass on numpy buffers, the hair
shell and its transported normals, the checks at the boundary, and the OpenVDB file."""

import bpy
import numpy as np
import pytest

from hairdyn import _native, volume_vdb


def ball(center, radius=0.05, spacing=0.004):
    """Vertical strands filling a ball (chords on a square lattice), nodes `spacing` apart."""
    offsets, points = [0], []
    n = int(radius / spacing)
    for a in range(-n, n + 1):
        for b in range(-n, n + 1):
            xy = spacing * np.array([a + 0.3, b + 0.1])
            half = np.sqrt(max(radius * radius - xy @ xy, 0.0))
            count = int(2 * half / spacing) + 1
            if count < 2:
                continue
            z = np.linspace(-half, half, count)
            points += [[center[0] + xy[0], center[1] + xy[1], center[2] + zi] for zi in z]
            offsets.append(len(points))
    return np.array(offsets, np.int32), np.array(points, np.float32)


def wavy_groom(strands=40, points=10, seed=0):
    rng = np.random.default_rng(seed)
    offsets = np.arange(0, strands * points + 1, points, dtype=np.int32)
    roots = rng.uniform(-0.05, 0.05, (strands, 3)) * [1, 1, 0.2]
    steps = np.stack([0.01 * np.sin(np.arange(points) * 0.7 + s) for s in range(strands)])
    positions = np.zeros((strands, points, 3))
    positions[:, :, 0] = roots[:, None, 0] + np.cumsum(steps, axis=1)
    positions[:, :, 1] = roots[:, None, 1]
    positions[:, :, 2] = roots[:, None, 2] - 0.015 * np.arange(points)
    return offsets, positions.reshape(-1, 3).astype(np.float32)


def density_reference(points_grid, shape):
    """eq. 1 in numpy: each point adds the tent weights to its cell's 8 corners."""
    density = np.zeros(shape)
    for p in points_grid:
        cell = np.minimum(np.floor(p).astype(int), np.array(shape) - 2)
        f = p - cell
        for corner in np.ndindex(2, 2, 2):
            w = np.prod(np.where(corner, f, 1.0 - f))
            density[tuple(cell + corner)] += w
    return density


def test_params_carry_the_papers_symbols():
    fields = {row["name"]: row for row in _native.VolumeParams.fields()}
    assert fields["cell_size"]["symbol"] == "h" and fields["cell_size"]["unit"] == "m"
    assert fields["smoothing"]["symbol"] == "s" and fields["smoothing"]["max"] == 1.0
    assert fields["target_strength"]["symbol"] == "κ"
    assert all(row["description"] for row in fields.values())
    with pytest.raises(ValueError, match="smoothing"):
        _native.VolumeParams(smoothing=1.5)


def test_density_grid_matches_numpy_reference():
    offsets, positions = wavy_groom(strands=12, points=8)
    head = np.eye(4)
    head[:3, 3] = [0.3, -0.2, 1.1]
    density, grid_to_world = _native.density_grid(
        offsets, positions + head[:3, 3].astype(np.float32), head, cell_size=0.02
    )
    world_to_grid = np.linalg.inv(grid_to_world)
    shifted = positions + head[:3, 3]
    grid_points = (np.c_[shifted, np.ones(len(shifted))] @ world_to_grid.T)[:, :3]
    reference = density_reference(grid_points, density.shape)
    np.testing.assert_allclose(density, reference, atol=1e-4)  # float32 world coordinates
    assert density.sum() == pytest.approx(len(positions), rel=1e-6)


def test_pass_keeps_a_uniform_field_and_never_adds_energy():
    offsets, positions = wavy_groom()
    velocities = np.tile(np.float32([0.2, -0.1, 0.05]), (len(positions), 1))
    volume = _native.VolumePass(_native.VolumeParams(smoothing=1.0))
    moved = positions.copy()
    volume.apply(offsets, moved, velocities, 0.01)
    np.testing.assert_allclose(velocities, [[0.2, -0.1, 0.05]] * len(positions), atol=1e-6)
    assert volume.density_max > 0 and volume.substeps_num == 1

    rng = np.random.default_rng(3)
    velocities = rng.normal(size=positions.shape).astype(np.float32)
    velocities[offsets[:-1]] = 0.0  # roots are carried by the head, not by the pass
    before = (velocities**2).sum()
    roots = positions[offsets[:-1]].copy()
    moved = positions.copy()
    volume.apply(offsets, moved, velocities, 0.01)
    assert (velocities**2).sum() < before
    np.testing.assert_array_equal(moved[offsets[:-1]], roots)


def test_targeting_lowers_the_error_of_eq3():
    """Free nodes (strands of two points whose roots stay) pushed by the density force alone,
    with damping, toward a shifted copy: eq. 3's error falls."""
    offsets, positions = wavy_groom(strands=60, points=6, seed=4)
    target = positions + np.float32([0.02, 0.0, 0.0])
    volume = _native.VolumePass(
        _native.VolumeParams(smoothing=0.0, cell_size=0.015, target_strength=5.0, target_levels=2)
    )
    volume.set_target(offsets, target)
    velocities = np.zeros_like(positions)
    errors = []
    for _ in range(150):
        volume.apply(offsets, positions, velocities, 0.01)
        velocities *= 0.9
        errors.append(volume.target_error)
    assert errors[-1] < 0.5 * errors[0]
    assert volume.target_level == 0


def test_shell_normals_are_radial_and_follow_rigid_motion():
    center = np.array([0.0, 0.0, 1.0])
    offsets, positions = ball(center)
    params = _native.VolumeParams(shell_cell_size=0.008, shell_threshold=2.0, shell_blur=3)
    shell = _native.HairShell(offsets, positions, None, params)
    radial = positions - center
    distance = np.linalg.norm(radial, axis=1)
    surface = distance > 0.9 * 0.05
    cosines = (shell.rest_normals[surface] * radial[surface]).sum(axis=1) / distance[surface]
    assert np.degrees(np.arccos(np.clip(cosines, -1, 1))).max() < 5.0
    assert shell.signed_distance.min() < 0 < shell.signed_distance.max()
    np.testing.assert_allclose(
        _native.shell_normals(offsets, positions, None, params), shell.rest_normals
    )

    angle = 0.8
    motion = np.eye(4)
    motion[:3, :3] = [
        [np.cos(angle), -np.sin(angle), 0],
        [np.sin(angle), np.cos(angle), 0],
        [0, 0, 1],
    ]
    motion[:3, 3] = [0.1, 0.2, -0.3]
    moved = (positions @ motion[:3, :3].T + motion[:3, 3]).astype(np.float32)
    normals = shell.transport(moved, motion)
    np.testing.assert_allclose(normals, shell.rest_normals @ motion[:3, :3].T, atol=1e-4)


def test_bad_input_is_a_clear_error():
    offsets, positions = wavy_groom()
    volume = _native.VolumePass()
    with pytest.raises(ValueError, match="writeable"):
        frozen = positions.copy()
        frozen.flags.writeable = False
        volume.apply(offsets, frozen, np.zeros_like(positions), 0.01)
    with pytest.raises(ValueError, match="velocities_wo"):
        volume.apply(offsets, positions.copy(), np.zeros((3, 3), np.float32), 0.01)
    with pytest.raises(ValueError, match="float32"):
        volume.apply(offsets, positions.astype(np.float64), np.zeros_like(positions), 0.01)
    with pytest.raises(ValueError, match="h must be"):
        volume.apply(offsets, positions.copy(), np.zeros_like(positions), float("nan"))
    broken = positions.copy()
    broken[5, 1] = np.nan
    with pytest.raises(ValueError, match="finite"):
        _native.density_grid(offsets, broken)
    with pytest.raises(ValueError, match="shell threshold"):
        _native.HairShell(offsets, positions, None, _native.VolumeParams(shell_threshold=1e4))


def test_density_grid_as_openvdb(tmp_path):
    """The grid written as a .vdb reads back with its values and placement, and loads into a
    Blender Volume datablock."""
    writer, reason = volume_vdb.find_writer()
    offsets, positions = wavy_groom()
    density, grid_to_world = _native.density_grid(offsets, positions, None, 0.01)
    path = str(tmp_path / "density.vdb")
    if writer is None:
        with pytest.raises(RuntimeError, match="OpenVDB|pyopenvdb"):
            volume_vdb.write_density_vdb(path, density, grid_to_world)
        pytest.skip(f"no OpenVDB writer in this host: {reason}")
    volume_vdb.write_density_vdb(path, density, grid_to_world)
    grid = writer.read(path, "density")
    ijk = tuple(int(i) for i in np.unravel_index(np.argmax(density), density.shape))
    assert grid.getConstAccessor().getValue(ijk) == pytest.approx(float(density[ijk]))
    np.testing.assert_allclose(
        grid.transform.indexToWorld(ijk), (grid_to_world @ [*ijk, 1])[:3], atol=1e-6
    )
    volume = bpy.data.volumes.new("density")
    volume.filepath = path
    volume.grids.load()
    assert [g.name for g in volume.grids] == ["density"]


def test_pass_runs_inside_the_strand_solver():
    """Registered with the solver, the pass runs after every substep and the solver times it."""
    offsets, positions = wavy_groom()
    solver = _native.StrandSolver(offsets, positions, np.eye(4))
    volume = _native.VolumePass(_native.VolumeParams(smoothing=0.5))
    solver.add_pass(volume)
    for _ in range(3):
        solver.step(1 / 24, np.eye(4))
    assert volume.substeps_num == 3 * solver.params.substeps
    assert solver.pass_ms("volume") > 0.0
    assert volume.density_max > 0.0
    assert np.isfinite(solver.positions).all()
