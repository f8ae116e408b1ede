"""Owns: frame-change playback into the output objects: baked frames, else live simulation.

A persistent frame_change_post handler, for every hair object of the scene:
  - loads the current frame from the bake when it is baked (use_cache), else
  - simulates live (use_live), like Blender's cloth: the simulation restarts at the start
    frame and steps when the frame advances by one; other jumps leave the outputs as they are.
A bake that cannot be shown (another groom's topology, a missing manifest, a frame that is not
a file, values that are not finite) is an error in the panel and on the console, and nothing
of it reaches the scene. State is keyed by the object's stable identity (settings.uid), so a
renamed object keeps its live simulation; its bake folder is the one recorded at bake time.
It survives saving and reopening the file; caches are re-read when their manifest changes.
"""

import uuid

import bpy
from bpy.app.handlers import persistent

from . import bake, bridge, outputs, simulation
from .cache import MAIN, Cache, CacheError
from .errors import HairdynError, Once

# A bake made before the manifest recorded its streams' outputs.
_LEGACY_OUTPUTS = {
    "children": {"outputs": ["output_children"], "billboards": False},
    "particles": {"outputs": ["output_points"], "billboards": True},
}

_open_caches = {}  # cache directory -> (manifest stat key, Cache, curve_offsets, stream offsets)
_verified = {}  # (object uid, cache directory) -> manifest stat key whose topology matched
_errors = Once()  # object uid -> the last playback error, shown in the panel
_live = {}  # object uid -> [Simulation, last simulated frame]


def forget(directory=None):
    """Drop what is known of a cache (all caches when None): it changed on disk."""
    if directory is None:
        _open_caches.clear()
        _verified.clear()
    else:
        _open_caches.pop(str(directory), None)


def identity(obj):
    """The object's stable id (made on first use; survives renames)."""
    settings = obj.hairdyn
    if not settings.uid:
        settings.uid = uuid.uuid4().hex
    return settings.uid


def last_error(obj):
    return _errors.get(obj.hairdyn.uid) if obj.hairdyn.uid else None


def _stat_key(path):
    stat = path.stat()
    return stat.st_mtime_ns, stat.st_size, stat.st_ino


def open_cache(directory):
    """(Cache, curve_offsets, {stream: offsets or None}) for a directory, or None when nothing
    is baked there; a CacheError when frames are there without a readable manifest."""
    manifest = Cache.manifest_path(directory)
    try:
        key = _stat_key(manifest)
    except OSError:
        _open_caches.pop(str(directory), None)
        if directory.is_dir() and any(directory.glob(f"{MAIN}_*.npy")):
            raise CacheError(
                f"The bake in '{directory}' has frames but no manifest.json: "
                "bake again, or free the bake"
            ) from None
        return None
    known = _open_caches.get(str(directory))
    if known is None or known[0] != key:
        cache = Cache.open(directory)
        offsets = {
            name: cache.stream_offsets(name)
            if cache.manifest["streams"][name].get("has_offsets")
            else None
            for name in cache.streams
        }
        known = (key, cache, cache.curve_offsets(), offsets)
        _open_caches[str(directory)] = known
    return known[1:]


def _check_topology(obj, directory, cache, depsgraph):
    """CacheError when the bake was made from another groom than obj's (checked once per bake
    and object)."""
    key = (identity(obj), str(directory))
    stamp = _open_caches[str(directory)][0]
    if _verified.get(key) != stamp:
        groom = bridge.read_groom(obj, depsgraph or bpy.context.evaluated_depsgraph_get())
        cache.check_topology(groom.curve_offsets)
        _verified[key] = stamp


def _read_checked(cache, name, frame):
    path = cache.path(name, frame)
    if path.exists() and not path.is_file():
        raise CacheError(f"The baked frame '{path}' is not a file: bake again")
    # The reader refuses a torn, garbled or non-finite frame (cache.py). The arrays are the
    # cache's own buffers, reused frame after frame: outputs.write copies them into Blender.
    if name == MAIN:
        return cache.read_frame(frame, reuse=True)
    return cache.read_stream(name, frame, reuse=True)


def load_frame(obj, frame, depsgraph=None):
    """Put the baked frame into obj's output objects; False when it is not baked. Anything
    wrong with the bake is a CacheError, and nothing is written."""
    try:
        directory = bake.cache_directory(obj)
    except HairdynError:  # an unsaved file with a '//' folder: nothing can be baked there
        return False
    opened = open_cache(directory)
    if opened is None:
        return False
    cache, curve_offsets, stream_offsets = opened
    path = cache.frame_path(frame)
    if not path.exists():
        return False
    _check_topology(obj, directory, cache, depsgraph)
    recorded = cache.manifest.get("outputs", _LEGACY_OUTPUTS)
    shown = {
        outputs.STRANDS: (_read_checked(cache, MAIN, frame), curve_offsets, outputs.STRAND_OUTPUT)
    }
    for name in cache.streams:
        shown[name] = (
            _read_checked(cache, name, frame),
            stream_offsets[name],
            recorded.get(name, {"outputs": [], "billboards": False}),
        )
    simulation.show_frame(obj, shown, cache.manifest.get("solver", ""))
    return True


def live_step(obj, scene, depsgraph):
    """Simulate obj live for the scene's current frame; True when the outputs changed."""
    settings, frame, key = obj.hairdyn, scene.frame_current, identity(obj)
    if frame == settings.frame_start:
        _live.pop(key, None)
        live = simulation.Simulation(obj, depsgraph, scene)
        _live[key] = [live, frame]
    else:
        known = _live.get(key)
        if known is None or known[1] + 1 != frame or frame > settings.frame_end:
            return False
        live = known[0]
        live.step(depsgraph, simulation.frame_dt(scene))
        known[1] = frame
    live.write_outputs(live.frame())
    return True


def _unique_identities(scene):
    """A copied object carries its original's uid: give the copy one of its own."""
    seen = set()
    for obj in scene.objects:
        uid = obj.hairdyn.uid
        if uid and uid in seen:
            obj.hairdyn.uid = uuid.uuid4().hex
        seen.add(obj.hairdyn.uid)


@persistent
def on_frame_change(scene, depsgraph=None):
    if simulation.setting_frames() or not hasattr(bpy.types.Object, "hairdyn"):
        return
    depsgraph = depsgraph or bpy.context.evaluated_depsgraph_get()
    _unique_identities(scene)
    for obj in scene.objects:
        settings = obj.hairdyn
        enabled = settings.enabled and bridge.is_hair_object(obj)
        if not enabled and settings.output_curves is None:
            continue
        key = identity(obj)
        try:
            # The groom back in renders once the outputs it hides behind left the scene (the
            # artist deleted them), hairdyn on or off: renders, stills too, change frames.
            outputs.show_source_as_set(obj)
            if not enabled:
                continue
            with simulation.moving_frames():  # reading hair may evaluate the scene: no re-entry
                shown = (
                    settings.use_cache and load_frame(obj, scene.frame_current, depsgraph)
                ) or (settings.use_live and live_step(obj, scene, depsgraph))
            if shown:  # an error stays in the panel until a frame shows again
                _errors.clear(key)
        except Exception as error:  # noqa: BLE001 - the handler's error boundary
            _live.pop(key, None)  # a broken live simulation restarts at the start frame
            _errors.report(key, obj.name, error)


@persistent
def on_load(_filepath=None, _unused=None):
    forget()
    _errors.clear()
    _live.clear()


def register():
    if on_frame_change not in bpy.app.handlers.frame_change_post:
        bpy.app.handlers.frame_change_post.append(on_frame_change)
    if on_load not in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.append(on_load)


def unregister():
    for handlers, handler in (
        (bpy.app.handlers.frame_change_post, on_frame_change),
        (bpy.app.handlers.load_post, on_load),
    ):
        while handler in handlers:
            handlers.remove(handler)
    forget()
    _live.clear()
