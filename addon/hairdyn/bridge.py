"""Blender <-> numpy: read hair and meshes, write simulated positions back.

Everything goes through foreach_get / foreach_set on numpy arrays (the writes of every frame
straight into Blender's array where it is one, set_rows): no per-point Python loop.
Arrays handed to the native module are C-contiguous (N, 3) float32 / int32, so they cross
the boundary without copies.
"""

import ctypes
import sys
from dataclasses import dataclass, field

import bpy
import numpy as np

from .errors import HairdynError

# Attribute Blender's hair tools store the root's surface UV in (Curves, curve domain).
SURFACE_UV_ATTRIBUTE = "surface_uv_coordinate"
# Point attribute (BOOLEAN) of pinned points, kinematic like the roots: TressFX's immovable
# vertices (io_import writes it), or painted by the artist.
FIXED_ATTRIBUTE = "hairdyn_fixed"


@dataclass
class Groom:
    """Strands as Blender stores curves: offsets into one positions array (world space)."""

    positions_wo: np.ndarray  # (N, 3) float32
    curve_offsets: np.ndarray  # (C + 1,) int32
    surface: object  # bpy.types.Object the roots sit on, or None
    root_uvs: object  # (C, 2) float32 surface UVs of the roots, or None
    warnings: list = field(default_factory=list)  # sentences for the report / console
    # (N,) bool pinned points (FIXED_ATTRIBUTE; the roots are pinned anyway), or None: only
    # the roots (legacy particle hair, or Curves without the attribute)
    fixed: object = None
    # (N,) float32 strand radius per point in world meters (a Curves radius attribute), or
    # None: the swept spheres' thickness setting stands for it
    radii: object = None

    @property
    def pins_num(self):
        """Pinned points other than the roots."""
        if self.fixed is None:
            return 0
        return int(self.fixed.sum() - self.fixed[self.curve_offsets[:-1]].sum())

    @property
    def curves_num(self):
        return len(self.curve_offsets) - 1

    @property
    def points_num(self):
        return len(self.positions_wo)


@dataclass
class MeshData:
    """An evaluated mesh in its object space, and where the object is (rigid motion is the
    matrix, not new geometry)."""

    name: str
    vertices: np.ndarray  # (V, 3) float32, object space
    blender_normals: np.ndarray  # (V, 3) float32, object space: Blender's (see normals())
    triangles: np.ndarray  # (T, 3) int32
    triangle_faces: np.ndarray  # (T,) int32, the polygon each triangle belongs to
    matrix_world: np.ndarray  # (4, 4) float64, row-major as Blender

    def vertices_wo(self):
        return to_world(self.matrix_world, self.vertices)

    def normals(self):
        """(V, 3) float64 unit vertex normals in object space, the same bits in every run:
        each triangle's unit normal weighted by its angle at the vertex (as Blender weights
        its faces), summed in the triangles' order. Blender's own vertex normals are summed in
        parallel and change in their last bits from run to run, and so did the simulation (a
        strand's root normal one bit off, then chaos). A vertex in no triangle keeps Blender's
        normal."""
        v = self.vertices.astype(np.float64)
        t = self.triangles
        face = np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]])
        face /= np.maximum(np.sqrt(np.einsum("ij,ij->i", face, face)), 1e-300)[:, None]
        normals = np.zeros_like(v)
        for corner in range(3):
            to_next = v[t[:, (corner + 1) % 3]] - v[t[:, corner]]
            to_previous = v[t[:, (corner + 2) % 3]] - v[t[:, corner]]
            across = np.cross(to_next, to_previous)
            angle = np.arctan2(
                np.sqrt(np.einsum("ij,ij->i", across, across)),
                np.einsum("ij,ij->i", to_next, to_previous),
            )
            np.add.at(normals, t[:, corner], angle[:, None] * face)  # in order: deterministic
        lengths = np.sqrt(np.einsum("ij,ij->i", normals, normals))[:, None]
        loose = lengths[:, 0] == 0.0
        normals[loose] = self.blender_normals[loose]
        lengths[loose] = 1.0
        return normals / lengths

    def normals_wo(self):
        """World-space unit normals (inverse-transpose, so non-uniform scale is right), the
        same bits in every run (normals(); no BLAS product, whose sums may be split
        differently)."""
        normal_matrix = np.linalg.inv(self.matrix_world[:3, :3]).T
        normals = np.einsum("ij,kj->ik", self.normals(), normal_matrix)
        lengths = np.sqrt(np.einsum("ij,ij->i", normals, normals))[:, None]
        return (normals / np.maximum(lengths, 1e-30)).astype(np.float32)


def matrix_array(matrix):
    """A Blender Matrix as a (4, 4) float64 numpy array (row-major, as printed)."""
    return np.array(matrix, dtype=np.float64)


def to_world(matrix_world, points):
    """(N, 3) object-space float32 points to world space (float64 product, float32 result)."""
    m = np.asarray(matrix_world, dtype=np.float64)
    return np.ascontiguousarray((points @ m[:3, :3].T + m[:3, 3]).astype(np.float32))


def to_local(matrix_world, points):
    """(N, 3) world-space points into the object's space, in float64."""
    m = np.linalg.inv(np.asarray(matrix_world, dtype=np.float64))
    return np.asarray(points, dtype=np.float64) @ m[:3, :3].T + m[:3, 3]


def hair_particle_system(obj):
    """The mesh's hair particle system (the active one if it is hair), or None."""
    if obj is None or obj.type != 'MESH':
        return None
    systems = obj.particle_systems
    active = systems.active
    if active is not None and active.settings.type == 'HAIR':
        return active
    return next((psys for psys in systems if psys.settings.type == 'HAIR'), None)


def hair_system_modifiers(obj):
    """The object's particle system modifiers that carry hair (none for a Curves object)."""
    return [
        modifier
        for modifier in getattr(obj, "modifiers", ())
        if modifier.type == 'PARTICLE_SYSTEM'
        and modifier.particle_system is not None
        and modifier.particle_system.settings.type == 'HAIR'
    ]


def is_hair_object(obj):
    """Curves objects, and meshes that carry a hair particle system."""
    return obj is not None and (obj.type == 'CURVES' or hair_particle_system(obj) is not None)


# ---------------------------------------------------------------------------------------------
# Reading hair


def _curve_offsets(curves):
    """The curve_offsets (C + 1,) int32 of a Curves ID."""
    curve_offsets = np.zeros(len(curves.curves) + 1, dtype=np.int32)
    if len(curves.curves):  # an empty Curves ID stores no offsets at all, not [0]
        curves.curve_offset_data.foreach_get("value", curve_offsets)
    return curve_offsets


def _curves_arrays(curves):
    """(positions (N, 3) float32 object space, curve_offsets (C + 1,) int32) of a Curves ID."""
    positions = np.empty((len(curves.points), 3), dtype=np.float32)
    if len(curves.curves):
        curves.position_data.foreach_get("vector", positions.ravel())
    return positions, _curve_offsets(curves)


def read_curves(obj, depsgraph):
    """A Curves hair object, evaluated, in world space."""
    evaluated = obj.evaluated_get(depsgraph)
    curves = evaluated.data
    if not isinstance(curves, bpy.types.Curves):
        raise HairdynError(f"'{obj.name}' does not evaluate to hair curves")
    positions, curve_offsets = _curves_arrays(curves)
    if len(curve_offsets) < 2:
        raise HairdynError(f"'{obj.name}' has no hair strands")
    root_uvs = None
    # UVs as the artist authored them (the original ID: evaluated attributes may be
    # read-only views that Blender refuses to hand out).
    attribute = obj.data.attributes.get(SURFACE_UV_ATTRIBUTE)
    if (
        attribute is not None
        and attribute.domain == 'CURVE'
        and attribute.data_type == 'FLOAT2'
        and len(attribute.data) == len(curve_offsets) - 1
    ):
        root_uvs = np.empty((len(curve_offsets) - 1, 2), dtype=np.float32)
        attribute.data.foreach_get("vector", root_uvs.ravel())
    matrix_world = matrix_array(evaluated.matrix_world)
    radii, warnings = read_radii(obj, len(positions), matrix_world)
    return Groom(
        positions_wo=to_world(matrix_world, positions),
        curve_offsets=curve_offsets,
        surface=obj.data.surface,
        root_uvs=root_uvs,
        warnings=warnings,
        fixed=read_fixed(obj, len(positions)),
        radii=radii,
    )


def read_radii(obj, points_num, matrix_world):
    """((N,) float32 radii in world meters, [warning]) from the FLOAT point attribute
    "radius" of a Curves object (scaled by the object's mean scale), or (None, []) when it has
    none, or one for other points than the evaluated ones; (None, [sentence]) when a value is
    negative, not a number, or thicker than the swept spheres' Strand Thickness may be (it
    stands for the attribute: every pair of segments would overlap)."""
    from . import native

    radii = _point_values(obj, "radius", 'FLOAT', points_num, np.float32)
    if radii is None:
        return None, []
    scale = abs(float(np.linalg.det(matrix_world[:3, :3]))) ** (1.0 / 3.0)
    with np.errstate(over="ignore", invalid="ignore"):
        radii = (radii * np.float32(scale)).astype(np.float32)
    (thickness,) = (f for f in native.load().SweptSphereParams.fields() if f["name"] == "thickness")
    if not (
        np.isfinite(radii).all() and (radii >= 0.0).all() and (radii <= thickness["max"]).all()
    ):
        message = (
            f"the radius attribute of '{obj.name}' has values that are negative, not "
            f"numbers or over {1e3 * thickness['max']:g} mm; the swept spheres' Strand "
            "Thickness stands for it"
        )
        print(f"hairdyn: warning: {message}", file=sys.stderr)
        return None, [message]
    return radii, []


def read_fixed(obj, points_num):
    """(N,) bool from the BOOLEAN point attribute FIXED_ATTRIBUTE of a Curves object, or None
    when it has none (or one of another kind, or for other points than the evaluated ones: a
    modifier that adds or removes points leaves the pins without their points)."""
    fixed = _point_values(obj, FIXED_ATTRIBUTE, 'BOOLEAN', points_num, bool)
    return fixed if fixed is not None and fixed.any() else None


def _point_values(obj, name, data_type, points_num, dtype):
    """(N,) values of the Curves object's point attribute `name` of `data_type`, or None when it
    has none of that kind and count. The original ID's: evaluated attributes may be read-only
    views that Blender refuses to hand out."""
    attribute = obj.data.attributes.get(name)
    if (
        attribute is None
        or attribute.domain != 'POINT'
        or attribute.data_type != data_type
        or len(attribute.data) != points_num
    ):
        return None
    values = np.empty(points_num, dtype=dtype)
    attribute.data.foreach_get("value", values)
    return values


def read_particle_hair(obj, depsgraph):
    """Legacy particle hair: the evaluated guide strands (parents), in world space.

    Blender's evaluated hair is the particle system's path cache, the strands the viewport
    draws (the same data ParticleSystem.co_hair returns). Blender's own converter
    (curves.convert_from_particle_system) copies it into a temporary Curves object in C, so
    no Python loop touches a point; parents come first when the settings show them, which
    this switches on for the moment of the conversion.
    """
    psys = hair_particle_system(obj)
    if psys is None:
        raise HairdynError(f"'{obj.name}' has no hair particle system")
    settings = psys.settings
    parents_num = len(obj.evaluated_get(depsgraph).particle_systems[psys.name].particles)
    if parents_num == 0:
        raise HairdynError(f"The hair particle system of '{obj.name}' has no strands")

    showed_parents = settings.use_parent_particles
    active_index = obj.particle_systems.active_index
    index = list(obj.particle_systems).index(psys)
    # Setting either (even to the value it has) makes Blender evaluate the particle system
    # again, there and back: 26 of a read's 33 ms for 2,000 strands. So only what must
    # change is set: without children the path cache holds the parents alone.
    show_parents = settings.child_type != 'NONE' and not showed_parents
    switch = show_parents or active_index != index
    before = set(bpy.data.objects)
    try:
        if show_parents:
            settings.use_parent_particles = True
        if active_index != index:
            obj.particle_systems.active_index = index
        if switch:
            depsgraph.update()
        with bpy.context.temp_override(
            object=obj, active_object=obj, selected_objects=[obj], selected_editable_objects=[obj]
        ):
            bpy.ops.curves.convert_from_particle_system()
        created = [o for o in bpy.data.objects if o not in before]
        if len(created) != 1 or created[0].type != 'CURVES':
            raise HairdynError(f"Blender could not convert the hair of '{obj.name}'")
        converted = created[0]
        positions, curve_offsets = _curves_arrays(converted.data)
        matrix_world = matrix_array(converted.matrix_world)
    finally:
        for leftover in [o for o in bpy.data.objects if o not in before]:
            data = leftover.data
            bpy.data.objects.remove(leftover)
            if data is not None and data.users == 0:
                bpy.data.hair_curves.remove(data)
        if show_parents:
            settings.use_parent_particles = showed_parents
        if active_index != index:
            obj.particle_systems.active_index = active_index
        depsgraph.update()

    curve_offsets = np.ascontiguousarray(curve_offsets[: parents_num + 1])
    positions = positions[: curve_offsets[-1]]
    return Groom(
        positions_wo=to_world(matrix_world, positions),
        curve_offsets=curve_offsets,
        surface=obj,
        root_uvs=None,
    )


def read_groom(obj, depsgraph):
    """The strands of any hair object, world space, without its degenerate strands (see
    drop_degenerate_strands)."""
    if obj is None:
        raise HairdynError("No hair object given")
    if obj.type == 'CURVES':
        groom = read_curves(obj, depsgraph)
    elif hair_particle_system(obj) is not None:
        groom = read_particle_hair(obj, depsgraph)
    else:
        raise HairdynError(
            f"'{obj.name}' is not hair: use a Curves object or a mesh with a hair particle system"
        )
    return drop_degenerate_strands(groom, obj.name)


def degenerate_strand_mask(curve_offsets, positions):
    """(C,) bool: strands with a segment shorter than a millionth of the groom's size (the
    native tolerance, relative so that units do not matter), or None when the groom is
    broken in another way (the solvers' own check then names the problem)."""
    from . import native

    module = native.load()
    try:
        return module.degenerate_strands(
            np.ascontiguousarray(curve_offsets, dtype=np.int32),
            np.ascontiguousarray(positions, dtype=np.float32),
        )
    except ValueError:
        return None


def keep_strands(curve_offsets, keep):
    """(new curve offsets, point mask) keeping the strands where keep is True."""
    sizes = np.diff(curve_offsets)[keep]
    offsets = np.zeros(len(sizes) + 1, dtype=np.int32)
    np.cumsum(sizes, out=offsets[1:])
    return offsets, np.repeat(keep, np.diff(curve_offsets))


def drop_degenerate_strands(groom, name):
    """The groom without strands too short to have a direction (real assets carry a few:
    TressFX strands of 2 µm); the count goes to groom.warnings and the console."""
    degenerate = degenerate_strand_mask(groom.curve_offsets, groom.positions_wo)
    if degenerate is None or not degenerate.any():
        return groom
    count = int(degenerate.sum())
    if count == len(degenerate):
        raise HairdynError(
            f"Every strand of '{name}' ({count}) has a zero-length segment "
            "(shorter than a millionth of the groom's size)"
        )
    offsets, points = keep_strands(groom.curve_offsets, ~degenerate)
    message = (
        f"{count} of the {len(degenerate)} strands of '{name}' have a zero-length "
        "segment (shorter than a millionth of the groom's size) and were left out"
    )
    print(f"hairdyn: warning: {message}", file=sys.stderr)
    return Groom(
        positions_wo=np.ascontiguousarray(groom.positions_wo[points]),
        curve_offsets=offsets,
        surface=groom.surface,
        root_uvs=None
        if groom.root_uvs is None
        else np.ascontiguousarray(groom.root_uvs[~degenerate]),
        warnings=groom.warnings + [message],
        fixed=None if groom.fixed is None else np.ascontiguousarray(groom.fixed[points]),
        radii=None if groom.radii is None else np.ascontiguousarray(groom.radii[points]),
    )


# ---------------------------------------------------------------------------------------------
# Reading meshes


def read_mesh(obj, depsgraph):
    """An evaluated mesh object's triangles and normals in object space, plus its matrix."""
    if obj is None or obj.type != 'MESH':
        raise HairdynError(f"'{getattr(obj, 'name', obj)}' is not a mesh object")
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        vertices = np.empty((len(mesh.vertices), 3), dtype=np.float32)
        normals = np.empty_like(vertices)
        mesh.vertices.foreach_get("co", vertices.ravel())
        mesh.vertices.foreach_get("normal", normals.ravel())
        mesh.calc_loop_triangles()
        triangles = np.empty((len(mesh.loop_triangles), 3), dtype=np.int32)
        mesh.loop_triangles.foreach_get("vertices", triangles.ravel())
        triangle_faces = np.empty(len(mesh.loop_triangles), dtype=np.int32)
        mesh.loop_triangles.foreach_get("polygon_index", triangle_faces)
    finally:
        evaluated.to_mesh_clear()
    if len(vertices) == 0:
        raise HairdynError(
            f"The mesh '{obj.name}' has no vertices: a head or collider needs a mesh with faces"
        )
    return MeshData(
        obj.name, vertices, normals, triangles, triangle_faces, matrix_array(evaluated.matrix_world)
    )


def vertex_group_weights(obj, names, vertices_num):
    """{group name: (vertices_num,) float32 weight of each vertex, 0 outside the group} for the
    named groups obj has.

    Blender has no bulk read of group weights, so this walks the vertices once; call it when
    a simulation is set up, never per frame."""
    indices = {group.index: group.name for group in obj.vertex_groups if group.name in names}
    weights = {name: np.zeros(vertices_num, dtype=np.float32) for name in indices.values()}
    for vertex in obj.data.vertices[:vertices_num]:
        for element in vertex.groups:
            name = indices.get(element.group)
            if name is not None:
                weights[name][vertex.index] = element.weight
    return weights


def vertex_group_members(obj, names, vertices_num):
    """{group name: int32 vertex indices with weight > 0.5} for the named groups obj has."""
    return {
        name: np.flatnonzero(weights > 0.5).astype(np.int32)
        for name, weights in vertex_group_weights(obj, names, vertices_num).items()
    }


def selected_faces(obj):
    """(P,) bool: which polygons of a mesh object the artist selected (in Edit Mode, the
    selection as it is now)."""
    if obj.mode == 'EDIT':
        obj.update_from_editmode()
    polygons = obj.data.polygons
    selected = np.zeros(len(polygons), dtype=bool)
    polygons.foreach_get("select", selected)
    return selected


def image_grey(image):
    """An image's grey values (H, W) float32, rows from the bottom as Blender stores them:
    the mean of R, G and B, or the only channel. Empty (0, 0) when the image has no pixels."""
    width, height = image.size
    pixels = np.empty(len(image.pixels), dtype=np.float32)
    if len(pixels) == 0 or width * height == 0:
        return np.zeros((0, 0), dtype=np.float32)
    image.pixels.foreach_get(pixels)
    pixels = pixels.reshape(height, width, image.channels)
    grey = pixels[:, :, :3].mean(axis=2) if image.channels >= 3 else pixels[:, :, 0]
    return np.ascontiguousarray(grey, dtype=np.float32)


def object_matrix(obj, depsgraph):
    """The evaluated object-to-world matrix, (4, 4) float64."""
    return matrix_array(obj.evaluated_get(depsgraph).matrix_world)


# ---------------------------------------------------------------------------------------------
# Writing results


def _link_like(new_obj, like):
    collections = like.users_collection if like is not None else ()
    target = collections[0] if collections else bpy.context.scene.collection
    target.objects.link(new_obj)


def new_curves_data(name, sizes):
    """A Curves ID with the given points per curve, on any supported Blender.

    Newer Blender resizes Curves directly (Curves.add_curves). Older Blender has no such API,
    so the topology is made as a legacy poly curve and converted by Blender's own operator.
    """
    if "add_curves" in bpy.types.Curves.bl_rna.functions:
        curves = bpy.data.hair_curves.new(name)
        curves.add_curves([int(size) for size in sizes])
        return curves
    legacy = bpy.data.curves.new(name, 'CURVE')
    for size in sizes:  # one call per strand: Blender 3.x offers no bulk curve creation
        legacy.splines.new('POLY').points.add(int(size) - 1)
    temp = bpy.data.objects.new(name, legacy)
    bpy.context.scene.collection.objects.link(temp)
    view_layer = bpy.context.view_layer
    previous_active = view_layer.objects.active
    previous_selection = [o for o in view_layer.objects if o.select_get()]
    try:
        for o in previous_selection:
            o.select_set(False)
        temp.select_set(True)
        view_layer.objects.active = temp
        bpy.ops.object.convert(target='CURVES')
        curves = temp.data
        if not isinstance(curves, bpy.types.Curves):
            raise HairdynError("Blender could not create the output hair curves")
        curves.name = name
        if "radius" in curves.attributes:  # legacy points carry radius 1 m; hair must not
            curves.attributes.remove(curves.attributes["radius"])
    finally:
        bpy.data.objects.remove(temp)
        if legacy.users == 0:
            bpy.data.curves.remove(legacy)
        for o in previous_selection:
            o.select_set(True)
        view_layer.objects.active = previous_active
    return curves


def _topology_matches(curves, curve_offsets):
    if len(curves.curves) + 1 != len(curve_offsets) or len(curves.points) != curve_offsets[-1]:
        return False
    return np.array_equal(_curve_offsets(curves), curve_offsets)


def _along_strands(sizes):
    """Per point of curves of these point counts: its place along its strand, 0 at the root
    and 1 at the tip."""
    sizes = np.asarray(sizes, dtype=np.int64)
    starts = np.repeat(np.cumsum(sizes) - sizes, sizes)
    steps = np.repeat(np.maximum(sizes - 1, 1), sizes)
    return (np.arange(int(sizes.sum())) - starts) / steps


def tapered_radius(sizes, root_radius):
    """Per point of curves of these point counts: root_radius at the root, tapering linearly
    to a fifth of it at the tip (a single hair; the groom's own radius is a guide's)."""
    return (root_radius * (1.0 - 0.8 * _along_strands(sizes))).astype(np.float32)


def particle_hair_radius(sizes, settings):
    """Per point of curves of these point counts, the radius Cycles renders particle hair with
    (ParticleSettings `settings`; Cycles' blender/curves.cpp): radius_scale / 2 times the root
    and tip factors, blended along the strand by its shape, the tip closed to 0 when asked."""
    t = _along_strands(sizes)
    half = 0.5 * settings.radius_scale
    root, tip = half * settings.root_radius, half * settings.tip_radius
    shape = settings.shape  # in [-1, 1]
    exponent = 1.0 + shape if shape < 0.0 else 1.0 / max(1.0 - shape, 1e-6)
    radius = (1.0 - t) ** exponent * (root - tip) + tip
    if settings.use_close_tip:
        radius[t >= 1.0] = 0.0
    return radius.astype(np.float32)


def ensure_curves_output(obj, name, curve_offsets, like=None):
    """`obj` if it is a Curves object with this topology, otherwise a new one named `name`.

    The new object sits at the world origin (positions are written in world space), in the
    collection of `like`, with `like`'s materials and strand radius (particle hair: its
    system's material and the radius Cycles renders it with).
    """
    if obj is not None and obj.type == 'CURVES' and _topology_matches(obj.data, curve_offsets):
        return obj
    curves = new_curves_data(name, np.diff(curve_offsets))
    particle_hair = hair_particle_system(like)
    if like is not None and like.type == 'CURVES':
        for material in like.data.materials:
            curves.materials.append(material)
        radius = like.data.attributes.get("radius")
        if radius is not None and radius.domain == 'POINT' and len(radius.data):
            values = np.empty(len(radius.data), dtype=np.float32)
            radius.data.foreach_get("value", values)
            if len(values) != len(curves.points):  # child hairs: thinner, tapering
                values = tapered_radius(np.diff(curve_offsets), 0.5 * float(values.min()))
            curves.attributes.new("radius", 'FLOAT', 'POINT').data.foreach_set("value", values)
    elif particle_hair is not None:
        # Particle hair: its system's material slot and the radius Cycles gives it.
        settings = particle_hair.settings
        slots = like.material_slots
        if 1 <= settings.material <= len(slots) and slots[settings.material - 1].material:
            curves.materials.append(slots[settings.material - 1].material)
        values = particle_hair_radius(np.diff(curve_offsets), settings)
        curves.attributes.new("radius", 'FLOAT', 'POINT').data.foreach_set("value", values)
    new_obj = bpy.data.objects.new(name, curves)
    _link_like(new_obj, like)
    return new_obj


def write_curves(obj, positions_wo):
    """Positions (N, 3) float32 into a Curves object of the same point count."""
    curves = obj.data
    if len(curves.points) != len(positions_wo):
        raise HairdynError(
            f"'{obj.name}' has {len(curves.points)} points, the simulation {len(positions_wo)}"
        )
    set_rows(curves.position_data, "vector", positions_wo)
    _tag_positions_changed(curves)
    curves.update_tag()


_CURVE_TYPES = ('CATMULL_ROM', 'POLY')  # the "curve_type" values 0 and 1 (CurveType)


def _tag_positions_changed(curves):
    """Tell Blender that the positions changed, so that it recomputes what it caches from them
    (the bounds it culls, shadows and frames the object by; the evaluated curves).

    foreach_set writes the array behind Blender's back, and where copies share those caches
    (Blender 5.x) the evaluated object keeps the first frame's bounds. Python has no call for
    "positions changed"; setting the first curve's type to the type it has tags the whole
    geometry changed, the only tag reachable from Python that does. Blender then finds the
    bounds from the evaluated curves, at its own cost (1.3 ms for 34,000 Catmull-Rom points).
    Blender 3.x (no Curves.set_types) copies no caches. Bézier and NURBS curves, which hairdyn
    never makes, are left alone: setting their type could move their handles."""
    if not hasattr(curves, "set_types") or not len(curves.curves):
        return
    attribute = curves.attributes.get("curve_type")
    curve_type = 0 if attribute is None else attribute.data[0].value
    if curve_type < len(_CURVE_TYPES):
        curves.set_types(type=_CURVE_TYPES[curve_type], indices=[0])


def ensure_points_output(obj, name, like=None):
    """`obj` if it is a mesh object, otherwise a new empty mesh object named `name`."""
    if obj is not None and obj.type == 'MESH':
        return obj
    new_obj = bpy.data.objects.new(name, bpy.data.meshes.new(name))
    _link_like(new_obj, like)
    return new_obj


_ATTRIBUTE_TYPES = {1: ("FLOAT", "value"), 3: ("FLOAT_VECTOR", "vector")}


def write_points(obj, positions_wo, attributes=None):
    """Positions as loose vertices of a mesh, plus named point attributes.

    `attributes` maps a name to an (N,) or (N, 3) float32 array; geometry nodes and Cycles
    read them by name (Attribute node).
    """
    mesh = obj.data
    count = len(positions_wo)
    if len(mesh.vertices) != count or len(mesh.edges) or len(mesh.polygons):
        mesh.clear_geometry()
        mesh.vertices.add(count)
    _write_mesh(mesh, positions_wo, attributes)


def ribbon_faces(offsets):
    """(F, 4) int32 quads of ribbons whose vertices lie in pairs, ribbon r's from offsets[r]
    to offsets[r + 1]: one quad between each pair and the next (2k, 2k + 1, 2k + 3, 2k + 2)."""
    offsets = np.asarray(offsets, dtype=np.int64)
    pairs = np.arange(offsets[-1] // 2, dtype=np.int64)
    last = offsets[1:] // 2 - 1  # each ribbon's last pair starts no quad
    starts = 2 * np.setdiff1d(pairs, last)
    return np.stack([starts, starts + 1, starts + 3, starts + 2], axis=1).astype(np.int32)


def write_ribbons(obj, positions_wo, offsets, attributes=None):
    """Ribbons as a mesh of quads (ribbon_faces of the curve offsets, made when the mesh has
    other counts), plus named point attributes as write_points."""
    mesh = obj.data
    faces_num = int(offsets[-1]) // 2 - (len(offsets) - 1)  # a quad less than pairs, per ribbon
    if len(mesh.vertices) != len(positions_wo) or len(mesh.polygons) != faces_num:
        faces = ribbon_faces(offsets).tolist()
        mesh.clear_geometry()
        mesh.from_pydata(np.asarray(positions_wo, dtype=np.float64).tolist(), [], faces)
    _write_mesh(mesh, positions_wo, attributes)


def _write_mesh(mesh, positions_wo, attributes):
    """A mesh's vertex positions (as many as it has) and named point attributes."""
    count = len(positions_wo)
    positions = np.ascontiguousarray(positions_wo, dtype=np.float32)
    attribute = _position_attribute(mesh)
    if attribute is not None:
        # Straight into the positions (Blender 3.5 and later keep them as this attribute):
        # MeshVertex.co there is a proxy that Blender sets one vertex at a time, 600 times
        # slower (65 ms for 170,000 vertices on bpy 5.0).
        set_rows(attribute.data, "vector", positions)
        if count:
            # foreach_set leaves the bounds Blender caches as they were (Blender 5.0); one
            # vertex set through MeshVertex.co tags the positions changed.
            mesh.vertices[0].co = mesh.vertices[0].co
        if not getattr(mesh, "use_auto_texspace", True):  # a file last played by Blender 3.4
            mesh.use_auto_texspace = True
    else:
        mesh.vertices.foreach_set("co", positions.ravel())
        _set_texspace(mesh, positions)
    write_point_attributes(mesh, attributes or {})
    mesh.update()


def _position_attribute(mesh):
    """The mesh's "position" point attribute, or None where vertices hold their positions."""
    attribute = mesh.attributes.get("position")
    if attribute is None or attribute.domain != 'POINT' or attribute.data_type != 'FLOAT_VECTOR':
        return None
    return attribute


def _set_texspace(mesh, positions):
    """The texture space Blender's automatic one would be (BKE_mesh_texspace_calc: the
    positions' bounding box, sizes of 0 made 1 and tiny ones 1e-5), set here.

    Where vertices hold their positions (before Blender 3.5), Blender finds the bounds for the
    automatic texture space in a loop of its own that costs 5 ms for 170,000 points at each
    evaluation, a third of the point object's; the native module's vectorised pass finds them
    in a few hundredths of that. Meshes with a position attribute keep Blender's automatic
    one, which reuses the bounds Blender caches. Either way the point object's texture space
    is the automatic one."""
    if not hasattr(mesh, "use_auto_texspace"):
        return
    if len(positions):
        from . import native

        low, high = native.load().point_bounds(positions)
    else:
        low, high = np.full(3, -1, np.float32), np.full(3, 1, np.float32)
    location = np.float32(0.5) * (low + high)
    size = (high - low) / np.float32(2)
    size[size == 0] = 1
    size[(size > 0) & (size < 1e-5)] = np.float32(1e-5)
    if mesh.use_auto_texspace:
        mesh.use_auto_texspace = False
    mesh.texspace_location = location
    mesh.texspace_size = size


def write_point_attributes(data, attributes):
    """Named (N,) or (N, 3) float32 arrays as point attributes of a Mesh or Curves."""
    for name, values in attributes.items():
        values = np.ascontiguousarray(values, dtype=np.float32)
        width = 1 if values.ndim == 1 else values.shape[1]
        data_type, field = _ATTRIBUTE_TYPES[width]
        attribute = data.attributes.get(name)
        if attribute is None or attribute.data_type != data_type or attribute.domain != 'POINT':
            if attribute is not None:
                data.attributes.remove(attribute)
            attribute = data.attributes.new(name, data_type, 'POINT')
        set_rows(attribute.data, field, values)


def set_rows(collection, field, rows):
    """collection.foreach_set(field, rows) for (N,) or (N, 3) float32 rows, one an item.

    Blender 3.4's foreach_set copies item by item: 0.11 ms for 32,000 float3, six times a
    frame for the strands' outputs. Where the items are the rows themselves, packed in one
    array (an attribute's layer), the rows are copied into that array at once (0.014 ms;
    on Blender 5, whose foreach_set copies at once, 0.009 ms against 0.014 ms). It is the
    array foreach_set writes, found the same way: through the collection's iterator, which
    first makes data Blender shares with a copy (undo, the evaluated object) the object's
    own, as foreach_set does. The field must be the row's floats, and the items' addresses
    show the layout: the first, second and last one row apart, so that an item is the
    field alone. The first and last rows are read back. Any other layout (Blender 3.4's
    vertices: 16 bytes for a 12-byte position) goes through foreach_set."""
    rows = np.ascontiguousarray(rows, dtype=np.float32)
    count = len(rows)
    # The iterator first: Blender's own array, not a shared one.
    first = next(iter(collection), None) if count >= 2 and len(collection) == count else None
    if first is not None:
        start = first.as_pointer()
        width = rows.size // count
        row_bytes = rows.itemsize * width
        last = collection[count - 1]
        prop = first.bl_rna.properties.get(field)
        if (
            prop is not None
            and prop.type == 'FLOAT'
            and prop.array_length == (width if rows.ndim > 1 else 0)
            and collection[1].as_pointer() - start == row_bytes
            and last.as_pointer() - start == (count - 1) * row_bytes
        ):
            target = (ctypes.c_char * rows.nbytes).from_address(start)
            np.frombuffer(target, dtype=np.float32)[:] = rows.ravel()
            if _reads_back(first, field, rows[0]) and _reads_back(last, field, rows[-1]):
                return
    collection.foreach_set(field, rows.ravel())


def _reads_back(item, field, row):
    value = getattr(item, field)
    return list(value) == row.tolist() if row.ndim else value == row
