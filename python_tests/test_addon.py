"""The add-on registers cleanly in both hosts and tells when its native module is unusable."""
import bpy
import pytest

import hairdyn
from hairdyn import native, ui


def test_register_unregister_twice():
    for _ in range(2):
        hairdyn.unregister()
        assert not hasattr(bpy.types.Object, "hairdyn")
        assert not hasattr(bpy.types, "HAIRDYN_PT_main")
        hairdyn.register()
        assert hasattr(bpy.types.Object, "hairdyn")
        assert hasattr(bpy.ops.hairdyn, "simulate")
        assert bpy.types.HAIRDYN_PT_main.bl_context == "physics"


def test_native_module_loads():
    ok, version = native.status()
    assert ok, version
    assert native.load().__version__ == version


def test_missing_native_module_is_one_sentence(monkeypatch, tmp_path):
    def fail_import():
        raise ImportError("No module named 'hairdyn._native'")

    monkeypatch.setattr(native, "_import", fail_import)
    monkeypatch.setattr(native, "_PACKAGE_DIR", tmp_path)
    ok, message = native.status()
    assert not ok
    assert message.startswith("The hairdyn native module is not built")
    assert message.count(". ") == 0 and message.endswith(".")
    with pytest.raises(hairdyn.errors.HairdynError, match="not built"):
        native.load()


def test_native_module_for_another_python_is_named(monkeypatch, tmp_path):
    (tmp_path / "_native.cpython-39-x86_64-linux-gnu.so").write_bytes(b"")

    def fail_import():
        raise ImportError("bad magic")

    monkeypatch.setattr(native, "_import", fail_import)
    monkeypatch.setattr(native, "_PACKAGE_DIR", tmp_path)
    ok, message = native.status()
    assert not ok
    assert "built for another Python" in message
    assert "cpython-39" in message


def test_panel_polls_hair_objects_only(open_fixture):
    open_fixture("head_particles.blend")
    body = bpy.data.objects["Body"]
    camera = bpy.data.objects["Camera"]

    class Context:
        object = None

    Context.object = body
    assert ui.HAIRDYN_PT_main.poll(Context)
    Context.object = camera
    assert not ui.HAIRDYN_PT_main.poll(Context)
    open_fixture("head_curves.blend")
    Context.object = bpy.data.objects["Hair"]
    assert ui.HAIRDYN_PT_main.poll(Context)
    Context.object = bpy.data.objects["Body"]  # a mesh without hair
    assert not ui.HAIRDYN_PT_main.poll(Context)
