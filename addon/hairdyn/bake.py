"""Owns: baking: where an object's bake lives (the folder name recorded when it was first
baked, so a renamed object keeps it), starting a bake or resuming one into a Cache, and
finishing it (its report in the manifest), and a snapshot of a baked frame as a Curves object.
The frames are simulated by simulation.Runner.
"""

from pathlib import Path

import bpy

import numpy as np

from . import bridge, frame_record, properties
from .cache import Cache
from .errors import HairdynError
from .outputs import STRANDS
from .simulation import Runner, frame_set, head_object


def folder_name(hair_obj):
    """The subfolder of the cache folder the object bakes into."""
    return hair_obj.hairdyn.bake_folder or bpy.path.clean_name(hair_obj.name)


def cache_directory(hair_obj):
    """The object's bake folder: <cache_directory>/<folder>, `//` relative to the .blend."""
    base = hair_obj.hairdyn.cache_directory
    if not base:
        raise HairdynError("Set a cache folder in the hairdyn panel")
    if base.startswith("//") and not bpy.data.filepath:
        raise HairdynError(
            f"Save the .blend file first: the cache folder '{base}' is relative to it"
        )
    return Path(bpy.path.abspath(base)) / folder_name(hair_obj)


def _claim_folder(hair_obj):
    """Records the object's bake folder; a copy of a baked object (same recorded folder as
    another object) gets one of its own rather than overwriting the original's bake."""
    settings = hair_obj.hairdyn
    shared = settings.bake_folder and any(
        other is not hair_obj
        and other.hairdyn.bake_folder == settings.bake_folder
        and other.hairdyn.cache_directory == settings.cache_directory
        for other in bpy.data.objects
    )
    if not settings.bake_folder or shared:
        settings.bake_folder = bpy.path.clean_name(hair_obj.name)


def parameters(context, settings):
    """What a bake depends on besides the groom: the settings and the scene's gravity."""
    scene = context.scene
    gravity = list(scene.gravity) if scene.use_gravity else [0.0, 0.0, 0.0]
    return {**properties.settings_dict(settings), "scene_gravity": gravity}


def start_bake(context, hair_obj, resume_after=None, show_frames=True):
    """A Runner that bakes the object's frame range into its cache.

    resume_after=None bakes from the start (an older bake is replaced). resume_after=frame
    keeps the cached frames up to that frame and continues after it; this needs an unbroken
    run of cached frames from the start to there, baked with the same parameters.
    show_frames: see Runner (off for headless bakes).
    """
    settings = hair_obj.hairdyn
    if resume_after is None:
        _claim_folder(hair_obj)
    directory = cache_directory(hair_obj)
    baked_with = parameters(context, settings)
    settings.enabled = True  # a baked object plays its bake back
    if resume_after is not None:
        cache = Cache.open(directory)
        if cache.manifest["parameters"] != baked_with:
            raise HairdynError(
                "The parameters changed since this bake started: bake from the "
                "start, or restore them"
            )
        last = cache.prepare_resume(resume_after)
        runner = Runner(
            context,
            hair_obj,
            cache.manifest["frame_start"],
            cache.manifest["frame_end"],
            cache=cache,
            resume_from=last,
            show_frames=show_frames,
        )
    else:
        runner = Runner(
            context, hair_obj, settings.frame_start, settings.frame_end, show_frames=show_frames
        )
    try:
        if runner.cache is None:
            runner.cache = _create_cache(runner, directory, settings, baked_with)
        runner.record = frame_record.start(directory, resume=resume_after is not None)
    except BaseException:
        runner.close()  # a run that never starts gives the hair systems back
        raise
    return runner


def _create_cache(runner, directory, settings, baked_with):
    """A new cache for the runner's bake."""
    streams = runner.simulation.streams()
    strands = streams.pop(STRANDS)
    return Cache.create(
        directory,
        solver=runner.simulation.method.identifier.lower(),
        parameters=baked_with,
        curve_offsets=strands.offsets,
        columns=strands.columns,
        frame_start=settings.frame_start,
        frame_end=settings.frame_end,
        fps=1.0 / runner.dt,
        streams={name: stream.layout() for name, stream in streams.items()},
        extra={
            "object": runner.object_name,
            "outputs": {name: stream.output() for name, stream in streams.items()},
        },
        rest_positions=runner.simulation.groom.positions_wo,
    )


def finish_bake(runner):
    """Records the bake's figures in its manifest; returns the report."""
    report = runner.report()
    report["frame_record"] = str(runner.record.finish())  # frame_record.csv and its plot
    manifest = runner.cache.manifest
    manifest["complete"] = runner.cache.last_contiguous_frame() == manifest["frame_end"]
    manifest["report"] = report
    manifest["timings"] = {
        "ms_per_frame": report["ms_per_frame"],
        "total_s": report["total_s"],
        "frames": report["frames"],
    }
    runner.cache.save_manifest()
    return report


def snapshot_frame(context, hair_obj, frame, name):
    """A Curves object `name` (made, or updated when it exists with the groom's topology) with
    the shape of `frame` of the hair object's bake, placed where the head at the first frame to
    simulate carries it: what reads a shape with that frame's head (the volume's target) finds
    the baked frame's shape on the head. Returns it."""
    cache = Cache.open(cache_directory(hair_obj))
    positions = np.asarray(cache.read_frame(frame)["position"], dtype=np.float64)
    offsets = cache.curve_offsets()
    scene = context.scene
    head = head_object(hair_obj)
    current = scene.frame_current
    try:
        matrices = []
        for at in (frame, hair_obj.hairdyn.frame_start):
            frame_set(scene, at)
            matrices.append(bridge.object_matrix(head, context.evaluated_depsgraph_get()))
    finally:
        frame_set(scene, current)
    to_start = matrices[1] @ np.linalg.inv(matrices[0])
    placed = positions @ to_start[:3, :3].T + to_start[:3, 3]
    snapshot = bridge.ensure_curves_output(bpy.data.objects.get(name), name, offsets, like=hair_obj)
    bridge.write_curves(snapshot, placed.astype(np.float32))
    return snapshot
