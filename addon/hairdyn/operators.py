"""Owns: the operators, thin: gather from the context, call the simulation or the bake, and
report through the one error boundary (errors.operator_boundary): a user error is an ERROR
report, anything else an internal-error report with its traceback on the console; a bake that
fails still records the frames it wrote in its manifest."""

import bpy
from bpy.props import BoolProperty, IntProperty

from .errors import operator_boundary


def _hair_poll(context):
    from . import bridge

    return bridge.is_hair_object(context.object)


class HAIRDYN_OT_simulate(bpy.types.Operator):
    """Simulate the hairdyn frame range into the output objects, without baking"""

    bl_idname = "hairdyn.simulate"
    bl_label = "Simulate Frame Range"
    bl_options = {'REGISTER', 'UNDO'}

    @classmethod
    def poll(cls, context):
        return _hair_poll(context)

    @operator_boundary
    def execute(self, context):
        from . import simulation

        obj, scene = context.object, context.scene
        settings = obj.hairdyn
        frame = scene.frame_current
        window_manager = context.window_manager
        window_manager.progress_begin(settings.frame_start, settings.frame_end)
        try:
            report = simulation.run(
                context,
                obj,
                settings.frame_start,
                settings.frame_end,
                on_frame=lambda f, _ms: window_manager.progress_update(f),
                show_frames=False,  # blocking: nothing redraws until it ends
            )
        finally:
            window_manager.progress_end()
            scene.frame_set(frame)
        self.report(
            {'INFO'},
            f"hairdyn: {report['frames']} frames, {report['ms_per_frame']:.2f} ms per frame",
        )
        return {'FINISHED'}


class HAIRDYN_OT_bake(bpy.types.Operator):
    """Bake the hairdyn frame range to the cache folder. Esc stops and keeps every frame baked"""

    bl_idname = "hairdyn.bake"
    bl_label = "Bake"
    bl_options = {'REGISTER'}

    from_current: BoolProperty(
        name="From Current Frame",
        default=False,
        description="Keep the baked frames before the current frame and bake on from there "
        "(resumes a bake that stopped)",
    )

    _runner = None
    _timer = None

    @classmethod
    def poll(cls, context):
        return _hair_poll(context)

    def _start(self, context, show_frames):
        from . import bake

        resume_after = context.scene.frame_current - 1 if self.from_current else None
        self._frame = context.scene.frame_current
        self._runner = bake.start_bake(context, context.object, resume_after, show_frames)

    def _finish(self, context, cancelled):
        from . import bake

        runner, self._runner = self._runner, None
        report = bake.finish_bake(runner)
        context.scene.frame_set(self._frame)
        baked = len(runner.cache.frames())
        verb = "Stopped" if cancelled else "Baked"
        self.report(
            {'WARNING' if cancelled else 'INFO'},
            f"{verb}: {baked} frames in the cache, {report['ms_per_frame']:.2f} ms per frame",
        )
        return report

    def cleanup(self, context):
        """After an error: the modal timer off, and the frames baked so far recorded."""
        if self._timer is not None:
            self._end_modal(context)
        if self._runner is not None:
            self._finish(context, cancelled=True)

    @operator_boundary
    def execute(self, context):
        """Blocking bake (scripts, headless): nothing redraws until it ends, so the output
        objects get only the last frame (Runner's show_frames)."""
        self._start(context, show_frames=False)
        while not self._runner.done:
            self._runner.advance()
        self._finish(context, cancelled=False)
        return {'FINISHED'}

    @operator_boundary
    def invoke(self, context, _event):
        self._start(context, show_frames=True)  # the viewport follows the bake
        window_manager = context.window_manager
        window_manager.progress_begin(self._runner.frame_start, self._runner.frame_end)
        self._timer = window_manager.event_timer_add(0.001, window=context.window)
        window_manager.modal_handler_add(self)
        return {'RUNNING_MODAL'}

    def _end_modal(self, context):
        window_manager = context.window_manager
        window_manager.event_timer_remove(self._timer)
        self._timer = None
        window_manager.progress_end()
        if context.workspace is not None:
            context.workspace.status_text_set(None)

    @operator_boundary
    def modal(self, context, event):
        if event.type == 'ESC':
            self._end_modal(context)
            self._finish(context, cancelled=True)
            return {'CANCELLED'}
        if event.type != 'TIMER':
            return {'PASS_THROUGH'}
        runner = self._runner
        frame, ms = runner.advance()
        context.window_manager.progress_update(frame)
        if context.workspace is not None:
            context.workspace.status_text_set(
                f"hairdyn: baking frame {frame} of {runner.frame_end} ({ms:.1f} ms) - Esc stops"
            )
        if runner.done:
            self._end_modal(context)
            self._finish(context, cancelled=False)
            return {'FINISHED'}
        return {'RUNNING_MODAL'}


class HAIRDYN_OT_free_bake(bpy.types.Operator):
    """Delete the baked frames of this hair object from the cache folder"""

    bl_idname = "hairdyn.free_bake"
    bl_label = "Free Bake"
    bl_options = {'REGISTER'}

    @classmethod
    def poll(cls, context):
        return _hair_poll(context)

    def invoke(self, context, event):
        return context.window_manager.invoke_confirm(self, event)

    @operator_boundary
    def execute(self, context):
        from . import bake, playback
        from .cache import Cache

        directory = bake.cache_directory(context.object)
        Cache.open(directory).free()
        playback.forget(directory)
        self.report({'INFO'}, f"Freed the bake in '{directory}'")
        return {'FINISHED'}


class HAIRDYN_OT_target_from_bake(bpy.types.Operator):
    """Direct the hair toward its own shape at a frame of its bake (Petrovic 2006 §5.2): a
    snapshot of that frame becomes the volume's Target"""

    bl_idname = "hairdyn.target_from_bake"
    bl_label = "Target from Bake Frame"
    bl_options = {'REGISTER', 'UNDO'}

    frame: IntProperty(
        name="Frame",
        description="The frame of this object's bake whose shape the hair is directed toward",
    )

    @classmethod
    def poll(cls, context):
        return _hair_poll(context)

    def invoke(self, context, event):
        self.frame = context.scene.frame_current
        return context.window_manager.invoke_props_dialog(self)

    @operator_boundary
    def execute(self, context):
        from . import bake

        obj = context.object
        # A snapshot, so the target stays when the bake is redone; hidden in renders.
        target = bake.snapshot_frame(context, obj, self.frame, f"{obj.name} target {self.frame}")
        target.hide_render = True
        obj.hairdyn.volume_options.target = target
        self.report({'INFO'}, f"Target: '{target.name}', frame {self.frame} of the bake")
        return {'FINISHED'}


class HAIRDYN_OT_open_frame_record(bpy.types.Operator):
    """Open the plot of the bake's per-frame record (ms, penetration, stretch, energy, contacts)"""

    bl_idname = "hairdyn.open_frame_record"
    bl_label = "Open Frame Record"
    bl_options = {'REGISTER'}

    @staticmethod
    def plot_path(context):
        from . import bake, bridge, frame_record
        from .errors import HairdynError

        if not bridge.is_hair_object(context.object):
            return None
        try:
            path = bake.cache_directory(context.object) / frame_record.PNG_NAME
        except HairdynError:
            return None
        return path if path.is_file() else None

    @classmethod
    def poll(cls, context):
        return cls.plot_path(context) is not None

    def execute(self, context):
        path = self.plot_path(context)
        image = bpy.data.images.load(str(path), check_existing=True)
        image.reload()
        for area in context.screen.areas if context.screen else ():
            if area.type == 'IMAGE_EDITOR':
                area.spaces.active.image = image
                break
        else:
            bpy.ops.wm.path_open(filepath=str(path))
        self.report({'INFO'}, f"Frame record: {path}")
        return {'FINISHED'}


class HAIRDYN_OT_collider_add(bpy.types.Operator):
    """Add a collider slot (pick the mesh in the list)"""

    bl_idname = "hairdyn.collider_add"
    bl_label = "Add Collider"
    bl_options = {'REGISTER', 'UNDO', 'INTERNAL'}

    @classmethod
    def poll(cls, context):
        return _hair_poll(context)

    def execute(self, context):
        settings = context.object.hairdyn
        settings.colliders.add()
        settings.collider_index = len(settings.colliders) - 1
        return {'FINISHED'}


class HAIRDYN_OT_collider_remove(bpy.types.Operator):
    """Remove the selected collider from the list"""

    bl_idname = "hairdyn.collider_remove"
    bl_label = "Remove Collider"
    bl_options = {'REGISTER', 'UNDO', 'INTERNAL'}

    @classmethod
    def poll(cls, context):
        return _hair_poll(context) and len(context.object.hairdyn.colliders) > 0

    def execute(self, context):
        settings = context.object.hairdyn
        settings.colliders.remove(settings.collider_index)
        settings.collider_index = max(0, min(settings.collider_index, len(settings.colliders) - 1))
        return {'FINISHED'}
