"""Swept spheres (Ward & Lin 2003 §5) in the add-on: the Strands method's hair-hair and
segment-exact body collision passes, set from the panel's group or --set, and their report."""

import bpy

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
    cli.apply_settings(settings, ["method=strands", "body_collision=both",
                                  "strands.children_per_guide=0"])
    lowest = settings.collision.bl_rna.properties["penetration_tolerance"].hard_min
    settings.collision.penetration_tolerance = lowest
    assert settings.collision.penetration_tolerance == 0.0
    report = simulation.run(bpy.context, hair, 1, 3)
    assert report["nan_frames"] == 0
    assert 0.0 <= report["segment_penetration_share"] <= 1.0
    assert report["penetration_tolerance"] == 0.0
