"""Owns: Object.hairdyn, the settings an artist edits, and their registration.

`HairdynSettings` holds the add-on's own options (method, head, colliders, frame range,
outputs, cache). At registration one PointerProperty is added per settings group: a group
generated from each native `<X>Params` struct (parameters.py; its attribute is the name a
method adapter gives it in `Method.params`, else the struct's name in snake case; the native
defaults but where a method's `defaults` differs) and each method's add-on-only options
(`Method.options`). The Method enum comes from the registry.
"""

import re

import bpy
from bpy.props import (
    BoolProperty,
    CollectionProperty,
    EnumProperty,
    IntProperty,
    PointerProperty,
    StringProperty,
)

from . import methods, native, outputs, parameters
from .methods.base import object_poll

# Groups not tied to one method: the colliders' maps and response, the wind (core/wind.hh).
SHARED_PARAMS = {"collision": "CollisionParams", "wind": "WindParams"}
# A path that may start with // (relative to the .blend): Blender 4.5 and later warn on such a
# value unless the property says so; 3.4 has no such option.
RELATIVE_PATH = (
    {'PATH_SUPPORTS_BLEND_RELATIVE'}
    if "is_path_supports_blend_relative" in bpy.types.Property.bl_rna.properties
    else set()
)
_registered = []  # the classes register() registered, in order
_groups = {}  # settings attribute -> PropertyGroup class, as registered


class HairdynColliderItem(bpy.types.PropertyGroup):
    object: PointerProperty(
        name="Collider",
        type=bpy.types.Object,
        poll=object_poll('MESH'),
        description="A mesh the hair collides with",
    )


class HairdynSettings(bpy.types.PropertyGroup):
    enabled: BoolProperty(
        name="hairdyn",
        default=False,
        description="Simulate this hair with hairdyn: play back its bake, or simulate it live, "
        "whenever the frame changes",
    )
    head: PointerProperty(
        name="Head",
        type=bpy.types.Object,
        poll=object_poll('MESH'),
        description="Mesh the hair roots are attached to. Empty: the Curves object's surface, "
        "or the mesh that emits the particle hair",
    )
    use_billboards: BoolProperty(
        name="Billboards",
        default=True,
        description="Show LCP particles as hair-textured cards along the hair direction, "
        "faded by 1/sin θ (Bando 2003 §4), in the viewport and in Cycles",
    )
    output_children: PointerProperty(
        name="Output Children",
        type=bpy.types.Object,
        description="Curves object that receives the child hairs every frame (created when empty)",
    )
    use_collision: BoolProperty(
        name="Collision",
        default=True,
        description="Collide the hair with the head and the other colliders (cylindrical and "
        "spherical maps, Kurihara 1993 §3)",
    )
    use_default_colliders: BoolProperty(
        name="Default Colliders",
        default=True,
        description="Collide with the head, and with every mesh that has Blender's Collision "
        "modifier",
    )
    colliders: CollectionProperty(
        type=HairdynColliderItem, name="Colliders", description="More meshes the hair collides with"
    )
    collider_index: IntProperty(name="Active Collider", default=0, min=0)
    collider_parts: StringProperty(
        name="Parts",
        default="head,neck,torso,arms,arm.L,arm.R",
        description="Vertex groups that get a map of their own (comma separated): head, neck, "
        "torso... A collider with none of them is one part",
    )
    frame_start: IntProperty(
        name="Start",
        default=1,
        min=-1048574,
        max=1048574,
        description="First frame of the simulation: the groom's rest shape is read here",
    )
    frame_end: IntProperty(
        name="End",
        default=250,
        min=-1048574,
        max=1048574,
        description="Last frame of the simulation",
    )
    output_curves: PointerProperty(
        name="Output Curves",
        type=bpy.types.Object,
        description="Curves object that receives the simulated strands every frame "
        "(created when empty)",
    )
    hide_source_in_renders: BoolProperty(
        name="Hide Source",
        default=True,
        update=lambda settings, _context: outputs.show_source_as_set(settings.id_data),
        description="Leave this object's own groom out of renders once the output curves show "
        "the simulated hair (they take its material). Particle hair: its particle systems, "
        "the emitter still renders",
    )
    output_points: PointerProperty(
        name="Output Points",
        type=bpy.types.Object,
        description="Mesh of loose vertices that receives the simulated points and their "
        "attributes every frame (created when empty)",
    )
    output_strips: PointerProperty(
        name="Output Strips",
        type=bpy.types.Object,
        description="Mesh that receives the level of detail's strips as ribbons every frame "
        "(created when empty; shown while Strips as Ribbons is on)",
    )
    cache_directory: StringProperty(
        name="Cache",
        subtype='DIR_PATH',
        options=RELATIVE_PATH,
        default="//hairdyn_cache/",
        description="Folder the bake writes to; // is relative to the .blend file. Each hair "
        "object bakes into a subfolder named after it when it is first baked",
    )
    use_cache: BoolProperty(
        name="Play Back Bake",
        default=True,
        description="Load the baked frame into the output objects whenever the frame changes",
    )
    use_live: BoolProperty(
        name="Live Playback",
        default=True,
        description="Where no frame is baked, simulate while the animation plays: restart at "
        "the start frame, step when the frame advances by one (like cloth)",
    )
    uid: StringProperty(
        name="Identity",
        default="",
        options={'HIDDEN'},
        description="Stable identity of this hair object for live playback (survives renames)",
    )
    bake_folder: StringProperty(
        name="Bake Folder",
        default="",
        options={'HIDDEN'},
        description="Subfolder of the cache folder this object was baked into (its name when "
        "first baked), so a renamed object still finds its bake",
    )


def _method_property():
    items = methods.enum_items()
    return EnumProperty(
        name="Method", items=items, default=items[0][0], description="How the hair moves"
    )


def _group_attribute(struct_name):
    for attribute, name in SHARED_PARAMS.items():
        if name == struct_name:
            return attribute
    for method in methods.all_methods():
        for attribute, name in method.params.items():
            if name == struct_name:
                return attribute
    return re.sub(r"(?<!^)(?=[A-Z])", "_", struct_name[: -len("Params")]).lower()


def group_defaults(attribute):
    """{field: default} where the add-on's default for a generated group differs from the
    native struct's (the methods' `defaults`)."""
    found = {}
    for method in methods.all_methods():
        found.update(method.defaults.get(attribute, {}))
    return found


def settings_groups():
    """{settings attribute: PropertyGroup class} of every group the settings hold: generated
    from the native structs (none when the native module does not load: the panel says why)
    and the methods' add-on-only options."""
    groups = {}
    ok, _ = native.status()
    if ok:
        for struct_name, params_class in parameters.native_structs(native.load()).items():
            attribute = _group_attribute(struct_name)
            groups[attribute] = parameters.property_group(params_class, group_defaults(attribute))
    for method in methods.all_methods():
        groups.update(method.options)
    return groups


def _refresh_methods():
    if _registered:
        HairdynSettings.method = _method_property()


def register():
    groups = settings_groups()
    annotations = HairdynSettings.__annotations__
    for attribute in ("method", *_groups):
        annotations.pop(attribute, None)
    _groups.clear()
    _groups.update(groups)
    annotations["method"] = _method_property()
    for attribute, group in groups.items():
        annotations[attribute] = PointerProperty(type=group)
    for cls in (*dict.fromkeys(groups.values()), HairdynColliderItem, HairdynSettings):
        bpy.utils.register_class(cls)
        _registered.append(cls)
    bpy.types.Object.hairdyn = PointerProperty(type=HairdynSettings)
    methods.on_change(_refresh_methods)


def unregister():
    del bpy.types.Object.hairdyn
    while _registered:
        bpy.utils.unregister_class(_registered.pop())


def preset_paths():
    """Every solver setting a preset stores, as Python paths under `settings`: the top-level
    choices and every plain value of every settings group."""
    paths = [
        "settings.method",
        "settings.use_collision",
        "settings.use_default_colliders",
        "settings.collider_parts",
    ]
    for attribute, group in _groups.items():
        paths += [
            f"settings.{attribute}.{prop.identifier}"
            for prop in group.bl_rna.properties
            if prop.identifier not in ("rna_type", "name") and prop.type != 'POINTER'
        ]
    return paths


_NOT_PARAMETERS = frozenset(
    {
        "rna_type",
        "name",
        "enabled",
        "head",
        "collider_index",
        "output_children",
        "use_billboards",
        "output_curves",
        "output_points",
        "output_strips",
        "hide_source_in_renders",
        "cache_directory",
        "use_cache",
        "use_live",
        "uid",
        "bake_folder",
    }
)


def settings_dict(settings, skip=_NOT_PARAMETERS):
    """The solver parameters of a settings group as plain values (for a cache manifest):
    every property but object pointers and the cache's own settings (top level only: a
    parameter group's own `enabled` is a parameter); images by name."""
    result = {}
    for prop in settings.bl_rna.properties:
        if prop.identifier in skip:
            continue
        value = getattr(settings, prop.identifier)
        if prop.type == 'POINTER':
            if isinstance(value, bpy.types.PropertyGroup):
                result[prop.identifier] = settings_dict(value, skip={"rna_type", "name"})
            elif prop.fixed_type.identifier == 'Image':  # the length map: by name
                result[prop.identifier] = value.name if value is not None else None
        elif prop.type == 'COLLECTION':
            result[prop.identifier] = [item.object.name for item in value if item.object]
        elif hasattr(value, "__len__") and not isinstance(value, str):
            result[prop.identifier] = list(value)
        else:
            result[prop.identifier] = value
    return result
