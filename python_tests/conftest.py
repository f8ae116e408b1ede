"""pytest inside Blender: the `blender` binary (run_in_blender.py) and the `bpy` module.

Every test that needs a scene opens a fixture from blend_fixtures/ fresh.
"""

import os
import shutil
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
FIXTURES = ROOT / "blend_fixtures"
ARTIFACTS = Path(os.environ.get("HAIRDYN_ARTIFACTS", ROOT / "out" / "test_artifacts"))
sys.path.insert(0, str(ROOT / "addon"))

import bpy  # noqa: E402

import hairdyn  # noqa: E402


def host_name():
    """'blender' for the blender binary, 'bpy' for the bpy module."""
    return "blender" if bpy.app.binary_path else "bpy"


def pytest_report_header(config):
    return f"hairdyn host: {host_name()} (Blender {bpy.app.version_string})"


def shown(struct_name, field_name, si_value):
    """What the panel's property holds for an SI value of a native field: value × the field's
    display_scale (native ParamInfo.shown_as), so tests hold whatever the panel's unit is."""
    from hairdyn import native

    fields = getattr(native.load(), struct_name).fields()
    return si_value * next(f for f in fields if f["name"] == field_name)["display_scale"]


def scale_radius_attribute(hair, scale, broken=None):
    """The Curves object's point attribute "radius" times `scale`, or removed when scale is
    None; with broken = (row, value), that point's radius made `value` first (a broken
    attribute)."""
    import numpy as np

    radius = hair.data.attributes["radius"]
    if scale is None:
        hair.data.attributes.remove(radius)
        return
    values = np.empty(len(radius.data), dtype=np.float32)
    radius.data.foreach_get("value", values)
    if broken is not None:
        values[broken[0]] = broken[1]
    radius.data.foreach_set("value", values * np.float32(scale))


@pytest.fixture(scope="session", autouse=True)
def addon():
    if not hasattr(bpy.types.Object, "hairdyn"):
        hairdyn.register()
    yield hairdyn


@pytest.fixture
def open_fixture():
    """open_fixture("head_curves.blend") loads a fixture as the current file."""

    def load(name):
        path = FIXTURES / name
        assert path.is_file(), f"missing fixture {path}: run blend_fixtures/make_fixtures.py"
        bpy.ops.wm.open_mainfile(filepath=str(path), load_ui=False)
        return bpy.context.scene

    return load


@pytest.fixture
def saved_fixture(tmp_path):
    """saved_fixture("head_shake.blend") opens a copy saved in tmp_path (so '//' cache folders
    land there) and returns its "Hair" object, active, its frame range ending at frame_end."""

    def load(name, frame_end):
        path = tmp_path / name
        shutil.copy(FIXTURES / name, path)
        bpy.ops.wm.open_mainfile(filepath=str(path), load_ui=False)
        hair = bpy.data.objects["Hair"]
        hair.hairdyn.frame_end = frame_end
        bpy.context.view_layer.objects.active = hair
        return hair

    return load


@pytest.fixture
def empty_scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    return bpy.context.scene


@pytest.fixture
def artifacts():
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    return ARTIFACTS
