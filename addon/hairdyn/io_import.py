"""File > Import for hair files: TressFX (.tfx) and Cem Yuksel's .hair, as a Curves object."""
import bpy
import numpy as np
from bpy.props import EnumProperty, FloatProperty, StringProperty
from bpy_extras.io_utils import ImportHelper

# FIXED_ATTRIBUTE marks the vertices a file pins (TressFX w == 0; the roots otherwise); every
# simulating method holds them with the head (bridge.read_fixed).
from .bridge import FIXED_ATTRIBUTE
from .errors import HairdynError
from .hair_formats import HairFile, read_cem_hair, read_tfx


def to_blender_axes(positions, up_axis):
    """File coordinates to Blender's Z-up: Y-up files turn as Blender's OBJ importer does
    (x, y, z) -> (x, -z, y), so hair lines up with a mesh imported from OBJ."""
    if up_axis == 'Y':
        return np.ascontiguousarray(positions[:, [0, 2, 1]] * np.array([1, -1, 1], np.float32))
    return positions


# A groom whose bounding box is outside this range (metres) is probably in other units.
PLAUSIBLE_SIZE = (0.01, 10.0)


def size_warning(positions):
    """A sentence when the groom is implausibly large or small for hair (metres), else None."""
    if len(positions) == 0:
        return None
    size = float(np.linalg.norm(positions.max(axis=0) - positions.min(axis=0)))
    low, high = PLAUSIBLE_SIZE
    if low <= size <= high:
        return None
    return (f"The groom is {size:.3g} m across, {'more' if size > high else 'less'} than hair "
            f"usually is ({low:g} to {high:g} m): check the Scale (TressFX files carry no "
            "units; 0.01 turns centimetres into metres)")


def drop_degenerate_strands(hair, positions):
    """(hair, positions) without the strands whose segments are too short to have a direction
    (the native tolerance: a millionth of the groom's size), and how many were dropped."""
    from . import bridge

    degenerate = bridge.degenerate_strand_mask(hair.curve_offsets, positions)
    if degenerate is None or not degenerate.any():
        return hair, positions, 0
    if degenerate.all():
        raise HairdynError(f"Every strand ({len(degenerate)}) has a zero-length segment")
    offsets, points = bridge.keep_strands(hair.curve_offsets, ~degenerate)
    kept = HairFile(np.ascontiguousarray(hair.positions[points]), offsets, hair.fixed[points],
                    None if hair.thickness is None else hair.thickness[points])
    return kept, np.ascontiguousarray(positions[points]), int(degenerate.sum())


def create_hair_object(context, name, hair, up_axis='Y', scale=1.0, warnings=None):
    """A new Curves object holding a HairFile, linked to the active collection. Strands too
    short to simulate are left out; `warnings` (a list) receives what the artist should know."""
    from . import bridge

    positions = to_blender_axes(hair.positions, up_axis) * np.float32(scale)
    hair, positions, dropped = drop_degenerate_strands(hair, positions)
    notes = [] if warnings is None else warnings
    if dropped:
        notes.append(f"{dropped} strands with a zero-length segment (shorter than a millionth "
                     "of the groom's size) were left out")
    size_note = size_warning(positions)
    if size_note:
        notes.append(size_note)
    curves = bridge.new_curves_data(name, np.diff(hair.curve_offsets))
    curves.position_data.foreach_set("vector", np.ascontiguousarray(positions).ravel())
    fixed = curves.attributes.new(FIXED_ATTRIBUTE, 'BOOLEAN', 'POINT')
    fixed.data.foreach_set("value", hair.fixed.astype(bool))
    if hair.thickness is not None and hair.thickness.max() > 0:
        radius = curves.attributes.new("radius", 'FLOAT', 'POINT')
        radius.data.foreach_set("value", hair.thickness * np.float32(0.5 * scale))
    obj = bpy.data.objects.new(name, curves)
    context.collection.objects.link(obj)
    return obj


class _ImportHair(ImportHelper):
    """Shared options and execute(); subclasses set `reader` (path -> HairFile)."""

    up_axis: EnumProperty(
        name="Up Axis", default='Y',
        items=(('Y', "Y Up", "The file is Y-up (TressFX, most game engines): turn it to Z-up"),
               ('Z', "Z Up", "The file is already Z-up like Blender")),
        description="Which axis points up in the file")
    scale: FloatProperty(
        name="Scale", default=1.0, min=1e-6, max=1e6, soft_min=0.001, soft_max=1000.0,
        description="Multiplies every coordinate (file units to Blender meters)")

    def execute(self, context):
        from pathlib import Path

        path = Path(self.filepath)
        try:
            hair = self.reader(path)
        except (HairdynError, OSError) as error:
            self.report({'ERROR'}, str(error))
            return {'CANCELLED'}
        for other in context.selected_objects:
            other.select_set(False)
        warnings = []
        try:
            obj = create_hair_object(context, path.stem, hair, self.up_axis, self.scale, warnings)
        except HairdynError as error:
            self.report({'ERROR'}, str(error))
            return {'CANCELLED'}
        obj.select_set(True)
        context.view_layer.objects.active = obj
        for warning in warnings:
            self.report({'WARNING'}, warning)
        self.report({'INFO'}, f"Imported {len(obj.data.curves)} strands, "
                              f"{len(obj.data.points)} points from '{path.name}'")
        return {'FINISHED'}


class HAIRDYN_OT_import_tfx(bpy.types.Operator, _ImportHair):
    """Import TressFX hair (.tfx, versions 3 and 4) as a Curves object"""

    bl_idname = "hairdyn.import_tfx"
    bl_label = "Import TressFX Hair"
    bl_options = {'REGISTER', 'UNDO', 'PRESET'}
    filename_ext = ".tfx"
    filter_glob: StringProperty(default="*.tfx", options={'HIDDEN'})
    reader = staticmethod(read_tfx)


class HAIRDYN_OT_import_cem_hair(bpy.types.Operator, _ImportHair):
    """Import hair in Cem Yuksel's .hair format as a Curves object"""

    bl_idname = "hairdyn.import_cem_hair"
    bl_label = "Import Cem Yuksel Hair"
    bl_options = {'REGISTER', 'UNDO', 'PRESET'}
    filename_ext = ".hair"
    filter_glob: StringProperty(default="*.hair", options={'HIDDEN'})
    reader = staticmethod(read_cem_hair)


def menu_import(self, _context):
    self.layout.operator(HAIRDYN_OT_import_tfx.bl_idname, text="TressFX Hair (.tfx)")
    self.layout.operator(HAIRDYN_OT_import_cem_hair.bl_idname, text="Cem Yuksel Hair (.hair)")


def register():
    bpy.types.TOPBAR_MT_file_import.append(menu_import)


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(menu_import)
