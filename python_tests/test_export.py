"""Export Bake: the baked output hair (guides and child hairs) to Alembic and USD with Blender's
own exporters, read back with Blender's own importers: positions equal to the cache at three
frames. Hosts without an exporter (Debian's Blender 3.4 has neither) skip, naming it, and the
operator says why it is unavailable."""

import json
import subprocess
import sys

import bpy
import numpy as np
import pytest

from conftest import ROOT, host_name

FRAMES = (1, 6)
CHECKED = (2, 4, 6)


def _exporter_missing(suffix):
    from hairdyn import export

    return export.missing(suffix)


@pytest.fixture
def baked_shake(open_fixture, tmp_path):
    """head_shake.blend's hair baked over a few frames, with child hairs."""
    from hairdyn import bake, cli
    from hairdyn.cache import Cache

    open_fixture("head_shake.blend")
    hair = bpy.data.objects["Hair"]
    hair.hairdyn.cache_directory = str(tmp_path / "cache")
    hair.hairdyn.frame_start, hair.hairdyn.frame_end = FRAMES
    cli.apply_settings(hair.hairdyn, ["method=strands", "children_per_guide=2"])
    runner = bake.start_bake(bpy.context, hair)
    while not runner.done:
        runner.advance()
    bake.finish_bake(runner)
    return hair, Cache.open(bake.cache_directory(hair))


def _imported_curves(importer, path):
    """The Curves objects an importer added."""
    before = set(bpy.data.objects)
    importer(filepath=str(path))
    return [o for o in bpy.data.objects if o not in before and o.type == 'CURVES']


@pytest.mark.parametrize("suffix, importer", [(".abc", "alembic_import"), (".usd", "usd_import")])
def test_export_round_trip_matches_the_cache(suffix, importer, baked_shake, tmp_path):
    from hairdyn import export

    reason = _exporter_missing(suffix)
    if reason:
        pytest.skip(reason)
    hair, cache = baked_shake
    result = export.export_bake(bpy.context, hair, tmp_path / f"hair{suffix}")
    assert (result["frame_start"], result["frame_end"]) == FRAMES
    assert result["objects"] == [hair.hairdyn.output_curves.name, hair.hairdyn.output_children.name]
    assert bpy.context.scene.frame_current == 1  # the scene is restored
    assert not hair.hairdyn.output_curves.modifiers
    imported = _imported_curves(getattr(bpy.ops.wm, importer), result["file"])
    by_points = {len(o.data.points): o for o in imported}
    guides = by_points[cache.main.points_num]
    children = by_points[cache.streams["children"].points_num]
    assert "radius" in guides.data.attributes
    moved = []
    for frame in CHECKED:
        bpy.context.scene.frame_set(frame)
        depsgraph = bpy.context.evaluated_depsgraph_get()
        expected = cache.read_frame(frame)["position"]
        got = export.read_positions(guides, depsgraph)
        # float32 positions written and read back: equal to within a few ulps of ~1.5 m
        np.testing.assert_allclose(got, expected, rtol=0, atol=1e-6)
        np.testing.assert_allclose(
            export.read_positions(children, depsgraph),
            cache.read_stream("children", frame)["position"],
            rtol=0,
            atol=1e-6,
        )
        moved.append(expected)
        if suffix == ".usd":  # USD carries the point attributes too (Alembic: radius only)
            curves = guides.evaluated_get(depsgraph).data
            velocity = np.empty(len(curves.points) * 3, dtype=np.float32)
            curves.attributes["velocity"].data.foreach_get("vector", velocity)
            np.testing.assert_allclose(
                velocity.reshape(-1, 3), cache.read_frame(frame)["velocity"], rtol=0, atol=1e-5
            )
            assert "direction" in curves.attributes
    assert np.abs(moved[0] - moved[2]).max() > 1e-3  # the frames differ: a real animation


def test_export_needs_a_bake(open_fixture, tmp_path):
    from hairdyn import export
    from hairdyn.errors import HairdynError

    if not export.available():
        pytest.skip(f"this Blender ({bpy.app.version_string}) has no Alembic or USD exporter")
    open_fixture("head_shake.blend")
    hair = bpy.data.objects["Hair"]
    hair.hairdyn.cache_directory = str(tmp_path / "nothing")
    with pytest.raises(HairdynError, match="no hairdyn cache"):
        export.export_bake(bpy.context, hair, tmp_path / "x.abc")
    with pytest.raises(HairdynError, match="not '.obj'"):
        export.export_bake(bpy.context, hair, tmp_path / "x.obj")


def test_operator_says_what_this_host_lacks(open_fixture):
    """Feature detection: the operator is available exactly where the exporters exist, and its
    description names a missing one."""
    from hairdyn import export

    open_fixture("head_shake.blend")
    bpy.context.view_layer.objects.active = bpy.data.objects["Hair"]
    lacking = [export.missing(s) for s in (".abc", ".usd") if export.missing(s)]
    assert bool(bpy.ops.hairdyn.export_bake.poll()) == bool(export.available())
    description = export.HAIRDYN_OT_export_bake.description(bpy.context, None)
    for reason in lacking:
        assert reason in description
    if host_name() == "blender" and bpy.app.version < (4, 0, 0):
        assert lacking  # Debian's 3.4 is built without both


def test_cli_export(baked_shake, tmp_path):
    """cli.py export in a real process, from the saved scene."""
    hair, cache = baked_shake
    suffix = ".usda" if not _exporter_missing(".usda") else ".abc"
    blend = tmp_path / "scene.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(blend), copy=True)
    out = tmp_path / f"cli{suffix}"
    cli = ROOT / "addon" / "hairdyn" / "cli.py"
    args = ["export", "--object", "Hair", "--file", str(out), "--cache", str(tmp_path / "cache")]
    if host_name() == "blender":
        command = [
            bpy.app.binary_path,
            "-b",
            "--factory-startup",
            str(blend),
            "--python",
            str(cli),
            "--",
            *args,
        ]
    else:
        command = [sys.executable, str(cli), "--blend", str(blend), *args]
    process = subprocess.run(command, capture_output=True, text=True, timeout=300)
    reason = _exporter_missing(suffix)
    if reason:
        assert process.returncode == 1 and reason in process.stderr, process.stderr
        return
    assert process.returncode == 0, process.stderr[-2000:]
    result = json.loads(process.stdout[process.stdout.index("{") :])
    assert result["file"] == str(out) and out.stat().st_size > 1000
    if suffix == ".usda":  # a text file: the positions are animated, frame by frame
        assert out.read_text().count("points.timeSamples") >= 1
