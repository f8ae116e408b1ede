"""Presets: the papers' settings ship with the add-on; artists save and load their own."""
from pathlib import Path

import bpy
import pytest

from hairdyn import presets


def test_paper_presets_apply(open_fixture):
    open_fixture("head_curves.blend")
    hair = bpy.data.objects["Hair"]
    bpy.context.view_layer.objects.active = hair
    folder = presets.install_bundled()
    assert (folder / "kurihara_1993.py").is_file()
    assert hair.hairdyn.method == 'FOLLOW' and hair.hairdyn.collision.map_kind == 'AUTO'
    bpy.ops.script.execute_preset(filepath=str(folder / "kurihara_1993.py"),
                                  menu_idname="HAIRDYN_MT_presets")
    assert hair.hairdyn.method == 'STRANDS'
    assert hair.hairdyn.strands.integrator == 'EXPLICIT'
    assert hair.hairdyn.collision.map_kind == 'CYLINDER'
    assert (hair.hairdyn.collision.azimuth_num, hair.hairdyn.collision.height_num) == (40, 40)
    hair.hairdyn.lcp.neighbor_num = 5
    bpy.ops.script.execute_preset(filepath=str(folder / "bando_2003.py"),
                                  menu_idname="HAIRDYN_MT_presets")
    assert hair.hairdyn.method == 'LCP'
    assert (hair.hairdyn.lcp.a0, hair.hairdyn.lcp.neighbor_num) == (0.5, 12)


def test_user_preset_round_trip(open_fixture):
    open_fixture("head_curves.blend")
    hair = bpy.data.objects["Hair"]
    bpy.context.view_layer.objects.active = hair
    hair.hairdyn.method = 'STRANDS'
    hair.hairdyn.strands.k_theta = 0.777
    hair.hairdyn.collision.friction = 0.3
    assert bpy.ops.hairdyn.preset_add(name="pytest hairdyn preset") == {'FINISHED'}
    path = Path(bpy.utils.user_resource('SCRIPTS', path="presets/hairdyn")) / \
        "pytest_hairdyn_preset.py"
    try:
        assert path.is_file()
        text = path.read_text()
        assert "settings.strands.k_theta = 0.777" in text
        hair.hairdyn.strands.k_theta = 0.1
        hair.hairdyn.collision.friction = 0.0
        bpy.ops.script.execute_preset(filepath=str(path), menu_idname="HAIRDYN_MT_presets")
        assert hair.hairdyn.strands.k_theta == pytest.approx(0.777)
        assert hair.hairdyn.collision.friction == pytest.approx(0.3)
    finally:
        path.unlink(missing_ok=True)
