"""Bake to a cache on disk, play it back, resume it; bad caches give errors naming files."""
import json
import warnings
from pathlib import Path

import bpy
import numpy as np
import pytest

from hairdyn import bake, bridge, playback
from hairdyn.cache import Cache, CacheError


def make_cache(directory, points=6, offsets=(0, 3, 6)):
    return Cache.create(directory, solver="follow", parameters={"a": 1},
                        curve_offsets=np.array(offsets, np.int32),
                        columns={"position": 3, "density": 1}, frame_start=1, frame_end=4,
                        fps=24.0)


def frame_data(points=6, seed=0):
    rng = np.random.default_rng(seed)
    return {"position": rng.normal(size=(points, 3)).astype(np.float32),
            "density": rng.random(points).astype(np.float32)}


def test_cache_round_trip(tmp_path):
    cache = make_cache(tmp_path / "c")
    data = frame_data()
    cache.write_frame(2, data)
    cache.write_frame(1, frame_data(seed=1))
    assert cache.frames() == [1, 2]
    assert sorted(p.name for p in (tmp_path / "c").iterdir()) == [
        "curve_offsets.npy", "frame_000001.npy", "frame_000002.npy", "manifest.json"]
    back = Cache.open(tmp_path / "c").read_frame(2)
    assert np.array_equal(back["position"], data["position"])
    assert np.array_equal(back["density"], data["density"])
    assert Cache.open(tmp_path / "c").last_contiguous_frame() == 2
    manifest = json.loads((tmp_path / "c" / "manifest.json").read_text())
    assert manifest["format"] == "hairdyn-cache" and manifest["version"] == 1
    assert manifest["topology"]["points"] == 6 and manifest["columns"]["density"] == [3, 4]


def test_nan_frame_is_refused_and_nothing_is_written(tmp_path):
    cache = make_cache(tmp_path)
    data = frame_data()
    data["density"][3] = np.nan
    with pytest.raises(CacheError, match="Frame 3 has values that are not finite numbers in density"):
        cache.write_frame(3, data)
    assert cache.frames() == [] and not list(tmp_path.glob("*.tmp"))


def test_truncated_and_corrupted_frames_name_the_file(tmp_path):
    cache = make_cache(tmp_path)
    cache.write_frame(1, frame_data())
    path = cache.frame_path(1)
    path.write_bytes(path.read_bytes()[:-20])
    with pytest.raises(CacheError, match="frame_000001.npy' is corrupted or truncated"):
        cache.read_frame(1)
    path.write_bytes(b"not a numpy file at all")
    with pytest.raises(CacheError, match="frame_000001.npy' is corrupted or truncated"):
        cache.read_frame(1)
    np.save(path, np.zeros((5, 4), np.float32))
    with pytest.raises(CacheError, match=r"frame_000001.npy' holds float32 \(5, 4\)"):
        cache.read_frame(1)
    with pytest.raises(CacheError, match="frame_000002.npy' is missing"):
        cache.read_frame(2)


def test_topology_and_version_mismatch(tmp_path):
    cache = make_cache(tmp_path)
    with pytest.raises(CacheError, match="baked from another groom .2 strands, 6 points; this "
                                         "one has 1 strands, 6 points"):
        cache.check_topology(np.array([0, 6], np.int32))
    manifest = json.loads(Cache.manifest_path(tmp_path).read_text())
    manifest["version"] = 99
    Cache.manifest_path(tmp_path).write_text(json.dumps(manifest))
    with pytest.raises(CacheError, match="format version 99"):
        Cache.open(tmp_path)
    Cache.manifest_path(tmp_path).write_text("{ torn")
    with pytest.raises(CacheError, match="manifest.json' cannot be read"):
        Cache.open(tmp_path)
    with pytest.raises(CacheError, match="no hairdyn cache in"):
        Cache.open(tmp_path / "nothing")


def test_unwritable_cache_directory(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("a file where a folder should be")
    with pytest.raises(CacheError, match="Cannot create the cache directory"):
        make_cache(blocker / "cache")


@pytest.fixture
def saved_shake(saved_fixture, tmp_path):
    """head_shake.blend saved into tmp_path, so '//' caches land there."""
    return saved_fixture("head_shake.blend", 24), tmp_path


def read_output(hair):
    return bridge.read_curves(hair.hairdyn.output_curves,
                              bpy.context.evaluated_depsgraph_get()).positions_wo


def test_bake_playback_and_reopen(saved_shake):
    hair, tmp_path = saved_shake
    bpy.context.view_layer.objects.active = hair
    assert bpy.ops.hairdyn.bake() == {'FINISHED'}
    directory = tmp_path / "hairdyn_cache" / "Hair"
    cache = Cache.open(directory)
    assert cache.frames() == list(range(1, 25))
    assert cache.manifest["complete"] and cache.manifest["solver"] == "follow"
    assert cache.manifest["report"]["frames"] == 24
    # The blocking bake (outputs written at its last frame only) ends showing the frame the
    # scene was on.
    frame = bpy.context.scene.frame_current
    assert np.array_equal(read_output(hair), cache.read_frame(frame)["position"])
    # Scrubbing loads any cached frame into the output objects, backwards too.
    for frame in (20, 3, 12):
        bpy.context.scene.frame_set(frame)
        assert np.array_equal(read_output(hair), cache.read_frame(frame)["position"])
    # The bake survives saving and reopening; the handler is still there.
    bpy.ops.wm.save_mainfile()
    bpy.ops.wm.open_mainfile(filepath=str(tmp_path / "head_shake.blend"), load_ui=False)
    hair = bpy.data.objects["Hair"]
    assert playback.on_frame_change in bpy.app.handlers.frame_change_post
    bpy.context.scene.frame_set(7)
    assert np.array_equal(read_output(hair), cache.read_frame(7)["position"])
    assert bpy.ops.hairdyn.free_bake() == {'FINISHED'}
    assert not directory.exists() or not any(directory.iterdir())


def test_bake_is_deterministic_and_resumes_exactly(saved_shake):
    hair, tmp_path = saved_shake
    bpy.context.view_layer.objects.active = hair
    directory = tmp_path / "hairdyn_cache" / "Hair"
    assert bpy.ops.hairdyn.bake() == {'FINISHED'}
    first = {f: Cache.open(directory).frame_path(f).read_bytes() for f in range(1, 25)}
    assert bpy.ops.hairdyn.bake() == {'FINISHED'}
    second = {f: Cache.open(directory).frame_path(f).read_bytes() for f in range(1, 25)}
    assert first == second  # byte-identical frames
    # A bake that stopped after frame 10 resumes from there.
    for frame in range(11, 25):
        Cache.open(directory).frame_path(frame).unlink()
    bpy.context.scene.frame_set(11)
    assert bpy.ops.hairdyn.bake(from_current=True) == {'FINISHED'}
    resumed = {f: Cache.open(directory).frame_path(f).read_bytes() for f in range(1, 25)}
    assert resumed == first


def test_resume_with_changed_parameters_is_refused(saved_shake):
    hair, _ = saved_shake
    bpy.context.view_layer.objects.active = hair
    assert bpy.ops.hairdyn.bake() == {'FINISHED'}
    hair.hairdyn.frame_end = 30
    with pytest.raises(RuntimeError, match="parameters changed"):
        bpy.ops.hairdyn.bake(from_current=True)


def test_cache_of_another_groom_is_an_error(saved_shake):
    hair, tmp_path = saved_shake
    bpy.context.view_layer.objects.active = hair
    assert bpy.ops.hairdyn.bake() == {'FINISHED'}
    other = Cache.open(tmp_path / "hairdyn_cache" / "Hair")
    other_offsets = np.array([0, 2700], np.int32)
    with pytest.raises(CacheError, match="another groom"):
        other.check_topology(other_offsets)
    # Playback of a cache whose topology file does not match its manifest: message, no crash.
    np.save(tmp_path / "hairdyn_cache" / "Hair" / "curve_offsets.npy", other_offsets)
    playback.forget()
    bpy.context.scene.frame_set(5)
    assert "does not match its manifest" in playback.last_error(hair)


def test_a_relative_cache_folder_is_taken_without_a_warning(saved_shake):
    """Blender 4.5 and later warn when a path property that does not say it takes '//' is
    given one; the cache folder says so where Blender has the option."""
    hair, tmp_path = saved_shake
    hair.hairdyn.frame_end = 2
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        hair.hairdyn.cache_directory = "//elsewhere/"
    bpy.context.view_layer.objects.active = hair
    assert bpy.ops.hairdyn.bake() == {'FINISHED'}
    assert Cache.open(tmp_path / "elsewhere" / "Hair").frames() == [1, 2]


def test_unsaved_file_with_relative_cache_is_a_clear_error(empty_scene):
    from hairdyn.errors import HairdynError

    assert bpy.data.filepath == ""
    hair = bpy.data.objects.new("Hair", bpy.data.hair_curves.new("Hair"))
    empty_scene.collection.objects.link(hair)
    assert hair.hairdyn.cache_directory == "//hairdyn_cache/"
    with pytest.raises(HairdynError, match="Save the .blend file first"):
        bake.cache_directory(hair)
    bpy.context.view_layer.objects.active = hair
    with pytest.raises(RuntimeError, match="Save the .blend file first"):
        bpy.ops.hairdyn.bake()
    assert playback.load_frame(hair, 1) is False  # playback stays quiet: nothing was baked


def test_strand_bake_plays_back_guides_and_children(saved_shake):
    hair, tmp_path = saved_shake
    hair.hairdyn.method = 'STRANDS'
    hair.hairdyn.strands.children_per_guide = 3
    hair.hairdyn.frame_end = 12
    bpy.context.view_layer.objects.active = hair
    assert bpy.ops.hairdyn.bake() == {'FINISHED'}
    cache = Cache.open(tmp_path / "hairdyn_cache" / "Hair")
    assert cache.manifest["solver"] == "strands" and set(cache.streams) == {"children"}
    assert cache.streams["children"].points_num == 900 * 9
    assert len(cache.stream_offsets("children")) == 900 + 1
    for frame in (9, 4):
        bpy.context.scene.frame_set(frame)
        graph = bpy.context.evaluated_depsgraph_get()
        guides = bridge.read_curves(hair.hairdyn.output_curves, graph).positions_wo
        children = bridge.read_curves(hair.hairdyn.output_children, graph).positions_wo
        assert np.array_equal(guides, cache.read_frame(frame)["position"])
        assert np.array_equal(children, cache.read_stream("children", frame)["position"])
    assert not np.array_equal(cache.read_stream("children", 4)["position"],
                              cache.read_stream("children", 9)["position"])  # it moves
    cache.path("children", 7).write_bytes(b"torn")
    with pytest.raises(CacheError, match="children_000007.npy' is corrupted or truncated"):
        cache.read_stream("children", 7)


def test_object_deleted_during_a_bake_keeps_the_frames(saved_shake):
    hair, tmp_path = saved_shake
    runner = bake.start_bake(bpy.context, hair)
    for _ in range(5):
        runner.advance()
    bpy.data.objects.remove(hair)
    from hairdyn.errors import HairdynError

    with pytest.raises(HairdynError, match="deleted during the simulation; the frames written "
                                           "before are kept"):
        runner.advance()
    report = bake.finish_bake(runner)
    assert report["object"] == "Hair" and report["frames"] >= 5
    cache = Cache.open(tmp_path / "hairdyn_cache" / "Hair")
    frames = cache.frames()  # every frame simulated before the failure, complete
    assert frames[:5] == [1, 2, 3, 4, 5] and frames == list(range(1, len(frames) + 1))
    assert not cache.manifest["complete"]
    for frame in frames:
        assert cache.read_frame(frame)["position"].shape == (2700, 3)


def test_reloading_the_file_during_playback_forgets_the_open_caches(saved_shake):
    hair, tmp_path = saved_shake
    bpy.context.view_layer.objects.active = hair
    assert bpy.ops.hairdyn.bake() == {'FINISHED'}
    bpy.context.scene.frame_set(3)
    assert playback._open_caches  # playback opened the cache
    bpy.ops.wm.save_mainfile()
    bpy.ops.wm.open_mainfile(filepath=str(tmp_path / "head_shake.blend"), load_ui=False)
    assert not playback._open_caches  # the load handler dropped what belonged to the old file
    bpy.context.scene.frame_set(4)
    hair = bpy.data.objects["Hair"]
    cache = Cache.open(tmp_path / "hairdyn_cache" / "Hair")
    assert np.array_equal(read_output(hair), cache.read_frame(4)["position"])


def bake_through(hair, resume_after=None):
    """The bake as the command line runs it; returns the runner."""
    runner = bake.start_bake(bpy.context, hair, resume_after)
    try:
        while not runner.done:
            runner.advance()
    finally:
        bake.finish_bake(runner)
    return runner


def test_resume_rebakes_truncated_garbage_and_nan_frames(saved_shake):
    hair, tmp_path = saved_shake
    directory = tmp_path / "hairdyn_cache" / "Hair"
    bake_through(hair)
    first = {f: Cache.open(directory).frame_path(f).read_bytes() for f in range(1, 25)}
    cache = Cache.open(directory)
    nan = cache.read_frame(14)["position"].copy()
    table = np.load(cache.frame_path(14))
    table[3, 0] = np.nan
    np.save(cache.frame_path(14), table)  # a NaN frame of the right shape
    cache.frame_path(18).write_bytes(first[18][:100])  # truncated
    cache.frame_path(20).write_bytes(b"\x93NUMPY garbage" * 10)  # garbage
    for frame in (14, 18, 20):
        assert Cache.open(directory).frame_problem(frame) is not None
    assert np.isfinite(nan).all()
    runner = bake.start_bake(bpy.context, hair, 24)
    assert runner.next_frame == 14  # frames 1..13 kept, 14 onwards baked again
    assert Cache.open(directory).manifest["complete"] is False
    assert Cache.open(directory).frames() == list(range(1, 14))
    while not runner.done:
        runner.advance()
    bake.finish_bake(runner)
    resumed = {f: Cache.open(directory).frame_path(f).read_bytes() for f in range(1, 25)}
    assert resumed == first
    assert Cache.open(directory).manifest["complete"] is True


def test_resume_over_a_directory_frame_is_refused(saved_shake):
    hair, tmp_path = saved_shake
    directory = tmp_path / "hairdyn_cache" / "Hair"
    bake_through(hair)
    cache = Cache.open(directory)
    cache.frame_path(10).unlink()
    cache.frame_path(10).mkdir()
    with pytest.raises(CacheError, match="frame_000010.npy' is a directory"):
        bake.start_bake(bpy.context, hair, 24)
    assert Cache.open(directory).manifest["complete"] is False
    with pytest.raises(CacheError, match="is a directory"):
        Cache.open(directory).read_frame(10)


def test_resume_after_the_groom_moved_is_refused(saved_shake):
    hair, tmp_path = saved_shake
    bake_through(hair)
    positions = np.empty((len(hair.data.points), 3), np.float32)
    hair.data.position_data.foreach_get("vector", positions.ravel())
    positions[:, 2] += np.float32(0.01)  # 1 cm up, same strands
    hair.data.position_data.foreach_set("vector", positions.ravel())
    hair.data.update_tag()
    cache = Cache.open(tmp_path / "hairdyn_cache" / "Hair")
    for frame in range(13, 25):
        cache.frame_path(frame).unlink()
    with pytest.raises(CacheError, match="points moved since the bake"):
        bake.start_bake(bpy.context, hair, 24)


def test_reads_are_bit_exact_and_reused_buffers_stay_put(tmp_path):
    """A frame read through its memory map is the frame written, bit for bit; playback's reads
    (reuse) fill the same arrays frame after frame, and no map of the file stays open."""
    cache = make_cache(tmp_path)
    frames = {frame: frame_data(seed=frame) for frame in (1, 2)}
    frames[2]["position"][0] = [3e38, 3e38, 0]  # finite values whose sum overflows
    for frame, data in frames.items():
        cache.write_frame(frame, data)
    first = cache.read_frame(1, reuse=True)
    kept = {name: array for name, array in first.items()}
    for frame in (2, 1, 2):
        back = cache.read_frame(frame, reuse=True)
        assert all(back[name] is kept[name] for name in kept)
        for name, values in frames[frame].items():
            assert back[name].dtype == np.float32 and back[name].flags.c_contiguous
            assert back[name].tobytes() == values.tobytes()
    fresh = cache.read_frame(1)
    assert fresh["position"] is not kept["position"]
    assert fresh["position"].tobytes() == frames[1]["position"].tobytes()
    maps = Path("/proc/self/maps")
    if maps.is_file():
        assert str(cache.frame_path(1)) not in maps.read_text()


def test_split_columns_copies_every_width_and_checks_every_value():
    """The native pass behind every read: spans of widths 1, 2 and 3 (and none for column 5)
    of a table long enough for several chunks come out exact; a NaN or an infinity anywhere,
    in a column no span copies too, makes it report a table that is not finite."""
    from hairdyn import native

    split = native.load().split_columns
    rng = np.random.default_rng(3)
    table = rng.normal(size=(20_000, 9)).astype(np.float32)
    spans = {0: 3, 3: 2, 6: 2, 8: 1}  # first column: width (column 5 unused)
    outs = {start: np.empty(len(table) * width, np.float32) for start, width in spans.items()}
    assert split(table, [(outs[start], start) for start in spans])
    for start, width in spans.items():
        expected = np.ascontiguousarray(table[:, start:start + width])
        assert outs[start].tobytes() == expected.tobytes()
    for row, column, bad in ((19_999, 5, np.nan), (0, 0, np.inf), (12_345, 8, -np.inf)):
        broken = table.copy()
        broken[row, column] = bad
        assert not split(broken, [(outs[start], start) for start in spans])
    with pytest.raises(ValueError, match="C-contiguous"):
        split(np.asfortranarray(table), [])
    with pytest.raises(ValueError, match="whole rows of columns inside the table"):
        split(table, [(np.empty(len(table) * 3, np.float32), 7)])


def test_a_frame_cut_short_or_reordered_is_refused(tmp_path):
    cache = make_cache(tmp_path)
    cache.write_frame(1, frame_data())
    path = cache.frame_path(1)
    whole = path.read_bytes()
    path.write_bytes(whole[:-1])  # one byte short of its header's table
    with pytest.raises(CacheError, match=r"frame_000001.npy' is corrupted or truncated \("):
        cache.read_frame(1, reuse=True)
    np.save(path, np.asfortranarray(np.zeros((6, 4), np.float32)))
    with pytest.raises(CacheError, match=r"holds float32 \(6, 4\) in Fortran order"):
        cache.read_frame(1)
    path.write_bytes(whole)
    assert cache.read_frame(1, reuse=True)["position"].tobytes() == \
        frame_data()["position"].tobytes()


@pytest.mark.parametrize("fixture, hair_name", [("head_shake.blend", "Hair"),
                                                ("head_particles.blend", "Body")])
def test_the_outputs_replace_the_groom_in_renders(open_fixture, fixture, hair_name):
    """Once output curves show the simulated hair, the groom itself leaves the renders (a
    Curves object by its render switch, particle hair by its particle system's: the emitter
    still renders); the artist can keep it, and the switch is no solver parameter (a bake
    resumes across it)."""
    from hairdyn import bake, simulation

    open_fixture(fixture)
    hair = bpy.data.objects[hair_name]
    hair.hairdyn.method = 'STRANDS'
    systems = bridge.hair_system_modifiers(hair)
    assert (hair.type == 'CURVES') != bool(systems)

    def in_renders():
        if hair.type == 'CURVES':
            return not hair.hide_render
        assert not hair.hide_render  # the emitter is never hidden
        return all(modifier.show_render for modifier in systems)

    hair.hairdyn.hide_source_in_renders = True  # nothing to replace it yet
    assert in_renders()
    simulation.run(bpy.context, hair, 1, 2)
    assert not in_renders()
    hair.hairdyn.hide_source_in_renders = False
    assert in_renders()
    simulation.run(bpy.context, hair, 1, 2)
    assert in_renders()
    hair.hairdyn.hide_source_in_renders = True
    assert not in_renders()
    assert "hide_source_in_renders" not in bake.parameters(bpy.context, hair.hairdyn)


def test_an_output_deleted_from_the_scene_is_made_again_not_written_unseen(open_fixture):
    """Deleting an output object in the outliner takes it out of every scene, but the settings'
    pointer keeps it alive: the next run makes new outputs in the scene, and the groom, hidden
    from renders behind them, is hidden behind outputs that render."""
    from hairdyn import simulation

    open_fixture("head_shake.blend")
    hair = bpy.data.objects["Hair"]
    hair.hairdyn.method = 'STRANDS'
    simulation.run(bpy.context, hair, 1, 2)
    deleted = [hair.hairdyn.output_curves, hair.hairdyn.output_points]
    for obj in deleted:
        for collection in obj.users_collection:
            collection.objects.unlink(obj)
        assert not obj.users_scene
    deleted_positions = read_output(hair).copy()
    simulation.run(bpy.context, hair, 1, 3)
    for new, old in zip([hair.hairdyn.output_curves, hair.hairdyn.output_points], deleted):
        assert new != old and new.users_scene
    assert not np.array_equal(read_output(hair), deleted_positions)
    assert hair.hide_render  # behind outputs that render


@pytest.mark.parametrize("enabled", [True, False])
def test_a_groom_hidden_behind_outputs_returns_to_renders_when_they_are_deleted(
    open_fixture, enabled
):
    """The groom leaves the renders behind its outputs; if the artist then deletes them (with
    hairdyn on or off, so that nothing writes a frame), the next frame change, which every
    render makes, puts the groom back: a render never loses the hair."""
    from hairdyn import simulation

    open_fixture("head_shake.blend")
    hair = bpy.data.objects["Hair"]
    hair.hairdyn.method = 'STRANDS'
    simulation.run(bpy.context, hair, 1, 2)
    assert hair.hide_render
    hair.hairdyn.enabled = enabled
    hair.hairdyn.use_live = False  # nothing would write: the cache is empty too
    playback.on_frame_change(bpy.context.scene)
    assert hair.hide_render  # still behind outputs in the scene
    for obj in (hair.hairdyn.output_curves, hair.hairdyn.output_points):
        for collection in obj.users_collection:
            collection.objects.unlink(obj)
    playback.on_frame_change(bpy.context.scene)
    assert not hair.hide_render
    assert playback.last_error(hair) is None
