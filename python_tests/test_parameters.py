"""Parameters are declared once, in the native structs: the add-on's PropertyGroups are
generated from `_native.<X>Params.fields()` and must match them field by field; the scene
provides gravity; a cache manifest's parameters round-trip."""

import json
import math

import bpy
import pytest

from hairdyn import bake, native, parameters, properties

STRUCTS = sorted(parameters.native_structs(native.load()))


def settings_group(settings, struct_name):
    """The settings group generated from a native struct."""
    for prop in settings.bl_rna.properties:
        if (
            prop.type == 'POINTER'
            and prop.fixed_type.identifier == parameters.CLASS_PREFIX + struct_name
        ):
            return getattr(settings, prop.identifier)
    raise AssertionError(f"no settings group for {struct_name}")


def test_every_native_struct_has_a_group(empty_scene):
    assert {"StrandParams", "LcpParams", "CollisionParams"} <= set(STRUCTS)
    settings = bpy.data.objects.new("Hair", bpy.data.hair_curves.new("Hair")).hairdyn
    attributes = {settings_group(settings, name).path_from_id() for name in STRUCTS}
    assert {"hairdyn.strands", "hairdyn.lcp", "hairdyn.collision"} <= attributes


@pytest.mark.parametrize("struct_name", STRUCTS)
def test_generated_group_matches_the_native_struct(struct_name, empty_scene):
    """Field by field: kind, default (the native one, or the add-on's where a method declares
    its own: Method.defaults), hard and soft range (in the shown unit: × display_scale), enum
    items, label, and a tooltip naming the paper's symbol, the unit and the description.
    Fields the scene provides (gravity) have no property."""
    hair = bpy.data.objects.new("Hair", bpy.data.hair_curves.new("Hair"))
    group = settings_group(hair.hairdyn, struct_name)
    own_defaults = properties.group_defaults(group.path_from_id().rsplit(".", 1)[-1])
    rna = {
        p.identifier: p for p in group.bl_rna.properties if p.identifier not in ("rna_type", "name")
    }
    fields = getattr(native.load(), struct_name).fields()
    assert list(rna) == [f["name"] for f in fields if f["name"] not in parameters.SCENE_FIELDS]
    for field in fields:
        if field["name"] in parameters.SCENE_FIELDS:
            continue
        prop, where, scale = (
            rna[field["name"]],
            f"{struct_name}.{field['name']}",
            field["display_scale"],
        )
        default = own_defaults.get(field["name"], field["default"])
        assert field["description"] in prop.description, where
        for part in (field["symbol"], field["display_unit"] or field["unit"]):
            assert part in prop.description, where
        if field["display_scale"] != 1.0 and field["unit"]:
            assert field["unit"] in prop.description, where  # the SI unit too
        assert prop.name.startswith(field["label"] or field["name"].replace("_", " ").title())
        if field["symbol"]:  # in the tooltip, not the label (issue 17: labels fit)
            assert prop.description.startswith((field["symbol"] + ",", field["symbol"] + ":")), (
                where
            )
            assert f"({field['symbol']})" not in prop.name, where
        if field["choices"]:
            choices = field["choices"].split(",")
            assert prop.type == 'ENUM', where
            assert [i.identifier for i in prop.enum_items] == [c.upper() for c in choices], where
            assert prop.default == choices[default].upper(), where
            continue
        if isinstance(field["default"], bool):
            assert prop.type == 'BOOLEAN' and prop.default == default, where
            continue
        if isinstance(field["default"], (tuple, list)):
            assert list(prop.default_array) == pytest.approx(
                [v * scale for v in default], rel=1e-6
            ), where
        else:
            assert prop.type == ('INT' if isinstance(field["default"], int) else 'FLOAT'), where
            assert prop.default == pytest.approx(default * scale, rel=1e-6), where
        for key, rna_key in (
            ("min", "hard_min"),
            ("max", "hard_max"),
            ("soft_min", "soft_min"),
            ("soft_max", "soft_max"),
        ):
            expected = (
                field[key] if math.isfinite(field[key]) else field[key.replace("soft_", "")]
            )  # no soft range: the hard one
            if math.isfinite(expected):
                assert getattr(prop, rna_key) == pytest.approx(expected * scale, rel=1e-6), (
                    f"{where} {key}"
                )


@pytest.mark.parametrize("struct_name", STRUCTS)
def test_native_params_from_settings(struct_name, open_fixture):
    """The way back: a shown value ÷ display_scale, enums by position, range errors from the
    native struct."""
    open_fixture("head_curves.blend")
    group = settings_group(bpy.data.objects["Hair"].hairdyn, struct_name)
    params_class = getattr(native.load(), struct_name)
    fields = parameters.shown_fields(params_class)
    numeric = [f for f in fields if not f["choices"] and isinstance(f["default"], float)]
    for field in numeric:
        setattr(group, field["name"], field["max"] * field["display_scale"])
    params = parameters.native_params(group, params_class)
    for field in numeric:
        assert getattr(params, field["name"]) == pytest.approx(field["max"], rel=1e-6)
    for field in (f for f in fields if f["choices"]):
        last = field["choices"].split(",")[-1]
        setattr(group, field["name"], last.upper())
        params = parameters.native_params(group, params_class)
        assert getattr(params, field["name"]) == len(field["choices"].split(",")) - 1


@pytest.mark.parametrize(
    "struct_name",
    [s for s in STRUCTS if any(f["name"] == "gravity" for f in getattr(native.load(), s).fields())],
)
def test_gravity_comes_from_the_scene(struct_name, empty_scene):
    params_class = getattr(native.load(), struct_name)
    hair = bpy.data.objects.new("Hair", bpy.data.hair_curves.new("Hair"))
    group = settings_group(hair.hairdyn, struct_name)
    empty_scene.gravity = (0.0, 0.0, -3.5)
    gravity = parameters.native_params(group, params_class, empty_scene).gravity
    expected = (0.0, 0.0, -3.5) if isinstance(gravity, tuple) else 3.5
    assert gravity == pytest.approx(expected)
    empty_scene.use_gravity = False
    gravity = parameters.native_params(group, params_class, empty_scene).gravity
    assert gravity == pytest.approx((0.0, 0.0, 0.0) if isinstance(gravity, tuple) else 0.0)


def test_manifest_parameters_round_trip(saved_fixture):
    """settings_dict holds every setting of every group, survives JSON, and a bake's manifest
    holds it (with the scene's gravity) so a resume can compare."""
    hair = saved_fixture("head_shake.blend", 3)
    settings = hair.hairdyn
    settings.lcp.h2 = 0.02
    settings.lcp_init.length_source = 'WEIGHTS'
    values = properties.settings_dict(settings)
    assert json.loads(json.dumps(values)) == values
    for struct_name in STRUCTS:
        group = settings_group(settings, struct_name)
        attribute = group.path_from_id().split(".")[-1]
        assert set(values[attribute]) == {
            f["name"] for f in parameters.shown_fields(getattr(native.load(), struct_name))
        }
    assert values["lcp"]["h2"] == pytest.approx(0.02)
    assert values["lcp_init"]["length_source"] == 'WEIGHTS'
    runner = bake.start_bake(bpy.context, hair)
    while not runner.done:
        runner.advance()
    bake.finish_bake(runner)
    from hairdyn.cache import Cache

    manifest = Cache.open(bake.cache_directory(hair)).manifest
    assert manifest["parameters"] == bake.parameters(bpy.context, settings)
    assert manifest["parameters"]["scene_gravity"] == pytest.approx(list(bpy.context.scene.gravity))
