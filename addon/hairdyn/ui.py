"""Owns: the hairdyn panels in the Physics tab of hair objects. The main panel and the shared
sections (collision, cache, output) are written here; each method's sections are generated
from its adapter's `sections` at registration, and the collision settings show only the
kinds the method reads (colliders.collision_fields)."""

import bpy

from . import bake, bridge, colliders, methods, native, playback, presets
from .errors import HairdynError


class _HairdynPanel:
    bl_space_type = 'PROPERTIES'
    bl_region_type = 'WINDOW'
    bl_context = "physics"

    @classmethod
    def poll(cls, context):
        return bridge.is_hair_object(context.object)


class _SubPanel(_HairdynPanel):
    bl_parent_id = "HAIRDYN_PT_main"
    bl_options = {'DEFAULT_CLOSED'}

    def draw(self, context):
        self.layout.use_property_split = True
        self.draw_settings(self.layout, context.object.hairdyn)


def bake_status(obj):
    """One line: frames baked, ms per frame, the last quality figures."""
    try:
        opened = playback.open_cache(bake.cache_directory(obj))
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
        if report.get("collision"):
            text += (
                f", penetration {report['penetration_max'] * 1000:.2f} mm "
                f"({report['penetration_share'] * 100:.2f}%)"
            )
        if "lod_error" in report:
            text += f", lod_error {report['lod_error'] * 100:.2f}%"
    return text


class HAIRDYN_PT_main(_HairdynPanel, bpy.types.Panel):
    bl_label = "hairdyn"

    draw_calls = 0  # counted so a real-UI test can tell that the panel was drawn

    def draw_header(self, context):
        self.layout.prop(context.object.hairdyn, "enabled", text="")

    def draw(self, context):
        type(self).draw_calls += 1
        layout = self.layout
        ok, message = native.status()
        if not ok:
            layout.label(text=message, icon='ERROR')
        settings = context.object.hairdyn
        presets.draw_menu(layout)
        layout.use_property_split = True
        layout.prop(settings, "method")
        layout.prop(settings, "head")
        column = layout.column(align=True)
        column.prop(settings, "frame_start", text="Frame Start")
        column.prop(settings, "frame_end", text="End")
        layout.label(text=bake_status(context.object), icon='INFO')
        error = playback.last_error(context.object)
        if error:
            layout.label(text=error, icon='ERROR')
        row = layout.row(align=True)
        row.enabled = ok
        row.operator("hairdyn.bake", icon='REC').from_current = False
        row.operator("hairdyn.bake", text="From Current Frame").from_current = True
        row.operator("hairdyn.free_bake", icon='TRASH', text="")
        row = layout.row()
        row.enabled = ok
        row.operator("hairdyn.simulate", icon='PLAY', text="Simulate")
        row.operator("hairdyn.export_bake", icon='EXPORT')  # greyed out where no exporter exists
        row.operator("hairdyn.open_frame_record", icon='GRAPH', text="")


def section_fields(method, section, group):
    """The fields a method's section shows as rows: those it names, then with `rest` those of
    the group no section of the method names (nor draws in its header)."""
    names = [
        p.identifier for p in group.bl_rna.properties if p.identifier not in ("rna_type", "name")
    ]
    shown = [name for name in section.fields if name in names]
    if section.rest:
        named = {
            name
            for other in method.sections
            if other.group == section.group
            for name in (*other.fields, other.header)
        }
        shown += [name for name in names if name not in named]
    return shown


def _method_panel(method, index, section):
    """A sub-panel class for one section of a method."""

    def poll(cls, context):
        if not bridge.is_hair_object(context.object):
            return False
        settings = context.object.hairdyn
        group = getattr(settings, section.group, None)
        return (
            settings.method == method.identifier
            and group is not None
            and (section.draw is not None or bool(section_fields(method, section, group)))
        )

    def draw_settings(self, layout, settings):
        group = getattr(settings, section.group)
        if section.header is not None:
            layout.active = bool(getattr(group, section.header))
        if section.draw is not None:
            section.draw(layout, settings)
        for name in section_fields(method, section, group):
            row = layout.row()
            active = section.active.get(name)
            row.active = active is None or bool(active(group))
            row.prop(group, name)

    def draw_header(self, context):
        self.layout.prop(getattr(context.object.hairdyn, section.group), section.header, text="")

    attributes = {
        "bl_label": section.label,
        "bl_options": set() if section.open else {'DEFAULT_CLOSED'},
        "poll": classmethod(poll),
        "draw_settings": draw_settings,
    }
    if section.header is not None:
        attributes["draw_header"] = draw_header
    return type(
        f"HAIRDYN_PT_{method.identifier.lower()}_{index}",
        (_SubPanel, bpy.types.Panel),
        attributes,
    )


class HAIRDYN_UL_colliders(bpy.types.UIList):
    def draw_item(
        self,
        _context,
        layout,
        _data,
        item,
        _icon,
        _active_data,
        _active_prop,
        _index=0,
        _flt_flag=0,
    ):
        layout.prop(item, "object", text="", emboss=False, icon='MESH_DATA')


class HAIRDYN_PT_collision(_SubPanel, bpy.types.Panel):
    bl_label = "Collision"

    def draw_header(self, context):
        self.layout.prop(context.object.hairdyn, "use_collision", text="")

    def draw_settings(self, layout, settings):
        layout.active = settings.use_collision
        layout.prop(settings, "use_default_colliders")
        row = layout.row()
        row.template_list(
            "HAIRDYN_UL_colliders", "", settings, "colliders", settings, "collider_index", rows=2
        )
        buttons = row.column(align=True)
        buttons.operator("hairdyn.collider_add", icon='ADD', text="")
        buttons.operator("hairdyn.collider_remove", icon='REMOVE', text="")
        layout.prop(settings, "collider_parts")
        method = methods.get(settings.method)
        collision = getattr(settings, "collision", None)
        if method is None or collision is None:
            return
        for kind in ("maps", "response", "report"):
            if kind in method.collision:
                column = layout.column(align=kind == "maps")
                for name in colliders.collision_fields(kind, native.load().CollisionParams):
                    column.prop(collision, name)


class HAIRDYN_PT_cache(_SubPanel, bpy.types.Panel):
    bl_label = "Cache"

    def draw_settings(self, layout, settings):
        layout.prop(settings, "cache_directory")
        layout.prop(settings, "use_cache")
        layout.prop(settings, "use_live")


class HAIRDYN_PT_output(_SubPanel, bpy.types.Panel):
    bl_label = "Output"

    def draw_settings(self, layout, settings):
        layout.prop(settings, "output_curves")
        layout.prop(settings, "output_points")
        layout.prop(settings, "hide_source_in_renders")
        method = methods.get(settings.method)
        for name in method.shows if method is not None else ():
            layout.prop(settings, name)


_registered = []


def panel_classes():
    """Every class this module registers, in panel order."""
    generated = [
        _method_panel(method, index, section)
        for method in methods.all_methods()
        for index, section in enumerate(method.sections)
    ]
    return (
        HAIRDYN_UL_colliders,
        HAIRDYN_PT_main,
        *generated,
        HAIRDYN_PT_collision,
        HAIRDYN_PT_cache,
        HAIRDYN_PT_output,
    )


def register():
    for cls in panel_classes():
        bpy.utils.register_class(cls)
        _registered.append(cls)


def unregister():
    while _registered:
        bpy.utils.unregister_class(_registered.pop())
