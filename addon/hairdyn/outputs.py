"""Owns: writing a frame's streams into the hair object's output objects (created when
missing). A stream names the settings pointers that show it (Stream.outputs): curves slots get
its positions, the point slot a mesh of loose vertices with every array as a point attribute,
the ribbons slot a mesh of quads between each ribbon's vertex pairs. The strands ("frame") show
in output_curves and output_points, unless another stream takes output_points (LCP's
particles). A stream recorded with `shown_by` shows its objects while that switch is on; the
ribbons, shown only that way, hide when a frame has none (level of detail turned off).
"""

from operator import attrgetter

import bpy

from . import billboards, bridge

STRANDS = "frame"  # the strands' stream: the cache's main table
STRAND_OUTPUT = {"outputs": ["output_curves", "output_points"], "billboards": False}
SLOTS = {
    "output_curves": ("curves", "_hairdyn"),
    "output_children": ("curves", "_hairdyn_children"),
    "output_points": ("points", "_hairdyn_points"),
    "output_strips": ("ribbons", "_hairdyn_strips"),
}


def write(hair_obj, frame):
    """frame: {stream name: (arrays, curve offsets or None, output {"outputs": [slots],
    "billboards": bool})}, the strands under STRANDS."""
    settings = hair_obj.hairdyn
    taken = {
        slot
        for name, (_, _, output) in frame.items()
        if name != STRANDS
        for slot in output["outputs"]
    }
    for slot, (kind, _) in SLOTS.items():
        stale = getattr(settings, slot)
        if kind == "ribbons" and slot not in taken and stale is not None:
            show_output(stale, False)  # an earlier run's, not this frame's
    for name, (arrays, offsets, output) in frame.items():
        for slot in output["outputs"]:
            if name == STRANDS and slot in taken:
                continue
            kind, suffix = SLOTS[slot]
            target_name = f"{hair_obj.name}{suffix}"
            current = _in_a_scene(getattr(settings, slot))
            if kind == "curves":
                target = bridge.ensure_curves_output(current, target_name, offsets, like=hair_obj)
                setattr(settings, slot, target)
                bridge.write_curves(target, arrays["position"])
                bridge.write_point_attributes(  # velocity, shell_normal, lod_level...
                    target.data, {k: v for k, v in arrays.items() if k != "position"}
                )
                continue
            target = bridge.ensure_points_output(current, target_name, like=hair_obj)
            setattr(settings, slot, target)
            attributes = {key: value for key, value in arrays.items() if key != "position"}
            if kind == "ribbons":
                bridge.write_ribbons(target, arrays["position"], offsets, attributes)
            else:
                bridge.write_points(target, arrays["position"], attributes)
            if output["billboards"] and settings.use_billboards:
                billboards.ensure(target, bpy.context.scene.camera)
            if "shown_by" in output:
                show_output(target, attrgetter(output["shown_by"])(settings))
    if settings.hide_source_in_renders:  # writing never puts the groom back
        show_source_as_set(hair_obj)


def show_output(obj, shown):
    """An output object in or out of the viewport and renders (changes only what differs)."""
    for switch in ("hide_viewport", "hide_render"):
        if getattr(obj, switch) == shown:
            setattr(obj, switch, not shown)


def _in_a_scene(obj):
    """obj, or None when no scene holds it: the artist deleted it (the settings' pointer
    keeps it alive), and a new one takes its place rather than frames nobody sees."""
    return obj if obj is not None and obj.users_scene else None


def show_source_as_set(hair_obj):
    """The groom out of renders while output curves in a scene show it simulated and Hide
    Source is on, else back in (hide_source)."""
    settings = hair_obj.hairdyn
    replaced = _in_a_scene(settings.output_curves) is not None
    hide_source(hair_obj, settings.hide_source_in_renders and replaced)


def hide_source(hair_obj, hidden):
    """The groom's own hair in or out of renders, where the outputs show it simulated: the
    Curves object, or the emitter's hair particle systems (the emitter itself still renders).
    Changes only what differs, so a frame that finds it hidden costs nothing."""
    if hair_obj.type == 'CURVES' and hair_obj.hide_render != hidden:
        hair_obj.hide_render = hidden
    for modifier in bridge.hair_system_modifiers(hair_obj):
        if modifier.show_render == hidden:
            modifier.show_render = not hidden
