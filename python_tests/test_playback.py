"""Playback never shows what it did not verify: a bake from another groom, a missing
manifest, a frame that is a directory, values that are not finite each give a message in the
panel and on the console, and nothing of it reaches the scene. A renamed hair object keeps its
bake and its live simulation."""

import bpy
import numpy as np
import pytest

from hairdyn import bake, bridge, playback
from hairdyn.cache import Cache


@pytest.fixture
def baked(saved_fixture):
    hair = saved_fixture("head_shake.blend", 6)
    assert bpy.ops.hairdyn.bake() == {'FINISHED'}
    return hair, Cache.open(bake.cache_directory(hair))


def shown(hair):
    return bridge.read_curves(
        hair.hairdyn.output_curves, bpy.context.evaluated_depsgraph_get()
    ).positions_wo


def test_renamed_object_keeps_its_bake_and_its_live_simulation(baked):
    hair, cache = baked
    hair.name = "Renamed"
    bpy.context.scene.frame_set(3)
    assert playback.last_error(hair) is None
    assert np.array_equal(shown(hair), cache.read_frame(3)["position"])
    assert bake.cache_directory(hair) == cache.directory  # the folder recorded at bake time
    assert bpy.ops.hairdyn.bake() == {'FINISHED'}  # baking again: the same folder
    assert Cache.open(cache.directory).manifest["object"] == "Renamed"
    # Live: simulate from the start frame, rename mid-way, the simulation carries on.
    hair.hairdyn.use_cache = False
    for frame in (1, 2, 3):
        bpy.context.scene.frame_set(frame)
    before = shown(hair).copy()
    hair.name = "Renamed Again"
    bpy.context.scene.frame_set(4)
    assert playback.last_error(hair) is None
    assert not np.array_equal(shown(hair), before)  # stepped, not restarted nor stale
    assert np.array_equal(shown(hair), cache.read_frame(4)["position"])  # same as the bake


def test_a_copy_of_a_baked_object_bakes_into_its_own_folder(baked):
    hair, cache = baked
    copy = hair.copy()
    copy.data = hair.data.copy()
    copy.name = "Copy"
    bpy.context.scene.collection.objects.link(copy)
    bpy.context.view_layer.objects.active = copy
    copy.hairdyn.output_curves = copy.hairdyn.output_points = None
    assert bpy.ops.hairdyn.bake() == {'FINISHED'}
    assert bake.cache_directory(copy) != bake.cache_directory(hair)
    assert Cache.open(cache.directory).manifest["object"] == "Hair"


def expect_error(hair, frame, message, capsys):
    """The frame shows nothing new, the panel and the console name the problem."""
    before = shown(hair).copy()
    capsys.readouterr()
    bpy.context.scene.frame_set(frame)
    assert message in (playback.last_error(hair) or "")
    assert message in capsys.readouterr().out
    assert np.array_equal(shown(hair), before)
    assert np.isfinite(shown(hair)).all()


def test_a_bake_of_another_groom_is_not_shown(baked, capsys):
    hair, cache = baked
    bpy.context.scene.frame_set(2)
    data = bridge.new_curves_data("Other", np.array([3, 3]))
    data.attributes["position"].data.foreach_set(
        "vector", np.arange(18, dtype=np.float32) * 0.01
    )  # two real strands, not Hair's
    other = bpy.data.objects.new("Other", data)
    bpy.context.scene.collection.objects.link(other)
    other.hairdyn.enabled = True
    other.hairdyn.bake_folder = hair.hairdyn.bake_folder  # points at Hair's bake
    capsys.readouterr()
    bpy.context.scene.frame_set(3)
    assert "baked from another groom" in playback.last_error(other)
    assert "baked from another groom" in capsys.readouterr().out
    assert other.hairdyn.output_curves is None  # nothing was written


def test_a_deleted_manifest_is_an_error(baked, capsys):
    hair, cache = baked
    bpy.context.scene.frame_set(2)
    Cache.manifest_path(cache.directory).unlink()
    expect_error(hair, 3, "has frames but no manifest.json", capsys)


def test_a_frame_that_is_a_directory_is_an_error(baked, capsys):
    hair, cache = baked
    bpy.context.scene.frame_set(2)
    path = cache.frame_path(3)
    path.unlink()
    path.mkdir()
    expect_error(hair, 3, "frame_000003.npy' is not a file", capsys)


def test_a_frame_with_nan_is_not_shown(baked, capsys):
    hair, cache = baked
    bpy.context.scene.frame_set(2)
    table = np.load(cache.frame_path(4))
    table[7, 0] = np.nan
    np.save(cache.frame_path(4), table)
    expect_error(hair, 4, "not finite numbers in position", capsys)
    bpy.context.scene.frame_set(5)  # the next good frame shows, and clears the message
    assert playback.last_error(hair) is None
    assert np.array_equal(shown(hair), cache.read_frame(5)["position"])
