"""Export Bake: the baked frame range of a hair object's output Curves (guides and child
hairs, with `radius` and the cached point attributes) to Alembic (.abc) or USD (.usd, .usda,
.usdc), written by Blender's own exporters.

Hosts differ: Debian's Blender 3.4 is built without either exporter, the bpy wheels have
both. `missing(kind)` says which, by asking Blender for the operator (a feature, not a
version). During the export the scene's frame range is the bake's, the baked frames play back
through the playback handler, and a pass-through Geometry Nodes modifier marks the outputs as
changing over time (the exporters write one sample for geometry they deem static).
"""

import contextlib
from pathlib import Path

import bpy
import numpy as np

from .errors import HairdynError

# file suffix -> (kind, exporter, importer)
FORMATS = {
    ".abc": ("Alembic", "alembic_export", "alembic_import"),
    ".usd": ("USD", "usd_export", "usd_import"),
    ".usda": ("USD", "usd_export", "usd_import"),
    ".usdc": ("USD", "usd_export", "usd_import"),
}
_NODE_GROUP = "hairdyn export (pass-through)"


def has_operator(name):
    """True when this Blender has the window-manager operator `name` (bpy.ops.wm.<name>)."""
    try:
        getattr(bpy.ops.wm, name).get_rna_type()
    except (KeyError, AttributeError, RuntimeError):
        return False
    return True


def missing(suffix):
    """None when this Blender can export `suffix` (".abc", ".usd", ...), else why not."""
    if suffix not in FORMATS:
        return f"hairdyn exports to {', '.join(sorted(FORMATS))}, not '{suffix}'"
    kind, exporter, _ = FORMATS[suffix]
    if not has_operator(exporter):
        return f"This Blender ({bpy.app.version_string}) is built without the {kind} exporter"
    return None


def available():
    """The suffixes this Blender can export."""
    return [suffix for suffix in FORMATS if missing(suffix) is None]


def geometry_group(name):
    """A new Geometry Nodes group with one Geometry input and one Geometry output (either
    Blender's API for them), and its input and output nodes, not linked yet."""
    group = bpy.data.node_groups.new(name, 'GeometryNodeTree')
    if hasattr(group, "interface"):  # 4.0+
        for in_out in ('INPUT', 'OUTPUT'):
            group.interface.new_socket("Geometry", in_out=in_out, socket_type='NodeSocketGeometry')
    else:
        group.inputs.new('NodeSocketGeometry', "Geometry")
        group.outputs.new('NodeSocketGeometry', "Geometry")
    return group, group.nodes.new('NodeGroupInput'), group.nodes.new('NodeGroupOutput')


def _pass_through_group():
    """A Geometry Nodes group that returns its input unchanged."""
    group = bpy.data.node_groups.get(_NODE_GROUP)
    if group is not None:
        return group
    group, source, sink = geometry_group(_NODE_GROUP)
    group.links.new(source.outputs[0], sink.inputs[0])
    return group


@contextlib.contextmanager
def _exporting(scene, objects, frame_start, frame_end):
    """The scene set up for an export of `objects` over the frame range, restored after."""
    view_layer = bpy.context.view_layer
    saved = (
        scene.frame_start,
        scene.frame_end,
        scene.frame_current,
        view_layer.objects.active,
        [o for o in view_layer.objects if o.select_get()],
    )
    group = _pass_through_group()
    modifiers = []
    try:
        for obj in view_layer.objects:
            obj.select_set(obj in objects)
        view_layer.objects.active = objects[0]
        for obj in objects:
            modifier = obj.modifiers.new("hairdyn export", 'NODES')
            modifier.node_group = group
            modifiers.append((obj, modifier))
        scene.frame_start, scene.frame_end = frame_start, frame_end
        scene.frame_set(frame_start)
        yield
    finally:
        for obj, modifier in modifiers:
            obj.modifiers.remove(modifier)
        if group.users == 0:
            bpy.data.node_groups.remove(group)
        scene.frame_start, scene.frame_end = saved[0], saved[1]
        for obj in view_layer.objects:
            obj.select_set(obj in saved[4])
        view_layer.objects.active = saved[3]
        scene.frame_set(saved[2])


def _attribute_writer(curves_obj, cache):
    """A frame_change_post handler that puts the cached point attributes other than the
    position (velocity, direction, ...) on the output Curves, so they are exported too."""
    from . import bridge

    def write(scene, _depsgraph=None):
        frame = scene.frame_current
        if not cache.has_frame(frame):
            return
        arrays = cache.read_frame(frame)
        bridge.write_point_attributes(
            curves_obj.data, {name: values for name, values in arrays.items() if name != "position"}
        )
        curves_obj.data.update_tag()

    return write


def export_bake(context, hair_obj, filepath):
    """Write the baked frames of hair_obj's output Curves (and child hairs) to filepath; its
    suffix picks the format. Returns {"file", "format", "frame_start", "frame_end",
    "objects"}; HairdynError when the bake, the outputs or the exporter are missing."""
    from . import bake, playback, simulation
    from .cache import Cache

    path = Path(bpy.path.abspath(str(filepath))).resolve()
    reason = missing(path.suffix.lower())
    if reason:
        raise HairdynError(reason)
    cache = Cache.open(bake.cache_directory(hair_obj))
    frame_start = cache.manifest["frame_start"]
    frame_end = cache.last_contiguous_frame()
    if frame_end is None:
        raise HairdynError(f"'{hair_obj.name}' has no baked frame to export: bake first")
    settings = hair_obj.hairdyn
    settings.enabled = settings.use_cache = True
    scene = context.scene
    simulation.frame_set(scene, frame_start)
    if not playback.load_frame(hair_obj, frame_start):  # creates the output objects
        raise HairdynError(f"The bake of '{hair_obj.name}' cannot be played back")
    objects = [o for o in (settings.output_curves, settings.output_children) if o is not None]
    kind, exporter, _ = FORMATS[path.suffix.lower()]
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise HairdynError(f"Cannot create the folder '{path.parent}': {error.strerror}") from None
    handler = _attribute_writer(settings.output_curves, cache)
    bpy.app.handlers.frame_change_post.append(handler)
    try:
        with _exporting(scene, objects, frame_start, frame_end):
            if kind == "Alembic":
                result = bpy.ops.wm.alembic_export(
                    filepath=str(path), start=frame_start, end=frame_end, selected=True
                )
            else:
                result = bpy.ops.wm.usd_export(
                    filepath=str(path), selected_objects_only=True, export_animation=True
                )
    except RuntimeError as error:
        raise HairdynError(f"The {kind} export failed: {error}") from None
    finally:
        bpy.app.handlers.frame_change_post.remove(handler)
    if result != {'FINISHED'} or not path.is_file():
        raise HairdynError(f"The {kind} exporter wrote no file at '{path}'")
    return {
        "file": str(path),
        "format": kind,
        "frame_start": frame_start,
        "frame_end": frame_end,
        "objects": [o.name for o in objects],
    }


def read_positions(obj, depsgraph):
    """(N, 3) float32 world positions of a Curves object as evaluated (an imported cache's
    current frame)."""
    evaluated = obj.evaluated_get(depsgraph)
    curves = evaluated.data
    positions = np.empty(len(curves.points) * 3, dtype=np.float32)
    curves.position_data.foreach_get("vector", positions)
    matrix = np.array(evaluated.matrix_world, dtype=np.float64)
    positions = positions.reshape(-1, 3).astype(np.float64) @ matrix[:3, :3].T + matrix[:3, 3]
    return positions.astype(np.float32)


class HAIRDYN_OT_export_bake(bpy.types.Operator):
    """Export the baked output hair (guides, child hairs, radius, attributes) to Alembic or USD"""

    bl_idname = "hairdyn.export_bake"
    bl_label = "Export Bake"
    bl_options = {'REGISTER'}

    filepath: bpy.props.StringProperty(subtype='FILE_PATH')
    filter_glob: bpy.props.StringProperty(default="*.abc;*.usd;*.usda;*.usdc", options={'HIDDEN'})

    @classmethod
    def poll(cls, context):
        from . import bridge

        if not bridge.is_hair_object(context.object):
            return False
        if not available():
            if hasattr(cls, "poll_message_set"):  # 3.0+
                cls.poll_message_set(
                    f"This Blender ({bpy.app.version_string}) is built "
                    "without the Alembic and USD exporters"
                )
            return False
        return True

    @classmethod
    def description(cls, _context, _properties):
        lacking = [missing(suffix) for suffix in (".abc", ".usd") if missing(suffix)]
        text = cls.__doc__
        return text + (". " + "; ".join(lacking) if lacking else "")

    def invoke(self, context, _event):
        if not self.filepath:
            self.filepath = bpy.path.clean_name(context.object.name) + (
                ".abc" if ".abc" in available() else ".usd"
            )
        context.window_manager.fileselect_add(self)
        return {'RUNNING_MODAL'}

    def execute(self, context):
        try:
            result = export_bake(context, context.object, self.filepath)
        except HairdynError as error:
            self.report({'ERROR'}, str(error))
            return {'CANCELLED'}
        self.report(
            {'INFO'},
            f"Exported frames {result['frame_start']}-{result['frame_end']} "
            f"of {', '.join(result['objects'])} to {result['file']}",
        )
        return {'FINISHED'}
