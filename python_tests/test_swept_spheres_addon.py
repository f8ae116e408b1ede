"""Swept spheres (Ward & Lin 2003 §5) in the add-on: the Strands method's hair-hair and
segment-exact body collision passes, set from the panel's group or --set, and their report."""

import bpy

from conftest import scale_radius_attribute
from hairdyn import cli, simulation


def test_hair_hair_and_swept_sphere_body_collision_report(open_fixture):
    open_fixture("head_shake.blend")
    hair = bpy.data.objects["Hair"]
    settings = hair.hairdyn
    cli.apply_settings(
        settings,
        [
            "method=strands",
            "hair_hair=true",
            "body_collision=swept_spheres",
            "strands.children_per_guide=0",
        ],
    )
    assert (
        settings.swept_spheres.hair_hair
        and settings.swept_spheres.body_collision == 'SWEPT_SPHERES'
    )
    report = simulation.run(bpy.context, hair, 1, 4)
    assert report["nan_frames"] == 0 and report["stretch_max"] < 1e-4
    assert report["hair_hair_ms"] > 0.0 and report["hair_hair_pairs"] >= 0
    assert report["crossings"] >= 0
    assert 0.0 <= report["segment_penetration_share"] <= 0.001


def test_swept_spheres_off_adds_nothing(open_fixture):
    open_fixture("head_shake.blend")
    hair = bpy.data.objects["Hair"]
    hair.hairdyn.method = 'STRANDS'
    report = simulation.run(bpy.context, hair, 1, 2)
    assert "hair_hair_ms" not in report and "volume_ms" not in report


def test_report_tolerance_at_its_panel_minimum_counts_any_depth(open_fixture):
    """The panel lets the report tolerance go down to 0 (any depth counts); the segment
    measure takes it like the node measure, in bounded time."""
    open_fixture("head_shake.blend")
    hair = bpy.data.objects["Hair"]
    settings = hair.hairdyn
    cli.apply_settings(
        settings, ["method=strands", "body_collision=both", "strands.children_per_guide=0"]
    )
    lowest = settings.collision.bl_rna.properties["penetration_tolerance"].hard_min
    settings.collision.penetration_tolerance = lowest
    assert settings.collision.penetration_tolerance == 0.0
    report = simulation.run(bpy.context, hair, 1, 3)
    assert report["nan_frames"] == 0
    assert 0.0 <= report["segment_penetration_share"] <= 1.0
    assert report["penetration_tolerance"] == 0.0


def test_the_curves_radius_attribute_sizes_the_swept_spheres(open_fixture):
    """Each strand's swept spheres take its Curves radius attribute (in world meters, the
    object's scale applied); Strand Thickness stands in where there is none, or where the
    attribute holds a negative value or one thicker than Strand Thickness may be (with a
    warning in the report)."""

    def run_with(scale=None, broken=None):
        open_fixture("head_shake.blend")
        hair = bpy.data.objects["Hair"]
        scale_radius_attribute(hair, scale, broken)
        cli.apply_settings(
            hair.hairdyn,
            [
                "method=strands",
                "hair_hair=true",
                "swept_spheres.thickness=0.5",  # mm
                "strands.children_per_guide=0",
            ],
        )
        return simulation.run(bpy.context, hair, 1, 3)

    none, thin, thick = run_with(None), run_with(0.25), run_with(4.0)
    # The fixture's radii (0.4-1.2 mm) against the 0.5 mm thickness: the pairs within reach
    # grow with the radii.
    assert thin["hair_hair_pairs"] < none["hair_hair_pairs"] < thick["hair_hair_pairs"]
    assert thin["crossings"] < thick["crossings"]
    for value in (-1.0, 1e30):  # 1e30 m: every pair would be pushed kilometres apart
        broken = run_with(1.0, broken=(5, value))
        assert broken["hair_hair_pairs"] == none["hair_hair_pairs"]
        assert any("radius attribute" in w for w in broken["groom_warnings"])
