"""Presets: the papers' settings ship with the add-on; artists save and load their own."""
import hashlib
import json
from pathlib import Path

import bpy
import pytest

from hairdyn import presets, simulation


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
    assert hair.hairdyn.strands.model == 'KURIHARA1993' and hair.hairdyn.strands.form_drag == 0.0
    assert hair.hairdyn.collision.map_kind == 'CYLINDER'
    assert (hair.hairdyn.collision.azimuth_num, hair.hairdyn.collision.height_num) == (40, 40)
    hair.hairdyn.lcp.neighbor_num = 5
    bpy.ops.script.execute_preset(filepath=str(folder / "bando_2003.py"),
                                  menu_idname="HAIRDYN_MT_presets")
    assert hair.hairdyn.method == 'LCP'
    assert (hair.hairdyn.lcp.a0, hair.hairdyn.lcp.neighbor_num) == (0.5, 12)
    hair.hairdyn.volume.smoothing = 0.9
    bpy.ops.script.execute_preset(filepath=str(folder / "petrovic_2006.py"),
                                  menu_idname="HAIRDYN_MT_presets")
    assert hair.hairdyn.method == 'STRANDS'
    options = hair.hairdyn.volume_options
    assert options.use_smoothing and options.use_shell_normals and options.target is None
    assert hair.hairdyn.volume.smoothing == pytest.approx(0.2)
    # It runs on the shipped example as it stands: smoothing each substep, shell normals out.
    hair.hairdyn.strands.children_per_guide = 0
    report = simulation.run(bpy.context, hair, 1, 3)
    assert report["volume_ms"] > 0.0 and report["density_max"] > 0.0
    assert "shell_normal" in hair.hairdyn.output_curves.data.attributes


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


def test_bundled_presets_stay_up_to_date_and_keep_the_users_changes(tmp_path, monkeypatch):
    """A shipped preset updates an installed copy the add-on put there, and keeps a copy the
    user changed (or one installed before hairdyn recorded what it installed) as
    '<name> (yours).py'."""
    monkeypatch.setattr(bpy.utils, "user_resource", lambda *_args, **_kwargs: str(tmp_path))
    shipped = (presets.BUNDLED / "kurihara_1993.py").read_text()
    installed = tmp_path / "kurihara_1993.py"
    yours = tmp_path / "kurihara_1993 (yours).py"
    presets.install_bundled()
    assert installed.read_text() == shipped and not yours.exists()
    # An older release's copy, recorded as installed by hairdyn: brought up to date.
    installed.write_text("# an older hairdyn preset\n")
    record = json.loads((tmp_path / presets.INSTALLED_RECORD).read_text())
    record["kurihara_1993.py"] = hashlib.sha256(installed.read_bytes()).hexdigest()
    (tmp_path / presets.INSTALLED_RECORD).write_text(json.dumps(record))
    presets.install_bundled()
    assert installed.read_text() == shipped and not yours.exists()
    # The user's own edit: the shipped preset comes back, the edit is kept beside it.
    installed.write_text(shipped + "settings.strands.substeps = 3\n")
    presets.install_bundled()
    assert installed.read_text() == shipped
    assert yours.read_text().endswith("settings.strands.substeps = 3\n")
    # A copy from before the record (no record at all): replaced, kept too.
    yours.unlink()
    (tmp_path / presets.INSTALLED_RECORD).unlink()
    installed.write_text("# installed by a hairdyn without a record\n")
    presets.install_bundled()
    assert installed.read_text() == shipped
    assert yours.read_text() == "# installed by a hairdyn without a record\n"
