"""Run in a fresh Blender with a clean user folder: install a hairdyn package and enable it.

    blender -b --factory-startup --python install_check.py -- PACKAGE.zip addon|extension OUT.json
    python install_check.py PACKAGE.zip extension OUT.json          (bpy module)
"""
import importlib
import json
import sys
from pathlib import Path

import bpy

zip_path, kind, out_path = sys.argv[-3:]
if kind == "addon":
    steps = [bpy.ops.preferences.addon_install(filepath=zip_path),
             bpy.ops.preferences.addon_enable(module="hairdyn")]
    module_name = "hairdyn"
else:
    steps = [bpy.ops.extensions.package_install_files(filepath=zip_path, repo="user_default",
                                                      enable_on_install=True)]
    module_name = "bl_ext.user_default.hairdyn"
module = importlib.import_module(module_name)
Path(out_path).write_text(json.dumps({
    "steps": [sorted(step) for step in steps],
    "registered": hasattr(bpy.types.Object, "hairdyn") and hasattr(bpy.ops.hairdyn, "bake"),
    "native": list(module.native.status()),
    "file": module.__file__,
    "native_file": module.native.load().__file__ if module.native.status()[0] else None,
}))
