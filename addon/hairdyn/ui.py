"""The hairdyn panel in the Physics tab of hair objects."""
import bpy

from . import bridge, native


class HAIRDYN_PT_main(bpy.types.Panel):
    bl_label = "hairdyn"
    bl_space_type = 'PROPERTIES'
    bl_region_type = 'WINDOW'
    bl_context = "physics"

    draw_calls = 0  # counted so a real-UI test can tell that the panel was drawn

    @classmethod
    def poll(cls, context):
        return bridge.is_hair_object(context.object)

    def draw(self, context):
        type(self).draw_calls += 1
        layout = self.layout
        ok, message = native.status()
        if not ok:
            layout.label(text=message, icon='ERROR')
        else:
            layout.label(text=f"Native solver {message}", icon='CHECKMARK')
        settings = context.object.hairdyn
        layout.use_property_split = True
        layout.prop(settings, "method")
        layout.prop(settings, "head")
        column = layout.column(align=True)
        column.prop(settings, "frame_start", text="Frame Start")
        column.prop(settings, "frame_end", text="End")
        layout.prop(settings, "output_curves")
        layout.prop(settings, "output_points")
        row = layout.row()
        row.enabled = ok
        row.operator("hairdyn.simulate", icon='PLAY')
