"""Owns: presets with Blender's preset system: the papers' settings ship with the add-on, and
artists save their own (the + button next to the preset menu). What a preset stores is every
plain value of every settings group (properties.preset_paths), read at registration."""

import shutil
from pathlib import Path

import bpy
from bl_operators.presets import AddPresetBase

from . import properties

PRESET_SUBDIR = "hairdyn"
BUNDLED = Path(__file__).resolve().parent / "presets"


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


def install_bundled():
    """Copy the shipped presets into the user's preset folder (where Blender's preset menus
    look), without overwriting a file the user changed."""
    target = Path(bpy.utils.user_resource('SCRIPTS', path=f"presets/{PRESET_SUBDIR}"))
    try:
        target.mkdir(parents=True, exist_ok=True)
        for source in BUNDLED.glob("*.py"):
            destination = target / source.name
            if not destination.exists():
                shutil.copyfile(source, destination)
    except OSError as error:  # a read-only user folder: the add-on still works, without them
        print(f"hairdyn: the bundled presets could not be installed in '{target}': {error}")
    return target


def draw_menu(layout):
    row = layout.row(align=True)
    row.menu("HAIRDYN_MT_presets", text=HAIRDYN_MT_presets.bl_label)
    row.operator("hairdyn.preset_add", text="", icon='ADD')
    row.operator("hairdyn.preset_add", text="", icon='REMOVE').remove_active = True
