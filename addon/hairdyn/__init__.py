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

    for _module in (errors, native, cache, properties, bridge, playback, simulation, operators, ui):  # noqa: F821
        importlib.reload(_module)

import bpy

from . import errors, native, cache, properties, bridge, playback, simulation, operators, ui  # noqa: F401,E402

classes = (
    properties.HairdynSettings,
    operators.HAIRDYN_OT_simulate,
    operators.HAIRDYN_OT_bake,
    operators.HAIRDYN_OT_free_bake,
    ui.HAIRDYN_PT_main,
)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.Object.hairdyn = bpy.props.PointerProperty(type=properties.HairdynSettings)
    playback.register()


def unregister():
    playback.unregister()
    del bpy.types.Object.hairdyn
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
