"""Thin operators: gather from the context, call the simulation, report errors."""
import bpy

from .errors import HairdynError


class HAIRDYN_OT_simulate(bpy.types.Operator):
    """Simulate the hairdyn frame range into the output objects"""

    bl_idname = "hairdyn.simulate"
    bl_label = "Simulate Frame Range"
    bl_options = {'REGISTER', 'UNDO'}

    @classmethod
    def poll(cls, context):
        from . import bridge

        return bridge.is_hair_object(context.object)

    def execute(self, context):
        from . import simulation

        obj, scene = context.object, context.scene
        settings = obj.hairdyn
        frame = scene.frame_current
        window_manager = context.window_manager
        window_manager.progress_begin(settings.frame_start, settings.frame_end)
        try:
            report = simulation.run(context, obj, settings.frame_start, settings.frame_end,
                                    on_frame=lambda f, _ms: window_manager.progress_update(f))
        except HairdynError as error:
            self.report({'ERROR'}, str(error))
            return {'CANCELLED'}
        finally:
            window_manager.progress_end()
            scene.frame_set(frame)
        self.report({'INFO'}, f"hairdyn: {report['frames']} frames, "
                              f"{report['ms_per_frame']:.2f} ms per frame")
        return {'FINISHED'}
