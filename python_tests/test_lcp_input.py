"""LCP's native entry points name the bad point (issue 11 row 8), refuse a frame that needs
more substeps than allowed with the reason (row 9), and fail a diverged frame with a sentence
rather than returning NaN (row 4)."""

import numpy as np
import pytest

from hairdyn import native


def hanging_groom():
    offsets = np.array([0, 8, 16], np.int32)
    points = np.zeros((16, 3), np.float32)
    points[:8, 2] = points[8:, 2] = -0.02 * np.arange(8)
    points[8:, 0] = 0.03
    return offsets, points


def test_nan_in_the_hair_names_the_point():
    n = native.load()
    offsets, points = hanging_groom()
    points[11, 1] = np.nan
    with pytest.raises(ValueError, match="not a finite number .* at row 11"):
        n.lcp_particles_from_groom(n.LcpParams(particle_num=0), offsets, points)


def test_explicit_stiff_springs_are_refused_with_the_reason():
    n = native.load()
    offsets, points = hanging_groom()
    params = n.LcpParams(particle_num=0, implicit_springs=False, young_modulus=1e9)
    particles = n.lcp_particles_from_groom(params, offsets, points)
    solver = n.LcpSolver(
        params,
        particles["positions"],
        particles["directions"],
        particles["u"],
        particles["v"],
        particles["s"],
        np.eye(4, dtype=np.float32),
    )
    count, reason = solver.estimate_substeps(1.0 / 24.0)
    assert count > params.max_substeps and "explicit springs" in reason
    with pytest.raises(ValueError, match="max_substeps"):
        solver.step(1.0 / 24.0, np.eye(4, dtype=np.float32))
    assert "implicit springs" in solver.failure
    assert np.isfinite(solver.positions).all()


def test_a_spacing_too_fine_for_the_groom_is_refused_before_sampling():
    """Particles along a groom come from candidates every r/4 of every strand: two strands of
    5 km at the smallest spacing (0.1 mm) would be 400 million of them, 14 GB. Refused at once,
    with the setting to change."""
    n = native.load()
    offsets = np.array([0, 2, 4], np.int32)
    points = np.zeros((4, 3), np.float32)
    points[1, 2] = points[3, 2] = -5000.0
    points[2:, 0] = 0.03
    with pytest.raises(ValueError, match="Too many particles: .* raise the spacing"):
        n.lcp_particles_from_groom(
            n.LcpParams(particle_num=0, particle_spacing=1e-4), offsets, points
        )
