"""Frame-change playback of baked caches into the output objects.

A persistent frame_change_post handler loads the current frame of every hair object whose
settings play back a bake. It survives saving and reopening the file; caches are re-read
when their manifest changes on disk.
"""
import contextlib

import bpy
from bpy.app.handlers import persistent

from .errors import HairdynError

_open_caches = {}  # cache directory -> (manifest mtime, Cache, curve_offsets)
_errors = {}  # object name -> the last playback error, shown in the panel
_suspended = [0]  # > 0 while a simulation moves the frame itself


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
    """(Cache, curve_offsets) for a directory, or None when nothing is baked there."""
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
        known = (mtime, cache, cache.curve_offsets())
        _open_caches[str(directory)] = known
    return known[1], known[2]


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
    cache, curve_offsets = opened
    if not cache.has_frame(frame):
        return False
    simulation.write_outputs(obj, curve_offsets, cache.read_frame(frame))
    return True


@persistent
def on_frame_change(scene, _depsgraph=None):
    if _suspended[0] or not hasattr(bpy.types.Object, "hairdyn"):
        return
    from . import bridge

    for obj in scene.objects:
        if not obj.hairdyn.use_cache or not bridge.is_hair_object(obj):
            continue
        try:
            load_frame(obj, scene.frame_current)
            _errors.pop(obj.name, None)
        except HairdynError as error:
            if _errors.get(obj.name) != str(error):
                print(f"hairdyn: {obj.name}: {error}")
            _errors[obj.name] = str(error)


@persistent
def on_load(_filepath=None, _unused=None):
    forget()
    _errors.clear()


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
