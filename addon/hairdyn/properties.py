"""Settings an artist edits, one PropertyGroup per object (Object.hairdyn).

Solver parameter groups mirror the native parameter structs field for field; a test checks
them against hairdyn._native's `fields()` tables so the panel and the solver cannot drift.
"""
import bpy
from bpy.props import BoolProperty, EnumProperty, IntProperty, PointerProperty, StringProperty

METHODS = (
    ("FOLLOW", "Follow Head",
     "Kinematic baseline: every strand keeps its rest shape in the head's frame and follows "
     "the head rigidly"),
)


def _is_mesh(_self, obj):
    return obj.type == 'MESH'


class HairdynSettings(bpy.types.PropertyGroup):
    enabled: BoolProperty(
        name="hairdyn", default=False,
        description="Simulate this hair with hairdyn: play back its bake, or simulate it live, "
                    "whenever the frame changes")
    method: EnumProperty(
        name="Method", items=METHODS, default="FOLLOW",
        description="How the hair moves")
    head: PointerProperty(
        name="Head", type=bpy.types.Object, poll=_is_mesh,
        description="Mesh the hair roots are attached to. Empty: the Curves object's surface, "
                    "or the mesh that emits the particle hair")
    frame_start: IntProperty(
        name="Start", default=1, min=-1048574, max=1048574,
        description="First frame of the simulation: the groom's rest shape is read here")
    frame_end: IntProperty(
        name="End", default=250, min=-1048574, max=1048574,
        description="Last frame of the simulation")
    output_curves: PointerProperty(
        name="Output Curves", type=bpy.types.Object,
        description="Curves object that receives the simulated strands every frame "
                    "(created when empty)")
    output_points: PointerProperty(
        name="Output Points", type=bpy.types.Object,
        description="Mesh of loose vertices that receives the simulated points and their "
                    "attributes every frame (created when empty)")
    cache_directory: StringProperty(
        name="Cache", subtype='DIR_PATH', default="//hairdyn_cache/",
        description="Folder the bake writes to; // is relative to the .blend file. Each hair "
                    "object bakes into a subfolder named after it")
    use_cache: BoolProperty(
        name="Play Back Bake", default=True,
        description="Load the baked frame into the output objects whenever the frame changes")
    use_live: BoolProperty(
        name="Simulate on Playback", default=True,
        description="Where no frame is baked, simulate while the animation plays: restart at "
                    "the start frame, step when the frame advances by one (like cloth)")


def settings_dict(settings):
    """The solver parameters of a settings group as plain values (for a cache manifest):
    every property but object pointers and the cache's own settings."""
    skip = {"rna_type", "name", "enabled", "head", "output_curves", "output_points", "cache_directory",
            "use_cache", "use_live"}
    result = {}
    for prop in settings.bl_rna.properties:
        if prop.identifier in skip or prop.type == 'POINTER':
            continue
        value = getattr(settings, prop.identifier)
        result[prop.identifier] = list(value) if hasattr(value, "__len__") and not isinstance(value, str) else value
    return result
