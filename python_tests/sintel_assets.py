"""Sintel's real groom on Sintel's bust (../shared/data/sintel), imported as an artist would,
with a head turn: the scene of test_sintel.py and of scripts/bench_lcp_groom.py."""

from pathlib import Path

import bpy

SINTEL = Path(__file__).resolve().parent.parent.parent / "shared" / "data" / "sintel"
SCALE = 0.015  # the assets are about 40 units tall: a 0.6 m bust


def load():
    """(hair, bust) in a new empty scene, the bust turning about 35 degrees over half a second
    about its vertical axis, the hair on the Strands method with the bust as its head. Raises
    FileNotFoundError when the assets are missing."""
    if not SINTEL.is_dir():
        raise FileNotFoundError(f"needs the Sintel assets in {SINTEL}")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.hairdyn.import_tfx(filepath=str(SINTEL / "sintel_hair.tfx"), scale=SCALE)
    hair = bpy.context.view_layer.objects.active
    if hasattr(bpy.ops.wm, "obj_import"):
        bpy.ops.wm.obj_import(filepath=str(SINTEL / "sintel_bust.obj"), global_scale=SCALE)
    else:
        bpy.ops.import_scene.obj(filepath=str(SINTEL / "sintel_bust.obj"), global_scale=SCALE)
    bust = next(o for o in bpy.context.scene.objects if o.type == 'MESH')
    turn = bust.rotation_euler.copy()
    bust.keyframe_insert("rotation_euler", frame=1)
    turn.z += 0.6
    bust.rotation_euler = turn
    bust.keyframe_insert("rotation_euler", frame=12)
    settings = hair.hairdyn
    settings.method = 'STRANDS'
    settings.head = bust
    settings.strands.children_per_guide = 0
    return hair, bust
