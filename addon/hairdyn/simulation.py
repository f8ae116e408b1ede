"""One hair object's simulation: groom in, native solver, results out.

The flow is one way: `Simulation(...)` reads the groom and the head at the rest frame and
builds the native solver; `step()` reads the head's transform for the current frame and
advances the solver; `write()` puts the result into the output objects. Operators, the
headless entry point and playback all drive this one class.
"""
import time

import numpy as np

from . import bridge, native
from .errors import HairdynError


def point_tangents(curve_offsets, positions):
    """Unit direction of each point along its strand (forward difference, backward at tips)."""
    forward = np.empty_like(positions)
    forward[:-1] = positions[1:] - positions[:-1]
    tips = curve_offsets[1:] - 1
    forward[tips] = positions[tips] - positions[tips - 1]
    lengths = np.linalg.norm(forward, axis=1, keepdims=True)
    return np.ascontiguousarray(forward / np.maximum(lengths, 1e-30), dtype=np.float32)


def head_object(hair_obj, groom):
    """The mesh the roots follow: the artist's choice, else the hair's surface / emitter."""
    head = hair_obj.hairdyn.head or groom.surface
    if head is None:
        raise HairdynError(f"'{hair_obj.name}' has no head: set Head in the hairdyn panel, or "
                           "attach the curves to a surface")
    return head


class Simulation:
    """Build at the rest frame (the scene must be on settings.frame_start or the first frame
    to simulate), then step()/write() once per frame."""

    def __init__(self, hair_obj, depsgraph):
        self.native = native.load()
        self.hair_obj = hair_obj
        self.settings = hair_obj.hairdyn
        self.groom = bridge.read_groom(hair_obj, depsgraph)
        self.head = head_object(hair_obj, self.groom)
        self.method = self.settings.method
        try:
            self.solver = self._make_solver(bridge.object_matrix(self.head, depsgraph))
        except ValueError as error:
            raise HairdynError(f"'{hair_obj.name}': {error}") from None
        self.previous_positions = np.array(self.solver.positions)
        self.velocities = np.zeros_like(self.previous_positions)

    def _make_solver(self, head_matrix):
        if self.method == 'FOLLOW':
            return self.native.FollowSolver(self.groom.curve_offsets, self.groom.positions_wo,
                                            head_matrix)
        raise HairdynError(f"Unknown method '{self.method}'")

    @property
    def positions(self):
        """World-space positions (N, 3) float32, a zero-copy view of the solver's buffer."""
        return self.solver.positions

    def step(self, depsgraph, frame_dt):
        """Advance to the scene's current frame; returns the native stepping time in ms."""
        head_matrix = bridge.object_matrix(self.head, depsgraph)
        self.previous_positions[:] = self.solver.positions
        start = time.perf_counter()
        self.solver.step(head_matrix)
        elapsed_ms = (time.perf_counter() - start) * 1000.0
        self.velocities = (self.solver.positions - self.previous_positions) / np.float32(frame_dt)
        return elapsed_ms

    def stretch(self):
        return self.native.max_relative_stretch(self.groom.curve_offsets,
                                                self.groom.positions_wo, self.solver.positions)

    def nonfinite_points(self):
        return self.native.count_nonfinite(self.solver.positions)

    def write(self):
        """Positions into the output Curves object, points and attributes into the output
        mesh; creates them when missing. Never writes NaN: a broken frame raises instead."""
        broken = self.nonfinite_points()
        if broken:
            raise HairdynError(f"The simulation of '{self.hair_obj.name}' produced {broken} "
                               "points that are not finite numbers; nothing was written")
        settings, name = self.settings, self.hair_obj.name
        settings.output_curves = bridge.ensure_curves_output(
            settings.output_curves, f"{name}_hairdyn", self.groom.curve_offsets,
            like=self.hair_obj)
        settings.output_points = bridge.ensure_points_output(
            settings.output_points, f"{name}_hairdyn_points", like=self.hair_obj)
        positions = self.solver.positions
        bridge.write_curves(settings.output_curves, positions)
        bridge.write_points(settings.output_points, positions, {
            "direction": point_tangents(self.groom.curve_offsets, positions),
            "velocity": self.velocities,
        })


def frame_dt(scene):
    """Seconds per frame of the scene."""
    return scene.render.fps_base / scene.render.fps


def run(context, hair_obj, frame_start, frame_end, on_frame=None):
    """Simulate hair_obj over [frame_start, frame_end], writing every frame to the output
    objects. Returns the report every solver fills (see README, "Headless runs").

    on_frame(frame, ms) is called after each frame (progress). Frames whose result is not
    finite are counted in `nan_frames` and not written.
    """
    import bpy

    if frame_end < frame_start:
        raise HairdynError(f"The frame range {frame_start}..{frame_end} is empty")
    scene = context.scene
    start_time = time.perf_counter()
    scene.frame_set(frame_start)
    simulation = Simulation(hair_obj, context.evaluated_depsgraph_get())
    dt = frame_dt(scene)
    step_ms, nan_frames, stretch_max = [], 0, 0.0
    for frame in range(frame_start, frame_end + 1):
        scene.frame_set(frame)
        ms = simulation.step(context.evaluated_depsgraph_get(), dt)
        step_ms.append(ms)
        if simulation.nonfinite_points():
            nan_frames += 1
        else:
            stretch_max = max(stretch_max, simulation.stretch())
            simulation.write()
        if on_frame is not None:
            on_frame(frame, ms)
    return {
        "object": hair_obj.name,
        "solver": simulation.method.lower(),
        "strands": simulation.groom.curves_num,
        "points": simulation.groom.points_num,
        "frames": len(step_ms),
        "frame_start": frame_start,
        "frame_end": frame_end,
        "ms_per_frame": float(np.median(step_ms)),
        "total_s": time.perf_counter() - start_time,
        "nan_frames": nan_frames,
        "stretch_max": float(stretch_max),
        "blender_version": bpy.app.version_string,
        "native_version": simulation.native.__version__,
        "output_curves": hair_obj.hairdyn.output_curves.name if hair_obj.hairdyn.output_curves else None,
        "output_points": hair_obj.hairdyn.output_points.name if hair_obj.hairdyn.output_points else None,
    }
