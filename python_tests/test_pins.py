"""Pinned points (the BOOLEAN point attribute `hairdyn_fixed`, TressFX's immovable vertices):
every simulating method holds them on their rest positions carried by the head, like the roots
(Strands in both models, with a substep pass, and LCP through its particles and its skin);
level of detail, which simulates skeletons rather than the artist's strands, refuses them with
a sentence."""

import bpy
import numpy as np
import pytest

from hairdyn import bridge, cli, simulation
from hairdyn.errors import HairdynError

FRAMES = 16


def pin(hair, points):
    """Sets `hairdyn_fixed` on the roots (as the TressFX importer writes it) and on the given
    point indices of the hair."""
    curves = hair.data
    fixed = np.zeros(len(curves.points), dtype=bool)
    fixed[offsets(hair)[:-1]] = True
    fixed[np.asarray(points, dtype=np.int64)] = True
    old = curves.attributes.get(bridge.FIXED_ATTRIBUTE)
    if old is not None:
        curves.attributes.remove(old)
    curves.attributes.new(bridge.FIXED_ATTRIBUTE, 'BOOLEAN', 'POINT').data.foreach_set(
        "value", fixed
    )


def offsets(hair):
    result = np.empty(len(hair.data.curves) + 1, dtype=np.int32)
    hair.data.curve_offset_data.foreach_get("value", result)
    return result


def chosen_points(hair):
    """The tips of every other strand and the middle point of every fourth."""
    o = offsets(hair)
    return np.concatenate([o[1:][::2] - 1, ((o[:-1] + o[1:]) // 2)[::4]])


@pytest.fixture
def shake(saved_fixture):
    hair = saved_fixture("head_shake.blend", FRAMES)
    hair.hairdyn.strands.children_per_guide = 0
    return hair


def drift_over_bake(hair, points):
    """Simulates frames 1..FRAMES; returns (the farthest one of `points` got from its rest
    position carried by the head, the farthest any other point got, in metres; the report)."""
    bpy.context.scene.frame_set(1)
    rest = bridge.read_curves(hair, bpy.context.evaluated_depsgraph_get()).positions_wo
    body = bpy.data.objects["Body"]
    to_rest = np.linalg.inv(np.array(body.matrix_world, dtype=np.float64))
    others = np.ones(len(rest), dtype=bool)
    others[points] = False
    worst = {"points": 0.0, "others": 0.0}

    def on_frame(_frame, _ms):
        carry = np.array(body.matrix_world, dtype=np.float64) @ to_rest
        carried = rest @ carry[:3, :3].T + carry[:3, 3]
        output = bridge.read_curves(
            hair.hairdyn.output_curves, bpy.context.evaluated_depsgraph_get()
        ).positions_wo
        off = np.linalg.norm(output - carried, axis=1)
        worst["points"] = max(worst["points"], float(off[points].max()))
        worst["others"] = max(worst["others"], float(off[others].max()))

    report = simulation.run(bpy.context, hair, 1, FRAMES, on_frame=on_frame)
    return worst["points"], worst["others"], report


@pytest.mark.parametrize(
    "settings",
    [
        ["method=strands"],
        ["method=strands", "strands.model=articulated"],
        ["method=strands", "swept_spheres.hair_hair=true"],
        ["method=lcp", "lcp_init.particles_from=groom"],
        ["method=lcp"],
    ],
    ids=["kurihara1993", "articulated", "swept_spheres", "lcp_from_groom", "lcp_scalp"],
)
def test_pinned_points_are_carried_by_the_head(shake, settings):
    hair = shake
    points = chosen_points(hair)
    pin(hair, points)
    cli.apply_settings(hair.hairdyn, settings)
    pinned, others, report = drift_over_bake(hair, points)
    assert report["pinned_points"] == len(points)
    assert others > 0.005, "the shake does not move the free points: a vacuous test"
    # Output positions are float32 in world space ~1.5 m from the origin (0.1 µm steps).
    assert pinned <= 1e-4, f"pinned points moved {pinned * 1000:.3f} mm off the head"


def test_the_same_points_swing_without_pins(shake):
    """What the test above guards against: with only the roots pinned, as every TressFX
    import has them, the same points leave the head-carried rest shape by centimetres."""
    hair = shake
    pin(hair, [])
    cli.apply_settings(hair.hairdyn, ["method=strands"])
    points = chosen_points(hair)
    moved, _, report = drift_over_bake(hair, points)
    assert report["pinned_points"] == 0
    assert moved > 0.01


def test_level_of_detail_refuses_pinned_points(shake):
    hair = shake
    points = chosen_points(hair)
    pin(hair, points)
    cli.apply_settings(hair.hairdyn, ["method=strands", "lod.enabled=true"])
    with pytest.raises(HairdynError, match=f"cannot hold pinned points: {len(points)} points"):
        simulation.run(bpy.context, hair, 1, 1)
    # Only the roots pinned (every TressFX import): level of detail runs.
    pin(hair, [])
    assert simulation.run(bpy.context, hair, 1, 1)["pinned_points"] == 0
