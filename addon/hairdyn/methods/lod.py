"""Owns: level of detail on the Strands method (Ward & Lin 2003 §4, §6): the groom's hierarchy of
strips, clusters and strand groups, chosen every frame by the camera's view, distance and the
hair's speed, split and merged smoothly (native LodSolver). It replaces the StrandSolver (same
strand parameters, wind and colliders) and follows a camera: its view-projection matrix is read
from the scene every frame. Every strand of the groom follows the skeleton that drives it, so the
output keeps the groom's topology; the point attribute `lod_level` says which level drives it.

The swept spheres (hair-hair, segment-exact body collision) run over the active skeletons of every
level, each its group's volume (Ward & Lin 2003 §5.2: a strip a rectangle swept sphere, a cluster
or strand group a line swept sphere as thick as the group). The volume's smoothing and targeting
are refused with it (strands.NoPasses): a skeleton stands for many strands, which their density
grid does not know. Shell normals, child hairs and the collision maps work. Pinned points (the
`hairdyn_fixed` attribute) are refused too: the skeletons it simulates are not the artist's
strands, so nothing would hold a pinned point on the head. With "Measure Error" a plain
StrandSolver runs the same frames alongside (twice the work, the same passes) and the report gives
the mean distance between the two, as a share of the hair length.
"""

import time

import bpy
import numpy as np
from bpy.props import BoolProperty, PointerProperty

from .. import outputs
from ..errors import HairdynError
from .base import Section, Stream, node_material, object_poll
from .strands import Attached, Extension, NoPasses

NAME = "Level of detail (Ward & Lin 2003)"
LEVEL_MATERIAL = "hairdyn_lod_level"


def ensure_level_material(finest_level=None):
    """The material that colours hair by the `lod_level` point attribute: red on the coarsest
    strips through green to blue on the finest level (`finest_level`, when given, sets the
    scale; it is kept from the last run otherwise), lit diffusely with a little glow so that
    the colours read in any light. Shown in Material Preview and Rendered shading."""
    material = node_material(LEVEL_MATERIAL, _level_nodes)
    if finest_level is not None:
        material.node_tree.nodes["finest_level"].inputs[1].default_value = max(1, finest_level)
    return material


def _level_nodes(nodes, links):
    level = nodes.new("ShaderNodeAttribute")
    level.attribute_name = "lod_level"
    scale = nodes.new("ShaderNodeMath")
    scale.name = "finest_level"
    scale.operation = 'DIVIDE'
    scale.inputs[1].default_value = 1.0
    links.new(level.outputs["Fac"], scale.inputs[0])
    ramp = nodes.new("ShaderNodeValToRGB")
    stops = ramp.color_ramp.elements
    stops[0].color = (1.0, 0.08, 0.03, 1.0)
    stops[1].color = (0.05, 0.25, 1.0, 1.0)
    stops.new(0.5).color = (0.2, 0.9, 0.1, 1.0)
    links.new(scale.outputs[0], ramp.inputs["Fac"])
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    glow = nodes.new("ShaderNodeEmission")
    glow.inputs["Strength"].default_value = 0.3
    for shader in (diffuse, glow):
        links.new(ramp.outputs["Color"], shader.inputs["Color"])
    add = nodes.new("ShaderNodeAddShader")
    links.new(diffuse.outputs[0], add.inputs[0])
    links.new(glow.outputs[0], add.inputs[1])
    output = nodes.new("ShaderNodeOutputMaterial")
    links.new(add.outputs[0], output.inputs["Surface"])


def show_levels(hair_obj, has_levels):
    """While lod_options.color_by_level is on and the output curves show a level-of-detail
    frame (`has_levels`: it has lod_level), they wear the level material in their first slot
    as the object's own (the slot linked to the object), so the groom's materials stay in the
    curves data untouched; otherwise the slot shows the data's again."""
    settings = hair_obj.hairdyn
    output = settings.output_curves
    if output is None or output.type != 'CURVES':
        return
    slots = output.material_slots
    if settings.lod_options.color_by_level and has_levels:
        material = ensure_level_material()
        if not slots:
            output.data.materials.append(None)
        if slots[0].link != 'OBJECT' or slots[0].material != material:
            slots[0].link = 'OBJECT'
            slots[0].material = material
    elif slots and slots[0].link == 'OBJECT' and slots[0].material is not None:
        if slots[0].material.name == LEVEL_MATERIAL:
            slots[0].material = None
            slots[0].link = 'DATA'


def _color_by_level_changed(options, _context):
    output = options.id_data.hairdyn.output_curves
    show_levels(options.id_data, output is not None and "lod_level" in output.data.attributes)


def dress(hair_obj, frame):
    """The output objects of a Strands frame, simulated or played back: the curves coloured by
    level while Colour by Level is on and the frame is a level-of-detail one, and the strips'
    ribbons (made again by playback when the artist deleted them) in the level material,
    unless the artist gave them another."""
    show_levels(hair_obj, "lod_level" in frame[outputs.STRANDS][0])
    strips = hair_obj.hairdyn.output_strips
    if "strips" not in frame or strips is None:
        return
    materials = strips.data.materials
    if not materials:
        materials.append(ensure_level_material())
    elif materials[0] is None:
        materials[0] = ensure_level_material()


def _show_strips_changed(options, _context):
    settings = options.id_data.hairdyn
    if settings.output_strips is not None:  # an earlier run's ribbons stay hidden without LOD
        outputs.show_output(settings.output_strips, options.show_strips and settings.lod.enabled)


class HairdynLodOptions(bpy.types.PropertyGroup):
    """Add-on options of the level of detail: the camera it follows, and the fine reference."""

    camera: PointerProperty(
        name="Camera",
        type=bpy.types.Object,
        poll=object_poll('CAMERA'),
        description="Camera whose view, distance and frustum choose the level of detail every "
        "frame (Ward & Lin 2003 §6.1); empty: the scene's camera",
    )
    measure_error: BoolProperty(
        name="Measure Error",
        default=False,
        description="Also simulate every strand without level of detail over the same frames "
        "and report lod_error, the mean distance between the two as a share of the hair "
        "length. Doubles the work",
    )
    color_by_level: BoolProperty(
        name="Colour by Level",
        default=False,
        update=_color_by_level_changed,
        description="Shade the output strands by the level of detail that drives each one "
        "(the lod_level point attribute, §6.1): red the coarsest strips, green clusters, blue "
        "the finest level. Seen in Material Preview and Rendered shading; the groom's own "
        "materials come back when it is off",
    )
    show_strips: BoolProperty(
        name="Strips as Ribbons",
        default=False,
        update=_show_strips_changed,
        description="Show the strips of the hierarchy that drive hair as ribbons (Ward & Lin "
        "2003 §3: a strip is a flat surface along its skeleton, as wide as its strands "
        "spread), coloured by level, in the Output Strips mesh: made with every bake or run "
        "and hidden until this is on",
    )


def rotation(matrix):
    """The rotation of a (4, 4) object matrix, its axes' scale removed (a mirrored one kept
    proper, as the native HeadPose does)."""
    axes = np.array(matrix, dtype=np.float64)[:3, :3]
    scale = np.linalg.norm(axes, axis=0)
    if np.linalg.det(axes) < 0.0:
        scale[0] = -scale[0]
    return axes / scale


def view_projection(camera, scene, depsgraph):
    """World -> clip (4, 4) float64 of a camera as it renders: projection @ view, the
    projection from the scene's render size and pixel aspect (OpenGL clip space)."""
    evaluated = camera.evaluated_get(depsgraph)
    render = scene.render
    projection = evaluated.calc_matrix_camera(
        depsgraph,
        x=render.resolution_x,
        y=render.resolution_y,
        scale_x=render.pixel_aspect_x,
        scale_y=render.pixel_aspect_y,
    )
    view = evaluated.matrix_world.inverted()
    return np.array(projection @ view, dtype=np.float64)


def strand_lengths(curve_offsets, positions):
    """Each strand's length (C,)."""
    segments = np.linalg.norm(np.diff(positions.astype(np.float64), axis=0), axis=1)
    inside = np.ones(len(segments), dtype=bool)
    inside[curve_offsets[1:-1] - 1] = False  # the step from one strand's tip to the next root
    per_point = np.where(inside, segments, 0.0)
    cumulative = np.concatenate(([0.0], np.cumsum(per_point)))
    return cumulative[curve_offsets[1:] - 1] - cumulative[curve_offsets[:-1]]


class LodStrands(Attached):
    """A LodSolver in the StrandSolver's place (step, positions, root_frames, set_colliders)
    and the extension's attached figures: lod_level per point, the report."""

    strand_columns = {"lod_level": 1}

    def __init__(self, build, params, root_normals):
        native, groom, scene = build.native, build.groom, build.scene
        self.scene, self.options = scene, build.settings.lod_options
        self.camera = self._camera()
        self.view_projection = view_projection(self.camera, scene, build.depsgraph)
        wind = build.params("wind")
        self.native = native
        self.solver = native.LodSolver(
            groom.curve_offsets,
            groom.positions_wo,
            build.head_matrix,
            groom.root_uvs,
            root_normals,
            params,
            wind,
            build.params("lod"),
        )
        self.fine, self.colliders = None, None
        if self.options.measure_error:  # the same strands without level of detail
            self.fine = native.StrandSolver(
                groom.curve_offsets,
                groom.positions_wo,
                build.head_matrix,
                root_normals,
                params,
                wind,
            )
        self.hair_length = float(strand_lengths(groom.curve_offsets, groom.positions_wo).mean())
        self.rest_frames = np.array(
            native.root_frames(groom.curve_offsets, groom.positions_wo, root_normals)
        )
        self.rest_rotation = rotation(build.head_matrix)
        self.root_frames = self.rest_frames
        self.levels, self.switches, self.errors, self.ms, self.fine_ms = [], 0, [], [], []
        ensure_level_material(self.solver.finest_level)  # the scale of its colours
        # The strips as ribbons: two vertices per skeleton point, the strips side by side.
        levels = np.asarray(self.solver.strip_levels, dtype=np.float32)
        ribbon = 2 * self.solver.skeleton_points_num
        self.strip_offsets = np.arange(len(levels) + 1, dtype=np.int32) * ribbon
        self.strip_levels = np.repeat(levels, ribbon)

    def _camera(self):
        camera = self.options.camera or self.scene.camera
        if camera is None:
            raise HairdynError(
                f"{NAME} needs a camera: set Camera in its section, or give the scene a camera"
            )
        return camera

    # The StrandSolver's interface, as the Strands method uses it.

    def add_pass(self, substep_pass):
        """The swept spheres' passes run over the active skeletons, each seen as its group's
        swept-sphere volume around strands of the pass's thickness; the fine reference runs
        the same pass (a pass of its own, with the same parameters)."""
        kinds = (self.native.HairHairPass, self.native.SsvObjectPass)
        if not isinstance(substep_pass, kinds):
            raise NoPasses(f"{NAME} runs only the swept spheres' substep passes")
        self.solver.add_pass(substep_pass, substep_pass.params.thickness)
        if self.fine is not None:
            if isinstance(substep_pass, self.native.HairHairPass):
                twin = self.native.HairHairPass(substep_pass.params)
            else:
                twin = self.native.SsvObjectPass(self.colliders, substep_pass.params)
            self.fine.add_pass(twin)

    def set_radii(self, radii):
        """The Curves radius attribute for the passes' volumes: a group's at each skeleton
        point is its widest strand's radius there plus its spread; the fine reference's strands
        take their own."""
        self.solver.set_radii(radii)
        if self.fine is not None:
            self.fine.set_radii(radii)

    def pass_ms(self, name):
        return self.solver.pass_ms(name)

    def set_colliders(self, colliders, params):
        """Every skeleton collides (and the colliders hide hair from the camera, §6.1, and the
        placed strands stay out of them); the fine reference collides the same way. None after
        colliders were set (body collision by swept spheres only): the maps are off for the
        skeletons, and the colliders still hide hair and keep the placed strands out."""
        if colliders is None and self.colliders is not None:
            self.solver.set_colliders(None, params)
            self.solver.set_occluders(self.colliders)
            self.solver.set_bodies(self.colliders)
        else:
            self.solver.set_colliders(colliders, params)
            self.colliders = colliders
        if self.fine is not None:
            self.fine.set_colliders(colliders, params)

    def read_scene(self, depsgraph):
        self.camera = self._camera()  # the scene's camera may change (markers)
        self.view_projection = view_projection(self.camera, self.scene, depsgraph)

    def step(self, frame_dt, head_matrix):
        start = time.perf_counter()
        self.solver.step(frame_dt, head_matrix, self.view_projection)
        self.ms.append((time.perf_counter() - start) * 1000.0)
        self.levels.append(list(self.solver.skeletons_per_level))
        self.switches += self.solver.lod_switches
        # The StrandSolver's root frames: the rest frames turned with the head.
        turn = rotation(head_matrix) @ self.rest_rotation.T
        self.root_frames = np.ascontiguousarray(self.rest_frames @ turn.T, dtype=np.float32)
        if self.fine is not None:
            start = time.perf_counter()
            self.fine.step(frame_dt, head_matrix)
            self.fine_ms.append((time.perf_counter() - start) * 1000.0)
            distance = self.native.mean_distance(self.solver.positions, self.fine.positions)
            self.errors.append(distance / self.hair_length)

    @property
    def positions(self):
        return self.solver.positions

    @property
    def diverged_num(self):
        """The fine reference's diverged strands (the LodSolver does not count its own: its
        non-finite output is refused by Simulation.frame)."""
        return 0 if self.fine is None else self.fine.diverged_num

    @property
    def contacts_num(self):
        """The skeletons' contacts over the last step's substeps."""
        return self.solver.contacts_num

    # The extension's attached figures.

    def streams(self):
        """The strips as ribbons (LodSolver.strip_ribbons, `lod_level` per vertex), shown in
        output_strips while lod_options.show_strips is on."""
        return {
            "strips": Stream(
                {"position": 3, "lod_level": 1},
                lambda: {"position": self.solver.strip_ribbons, "lod_level": self.strip_levels},
                int(self.strip_offsets[-1]),
                offsets=self.strip_offsets,
                outputs=("output_strips",),
                shown_by="lod_options.show_strips",
            )
        }

    def strand_attributes(self):
        return {"lod_level": np.asarray(self.solver.lod_level, dtype=np.float32)}

    def report(self):
        """skeletons_per_level (min / mean / max over the frames, per level from the top
        strips), lod_switches (splits, merges and occlusion collapses over the run), lod_ms and,
        measured, lod_error (mean over the frames; lod_error_max the worst frame) and
        lod_fine_ms."""
        counts = np.array(self.levels, dtype=np.float64).reshape(-1, self.solver.max_depth + 1)
        figures = {
            "skeletons_per_level": {
                "min": [int(v) for v in counts.min(axis=0)] if len(counts) else [],
                "mean": [float(v) for v in counts.mean(axis=0)] if len(counts) else [],
                "max": [int(v) for v in counts.max(axis=0)] if len(counts) else [],
            },
            "lod_switches": int(self.switches),
            "lod_nodes": int(self.solver.nodes_num),
            "lod_skeleton_points": int(self.solver.skeleton_points_num),
            "lod_strips": int(self.solver.top_nodes_num),
            "lod_coarsest_level": int(self.solver.coarsest_level),
            "lod_finest_level": int(self.solver.finest_level),
            "lod_camera": self.camera.name,
            "lod_ms": float(np.median(self.ms)) if self.ms else 0.0,
        }
        if self.fine is not None:
            figures.update(
                lod_error=float(np.mean(self.errors)) if self.errors else 0.0,
                lod_error_max=float(np.max(self.errors)) if self.errors else 0.0,
                lod_fine_ms=float(np.median(self.fine_ms)) if self.fine_ms else 0.0,
            )
        return figures


def make_solver(build, params, root_normals):
    if not build.settings.lod.enabled:
        return None
    pins = build.groom.pins_num
    if pins:
        raise HairdynError(
            f"{NAME} cannot hold pinned points: {pins} points of the hair are pinned "
            "(the 'hairdyn_fixed' attribute) and it simulates strips and clusters, not the "
            "strands that carry them. Turn Level of Detail off, or remove the attribute"
        )
    return LodStrands(build, params, root_normals)


def attach(solver, _build):
    return solver if isinstance(solver, LodStrands) else None


def _draw(layout, settings):
    layout.prop(settings.lod_options, "camera")
    layout.prop(settings.lod_options, "measure_error")
    layout.prop(settings.lod_options, "color_by_level")
    row = layout.row()
    row.prop(settings.lod_options, "show_strips")
    row.prop(settings, "output_strips", text="")
    layout.label(text="Not with volume smoothing or targeting", icon='INFO')
    layout.label(text="Not with pinned points (hairdyn_fixed)", icon='INFO')


EXTENSION = Extension(
    "lod",
    attach,
    params={"lod": "LodParams"},
    options={"lod_options": HairdynLodOptions},
    defaults={"lod": {"enabled": False}},  # it needs a camera: an artist turns it on
    solver=make_solver,
    label=NAME,
    dress=dress,
    sections=(
        Section(
            "Level of Detail (Ward & Lin 2003)",
            "lod",
            (
                "distance_near",
                "distance_far",
                "velocity_slow",
                "velocity_fast",
                "finest_level",
                "coarsest_level",
                "merge_threshold",
            ),
            rest=True,
            header="enabled",
            draw=_draw,
        ),
    ),
)
