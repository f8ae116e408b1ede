"""Owns: the volume extension of the Strands method (Petrovic, Henne & Anderson 2006): velocity
smoothing on a density grid (§5.1), directing the hair toward a target shape (§5.2, eq. 3),
and hair-shell normals (§4.1, eq. 2) written as the `shell_normal` point attribute, with the
Cycles material that shades hair by them. Native VolumePass / HairShell do the work.
"""

import bpy
import numpy as np
from bpy.props import BoolProperty, PointerProperty

from ..errors import HairdynError
from .base import Section, node_material, object_poll
from .strands import Attached, Extension

SHELL_MATERIAL = "hairdyn_shell_normals"


class HairdynVolumeOptions(bpy.types.PropertyGroup):
    """Add-on options of the volume (Petrovic 2006): what is on, and the target shape."""

    use_smoothing: BoolProperty(
        name="Smoothing",
        default=False,
        description="Hair-hair friction and collision as velocity smoothing on the density "
        "grid, each substep (Petrovic 2006 §5.1); strength is Smoothing (s)",
    )
    target: PointerProperty(
        name="Target",
        type=bpy.types.Object,
        poll=object_poll('CURVES'),
        description="Curves object whose shape the hair is directed toward by the density "
        "force of Petrovic 2006 §5.2 (eq. 3); empty: no targeting",
    )
    use_shell_normals: BoolProperty(
        name="Shell Normals",
        default=False,
        description="Write the hair-shell normals N = ∇S (Petrovic 2006 §4.1, eq. 2) as the "
        "point attribute shell_normal of the output curves, for the shell-normal material",
    )
    use_grid_preview: BoolProperty(
        name="Grid Preview",
        default=False,
        description="Bake the hair density D (Petrovic 2006 eq. 1, nodes per grid vertex) of "
        "every frame as an OpenVDB file beside the bake (density/), shown by the Volume object "
        "'<hair> density' in the viewport and in renders. Needs an OpenVDB writer for this "
        "Python (Debian's python3-openvdb serves Python 3.11)",
    )


class VolumeAttached(Attached):
    def __init__(self, volume_pass, shell, groom, preview=None):
        self.volume_pass, self.shell, self.groom = volume_pass, shell, groom
        self.preview = preview  # GridPreview, or None
        self.ms, self.density_max, self.normals = [], 0.0, None
        if shell is not None:
            self.strand_columns = self.child_columns = {"shell_normal": 3}
            self.normals = np.array(shell.rest_normals, dtype=np.float32)

    def after_step(self, solver, head_matrix):
        if self.volume_pass is not None:
            self.ms.append(solver.pass_ms("volume"))
            self.density_max = max(self.density_max, self.volume_pass.density_max)
        if self.shell is not None:
            self.normals = self.shell.transport(solver.positions, head_matrix)
        if self.preview is not None:
            self.preview.step(solver.positions, head_matrix)

    def frame_baked(self, hair_obj, cache, frame):
        if self.preview is not None:
            self.preview.write(hair_obj, cache, frame)

    def strand_attributes(self):
        return {} if self.normals is None else {"shell_normal": self.normals}

    def child_attributes(self, children):
        """The guides' shell normals carried to the child hairs (§4.1), unit length."""
        if self.normals is None:
            return {}
        normals = children.blend(self.normals)
        lengths = np.linalg.norm(normals, axis=1, keepdims=True)
        return {"shell_normal": normals / np.maximum(lengths, 1e-12)}

    def report(self):
        if self.volume_pass is None:
            return {}
        figures = {
            "volume_ms": float(np.median(self.ms)) if self.ms else 0.0,
            "density_max": float(self.density_max),
        }
        if self.volume_pass.has_target:
            figures["target_error"] = float(self.volume_pass.target_error)
        return figures


class GridPreview:
    """The density grid of eq. 1 (on the pass's cell, moving with the head) of each baked frame
    as <bake>/density/density_<frame>.vdb, and a Volume object that plays them as a sequence.
    """

    FOLDER = "density"

    def __init__(self, native, curve_offsets, cell_size):
        self.writer_check()
        self.native, self.curve_offsets, self.cell_size = native, curve_offsets, cell_size
        self.density = self.grid_to_world = None
        self.first_frame = None

    @staticmethod
    def writer_check():
        from .. import volume_vdb

        writer, reason = volume_vdb.find_writer()
        if writer is None:
            raise HairdynError(f"Grid Preview: {reason}")

    def step(self, positions, head_matrix):
        self.density, self.grid_to_world = self.native.density_grid(
            self.curve_offsets, positions, head_matrix, self.cell_size
        )

    @classmethod
    def path(cls, directory, frame):
        return directory / cls.FOLDER / f"density_{int(frame):06d}.vdb"

    def write(self, hair_obj, cache, frame):
        from .. import volume_vdb

        path = self.path(cache.directory, frame)
        path.parent.mkdir(exist_ok=True)
        first = int(cache.manifest["frame_start"])
        if self.first_frame is None:
            # This run's first frame: files of an older bake go, those a resumed bake keeps
            # (its frames before this one) stay.
            self.first_frame = first
            for old in path.parent.glob("density_*.vdb"):
                number = old.stem.rsplit("_", 1)[-1]
                if not number.isdigit() or not first <= int(number) < frame:
                    old.unlink(missing_ok=True)
        volume_vdb.write_density_vdb(str(path), self.density, self.grid_to_world)
        show_grid_sequence(hair_obj, self.path(cache.directory, first), first, frame)


def show_grid_sequence(hair_obj, first_path, first, last):
    """The Volume object '<hair> density' playing the files of frames first..last (first_path
    is frame first's), each at its own scene frame."""
    name = f"{hair_obj.name} density"
    volume = bpy.data.volumes.get(name) or bpy.data.volumes.new(name)
    obj = bpy.data.objects.get(name)
    if obj is None or obj.type != 'VOLUME':
        obj = bpy.data.objects.new(name, volume)
        collections = hair_obj.users_collection
        (collections[0] if collections else bpy.context.scene.collection).objects.link(obj)
    obj.data = volume
    volume.filepath = bpy.path.relpath(str(first_path)) if bpy.data.filepath else str(first_path)
    volume.is_sequence = True
    volume.frame_start = first
    volume.frame_offset = first - 1
    volume.frame_duration = last - first + 1
    volume.sequence_mode = 'CLIP'
    volume.grids.load()


def attach(solver, build):
    options = build.settings.volume_options
    if not (
        options.use_smoothing
        or options.target
        or options.use_shell_normals
        or options.use_grid_preview
    ):
        return None
    from .. import bridge

    params = build.params("volume")
    groom = build.groom
    volume_pass = None
    if options.use_smoothing or options.target:
        if not options.use_smoothing:
            params.smoothing = 0.0
        volume_pass = build.native.VolumePass(params)
        if options.target is not None:
            target = bridge.read_curves(options.target, build.depsgraph)
            volume_pass.set_target(target.curve_offsets, target.positions_wo, build.head_matrix)
        solver.add_pass(volume_pass)
    shell = None
    if options.use_shell_normals:
        try:
            shell = build.native.HairShell(
                groom.curve_offsets, groom.positions_wo, build.head_matrix, params
            )
        except ValueError as error:
            raise HairdynError(f"Shell normals: {error} (lower Shell Threshold)") from None
        ensure_shell_material()
    preview = None
    if options.use_grid_preview:
        preview = GridPreview(build.native, groom.curve_offsets, params.cell_size)
    return VolumeAttached(volume_pass, shell, groom, preview)


def ensure_shell_material():
    """Hair shaded with the shell normals (Petrovic 2006 §4.1, Fig. 3(b)): a diffuse lobe about
    N = shell_normal, as if the hair volume were a surface, plus the strands' own highlight
    (the Principled Hair BSDF's reflection). Assign it to the output curves."""
    return node_material(SHELL_MATERIAL, _shell_nodes)


def _shell_nodes(nodes, links):
    normal = nodes.new("ShaderNodeAttribute")
    normal.attribute_name = "shell_normal"
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (0.32, 0.17, 0.08, 1.0)
    links.new(normal.outputs["Vector"], diffuse.inputs["Normal"])
    highlight = nodes.new("ShaderNodeBsdfHair")
    highlight.component = 'Reflection'
    highlight.inputs["Color"].default_value = (0.8, 0.7, 0.6, 1.0)
    mix = nodes.new("ShaderNodeAddShader")
    links.new(diffuse.outputs[0], mix.inputs[0])
    links.new(highlight.outputs[0], mix.inputs[1])
    output = nodes.new("ShaderNodeOutputMaterial")
    links.new(mix.outputs[0], output.inputs["Surface"])


EXTENSION = Extension(
    "volume",
    attach,
    params={"volume": "VolumeParams"},
    options={"volume_options": HairdynVolumeOptions},
    sections=(
        Section(
            "Volume (Petrovic 2006)",
            "volume",
            rest=True,
            draw=lambda layout, settings: [
                layout.prop(settings.volume_options, "use_smoothing"),
                layout.prop(settings.volume_options, "target"),
                layout.operator("hairdyn.target_from_bake", icon='CURVES'),
                layout.prop(settings.volume_options, "use_shell_normals"),
                layout.prop(settings.volume_options, "use_grid_preview"),
            ],
        ),
    ),
)
