# SPDX-License-Identifier: GPL-3.0-or-later
"""hairdyn: hair dynamics from Kurihara 1993, Ward & Lin 2003, Bando 2003 and Petrovic 2006,
with a native C++ solver (hairdyn._native)."""

bl_info = {
    "name": "hairdyn",
    "author": "hairdyn developers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Properties > Physics > hairdyn",
    "description": "Hair dynamics: strands, loosely connected particles, cylindrical-map collision",
    "category": "Physics",
}

if "bpy" in locals():
    import importlib

    for _module in (errors, native, cache, hair_formats, properties, bridge, playback,  # noqa: F821
                    simulation, operators, io_import, presets, billboards, export,  # noqa: F821
                    frame_record, ui):  # noqa: F821
        importlib.reload(_module)

import bpy

from . import (errors, native, cache, hair_formats, properties, bridge, playback,  # noqa: E402
               simulation, operators, io_import, presets, billboards, export, frame_record, ui)

classes = (
    properties.HairdynStrandSettings,
    properties.HairdynLcpSettings,
    properties.HairdynCollisionSettings,
    properties.HairdynColliderItem,
    properties.HairdynSettings,
    operators.HAIRDYN_OT_simulate,
    operators.HAIRDYN_OT_bake,
    operators.HAIRDYN_OT_free_bake,
    export.HAIRDYN_OT_export_bake,
    frame_record.HAIRDYN_OT_open_frame_record,
    io_import.HAIRDYN_OT_import_tfx,
    io_import.HAIRDYN_OT_import_cem_hair,
    operators.HAIRDYN_OT_collider_add,
    operators.HAIRDYN_OT_collider_remove,
    presets.HAIRDYN_MT_presets,
    presets.HAIRDYN_OT_preset_add,
    *ui.panel_classes,
)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.Object.hairdyn = bpy.props.PointerProperty(type=properties.HairdynSettings)
    playback.register()
    io_import.register()
    presets.install_bundled()


def unregister():
    io_import.unregister()
    playback.unregister()
    del bpy.types.Object.hairdyn
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
