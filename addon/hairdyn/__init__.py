# SPDX-License-Identifier: GPL-3.0-or-later
"""hairdyn: hair dynamics from Kurihara 1993, Ward & Lin 2003, Bando 2003 and Petrovic 2006,
with a native C++ solver (hairdyn._native).

Owns: registration. Modules import one way (no cycles):
  errors <- native <- parameters <- methods/ <- properties <- presets
  bridge, colliders, outputs <- simulation <- bake <- playback <- ui; operators and cli call
  simulation / bake / playback lazily.
"""

bl_info = {
    "name": "hairdyn",
    "author": "hairdyn developers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Properties > Physics > hairdyn",
    "description": "Hair dynamics: strands, loosely connected particles, cylindrical-map collision",
    "category": "Physics",
}

# Every module, dependencies first: a reload (F8, or the add-on re-enabled) reloads them all.
_MODULES = (
    "errors",
    "native",
    "cache",
    "hair_formats",
    "parameters",
    "bridge",
    "billboards",
    "colliders",
    "methods.base",
    "methods.follow",
    "methods.strands",
    "methods.lcp",
    "volume_vdb",
    "methods.volume",
    "methods.swept_spheres",
    "methods.lod",
    "methods",
    "properties",
    "outputs",
    "simulation",
    "bake",
    "frame_record",
    "export",
    "playback",
    "operators",
    "io_import",
    "presets",
    "ui",
    "wedge",  # not imported here: cli.py loads it on its own (its driver needs no bpy)
)

if "bpy" in locals():
    import importlib
    import sys

    for _name in _MODULES:
        _module = sys.modules.get(f"{__name__}.{_name}")
        if _module is not None:
            importlib.reload(_module)

import bpy  # noqa: E402

from . import (  # noqa: E402, F401 - every module, for the reload above
    bake,
    export,
    frame_record,
    billboards,
    bridge,
    cache,
    colliders,
    errors,
    hair_formats,
    io_import,
    methods,
    native,
    operators,
    outputs,
    parameters,
    playback,
    presets,
    properties,
    simulation,
    ui,
)

classes = (
    operators.HAIRDYN_OT_simulate,
    operators.HAIRDYN_OT_bake,
    operators.HAIRDYN_OT_free_bake,
    export.HAIRDYN_OT_export_bake,
    operators.HAIRDYN_OT_open_frame_record,
    operators.HAIRDYN_OT_target_from_bake,
    io_import.HAIRDYN_OT_import_tfx,
    io_import.HAIRDYN_OT_import_cem_hair,
    operators.HAIRDYN_OT_collider_add,
    operators.HAIRDYN_OT_collider_remove,
)


def register():
    properties.register()  # the settings groups, generated from the native structs
    for cls in classes:
        bpy.utils.register_class(cls)
    presets.register()
    ui.register()
    playback.register()
    io_import.register()


def unregister():
    io_import.unregister()
    playback.unregister()
    ui.unregister()
    presets.unregister()
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
    properties.unregister()
