"""Owns: running one hair object's simulation, whichever the method: `Simulation` reads the
groom, the head and the colliders at the rest frame and builds the method's adapter from the
registry (methods/); `step()` follows the head and the colliders to the current frame and
advances it; `frame()` is what the frame produced, every stream with its layout. `Runner`
steps a frame range, writing each frame to the output objects (outputs.py) and, for a bake,
to a cache. It knows no method by name.
"""

import contextlib
import time

import bpy
import numpy as np

from . import bridge, colliders, frame_record, methods, native, outputs
from .errors import HairdynError
from .methods.base import Build, Stream
from .outputs import STRAND_OUTPUT, STRANDS

_setting_frames = [0]  # > 0 while a run moves the scene's frame itself


def setting_frames():
    """True while a simulation moves the frame itself (playback then keeps out)."""
    return _setting_frames[0] > 0


@contextlib.contextmanager
def moving_frames():
    _setting_frames[0] += 1
    try:
        yield
    finally:
        _setting_frames[0] -= 1


def frame_set(scene, frame):
    """Set the scene's frame without the playback handler loading or simulating anything."""
    with moving_frames():
        scene.frame_set(frame)


def head_object(hair_obj, groom=None):
    """The mesh the roots follow: the artist's choice, else the hair's surface / emitter (the
    groom's, read from the object when not given)."""
    if groom is not None:
        surface = groom.surface
    else:
        surface = hair_obj.data.surface if hair_obj.type == 'CURVES' else hair_obj
    head = hair_obj.hairdyn.head or surface
    if head is None:
        raise HairdynError(
            f"'{hair_obj.name}' has no head: set Head in the hairdyn panel, or "
            "attach the curves to a surface"
        )
    return head


MAX_FRAME_DT = 10.0  # s: the solvers step at most this much a frame


def frame_dt(scene):
    """Seconds per frame of the scene; HairdynError beyond MAX_FRAME_DT (Blender allows
    1,000 s: 1 frame a second over a base of 1,000)."""
    dt = scene.render.fps_base / scene.render.fps
    if not 0.0 < dt <= MAX_FRAME_DT:
        raise HairdynError(
            f"The scene's frame rate ({scene.render.fps} / {scene.render.fps_base:g} frames a "
            f"second) makes a frame {dt:g} s long; hairdyn steps at most {MAX_FRAME_DT:g} s a "
            "frame: raise the frame rate (Output Properties > Format)"
        )
    return dt


def show_frame(hair_obj, frame, method):
    """A frame, simulated or baked (as outputs.write takes it), in the hair object's output
    objects, dressed by the method (identifier) that made it (Method.dress_outputs)."""
    outputs.write(hair_obj, frame)
    method = methods.get(method)
    if method is not None:
        method.dress_outputs(hair_obj, frame)


class Simulation:
    """Build at the rest frame (the scene on the first frame to simulate), then step() and
    frame() once per frame."""

    def __init__(self, hair_obj, depsgraph, scene):
        self.native = native.load()
        self.hair_obj = hair_obj
        settings = hair_obj.hairdyn
        method = methods.get(settings.method)
        if method is None:
            raise HairdynError(
                f"'{hair_obj.name}' uses the method '{settings.method}', which "
                "this hairdyn does not have"
            )
        self.groom = bridge.read_groom(hair_obj, depsgraph)
        self.head = head_object(hair_obj, self.groom)
        head_matrix = bridge.object_matrix(self.head, depsgraph)

        def make_colliders():
            if not settings.use_collision:
                return None
            return colliders.Colliders(hair_obj, self.head, scene, depsgraph)

        build = Build(
            hair_obj,
            self.groom,
            self.head,
            head_matrix,
            make_colliders,
            scene,
            depsgraph,
            self.native,
        )
        try:
            self.method = method(build)
            self.colliders = build.colliders  # the method may not have asked (Follow Head)
        except ValueError as error:
            raise HairdynError(f"'{hair_obj.name}': {error}") from None
        self.previous_positions = np.array(self.positions)
        self.velocities = np.empty_like(self.previous_positions)
        self.tangents = np.empty_like(self.previous_positions)
        self._measure(1.0)  # the rest frame: no velocity
        self.collision_ms = 0.0

    @property
    def positions(self):
        """World-space strand positions (N, 3) float32."""
        return self.method.positions

    def step(self, depsgraph, frame_dt):
        """Advance to the scene's current frame; returns the native stepping time in ms
        (collision queries included; collider updates are in self.collision_ms)."""
        head_matrix = bridge.object_matrix(self.head, depsgraph)
        if self.colliders is not None:
            start = time.perf_counter()
            self.colliders.update(depsgraph)
            self.collision_ms = (time.perf_counter() - start) * 1000.0
        self.method.read_scene(depsgraph)
        start = time.perf_counter()
        try:
            self.method.step(frame_dt, head_matrix)
        except ValueError as error:  # the native solver refused this frame, in a sentence
            raise HairdynError(str(error)) from None
        elapsed_ms = (time.perf_counter() - start) * 1000.0
        self._measure(frame_dt)
        return elapsed_ms

    def _measure(self, frame_dt):
        """What the reports and outputs take from the frame's positions, in one native pass
        into the same arrays every frame: velocities, tangents, the count of points that are
        not finite numbers, the stretch; previous_positions becomes the positions."""
        self.nonfinite_num, self.stretch = self.native.strand_frame(
            self.groom.curve_offsets,
            self.groom.positions_wo,
            self.positions,
            self.previous_positions,
            self.velocities,
            self.tangents,
            frame_dt,
        )

    def penetration(self):
        """Exact penetration of the strands into the colliders' real triangles, or None."""
        if self.colliders is None:
            return None
        return self.colliders.penetration(self.positions, self.groom.curve_offsets)

    def strand_arrays(self):
        return {
            "position": self.positions,
            "velocity": self.velocities,
            "direction": self.tangents,
            **self.method.strand_attributes(),
        }

    def streams(self):
        """{name: Stream} of everything a frame produces: the strands (STRANDS: position,
        velocity, direction), then the method's own streams."""
        strands = Stream(
            {"position": 3, "velocity": 3, "direction": 3, **self.method.strand_columns},
            self.strand_arrays,
            self.groom.points_num,
            offsets=self.groom.curve_offsets,
            outputs=STRAND_OUTPUT["outputs"],
        )
        return {STRANDS: strands, **self.method.streams()}

    def write_outputs(self, frame_data):
        """Shows `frame_data` (a frame()) in the hair object's output objects."""
        show_frame(self.hair_obj, frame_data, self.method.identifier)

    def frame(self):
        """{stream name: (arrays, curve offsets or None, output)} of the current frame, what
        the cache stores and outputs.write shows. Never NaN: a broken frame raises instead."""
        broken = self.nonfinite_num
        if broken:
            raise HairdynError(
                f"The simulation of '{self.hair_obj.name}' produced {broken} "
                "points that are not finite numbers"
            )
        return {
            name: (stream.read(), stream.offsets, stream.output())
            for name, stream in self.streams().items()
        }


class HairSystemsOff:
    """The hair object's own particle hair systems switched off in the viewport (what the
    evaluated depsgraph follows) while a Runner steps it, and switched back by restore().

    Nothing reads the source groom after its rest shape, but Blender evaluates a particle hair
    system again on every frame change of an animated object: 2,000 strands of 16 segments
    cost 9.5 ms of each frame, a third of a whole frame, for nothing. Curves hair objects are
    left alone (their evaluation is the deformation an artist sees)."""

    def __init__(self, hair_obj):
        self.obj = hair_obj
        self.names = []
        for modifier in bridge.hair_system_modifiers(hair_obj):
            if modifier.show_viewport:
                modifier.show_viewport = False
                self.names.append(modifier.name)

    def restore(self):
        names, self.names = self.names, []
        try:
            for name in names:
                modifier = self.obj.modifiers.get(name)
                if modifier is not None:
                    modifier.show_viewport = True
        except ReferenceError:  # the object was deleted meanwhile: nothing to restore
            pass


class Runner:
    """Steps a Simulation through a frame range, frame by frame: writes each frame to the
    output objects and, when given one, to a cache. The headless entry point, the operators
    and the bake all drive this; `advance()` does one frame so a modal operator can stay
    responsive between frames.

    With `resume_from` (a cached frame and its arrays) the simulation continues after that
    frame instead of starting at frame_start (the rest shape is still read at frame_start).

    With `show_frames` off (headless runs: nothing draws the frames in between) the output
    objects get only the last frame, or, if the run ends early, the last finite one: each
    frame written makes Blender evaluate the outputs again at the next frame change (on
    Blender 5.x their Catmull-Rom bounds, 1.6 ms a frame for 2,000 strands, more than the
    writing itself). The cache, when given, still gets every frame.
    """

    def __init__(
        self,
        context,
        hair_obj,
        frame_start,
        frame_end,
        cache=None,
        resume_from=None,
        show_frames=True,
    ):
        """resume_from: the last frame already baked (its successors are simulated)."""
        if frame_end < frame_start:
            raise HairdynError(f"The frame range {frame_start}..{frame_end} is empty")
        self.context, self.hair_obj, self.cache = context, hair_obj, cache
        self.object_name = hair_obj.name  # for the report, even if the object goes away
        self.frame_start, self.frame_end = frame_start, frame_end
        self.start_time = time.perf_counter()
        frame_set(context.scene, frame_start)
        self.simulation = Simulation(hair_obj, context.evaluated_depsgraph_get(), context.scene)
        if cache is not None:
            cache.check_topology(
                self.simulation.groom.curve_offsets, self.simulation.groom.positions_wo
            )
        self.dt = frame_dt(context.scene)
        self.next_frame = frame_start
        self.step_ms, self.collision_ms, self.nan_frames, self.stretch_max = [], [], 0, 0.0
        self.penetration_max, self.deeper_num, self.checked_num = 0.0, 0, 0
        self.roots_inside = 0
        self.record = None  # a bake's FrameRecord (bake.start_bake), one row per frame
        self.show_frames = show_frames
        self.unshown = None  # show_frames off: the last frame not yet written (a copy)
        self.hair_systems_off = HairSystemsOff(hair_obj)  # until close()
        if resume_from is not None:
            # Solvers carry state the cache does not hold (angles, the head's motion), so a
            # resumed bake re-simulates the frames it keeps, without writing them: the same
            # inputs give the same state, bit for bit.
            try:
                while self.next_frame <= resume_from:
                    self._step_frame()
            except BaseException:
                self.close()
                raise

    def close(self):
        """The run is over (done, stopped or failed): the hair systems back on. Safe to call
        more than once; advance() calls it after the last frame and when it fails. A frame
        not yet shown (show_frames off) goes into the output objects first."""
        unshown, self.unshown = self.unshown, None
        try:
            if unshown is not None:
                self.simulation.write_outputs(unshown)
        except ReferenceError:  # the hair object was deleted: nothing to show it in
            pass
        finally:
            self.hair_systems_off.restore()

    @property
    def done(self):
        return self.next_frame > self.frame_end

    def _step_frame(self):
        """Move the scene to the next frame and step the simulation there; returns its ms."""
        frame_set(self.context.scene, self.next_frame)
        ms = self.simulation.step(self.context.evaluated_depsgraph_get(), self.dt)
        self.next_frame += 1
        return ms

    def advance(self):
        """Simulate, measure, write and cache the next frame; returns (frame, native ms).
        A hair object or collider deleted meanwhile is a HairdynError; the frames already
        written stay."""
        try:
            result = self._advance()
        except ReferenceError:
            self.close()
            raise HairdynError(
                "The hair object or its head was deleted during the simulation; "
                "the frames written before are kept"
            ) from None
        except BaseException:
            self.close()
            raise
        if self.done:
            self.close()
        return result

    def _advance(self):
        frame = self.next_frame
        ms = self._step_frame()
        self.step_ms.append(ms)
        self.collision_ms.append(self.simulation.collision_ms)
        if self.simulation.nonfinite_num:
            self.nan_frames += 1
            return frame, ms
        stretch = self.simulation.stretch
        self.stretch_max = max(self.stretch_max, stretch)
        penetration = self.simulation.penetration()
        if penetration is not None:
            self.penetration_max = max(self.penetration_max, penetration["penetration_max"])
            self.deeper_num += penetration["deeper_num"]
            self.checked_num += penetration["points_num"]
            self.roots_inside = max(self.roots_inside, penetration["roots_inside"])
        if self.record is not None:
            self.record.add(
                frame,
                {
                    "ms": ms,
                    "penetration_share": penetration["penetration_share"] if penetration else 0.0,
                    "stretch": stretch,
                    "kinetic_energy": frame_record.kinetic_energy(self.simulation.velocities),
                    "contacts": self.simulation.method.contacts_num(),
                },
            )
        frame_data = self.simulation.frame()
        if self.cache is not None:
            self.cache.write_frame(
                frame,
                frame_data[STRANDS][0],
                {name: arrays for name, (arrays, _, _) in frame_data.items() if name != STRANDS},
            )
            self.simulation.method.frame_baked(self.hair_obj, self.cache, frame)
        if self.show_frames or self.done:
            self.unshown = None
            self.simulation.write_outputs(frame_data)
        else:  # the arrays are views of the solver's buffers, which the next step overwrites
            self.unshown = {
                name: ({key: value.copy() for key, value in arrays.items()}, offsets, output)
                for name, (arrays, offsets, output) in frame_data.items()
            }
        return frame, ms

    def report(self):
        """The figures every solver reports (see README, "Headless runs"); the run is over."""
        self.close()
        simulation = self.simulation
        names = dict.fromkeys(outputs.SLOTS)  # every output object's, None where none was written
        written = {slot for stream in simulation.streams().values() for slot in stream.outputs}
        try:
            for slot in written:
                output = getattr(self.hair_obj.hairdyn, slot)
                names[slot] = output.name if output is not None else None
        except ReferenceError:  # the object was deleted: the figures still stand
            pass
        return {
            "object": self.object_name,
            "solver": simulation.method.identifier.lower(),
            "strands": simulation.groom.curves_num,
            "points": simulation.groom.points_num,
            "frames": len(self.step_ms),
            "frame_start": self.frame_start,
            "frame_end": self.frame_end,
            "ms_per_frame": float(np.median(self.step_ms)) if self.step_ms else 0.0,
            "total_s": time.perf_counter() - self.start_time,
            "nan_frames": self.nan_frames,
            "stretch_max": float(self.stretch_max),
            **simulation.method.report(),
            "collision": simulation.colliders is not None,
            "colliders": simulation.colliders.names if simulation.colliders else [],
            "penetration_max": float(self.penetration_max),
            "penetration_share": self.deeper_num / self.checked_num if self.checked_num else 0.0,
            "roots_inside": self.roots_inside,
            "groom_warnings": list(simulation.groom.warnings),
            "pinned_points": simulation.groom.pins_num,
            "penetration_tolerance": simulation.colliders.tolerance_wo()
            if simulation.colliders
            else None,
            "collision_build_ms": simulation.colliders.build_ms if simulation.colliders else 0.0,
            "collision_ms": float(np.median(self.collision_ms)) if self.collision_ms else 0.0,
            "blender_version": bpy.app.version_string,
            "native_version": simulation.native.__version__,
            **names,
        }


def run(context, hair_obj, frame_start, frame_end, on_frame=None, show_frames=True):
    """Simulate hair_obj over [frame_start, frame_end] into the output objects; returns the
    report. on_frame(frame, ms) is called after each frame (progress); show_frames: see
    Runner."""
    runner = Runner(context, hair_obj, frame_start, frame_end, show_frames=show_frames)
    try:
        while not runner.done:
            frame, ms = runner.advance()
            if on_frame is not None:
                on_frame(frame, ms)
    finally:
        runner.close()
    return runner.report()
