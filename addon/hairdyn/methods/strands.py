"""Owns: the Strands method (Kurihara 1993 angular strand dynamics, Ward & Lin 2003 implicit
hinges; native StrandSolver) with its child hairs (Kurihara 1993 §4), and the extensions that
plug groom-wide substep passes (volume, hair-hair collision, ...) into it.

An extension is an `Extension`: the settings group(s) it adds (a native parameter struct, whose
PropertyGroup is generated, and/or add-on-only options), its panel sections, and
`attach(solver, build)`, called once the solver is built, which adds its native pass. An
extension may instead replace the solver (`solver(build, params, root_normals)`: level of
detail); a replacement that cannot run a pass raises `NoPasses` (saying what it runs) from
add_pass, and the combination is refused with a sentence naming both.
`register_extension()` must run before the add-on registers (import it from methods/__init__).
"""

import numpy as np

from ..errors import HairdynError
from .base import Method, Section, Stream, nearest

EXPLICIT = 0  # StrandParams.integrator's choices: explicit, implicit


class Extension:
    """Something the strand solver runs each substep (native SubstepPass): params {settings
    attribute: native struct name}, options {settings attribute: PropertyGroup class},
    defaults (Method.defaults), sections (Section ...), attach(solver, build) adds the pass to
    a built solver and returns an `Attached` (or None when the artist left it off); `solver`,
    when given, is solver(build, strand_params, root_normals) -> a stand-in for the
    StrandSolver (or None when the artist left it off). `label` names it in messages; `dress`,
    when given, is dress(hair_obj, frame), the Strands method's dress_outputs for it (it runs on
    every frame of the method, attached or not: it acts on what it finds in the frame)."""

    def __init__(
        self,
        name,
        attach,
        params=None,
        options=None,
        sections=(),
        solver=None,
        defaults=None,
        label=None,
        dress=None,
    ):
        self.name, self.attach, self.solver, self.dress = name, attach, solver, dress
        self.params, self.options = dict(params or {}), dict(options or {})
        self.defaults = dict(defaults or {})
        self.sections = tuple(sections)
        self.label = label or (self.sections[0].label if self.sections else name)


class NoPasses(Exception):
    """Raised by a solver stand-in's add_pass: it cannot run that pass (its argument: what the
    stand-in runs, a clause naming it, for the message)."""


class Attached:
    """An extension at work on one solver: after_step() once per frame, strand_columns and
    strand_attributes() (per strand point arrays for the output Curves and the cache),
    streams() of its own (Method.streams), frame_baked() once a frame is in a bake's cache, and
    its report fields."""

    strand_columns = {}
    child_columns = {}  # what of strand_columns the child hairs carry too

    def after_step(self, solver, head_matrix):
        pass

    def strand_attributes(self):
        return {}

    def child_attributes(self, children):
        """Per child point arrays for child_columns (children: the native ChildHairs)."""
        return {}

    def streams(self):
        return {}

    def frame_baked(self, hair_obj, cache, frame):
        pass

    def report(self):
        return {}


def root_normals(groom, head_mesh):
    """Per strand, the world normal of the head-mesh vertex nearest to its root."""
    closest = nearest(groom.positions_wo[groom.curve_offsets[:-1]], head_mesh.vertices_wo())[0]
    return np.ascontiguousarray(head_mesh.normals_wo()[closest[:, 0]], dtype=np.float32)


def scalp_points(groom, head_mesh, count, seed):
    """`count` random points on the part of the head the groom's roots cover: area-weighted
    over the triangles whose corners all lie within twice the typical root spacing of a
    root."""
    roots = groom.positions_wo[groom.curve_offsets[:-1]].astype(np.float64)
    if len(roots) > 1:
        spacing = np.median(nearest(roots, roots, 2)[1].max(axis=1))  # itself, and the next
    else:
        spacing = np.linalg.norm(groom.positions_wo[1] - groom.positions_wo[0])
    vertices = head_mesh.vertices_wo().astype(np.float64)
    near = nearest(vertices, roots)[1][:, 0] <= 2.0 * spacing
    triangles = head_mesh.triangles[near[head_mesh.triangles].all(axis=1)]
    if len(triangles) == 0:
        raise HairdynError(
            "No part of the head lies under the hair roots: interpolated "
            "children need the roots on the head's surface"
        )
    corners = vertices[triangles]
    areas = 0.5 * np.linalg.norm(
        np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
    )
    rng = np.random.default_rng(seed)
    chosen = rng.choice(len(triangles), size=count, p=areas / areas.sum())
    u, v = rng.random(count), rng.random(count)
    flip = u + v > 1.0
    u[flip], v[flip] = 1.0 - u[flip], 1.0 - v[flip]
    a, b, c = corners[chosen, 0], corners[chosen, 1], corners[chosen, 2]
    points = a + u[:, None] * (b - a) + v[:, None] * (c - a)
    return np.ascontiguousarray(points, dtype=np.float32)


class Strands(Method):
    identifier = "STRANDS"
    label = "Strands"
    description = (
        "Strand dynamics: chains of rigid segments with hinge springs (Kurihara "
        "1993), implicit integration (Ward & Lin 2003)"
    )
    params = {"strands": "StrandParams"}
    collision = ("maps", "response", "report")
    sections = (
        Section(
            "Dynamics",
            "strands",
            ("integrator", "substeps", "k_theta", "k_phi", "damping", "line_density", "air_drag"),
            open=True,
        ),
        Section("Wind", "wind", rest=True),  # the shared WindParams group
        Section(
            "Child Hairs",
            "strands",
            ("children_per_guide", "child_mode", "child_spread", "seed"),
            active={"child_spread": lambda group: group.child_mode == 'CLUSTER'},
        ),
        Section("More Strand Settings", "strands", rest=True),  # fields added to StrandParams later
    )
    shows = ("output_children",)
    extensions = []  # Extension, in the order their passes run

    def __init__(self, build):
        from .. import bridge

        params = build.params("strands")
        groom = build.groom
        head_mesh = bridge.read_mesh(build.head, build.depsgraph)
        normals = root_normals(groom, head_mesh)
        self.solver = self._make_solver(build, params, normals)
        self.explicit = params.integrator == EXPLICIT
        self.children = self._make_children(build, params, head_mesh)
        if build.colliders is not None:
            self.solver.set_colliders(build.colliders.set, build.colliders.params)
        self.attached = []
        for extension in self.extensions:
            try:
                item = extension.attach(self.solver, build)
            except NoPasses as error:
                raise HairdynError(
                    f"{error}, so it cannot be combined with {extension.label}: turn one of "
                    "them off"
                ) from None
            if item is not None:
                self.attached.append(item)
        self.strand_columns = {
            name: width for item in self.attached for name, width in item.strand_columns.items()
        }

    def _make_solver(self, build, params, normals):
        """The native StrandSolver, or the stand-in an extension replaces it with."""
        for extension in self.extensions:
            if extension.solver is not None:
                solver = extension.solver(build, params, normals)
                if solver is not None:
                    return solver
        groom = build.groom
        solver = build.native.StrandSolver(
            groom.curve_offsets,
            groom.positions_wo,
            build.head_matrix,
            normals,
            params,
            build.params("wind"),
        )
        if groom.pins_num:  # pinned points (hairdyn_fixed) are held by the head like roots
            solver.set_pinned(groom.fixed)
        return solver

    def _make_children(self, build, params, head_mesh):
        """Kurihara 1993 §4: child hairs clustered around the guides, or spread over the
        scalp between them; None when there are none."""
        count, groom = params.children_per_guide, build.groom
        if count == 0:
            return None
        if params.child_mode == 0:  # cluster
            return build.native.ChildHairs.around_guides(
                groom.curve_offsets, count, params.child_spread, params.seed
            )
        roots = scalp_points(groom, head_mesh, count * groom.curves_num, params.seed)
        return build.native.ChildHairs.between_guides(
            groom.curve_offsets, groom.positions_wo, self.solver.root_frames, roots
        )

    def read_scene(self, depsgraph):
        read = getattr(self.solver, "read_scene", None)  # a stand-in that follows a camera
        if read is not None:
            read(depsgraph)

    def step(self, frame_dt, head_matrix):
        self.solver.step(frame_dt, head_matrix)
        if self.solver.diverged_num:
            raise HairdynError(
                f"{self.solver.diverged_num} strands diverged (a point passed 1,000 m/s or "
                "stopped being finite): "
                + ("use the implicit integrator, " if self.explicit else "")
                + "more substeps, softer hinges, or less wind and air drag (a gale whips "
                "thin, light hair faster than the steps follow)"
            )
        for item in self.attached:
            item.after_step(self.solver, head_matrix)
        if self.children is not None:
            self.children.update(self.solver.positions, self.solver.root_frames)

    def strand_attributes(self):
        return {k: v for item in self.attached for k, v in item.strand_attributes().items()}

    @classmethod
    def dress_outputs(cls, hair_obj, frame):
        for extension in cls.extensions:
            if extension.dress is not None:
                extension.dress(hair_obj, frame)

    def frame_baked(self, hair_obj, cache, frame):
        for item in self.attached:
            item.frame_baked(hair_obj, cache, frame)

    def report(self):
        return {k: v for item in self.attached for k, v in item.report().items()}

    def contacts_num(self):
        return int(self.solver.contacts_num)

    @property
    def positions(self):
        return self.solver.positions

    def streams(self):
        streams = {name: s for item in self.attached for name, s in item.streams().items()}
        if self.children is None:
            return streams
        offsets = np.asarray(self.children.curve_offsets)
        columns = {"position": 3}
        for item in self.attached:
            columns.update(item.child_columns)

        def read():
            arrays = {"position": self.children.positions}
            for item in self.attached:
                arrays.update(item.child_attributes(self.children))
            return arrays

        streams["children"] = Stream(
            columns,
            read,
            int(offsets[-1]),
            offsets=offsets,
            outputs=("output_children",),
        )
        return streams


def register_extension(extension):
    """Adds a substep pass with its settings to the Strands method (before the add-on
    registers: the settings groups and panels are made at registration)."""
    Strands.extensions.append(extension)
    Strands.params = {**Strands.params, **extension.params}
    Strands.options = {**Strands.options, **extension.options}
    Strands.defaults = {**Strands.defaults, **extension.defaults}
    Strands.sections = Strands.sections + extension.sections
