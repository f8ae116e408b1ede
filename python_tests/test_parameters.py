"""The add-on's PropertyGroups mirror the native parameter structs field for field."""
import math

import bpy
import pytest

from hairdyn import native, properties

MIRRORS = [
    ("StrandParams", properties.HairdynStrandSettings),
    ("LcpParams", properties.HairdynLcpSettings),
    ("CollisionParams", properties.HairdynCollisionSettings),
]


def rna_properties(group_class):
    return {p.identifier: p for p in group_class.bl_rna.properties
            if p.identifier not in ("rna_type", "name")}


@pytest.mark.parametrize("native_name, group_class", MIRRORS)
def test_property_group_mirrors_native_struct(native_name, group_class):
    fields = getattr(native.load(), native_name).fields()
    rna = rna_properties(group_class)
    assert [f["name"] for f in fields] == list(rna), "same fields, same order"
    for field in fields:
        prop = rna[field["name"]]
        where = f"{group_class.__name__}.{field['name']}"
        scale = properties.DISPLAY_SCALES.get((native_name, field["name"]), 1.0)
        field = dict(field)
        if scale != 1.0:  # shown in a scaled unit: compare in it, and the tooltip names it
            field.update(default=field["default"] * scale, min=field["min"] * scale,
                         max=field["max"] * scale, unit="")
        if field["choices"]:
            assert prop.type == 'ENUM', where
            assert [i.identifier for i in prop.enum_items] == \
                [c.upper() for c in field["choices"].split(",")], where
            assert prop.default == field["choices"].split(",")[field["default"]].upper(), where
            continue
        if isinstance(field["default"], bool):
            assert prop.type == 'BOOLEAN' and prop.default == field["default"], where
            continue
        default = list(prop.default_array) if getattr(prop, "is_array", False) else prop.default
        expected = field["default"]
        if isinstance(expected, (tuple, list)):
            assert default == pytest.approx(list(expected), rel=1e-6), where
        else:
            assert default == pytest.approx(expected, rel=1e-6, abs=1e-12), where
        assert prop.hard_min == pytest.approx(field["min"] if math.isfinite(field["min"]) else prop.hard_min, rel=1e-6), where
        assert prop.hard_max == pytest.approx(field["max"] if math.isfinite(field["max"]) else prop.hard_max, rel=1e-6), where
        # The tooltip names the paper's symbol and the unit.
        if field["symbol"]:
            assert field["symbol"] in prop.description, where
        if field["unit"]:
            assert field["unit"] in prop.description, where


@pytest.mark.parametrize("native_name, group_class", MIRRORS)
def test_native_params_from_settings(native_name, group_class, open_fixture):
    open_fixture("head_curves.blend")
    settings = bpy.data.objects["Hair"].hairdyn
    group = next(getattr(settings, p.identifier) for p in settings.bl_rna.properties
                 if p.type == 'POINTER' and p.fixed_type == group_class.bl_rna)
    fields = getattr(native.load(), native_name).fields()
    numeric = next(f for f in fields if not f["choices"] and isinstance(f["default"], float))
    setattr(group, numeric["name"], numeric["max"] if math.isfinite(numeric["max"]) else 123.0)
    params = properties.native_params(group, getattr(native.load(), native_name))
    scale = properties.DISPLAY_SCALES.get((native_name, numeric["name"]), 1.0)
    assert getattr(params, numeric["name"]) * scale == pytest.approx(getattr(group, numeric["name"]))
    enum = next((f for f in fields if f["choices"]), None)
    if enum is not None:
        last = enum["choices"].split(",")[-1]
        setattr(group, enum["name"], last.upper())
        params = properties.native_params(group, getattr(native.load(), native_name))
        assert getattr(params, enum["name"]) == len(enum["choices"].split(",")) - 1
