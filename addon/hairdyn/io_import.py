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

# Object property: the scale from file units to metres the groom was imported at (the fitted
# one with Fit to Object).
IMPORT_SCALE_PROPERTY = "hairdyn_import_scale"


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


def _width(points):
    """The larger of the x and y extents (the groom is upright after to_blender_axes)."""
    extent = points.max(axis=0) - points.min(axis=0)
    return float(max(extent[0], extent[1]))


def fit_to_surface(roots, vertices, nearest, samples=500):
    """(s, t, gap): the uniform scale and the offset that put the roots (N, 3, Z up) on a
    surface whose vertices are `vertices` (V, 3) and whose closest point to p is nearest(p),
    and the roots' median distance from it after the fit.

    The scalp is the top of the head: the roots' width is matched to the width of the
    surface's top band as tall as the scaled roots (a fixed point, iterated from a small scale
    so a body below the head does not count), the roots' top and centre placed on the band's;
    then iterative closest points refine scale and offset. No rotation: choose the Up Axis."""
    roots = np.asarray(roots, np.float64)
    vertices = np.asarray(vertices, np.float64)
    width_r = _width(roots)
    height_r = max(float(np.ptp(roots[:, 2])), 0.25 * width_r)
    top = vertices[:, 2].max()
    if width_r <= 0.0 or _width(vertices) <= 0.0:
        raise HairdynError("Cannot fit: the roots or the mesh have no width")
    s = 1e-3 * float(np.ptp(vertices[:, 2]) or _width(vertices)) / height_r
    for _ in range(100):
        band = vertices[vertices[:, 2] >= top - s * height_r]
        new_s = _width(band) / width_r if len(band) >= 3 else 2.0 * s
        if abs(new_s - s) <= 1e-4 * s:
            break
        s = new_s
    band = vertices[vertices[:, 2] >= top - s * height_r]
    center = 0.5 * (band.min(axis=0) + band.max(axis=0))
    roots_center = 0.5 * (roots.min(axis=0) + roots.max(axis=0))
    t = np.array([center[0] - s * roots_center[0], center[1] - s * roots_center[1],
                  top - s * roots[:, 2].max()])
    # Iterative closest points with scale, kept within a factor 2 of the band's estimate.
    chosen = np.random.default_rng(0).permutation(len(roots))[:samples]
    r = roots[chosen]
    r_mean = r.mean(axis=0)
    spread = float(((r - r_mean) ** 2).sum())
    s_band = s
    for _ in range(50):
        q = np.array([nearest(p) for p in s * r + t])
        q_mean = q.mean(axis=0)
        if spread > 0.0:
            s = float(np.clip(((r - r_mean) * (q - q_mean)).sum() / spread,
                              0.5 * s_band, 2.0 * s_band))
        new_t = q_mean - s * r_mean
        moved = np.linalg.norm(new_t - t)
        t = new_t
        if moved <= 1e-6 * s * width_r:
            break
    placed = s * r + t
    gap = float(np.median([np.linalg.norm(nearest(p) - p) for p in placed]))
    return s, t, gap


def fit_to_object(positions, roots_index, obj, depsgraph):
    """fit_to_surface for a mesh object (its evaluated surface in world space)."""
    from mathutils import Vector
    from mathutils.bvhtree import BVHTree

    from . import bridge

    mesh = bridge.read_mesh(obj, depsgraph)
    vertices = mesh.vertices_wo()
    tree = BVHTree.FromPolygons([Vector(v) for v in vertices], mesh.triangles.tolist())

    def nearest(p):
        location = tree.find_nearest(Vector(p))[0]
        return p if location is None else np.array(location)

    return fit_to_surface(positions[roots_index], vertices, nearest)


def create_hair_object(context, name, hair, up_axis='Y', scale=1.0, warnings=None,
                       fit_to=None):
    """A new Curves object holding a HairFile, linked to the active collection. Strands too
    short to simulate are left out; `warnings` (a list) receives what the artist should know.
    With `fit_to` (a mesh object) the groom is scaled and placed so its roots lie on it."""
    from . import bridge

    positions = to_blender_axes(hair.positions, up_axis) * np.float32(scale)
    hair, positions, dropped = drop_degenerate_strands(hair, positions)
    notes = [] if warnings is None else warnings
    if dropped:
        notes.append(f"{dropped} strands with a zero-length segment (shorter than a millionth "
                     "of the groom's size) were left out")
    if fit_to is not None:
        s, t, gap = fit_to_object(positions, hair.curve_offsets[:-1], fit_to,
                                  context.evaluated_depsgraph_get())
        positions = (positions * s + t).astype(np.float32)
        scale *= s
        width = _width(positions[hair.curve_offsets[:-1]])
        if gap > 0.02 * width:
            notes.append(f"After fitting to '{fit_to.name}' the roots lie {gap:.3g} m from its "
                         "surface (median): check the Up Axis, or fit to the head alone")
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
    obj[IMPORT_SCALE_PROPERTY] = scale
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
        description="Multiplies every coordinate (file units to Blender meters); with Fit to "
                    "Object the fit finds the scale")
    fit_to: StringProperty(
        name="Fit to Object",
        description="A head or body mesh: scale and place the groom so its roots lie on the "
                    "top of its surface (the file's units do not matter). Empty: keep the "
                    "file's size and place")

    def draw(self, _context):
        layout = self.layout
        layout.use_property_split = True
        layout.prop(self, "up_axis")
        layout.prop(self, "scale")
        layout.prop_search(self, "fit_to", bpy.data, "objects")

    def execute(self, context):
        from pathlib import Path

        path = Path(self.filepath)
        try:
            hair = self.reader(path)
        except (HairdynError, OSError) as error:
            self.report({'ERROR'}, str(error))
            return {'CANCELLED'}
        fit_to = None
        if self.fit_to:
            fit_to = bpy.data.objects.get(self.fit_to)
            if fit_to is None or fit_to.type != 'MESH':
                self.report({'ERROR'}, f"Fit to Object: '{self.fit_to}' is not a mesh object")
                return {'CANCELLED'}
        for other in context.selected_objects:
            other.select_set(False)
        warnings = []
        try:
            obj = create_hair_object(context, path.stem, hair, self.up_axis, self.scale, warnings,
                                     fit_to)
        except HairdynError as error:
            self.report({'ERROR'}, str(error))
            return {'CANCELLED'}
        obj.select_set(True)
        context.view_layer.objects.active = obj
        for warning in warnings:
            self.report({'WARNING'}, warning)
        self.report({'INFO'}, f"Imported {len(obj.data.curves)} strands, "
                              f"{len(obj.data.points)} points from '{path.name}' at scale "
                              f"{obj[IMPORT_SCALE_PROPERTY]:.4g}")
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
