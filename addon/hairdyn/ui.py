"""The hairdyn panel in the Physics tab of hair objects."""
import bpy

from . import bridge, native, playback
from .errors import HairdynError


class HAIRDYN_PT_main(bpy.types.Panel):
    bl_label = "hairdyn"
    bl_space_type = 'PROPERTIES'
    bl_region_type = 'WINDOW'
    bl_context = "physics"

    draw_calls = 0  # counted so a real-UI test can tell that the panel was drawn

    @classmethod
    def poll(cls, context):
        return bridge.is_hair_object(context.object)

    def draw_header(self, context):
        self.layout.prop(context.object.hairdyn, "enabled", text="")

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

        box = layout.box()
        box.label(text="Cache")
        box.prop(settings, "cache_directory")
        box.prop(settings, "use_cache")
        box.label(text=bake_status(context.object))
        row = box.row(align=True)
        row.enabled = ok
        row.operator("hairdyn.bake", icon='REC').from_current = False
        row.operator("hairdyn.bake", text="Bake from Current Frame").from_current = True
        row.operator("hairdyn.free_bake", icon='TRASH', text="")
        error = playback.last_error(context.object)
        if error:
            box.label(text=error, icon='ERROR')


def bake_status(obj):
    """One line: frames baked, ms per frame, the last quality figures."""
    from . import simulation

    try:
        opened = playback.open_cache(simulation.cache_directory(obj))
    except HairdynError as error:
        return str(error)
    if opened is None:
        return "Not baked"
    cache = opened[0]
    manifest = cache.manifest
    total = manifest["frame_end"] - manifest["frame_start"] + 1
    text = f"Baked {len(cache.frames())}/{total} frames"
    report = manifest.get("report")
    if report:
        text += f", {report['ms_per_frame']:.2f} ms/frame, stretch {report['stretch_max']:.1e}"
    return text
