"""Owns: presets with Blender's preset system: the papers' settings ship with the add-on, and
artists save their own (the + button next to the preset menu). What a preset stores is every
plain value of every settings group (properties.preset_paths), read at registration."""

import hashlib
import json
import shutil
from pathlib import Path

import bpy
from bl_operators.presets import AddPresetBase

from . import properties

PRESET_SUBDIR = "hairdyn"
BUNDLED = Path(__file__).resolve().parent / "presets"
INSTALLED_RECORD = ".hairdyn_bundled.json"  # {file name: sha256 of what was installed}


class HAIRDYN_MT_presets(bpy.types.Menu):
    bl_label = "hairdyn Presets"
    preset_subdir = PRESET_SUBDIR
    preset_operator = "script.execute_preset"
    draw = bpy.types.Menu.draw_preset


class HAIRDYN_OT_preset_add(AddPresetBase, bpy.types.Operator):
    """Save the hairdyn settings of the active object as a preset, or remove one"""

    bl_idname = "hairdyn.preset_add"
    bl_label = "Add hairdyn Preset"
    preset_menu = "HAIRDYN_MT_presets"
    preset_subdir = PRESET_SUBDIR
    preset_defines = ["settings = bpy.context.object.hairdyn"]
    preset_values = []  # filled by register(): the settings groups exist from then on


def register():
    HAIRDYN_OT_preset_add.preset_values = properties.preset_paths()
    for cls in (HAIRDYN_MT_presets, HAIRDYN_OT_preset_add):
        bpy.utils.register_class(cls)
    install_bundled()


def unregister():
    for cls in (HAIRDYN_OT_preset_add, HAIRDYN_MT_presets):
        bpy.utils.unregister_class(cls)


def _digest(path):
    return hashlib.sha256(path.read_bytes()).hexdigest()


def install_bundled():
    """Copy the shipped presets into the user's preset folder (where Blender's preset menus
    look), and bring an installed copy up to date when the add-on ships a new one, unless the
    user changed it. What was installed is recorded by hash; a copy installed before that
    record existed, or changed since, is kept under "<name> (yours).py" when replaced, so
    nothing is lost."""
    target = Path(bpy.utils.user_resource('SCRIPTS', path=f"presets/{PRESET_SUBDIR}"))
    try:
        target.mkdir(parents=True, exist_ok=True)
        record_path = target / INSTALLED_RECORD
        try:
            record = json.loads(record_path.read_text())
        except (OSError, ValueError):
            record = {}
        for source in sorted(BUNDLED.glob("*.py")):
            destination = target / source.name
            shipped = _digest(source)
            if destination.exists():
                installed = _digest(destination)
                if installed == shipped:
                    record[source.name] = shipped
                    continue
                if record.get(source.name) != installed:  # the user's own, or unknown
                    kept = target / f"{source.stem} (yours).py"
                    if not kept.exists():
                        shutil.copyfile(destination, kept)
            shutil.copyfile(source, destination)
            record[source.name] = shipped
        record_path.write_text(json.dumps(record, indent=1, sort_keys=True) + "\n")
    except OSError as error:  # a read-only user folder: the add-on still works, without them
        print(f"hairdyn: the bundled presets could not be installed in '{target}': {error}")
    return target


def draw_menu(layout):
    row = layout.row(align=True)
    row.menu("HAIRDYN_MT_presets", text=HAIRDYN_MT_presets.bl_label)
    row.operator("hairdyn.preset_add", text="", icon='ADD')
    row.operator("hairdyn.preset_add", text="", icon='REMOVE').remove_active = True
