"""Owns: the PropertyGroups generated from the native parameter structs, and the way back.

Every native `<X>Params` struct describes its fields once (native/core/params.hh: name,
symbol, unit, hard and soft range, default, description, enum choices, display scale and unit,
label). `property_group()` turns `_native.<X>Params.fields()` into a PropertyGroup class at
registration, and `native_params()` turns such a group back into the native struct, so a
parameter is declared once and the panel and the solver cannot drift apart. The panel shows
value × display_scale in display_unit. Fields the scene provides (SCENE_FIELDS: gravity, from
Blender's scene gravity) get no property; `scene_values()` fills them.
"""

import math

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, FloatVectorProperty, IntProperty

SCENE_FIELDS = frozenset({"gravity"})
CLASS_PREFIX = "Hairdyn"  # the group generated from StrandParams is HairdynStrandParams
_SUBTYPES = {"m": 'DISTANCE', "rad": 'ANGLE'}  # Blender shows these in the scene's units


def native_structs(module):
    """{struct name: class} of every parameter struct the native module exposes."""
    found = {}
    for name in sorted(dir(module)):
        cls = getattr(module, name)
        if name.endswith("Params") and callable(getattr(cls, "fields", None)):
            found[name] = cls
    return found


def struct_name(group):
    """The native struct a generated PropertyGroup (class or instance) mirrors."""
    return group.bl_rna.identifier[len(CLASS_PREFIX) :]


def shown_fields(params_class):
    """The fields that get a property, in declaration order."""
    return [field for field in params_class.fields() if field["name"] not in SCENE_FIELDS]


def label(field):
    """The panel label: short enough for the default properties editor (the paper's symbol
    is in the tooltip)."""
    return field["label"] or field["name"].replace("_", " ").title()


def tooltip(field):
    """The description with the paper's symbol and the unit shown (and its SI meaning)."""
    unit = field["display_unit"] or field["unit"]
    if field["display_scale"] != 1.0 and field["unit"]:
        unit += f" (= {1.0 / field['display_scale']:g} {field['unit']})"
    head = ", ".join(part for part in (field["symbol"], unit) if part)
    return f"{head}: {field['description']}" if head else field["description"]


def shown_unit(group, name, module):
    """The unit a generated group's property `name` holds its value in (the panel's: mm for a
    thickness the solver takes in m), or "" for any other property or a unitless one."""
    params_class = native_structs(module).get(struct_name(group))
    for field in shown_fields(params_class) if params_class is not None else ():
        if field["name"] == name:
            return field["display_unit"] if field["display_scale"] != 1.0 else field["unit"]
    return ""


def _finite(value, scale=1.0):
    return value * scale if math.isfinite(value) else None


def _precision(shown_default):
    if shown_default == 0.0:
        return 4
    return min(6, max(3, 3 - math.floor(math.log10(abs(shown_default)))))


def _property(field, default=None):
    """The bpy.props definition of one field (with the add-on's own default when given, in
    the native unit; the field's kind still comes from the native default)."""
    scale, native_default = field["display_scale"], field["default"]
    default = native_default if default is None else type(native_default)(default)
    common = {"name": label(field), "description": tooltip(field)}
    if field["choices"]:
        choices = field["choices"].split(",")
        items = [(c.upper(), c.replace("_", " ").title(), "") for c in choices]
        return EnumProperty(items=items, default=choices[default].upper(), **common)
    if isinstance(native_default, bool):
        return BoolProperty(default=default, **common)
    ranges = {
        key: value
        for key, value in (
            ("min", _finite(field["min"], scale)),
            ("max", _finite(field["max"], scale)),
            ("soft_min", _finite(field["soft_min"], scale)),
            ("soft_max", _finite(field["soft_max"], scale)),
        )
        if value is not None
    }
    if isinstance(native_default, int):
        return IntProperty(default=default, **{k: int(v) for k, v in ranges.items()}, **common)
    if isinstance(native_default, (tuple, list)):
        shown = tuple(v * scale for v in default)
        return FloatVectorProperty(
            default=shown,
            size=len(shown),
            subtype='XYZ',
            precision=_precision(max(map(abs, shown))),
            **ranges,
            **common,
        )
    subtype = _SUBTYPES.get(field["unit"], 'NONE') if scale == 1.0 else 'NONE'
    return FloatProperty(
        default=default * scale,
        precision=_precision(default * scale),
        subtype=subtype,
        **ranges,
        **common,
    )


def property_group(params_class, defaults=None):
    """A new PropertyGroup class (not registered) with one property per shown field; `defaults`
    {field: value in the native unit} where the add-on's default differs (Method.defaults)."""
    name = CLASS_PREFIX + params_class.__name__
    defaults = defaults or {}
    unknown = set(defaults) - {field["name"] for field in shown_fields(params_class)}
    if unknown:
        raise ValueError(f"{params_class.__name__} has no field {', '.join(sorted(unknown))}")
    annotations = {
        field["name"]: _property(field, defaults.get(field["name"]))
        for field in shown_fields(params_class)
    }
    return type(
        name,
        (bpy.types.PropertyGroup,),
        {
            "__annotations__": annotations,
            "__doc__": f"Generated from the native {params_class.__name__}.fields()",
        },
    )


def scene_values(params_class, scene):
    """The fields the scene provides, as params_class takes them: gravity from Blender's scene
    gravity (zero when the scene's gravity is off), a vector, or its size along −Z for a
    struct whose gravity is a float."""
    gravity = tuple(scene.gravity) if scene.use_gravity else (0.0, 0.0, 0.0)
    values = {}
    for field in params_class.fields():
        if field["name"] == "gravity":
            values["gravity"] = (
                gravity if isinstance(field["default"], (tuple, list)) else -gravity[2]
            )
    return values


def native_params(group, params_class, scene=None):
    """The native struct from its generated PropertyGroup: enums by their position in the
    native `choices`, shown values back to SI (÷ display_scale), the scene's fields from
    `scene` (left at the native default when None)."""
    values = scene_values(params_class, scene) if scene is not None else {}
    for field in shown_fields(params_class):
        value = getattr(group, field["name"])
        scale = field["display_scale"]
        if field["choices"]:
            value = field["choices"].split(",").index(value.lower())
        elif not isinstance(value, (bool, int, float)):
            value = tuple(v / scale for v in value) if scale != 1.0 else tuple(value)
        elif isinstance(value, float) and scale != 1.0:
            # Blender keeps the shown value inside the shown range; ÷ scale may round just
            # outside the SI one (90° → 1.5707963705 rad > π/2 as stored).
            value = min(max(value / scale, field["min"]), field["max"])
        values[field["name"]] = value
    return params_class(**values)
