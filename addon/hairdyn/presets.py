"""Presets with Blender's preset system: the papers' settings ship with the add-on, and
artists save their own (the + button next to the preset menu)."""
import shutil
from pathlib import Path

import bpy
from bl_operators.presets import AddPresetBase

from . import properties

PRESET_SUBDIR = "hairdyn"
BUNDLED = Path(__file__).resolve().parent / "presets"


def _values():
    """Every solver setting a preset stores, as Python paths under `settings`."""
    top = ["settings.method", "settings.use_collision", "settings.use_default_colliders",
           "settings.collider_parts", "settings.lcp_init", "settings.lcp_scalp_source",
           "settings.lcp_scalp", "settings.lcp_length_source", "settings.lcp_length_group"]
    groups = [("strands", properties.HairdynStrandSettings),
              ("lcp", properties.HairdynLcpSettings),
              ("collision", properties.HairdynCollisionSettings)]
    nested = [f"settings.{group}.{name}" for group, cls in groups
              for name in cls.__annotations__]
    return top + nested


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
    preset_values = _values()


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
