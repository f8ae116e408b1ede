"""The hairdyn panels in the Physics tab of hair objects: one section per concern."""
import bpy

from . import bridge, native, playback, presets
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
    methods = None  # the methods this section belongs to; None: all

    @classmethod
    def poll(cls, context):
        return super().poll(context) and (cls.methods is None or
                                          context.object.hairdyn.method in cls.methods)

    def draw(self, context):
        self.layout.use_property_split = True
        self.draw_settings(self.layout, context.object.hairdyn)


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
        if report.get("collision"):
            text += (f", penetration {report['penetration_max'] * 1000:.2f} mm "
                     f"({report['penetration_share'] * 100:.2f}%)")
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
        row.operator("hairdyn.simulate", icon='PLAY')
        row.operator("hairdyn.export_bake", icon='EXPORT')  # greyed out where no exporter exists
        row.operator("hairdyn.open_frame_record", icon='GRAPH', text="")


class HAIRDYN_PT_dynamics(_SubPanel, bpy.types.Panel):
    bl_label = "Dynamics"
    bl_options = set()
    methods = {'STRANDS'}

    def draw_settings(self, layout, settings):
        strands = settings.strands
        layout.prop(strands, "integrator")
        layout.prop(strands, "substeps")
        column = layout.column(align=True)
        column.prop(strands, "k_theta")
        column.prop(strands, "k_phi")
        layout.prop(strands, "damping")
        layout.prop(strands, "line_density")
        layout.prop(strands, "gravity")


class HAIRDYN_PT_wind(_SubPanel, bpy.types.Panel):
    bl_label = "Wind"
    methods = {'STRANDS'}

    def draw_settings(self, layout, settings):
        strands = settings.strands
        layout.prop(strands, "wind_speed")
        layout.prop(strands, "wind_direction")
        layout.prop(strands, "wind_noise")
        layout.prop(strands, "wind_noise_frequency")
        layout.prop(strands, "air_drag")


class HAIRDYN_PT_children(_SubPanel, bpy.types.Panel):
    bl_label = "Child Hairs"
    methods = {'STRANDS'}

    def draw_settings(self, layout, settings):
        strands = settings.strands
        layout.prop(strands, "children_per_guide")
        layout.prop(strands, "child_mode")
        row = layout.row()
        row.active = strands.child_mode == 'CLUSTER'
        row.prop(strands, "child_spread")
        layout.prop(strands, "seed")


class HAIRDYN_PT_lcp(_SubPanel, bpy.types.Panel):
    bl_label = "Loosely Connected Particles"
    bl_options = set()
    methods = {'LCP'}

    def draw_settings(self, layout, settings):
        lcp = settings.lcp
        self.draw_initialisation(layout, settings)
        column = layout.column(align=True)
        column.prop(lcp, "particle_spacing")
        column.prop(lcp, "particle_num")
        column.prop(lcp, "root_depth")
        column.prop(lcp, "beam_length")
        layout.prop(lcp, "substeps")
        layout.prop(lcp, "implicit_springs")
        for name in ("h1", "a0", "neighbor_num", "young_modulus", "material_density",
                     "spring_damping", "hair_density"):
            layout.prop(lcp, name)

    @staticmethod
    def draw_initialisation(layout, settings):
        """Where the particles start (Bando 2003 §3.2): only the rows the choices use."""
        layout.prop(settings, "lcp_init")
        if settings.lcp_init == 'GROOM':
            return
        obj = settings.id_data
        head = settings.head or (obj.data.surface if obj.type == 'CURVES' else obj)
        if head is not None and head.type != 'MESH':
            head = None

        def vertex_group(name):
            if head is None:
                layout.prop(settings, name)
            else:
                layout.prop_search(settings, name, head, "vertex_groups")

        layout.prop(settings, "lcp_scalp_source")
        if settings.lcp_scalp_source == 'GROUP':
            vertex_group("lcp_scalp")
        layout.prop(settings, "lcp_length_source")
        if settings.lcp_length_source == 'IMAGE':
            layout.prop(settings, "lcp_length_image")
        elif settings.lcp_length_source == 'WEIGHTS':
            vertex_group("lcp_length_group")


class HAIRDYN_PT_lcp_interactions(_SubPanel, bpy.types.Panel):
    bl_label = "Hair-Hair Interactions"
    methods = {'LCP'}

    def draw_settings(self, layout, settings):
        lcp = settings.lcp
        layout.prop(lcp, "h2")
        layout.prop(lcp, "attraction_repulsion")
        column = layout.column(align=True)
        column.active = lcp.attraction_repulsion
        column.prop(lcp, "pressure_stiffness")
        column.prop(lcp, "rest_density")
        layout.prop(lcp, "hair_collision")
        row = layout.row()
        row.active = lcp.hair_collision
        row.prop(lcp, "collision_damping")
        layout.prop(lcp, "hair_friction")
        row = layout.row()
        row.active = lcp.hair_friction
        row.prop(lcp, "friction_damping")


class HAIRDYN_PT_lcp_forces(_SubPanel, bpy.types.Panel):
    bl_label = "Forces and Wind"
    methods = {'LCP'}

    def draw_settings(self, layout, settings):
        lcp = settings.lcp
        for name in ("gravity", "air_friction", "body_friction", "wind_speed", "wind_heading",
                     "wind_particle_spacing", "wind_drag", "air_density"):
            layout.prop(lcp, name)


class HAIRDYN_PT_lcp_initial(_SubPanel, bpy.types.Panel):
    bl_label = "Initial Shape"
    methods = {'LCP'}

    def draw_settings(self, layout, settings):
        lcp = settings.lcp
        for name in ("max_length", "root_tangent_weight", "root_normal_weight", "whorl_u",
                     "whorl_v", "seed"):
            layout.prop(lcp, name)


class HAIRDYN_UL_colliders(bpy.types.UIList):
    def draw_item(self, _context, layout, _data, item, _icon, _active_data, _active_prop,
                  _index=0, _flt_flag=0):
        layout.prop(item, "object", text="", emboss=False, icon='MESH_DATA')


class HAIRDYN_PT_collision(_SubPanel, bpy.types.Panel):
    bl_label = "Collision"

    def draw_header(self, context):
        self.layout.prop(context.object.hairdyn, "use_collision", text="")

    def draw_settings(self, layout, settings):
        layout.active = settings.use_collision
        layout.prop(settings, "use_default_colliders")
        row = layout.row()
        row.template_list("HAIRDYN_UL_colliders", "", settings, "colliders", settings,
                          "collider_index", rows=2)
        buttons = row.column(align=True)
        buttons.operator("hairdyn.collider_add", icon='ADD', text="")
        buttons.operator("hairdyn.collider_remove", icon='REMOVE', text="")
        layout.prop(settings, "collider_parts")
        collision = settings.collision
        layout.prop(collision, "map_kind")
        layout.prop(collision, "axis_mode")
        column = layout.column(align=True)
        column.prop(collision, "azimuth_num")
        column.prop(collision, "height_num")
        layout.prop(collision, "stiffness")
        layout.prop(collision, "damping")
        layout.prop(collision, "friction")
        layout.prop(collision, "projection_tolerance")
        layout.prop(collision, "penetration_tolerance")


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
        if settings.method == 'LCP':
            layout.prop(settings, "use_billboards")
        if settings.method == 'STRANDS':
            layout.prop(settings, "output_children")


panel_classes = (HAIRDYN_UL_colliders, HAIRDYN_PT_main, HAIRDYN_PT_dynamics, HAIRDYN_PT_wind,
                 HAIRDYN_PT_children, HAIRDYN_PT_lcp, HAIRDYN_PT_lcp_interactions,
                 HAIRDYN_PT_lcp_forces, HAIRDYN_PT_lcp_initial, HAIRDYN_PT_collision,
                 HAIRDYN_PT_cache, HAIRDYN_PT_output)
