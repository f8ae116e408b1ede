"""The native particle skin (`_native.ParticleSkin`, Bando 2003 §4) on a small groom carried by
a running LCP solver (it replaced a numpy version, matched to 1e-5 before that was removed),
and the (u, v, s) binding of a strand to its own particles."""

from types import SimpleNamespace

import numpy as np

from hairdyn import native


def small_groom():
    """9 wavy strands of 10 points, 4 cm apart, hanging 9 cm from a head at (0.1, 0, 1.5)."""
    rng = np.random.default_rng(4)
    strands = []
    for a in range(3):
        for b in range(3):
            root = np.array([0.04 * a, 0.04 * b, 0.0])
            k = np.arange(10)[:, None]
            wave = 0.004 * np.sin(k * 0.9 + rng.uniform(0, 6)) * np.array([1.0, 0.0, 0.0])
            strands.append(root + k * np.array([0.0, 0.0, -0.01]) + wave)
    positions = np.concatenate(strands) + [0.1, 0.0, 1.5]
    return SimpleNamespace(
        curve_offsets=np.arange(0, 100, 10, dtype=np.int32),
        positions_wo=np.ascontiguousarray(positions, dtype=np.float32),
    )


def test_native_skin_carries_the_groom_on_a_running_solver():
    n = native.load()
    groom = small_groom()
    params = n.LcpParams(particle_spacing=0.012, particle_num=0, h1=0.016, h2=0.011)
    particles = n.lcp_particles_from_groom(params, groom.curve_offsets, groom.positions_wo)
    head = np.eye(4)
    head[:3, 3] = [0.1, 0.0, 1.4]
    solver = n.LcpSolver(
        params,
        particles["positions"],
        particles["directions"],
        particles["u"],
        particles["v"],
        particles["s"],
        head.astype(np.float32),
    )
    rest_lengths = np.linalg.norm(np.diff(groom.positions_wo.reshape(9, 10, 3), axis=1), axis=2)
    roots_local = groom.positions_wo[::10] - head[:3, 3]
    skin = n.ParticleSkin(groom, solver, head)
    assert skin.points_num == 90 and skin.particles_num == solver.particles_num
    assert np.abs(skin.apply(solver.positions, head) - groom.positions_wo).max() < 1e-6
    for frame in range(1, 7):  # the head turns and moves; the hair lags behind
        angle = 0.15 * frame
        head = np.eye(4)
        head[:3, :3] = [
            [np.cos(angle), -np.sin(angle), 0],
            [np.sin(angle), np.cos(angle), 0],
            [0, 0, 1],
        ]
        head[:3, 3] = [0.1 + 0.01 * frame, 0.0, 1.4]
        solver.step(1.0 / 24.0, head.astype(np.float32))
        got = skin.apply(solver.positions, head)
        assert got.dtype == np.float32 and got.shape == groom.positions_wo.shape
        lengths = np.linalg.norm(np.diff(got.reshape(9, 10, 3), axis=1), axis=2)
        assert np.abs(lengths - rest_lengths).max() < 1e-5, frame  # no stretch
        roots = roots_local @ head[:3, :3].T + head[:3, 3]  # roots carried by the head
        assert np.abs(got[::10] - roots).max() < 1e-5, frame
    assert np.abs(got - groom.positions_wo).max() > 0.01  # the case is not a rest state


def test_native_skin_binds_a_strand_to_its_own_particles():
    """Strand B's particles sit right on strand A's points, yet moving them moves B, never A:
    the binding is by (u, v, s) (eq. 3's distance), not by where the particles are."""
    down = np.array([0.0, 0.0, -1.0], np.float32)
    roots = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]], np.float32)
    groom = SimpleNamespace(
        curve_offsets=np.array([0, 3, 6], np.int32),
        positions_wo=np.concatenate(
            [root + np.outer([0.0, 0.1, 0.2], down) for root in roots]
        ).astype(np.float32),
    )
    s = np.array([-0.01, 0.1, 0.2] * 2, np.float32)
    positions = np.concatenate(
        [roots[0] + np.outer(s[:3], down), roots[0] + np.outer(s[3:], down) + 0.001]
    ).astype(np.float32)
    positions[3] = roots[1] - 0.01 * down  # B's root particle under B's root
    solver = SimpleNamespace(
        positions=positions,
        s=s,
        u=np.array([0.0] * 3 + [1.0] * 3, np.float32),
        v=np.zeros(6, np.float32),
        directions=np.tile(down, (6, 1)),
    )
    head = np.eye(4)
    skin = native.load().ParticleSkin(groom, solver, head, neighbours_num=2)
    assert np.allclose(skin.apply(solver.positions, head), groom.positions_wo, atol=1e-6)
    moved = solver.positions.copy()
    moved[4:] += [0.0, 0.05, 0.0]  # B's free particles
    strands = skin.apply(moved, head)
    assert np.allclose(strands[:3], groom.positions_wo[:3], atol=1e-6)  # A stays
    assert strands[5, 1] > 0.03  # B's tip moved with its particles
    assert np.allclose(np.linalg.norm(np.diff(strands[3:], axis=0), axis=1), 0.1, atol=1e-5)


def test_native_skin_refuses_bad_input_with_a_sentence():
    import pytest

    n = native.load()
    groom = small_groom()
    params = n.LcpParams(particle_spacing=0.012, particle_num=0, h1=0.016, h2=0.011)
    particles = n.lcp_particles_from_groom(params, groom.curve_offsets, groom.positions_wo)
    solver = SimpleNamespace(
        **{k: particles[k] for k in ("positions", "directions", "u", "v", "s")}
    )
    with pytest.raises(ValueError, match="singular"):
        n.ParticleSkin(groom, solver, np.zeros((4, 4)))
    skin = n.ParticleSkin(groom, solver, np.eye(4))
    with pytest.raises(ValueError, match="one row per particle"):
        skin.apply(particles["positions"][:-1], np.eye(4))
    bad = particles["positions"].copy()
    bad[7, 1] = np.nan
    with pytest.raises(ValueError, match="row 7|point 7|7"):
        skin.apply(bad, np.eye(4))


def test_native_skin_from_the_particles_shape_needs_their_directions():
    """A skin that gives the strands the particles' shape reads their directions; without
    them, or with the wrong count, a sentence, not a crash."""
    import pytest

    n = native.load()
    groom = small_groom()
    params = n.LcpParams(particle_spacing=0.012, particle_num=0, h1=0.016, h2=0.011)
    particles = n.lcp_particles_from_groom(params, groom.curve_offsets, groom.positions_wo)
    solver = SimpleNamespace(
        **{k: particles[k] for k in ("positions", "directions", "u", "v", "s")}
    )
    skin = n.ParticleSkin(groom, solver, np.eye(4), shape_from_particles=True)
    with pytest.raises(ValueError, match="needs the particles' directions"):
        skin.apply(particles["positions"], np.eye(4))
    with pytest.raises(ValueError, match="directions_wo must have one row per particle"):
        skin.apply(particles["positions"], np.eye(4), directions_wo=particles["directions"][:-1])
    # Particles along the groom: the groom's own shape, within the particles' spread.
    strands = skin.apply(particles["positions"], np.eye(4), directions_wo=particles["directions"])
    assert np.abs(strands - groom.positions_wo).max() < 0.012
