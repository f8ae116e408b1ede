"""Frame-change playback into the output objects: baked frames, else live simulation.

A persistent frame_change_post handler, for every hair object of the scene:
  - loads the current frame from the bake when it is baked (use_cache), else
  - simulates live (use_live), like Blender's cloth: the simulation restarts at the start
    frame and steps when the frame advances by one; other jumps leave the outputs as they are.
It survives saving and reopening the file; caches are re-read when their manifest changes.
"""
import contextlib

import bpy
from bpy.app.handlers import persistent

from .errors import HairdynError

_open_caches = {}  # cache directory -> (manifest mtime, Cache, curve_offsets, children offsets)
_errors = {}  # object name -> the last playback error, shown in the panel
_suspended = [0]  # > 0 while a simulation moves the frame itself
_live = {}  # object name -> [Simulation, last simulated frame]


@contextlib.contextmanager
def suspended():
    """No cache loading while a simulation or bake sets frames itself."""
    _suspended[0] += 1
    try:
        yield
    finally:
        _suspended[0] -= 1


def forget(directory=None):
    """Drop what is known of a cache (all caches when None): it changed on disk."""
    if directory is None:
        _open_caches.clear()
    else:
        _open_caches.pop(str(directory), None)


def last_error(obj):
    return _errors.get(obj.name)


def open_cache(directory):
    """(Cache, curve_offsets, children offsets or None) for a directory, or None when
    nothing is baked there."""
    from .cache import Cache

    manifest = Cache.manifest_path(directory)
    try:
        mtime = manifest.stat().st_mtime_ns
    except OSError:
        _open_caches.pop(str(directory), None)
        return None
    known = _open_caches.get(str(directory))
    if known is None or known[0] != mtime:
        cache = Cache.open(directory)
        known = (mtime, cache, cache.curve_offsets(),
                 cache.stream_offsets("children") if "children" in cache.streams else None)
        _open_caches[str(directory)] = known
    return known[1:]


def load_frame(obj, frame):
    """Put the baked frame into obj's output objects; False when it is not baked."""
    from . import simulation

    try:
        directory = simulation.cache_directory(obj)
    except HairdynError:  # an unsaved file with a '//' folder: nothing can be baked there
        return False
    opened = open_cache(directory)
    if opened is None:
        return False
    cache, curve_offsets, children_offsets = opened
    if not cache.has_frame(frame):
        return False
    children = None if children_offsets is None else \
        (children_offsets, cache.read_stream("children", frame)["position"])
    particles = cache.read_stream("particles", frame) if "particles" in cache.streams else None
    simulation.write_outputs(obj, curve_offsets, cache.read_frame(frame), children, particles)
    return True


def live_step(obj, scene, depsgraph):
    """Simulate obj live for the scene's current frame; True when the outputs changed."""
    from . import simulation

    settings, frame = obj.hairdyn, scene.frame_current
    if frame == settings.frame_start:
        live = simulation.Simulation(obj, depsgraph, scene)
        _live[obj.name] = [live, frame]
    else:
        known = _live.get(obj.name)
        if known is None or known[1] + 1 != frame or frame > settings.frame_end:
            return False
        live = known[0]
        live.step(depsgraph, simulation.frame_dt(scene))
        known[1] = frame
    live.write(live.frame_arrays())
    return True


@persistent
def on_frame_change(scene, depsgraph=None):
    if _suspended[0] or not hasattr(bpy.types.Object, "hairdyn"):
        return
    from . import bridge

    depsgraph = depsgraph or bpy.context.evaluated_depsgraph_get()
    for obj in scene.objects:
        settings = obj.hairdyn
        if not settings.enabled or not bridge.is_hair_object(obj):
            continue
        try:
            with suspended():  # reading hair may evaluate the scene: no re-entry
                if not (settings.use_cache and load_frame(obj, scene.frame_current)) \
                        and settings.use_live:
                    live_step(obj, scene, depsgraph)
            _errors.pop(obj.name, None)
        except HairdynError as error:
            if _errors.get(obj.name) != str(error):
                print(f"hairdyn: {obj.name}: {error}")
            _errors[obj.name] = str(error)


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
    for handlers, handler in ((bpy.app.handlers.frame_change_post, on_frame_change),
                              (bpy.app.handlers.load_post, on_load)):
        while handler in handlers:
            handlers.remove(handler)
    forget()
    _live.clear()
