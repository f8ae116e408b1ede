"""Owns: what a method adapter is. Every method (follow, strands, LCP, and the next ones)
implements `Method`: built from the scene (`Build`), stepped once per frame, its strand
positions, the other point sets it writes (`Stream`: layout and arrays together), its own
report fields, and what the panel shows for it (`Section`). Nothing here knows a method by
name; `methods/__init__.py` is the registry.
"""

import bpy
import numpy as np

from .. import parameters


def node_material(name, build):
    """The material `name`; made the first time with nodes, its tree emptied and filled by
    build(nodes, links)."""
    material = bpy.data.materials.get(name)
    if material is None:
        material = bpy.data.materials.new(name)
        if material.node_tree is None:  # newer Blender gives every material its node tree
            material.use_nodes = True
        tree = material.node_tree
        tree.nodes.clear()
        build(tree.nodes, tree.links)
    return material


def object_poll(kind):
    """A PointerProperty poll that offers only objects of this type ('MESH', 'CURVES', ...)."""

    def poll(_self, obj):
        return obj.type == kind

    return poll


class Stream:
    """A point set a method writes every frame besides the strands: its layout (points,
    columns {name: width} in order, curve offsets for curves), `read()` giving its arrays for
    the current frame, and the output objects that show it: settings pointers such as
    "output_children" (curves), "output_points" (points, which then show this stream
    instead of the strand points) or "output_strips" (ribbons); `billboards`: shown as hair
    cards (Bando 2003 §4); `shown_by`: the path, from the hair object's settings, of the switch
    that shows its output objects (else they always show)."""

    def __init__(
        self, columns, read, points_num, offsets=None, outputs=(), billboards=False, shown_by=None
    ):
        self.columns = dict(columns)
        self.read = read
        self.points_num = int(points_num)
        self.offsets = None if offsets is None else np.asarray(offsets, dtype=np.int32)
        self.outputs = tuple(outputs)
        self.billboards = billboards
        self.shown_by = shown_by

    def layout(self):
        """What Cache.create takes for this stream."""
        return {"points": self.points_num, "columns": self.columns, "offsets": self.offsets}

    def output(self):
        """What playback needs to show it again (recorded in the cache manifest)."""
        output = {"outputs": list(self.outputs), "billboards": self.billboards}
        if self.shown_by is not None:
            output["shown_by"] = self.shown_by
        return output


class Section:
    """One panel section of a method: `fields` of the settings group `group`, then with
    `rest` every field of the group no section of the method names (so a field added to the
    native struct shows up without touching the add-on); `active` {field: predicate(group)}
    greys a row out; `draw(layout, settings)` draws extra rows first; `header` names a boolean
    field of the group drawn in the section's header as its on/off switch (the rows grey out
    while it is off)."""

    def __init__(
        self,
        label,
        group,
        fields=(),
        rest=False,
        active=None,
        draw=None,
        open=False,
        header=None,
    ):
        self.label, self.group, self.fields, self.rest = label, group, tuple(fields), rest
        self.active = active or {}
        self.draw, self.open, self.header = draw, open, header


class Build:
    """What a method is built from, at the rest frame: the hair object and its settings, the
    groom (world space), the head and its matrix, the scene, the depsgraph and the native
    module; `colliders` (colliders.Colliders, or None when collision is off) are built when
    first asked for, so a method checks its own input (the groom) before them."""

    def __init__(
        self, hair_obj, groom, head, head_matrix, make_colliders, scene, depsgraph, native
    ):
        self.hair_obj, self.settings = hair_obj, hair_obj.hairdyn
        self.groom, self.head, self.head_matrix = groom, head, head_matrix
        self.scene, self.depsgraph, self.native = scene, depsgraph, native
        self._make_colliders, self._colliders = make_colliders, []

    @property
    def colliders(self):
        if not self._colliders:
            self._colliders.append(self._make_colliders())
        return self._colliders[0]

    def params(self, group_name):
        """The native parameter struct of the settings group `group_name`, with the scene's
        fields (gravity) filled in."""
        group = getattr(self.settings, group_name)
        return parameters.native_params(
            group, getattr(self.native, parameters.struct_name(group)), self.scene
        )

    @property
    def collider_set(self):
        return None if self.colliders is None else self.colliders.set


class Method:
    """One simulation method. Subclass it, fill the class attributes, implement __init__ and
    step, and add the class to the registry (methods.register)."""

    identifier = ""  # enum identifier ("STRANDS"); lower-cased it is the cache's "solver"
    label = ""
    description = ""
    params = {}  # settings attribute -> native struct name it reads ({"strands": "StrandParams"})
    options = {}  # settings attribute -> PropertyGroup class of add-on-only options
    # settings attribute -> {field: default}: where the add-on's default differs from the
    # native struct's (level of detail is off until an artist turns it on: it needs a camera)
    defaults = {}
    collision = ("report",)  # collision settings it reads: "maps", "response", "report"
    sections = ()  # Section(...)s of its panel
    shows = ()  # output settings the Output panel shows for it ("output_children", ...)

    def __init__(self, build):
        """Build the solver from the scene at the rest frame (a ValueError from the native
        module becomes a HairdynError naming the object)."""
        raise NotImplementedError

    def read_scene(self, depsgraph):
        """Read what it follows in the scene at the current frame besides the head and the
        colliders (a camera), before step(); most methods follow nothing else."""

    def step(self, frame_dt, head_matrix):
        """Advance one frame of frame_dt seconds to the head's new world matrix."""
        raise NotImplementedError

    @property
    def positions(self):
        """World-space strand positions (N, 3) float32 after the last step."""
        raise NotImplementedError

    strand_columns = {}  # per strand point attributes it adds: {name: width}

    def strand_attributes(self):
        """{name: (N,) or (N, k) array} for strand_columns, after the last step."""
        return {}

    def streams(self):
        """{name: Stream} of the other point sets it writes (names other than "frame")."""
        return {}

    def report(self):
        """Its own figures for the run's report."""
        return {}

    @classmethod
    def dress_outputs(cls, hair_obj, frame):
        """After a frame of it was written into the hair object's output objects (they exist
        from then on), simulated or played back from its bake: what it shows there beyond
        positions and attributes (materials). frame: what outputs.write took."""

    def frame_baked(self, hair_obj, cache, frame):
        """After `frame` was written into the bake's `cache` (files beside it go in
        cache.directory)."""

    def contacts_num(self):
        """Points its collision response touched in the last step (0 for a method that does
        not count them); the frame record's `contacts`."""
        return 0


def nearest(points, targets, k=1, chunk=1024):
    """The k targets nearest to each point (brute force in chunks): indices and distances,
    (P, k) each, in no particular order among the k."""
    points = np.asarray(points, dtype=np.float64)
    targets = np.asarray(targets, dtype=np.float64)
    k = min(k, len(targets))
    indices = np.empty((len(points), k), dtype=np.int64)
    distances = np.empty((len(points), k))
    # One (chunk, T) array per axis, summed in the order a sum over the axes takes (the same
    # bits), instead of a (chunk, T, 3) one reduced: 8-10x faster.
    tx, ty, tz = (np.ascontiguousarray(targets[:, axis]) for axis in range(3))
    for start in range(0, len(points), chunk):
        p = points[start : start + chunk]
        block = (p[:, 0:1] - tx) ** 2
        block += (p[:, 1:2] - ty) ** 2
        block += (p[:, 2:3] - tz) ** 2
        found = (
            np.argpartition(block, k - 1, axis=1)[:, :k] if k > 1 else block.argmin(axis=1)[:, None]
        )
        indices[start : start + chunk] = found
        distances[start : start + chunk] = np.sqrt(np.take_along_axis(block, found, axis=1))
    return indices, distances
