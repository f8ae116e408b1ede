"""Owns: the scene's colliders for one hair object: which meshes, which parts, the native
maps, and which collision settings do what.

By Blender's convention the hair collides with its head (the Curves surface or the particle
emitter) and with every mesh carrying Blender's Collision modifier; the artist adds more in
the panel's list (or with --set colliders=A,B). Each collider becomes one native Collider
whose parts are its vertex groups named in `collider_parts` (head, neck, torso...). Rigid
motion only updates the collider's transform; a deforming collider is rebuilt each frame.
"""

import time

import numpy as np

from . import bridge, native, parameters
from .errors import HairdynError

# The collision settings (the generated CollisionParams group) by what they shape: the fields
# that build the maps, the report tolerance, and the response (every other field: the reaction
# constraint, friction, projection). A method shows and reads the kinds it names in
# Method.collision.
MAP_FIELDS = ("map_kind", "axis_mode", "azimuth_num", "height_num")
REPORT_FIELDS = ("penetration_tolerance",)


def collision_fields(kind, params_class):
    """The CollisionParams fields of one kind: "maps", "response" or "report"."""
    names = [field["name"] for field in parameters.shown_fields(params_class)]
    if kind == "maps":
        return [name for name in MAP_FIELDS if name in names]
    if kind == "report":
        return [name for name in REPORT_FIELDS if name in names]
    return [name for name in names if name not in MAP_FIELDS + REPORT_FIELDS]


def collider_objects(hair_obj, head, scene):
    """The meshes hair_obj collides with, each once, in a stable order."""
    settings = hair_obj.hairdyn
    found = []
    if settings.use_default_colliders:
        if head is not None:
            found.append(head)
        found += sorted(
            (
                o
                for o in scene.objects
                if o.type == 'MESH' and any(m.type == 'COLLISION' for m in o.modifiers)
            ),
            key=lambda o: o.name,
        )
    found += [item.object for item in settings.colliders if item.object is not None]
    unique = []
    for obj in found:
        # Not the hair object itself, unless it is the head: legacy particle hair grows from
        # its emitter, the mesh it lies on.
        if obj not in unique and (obj != hair_obj or obj == head):
            unique.append(obj)
    return unique


def part_names(settings):
    return [name.strip() for name in settings.collider_parts.split(",") if name.strip()]


def vertex_group_parts(obj, mesh_vertices_num, names):
    """int32 vertex-index arrays, one per named vertex group the object has, or None."""
    members = bridge.vertex_group_members(obj, names, mesh_vertices_num)
    parts = [members[name] for name in names if len(members.get(name, ()))]
    return parts or None


# Modifiers that never change the mesh they sit on: a particle system (the emitter of
# particle hair carries one) and Blender's Collision modifier.
_SHAPE_KEEPING_MODIFIERS = {'PARTICLE_SYSTEM', 'COLLISION'}


def may_deform(obj):
    """Whether obj's shape (not just its transform) can change over time: it has modifiers
    that may change it, or shape keys. Blender's is_deform_modified() is no help here: it
    answers for the current frame's values (a Displace of strength 0 "does not deform")."""
    return (
        any(m.type not in _SHAPE_KEEPING_MODIFIERS for m in obj.modifiers)
        or obj.data.shape_keys is not None
    )


class Colliders:
    """Native colliders for a hair object, kept in step with the scene frame by frame."""

    def __init__(self, hair_obj, head, scene, depsgraph):
        self.native = native.load()
        settings = hair_obj.hairdyn
        self.params = parameters.native_params(
            settings.collision, self.native.CollisionParams, scene
        )
        self.objects = collider_objects(hair_obj, head, scene)
        self.names = [obj.name for obj in self.objects]
        self.colliders = []
        self.deforming = []
        self.vertices = []  # object-space vertices each collider was last built from
        start = time.perf_counter()
        for obj in self.objects:
            mesh = bridge.read_mesh(obj, depsgraph)
            parts = vertex_group_parts(obj, len(mesh.vertices), part_names(settings))
            try:
                collider = self.native.Collider(mesh.vertices, mesh.triangles, parts, self.params)
            except ValueError as error:
                raise HairdynError(f"Collider '{obj.name}': {error}") from None
            collider.set_transform(mesh.matrix_world)
            self.colliders.append(collider)
            self.deforming.append(may_deform(obj))
            self.vertices.append(mesh.vertices)
        self.build_ms = (time.perf_counter() - start) * 1000.0
        self.set = self.native.ColliderSet(self.colliders)

    def update(self, depsgraph):
        """Follow the colliders to the current frame: a new transform for each, and a rebuild
        for those whose evaluated shape changed. Returns the ms spent rebuilding."""
        rebuild_ms = 0.0
        for index, (obj, collider) in enumerate(zip(self.objects, self.colliders)):
            try:
                rebuild_ms += self._update(index, obj, collider, depsgraph)
            except ValueError as error:  # the native module's sentence: a transform or shape
                raise HairdynError(
                    f"Collider '{obj.name}' at frame {depsgraph.scene.frame_current}: {error}"
                ) from None
        return rebuild_ms

    def _update(self, index, obj, collider, depsgraph):
        if not self.deforming[index]:
            collider.set_transform(bridge.object_matrix(obj, depsgraph))
            return 0.0
        mesh = bridge.read_mesh(obj, depsgraph)
        if len(mesh.vertices) != len(self.vertices[index]):
            raise HairdynError(
                f"Collider '{obj.name}' changed its vertex count during the simulation; "
                "hairdyn follows deforming colliders of fixed topology"
            )
        rebuild_ms = 0.0
        if not np.array_equal(mesh.vertices, self.vertices[index]):
            collider.rebuild(mesh.vertices)
            rebuild_ms = collider.build_ms
            self.vertices[index] = mesh.vertices
        collider.set_transform(mesh.matrix_world)
        return rebuild_ms

    def penetration(self, positions_wo, curve_offsets=None):
        """Exact penetration of points against the real triangles (not the maps); with the
        strands' curve_offsets their roots are counted apart (roots_inside: a groom grown
        inside the body, which no solver can fix)."""
        return self.set.penetration_stats(
            positions_wo, tolerance=self.tolerance_wo(), curve_offsets=curve_offsets
        )

    def tolerance_wo(self):
        return self.params.penetration_tolerance * self.set.size_wo
