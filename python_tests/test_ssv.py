"""Swept-sphere collision (Ward & Lin 2003 section 5) from Python: the parameter table the
add-on generates its Collision settings from, the crossings and segment penetration measures,
the passes, and the errors a caller gets for bad input."""

import math

import numpy as np
import pytest

from hairdyn import native


@pytest.fixture(scope="module")
def n():
    return native.load()


def parallel_strands(gap, count=3, points=5):
    """`count` straight strands along x, `gap` apart along y, 1 cm segments."""
    offsets = np.arange(0, (count + 1) * points, points, dtype=np.int32)
    x = np.linspace(0.0, 0.01 * (points - 1), points, dtype=np.float32)
    positions = np.concatenate(
        [np.stack([x, np.full_like(x, i * gap), np.zeros_like(x)], axis=1) for i in range(count)]
    ).astype(np.float32)
    return offsets, positions


def blade(n, half_thickness=0.001):
    """A 10 cm square box, 2 * half_thickness thick along z, as a ColliderSet."""
    h = np.array([0.05, 0.05, half_thickness], dtype=np.float32)
    corners = (
        np.array(
            [[(1 if i & 1 else -1), (1 if i & 2 else -1), (1 if i & 4 else -1)] for i in range(8)],
            dtype=np.float32,
        )
        * h
    )
    triangles = np.array(
        [
            [0, 2, 3],
            [0, 3, 1],
            [4, 5, 7],
            [4, 7, 6],
            [0, 1, 5],
            [0, 5, 4],
            [2, 6, 7],
            [2, 7, 3],
            [0, 4, 6],
            [0, 6, 2],
            [1, 3, 7],
            [1, 7, 5],
        ],
        dtype=np.int32,
    )
    collider = n.Collider(corners, triangles)
    collider.set_transform(np.eye(4))
    return n.ColliderSet([collider])


def test_parameter_table(n):
    fields = {f["name"]: f for f in n.SweptSphereParams.fields()}
    assert list(fields) == [
        "hair_hair",
        "thickness",
        "near_parallel_angle",
        "push_strength",
        "body_collision",
        "friction",
        "distance_threshold",
    ]
    assert fields["hair_hair"]["default"] is False
    assert fields["thickness"]["unit"] == "m" and fields["thickness"]["display_unit"] == "mm"
    assert fields["thickness"]["display_scale"] == pytest.approx(1e3)
    assert fields["near_parallel_angle"]["display_scale"] == pytest.approx(180.0 / math.pi)
    assert fields["body_collision"]["choices"] == "maps,swept_spheres,both"
    assert fields["friction"]["symbol"] == "μ_f"
    params = n.SweptSphereParams(hair_hair=True, thickness=0.001, body_collision=2)
    assert params.to_dict()["thickness"] == pytest.approx(0.001)
    with pytest.raises(ValueError, match="thickness"):
        n.SweptSphereParams(thickness=-1.0)
    with pytest.raises(ValueError, match="body_collision"):
        params.body_collision = 3


def test_crossings_count_pairs_closer_than_the_radii(n):
    # Strands 3 mm apart: with 2 mm radii each strand's 4 segments touch the neighbour's
    # overlapping ones (same and adjacent segments: 4 + 3 + 3 = 10 pairs per neighbour pair).
    offsets, positions = parallel_strands(0.003)
    assert n.count_crossings(offsets, positions, thickness=0.001) == 0
    assert n.count_crossings(offsets, positions, thickness=0.002) == 2 * 10
    radii = np.full(len(positions), 0.002, dtype=np.float32)
    assert n.count_crossings(offsets, positions, radii) == 2 * 10
    with pytest.raises(ValueError, match="one value per point"):
        n.count_crossings(offsets, positions, radii[:-1])
    with pytest.raises(ValueError, match="negative"):
        n.count_crossings(offsets, positions, -radii)


def test_segment_penetration_share_sees_a_segment_through_a_thin_blade(n):
    colliders = blade(n)
    offsets = np.array([0, 3], dtype=np.int32)
    # Both nodes of the second segment are outside; the segment passes through the blade.
    positions = np.array([[-0.03, 0, 0.01], [-0.01, 0, 0.004], [0.01, 0, -0.004]], dtype=np.float32)
    assert n.segment_penetration_share(offsets, positions, colliders, 2e-4) == pytest.approx(0.5)
    stats = colliders.penetration_stats(positions, 2e-4)
    assert stats["penetration_share"] == 0.0  # the node measure sees nothing
    # 0: any depth (the add-on's report tolerance may be 0); a negative one is refused.
    assert n.segment_penetration_share(offsets, positions, colliders, 0.0) == pytest.approx(0.5)
    for bad in (-1e-4, float("nan")):
        with pytest.raises(ValueError, match="tolerance"):
            n.segment_penetration_share(offsets, positions, colliders, bad)


def test_passes_carry_their_parameters_and_statistics(n):
    colliders = blade(n)
    hair_hair = n.HairHairPass(n.SweptSphereParams(hair_hair=True))
    assert hair_hair.params.hair_hair is True
    hair_hair.params = n.SweptSphereParams(thickness=0.002)
    assert hair_hair.params.thickness == pytest.approx(0.002)
    assert hair_hair.stats == {
        "pairs_num": 0,
        "pushed_num": 0,
        "averaged_num": 0,
        "candidates_num": 0,
        "ms": 0.0,
    }
    body = n.SsvObjectPass(colliders, n.SweptSphereParams(body_collision=1))
    assert body.params.body_collision == 1
    assert set(body.stats) == {"pushed_num", "near_num", "unresolved_num", "ms"}
    body.rebuild()
    body.reset_stats()
