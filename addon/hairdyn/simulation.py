"""One hair object's simulation: groom in, native solver, results out.

The flow is one way: `Simulation(...)` reads the groom, the head and the colliders at the
rest frame and builds the native solver; `step()` reads the head's and the colliders'
transforms for the current frame and advances the solver; `frame_arrays()` is what a frame
produced, and `write()` puts it into the output objects. `Runner` steps a frame range for
the operators, the headless entry point and the bake; playback steps live.
"""
import time
from pathlib import Path

import bpy
import numpy as np

from . import billboards, bridge, native, playback, properties
from .cache import Cache
from .errors import HairdynError


def point_tangents(curve_offsets, positions):
    """Unit direction of each point along its strand (forward difference, backward at tips)."""
    forward = np.empty_like(positions)
    forward[:-1] = positions[1:] - positions[:-1]
    tips = curve_offsets[1:] - 1
    forward[tips] = positions[tips] - positions[tips - 1]
    lengths = np.linalg.norm(forward, axis=1, keepdims=True)
    return np.ascontiguousarray(forward / np.maximum(lengths, 1e-30), dtype=np.float32)


def head_object(hair_obj, groom):
    """The mesh the roots follow: the artist's choice, else the hair's surface / emitter."""
    head = hair_obj.hairdyn.head or groom.surface
    if head is None:
        raise HairdynError(f"'{hair_obj.name}' has no head: set Head in the hairdyn panel, or "
                           "attach the curves to a surface")
    return head


def root_normals(groom, head_mesh):
    """Per strand, the world normal of the head-mesh vertex nearest to its root."""
    closest = nearest(groom.positions_wo[groom.curve_offsets[:-1]], head_mesh.vertices_wo())[0]
    return np.ascontiguousarray(head_mesh.normals_wo()[closest[:, 0]], dtype=np.float32)


def nearest(points, targets, k=1, chunk=1024):
    """The k targets nearest to each point (brute force in chunks): indices and distances,
    (P, k) each, in no particular order among the k."""
    points = np.asarray(points, dtype=np.float64)
    targets = np.asarray(targets, dtype=np.float64)
    k = min(k, len(targets))
    indices = np.empty((len(points), k), dtype=np.int64)
    distances = np.empty((len(points), k))
    for start in range(0, len(points), chunk):
        block = ((points[start:start + chunk, None, :] - targets[None, :, :]) ** 2).sum(axis=2)
        found = np.argpartition(block, k - 1, axis=1)[:, :k] if k > 1 else block.argmin(axis=1)[:, None]
        indices[start:start + chunk] = found
        distances[start:start + chunk] = np.sqrt(np.take_along_axis(block, found, axis=1))
    return indices, distances


def blend_weights(distances):
    """Inverse-distance weights over each row, summing to 1."""
    weights = 1.0 / np.maximum(distances, 1e-6)
    return weights / weights.sum(axis=1, keepdims=True)


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
        raise HairdynError("No part of the head lies under the hair roots: interpolated "
                           "children need the roots on the head's surface")
    corners = vertices[triangles]
    areas = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0],
                                          corners[:, 2] - corners[:, 0]), axis=1)
    rng = np.random.default_rng(seed)
    chosen = rng.choice(len(triangles), size=count, p=areas / areas.sum())
    u, v = rng.random(count), rng.random(count)
    flip = u + v > 1.0
    u[flip], v[flip] = 1.0 - u[flip], 1.0 - v[flip]
    a, b, c = corners[chosen, 0], corners[chosen, 1], corners[chosen, 2]
    points = a + u[:, None] * (b - a) + v[:, None] * (c - a)
    return np.ascontiguousarray(points, dtype=np.float32)


def scalp_triangles(head, mesh, settings):
    """The head mesh's triangles the artist marked as scalp (Bando 2003 §3.2): those whose
    corners all lie in the scalp vertex group, or those of the selected faces."""
    if settings.lcp_scalp_source == 'FACES':
        selected = bridge.selected_faces(head)
        faces_num = int(mesh.triangle_faces.max()) + 1 if len(mesh.triangle_faces) else 0
        if faces_num != len(selected):
            raise HairdynError(f"The modifiers of '{head.name}' change its faces, so its face "
                               "selection does not mark the scalp: use a vertex group")
        triangles = mesh.triangles[selected[mesh.triangle_faces]]
        if len(triangles) == 0:
            raise HairdynError(f"No face of '{head.name}' is selected: select the scalp's faces "
                               "in Edit Mode (LCP samples the hair volume over them), or mark "
                               "the scalp with a vertex group")
        return triangles
    group_name = settings.lcp_scalp
    members = bridge.vertex_group_members(head, {group_name}, len(mesh.vertices)).get(group_name)
    if members is None or len(members) == 0:
        raise HairdynError(f"'{head.name}' has no vertex group '{group_name}' marking the scalp: "
                           "LCP samples the hair volume over it (set Scalp in the LCP panel, or "
                           "take the scalp from the selected faces)")
    inside = np.zeros(len(mesh.vertices), dtype=bool)
    inside[members] = True
    triangles = mesh.triangles[inside[mesh.triangles].all(axis=1)]
    if len(triangles) == 0:
        raise HairdynError(f"The scalp group '{group_name}' of '{head.name}' covers no face")
    return triangles


def scalp_patch(head, depsgraph, settings):
    """The scalp as a mesh of its own (Bando 2003 §3.2): world-space vertices and triangles of
    the part of the head the artist marked, and each patch vertex's index in the head mesh."""
    mesh = bridge.read_mesh(head, depsgraph)
    triangles = scalp_triangles(head, mesh, settings)
    used = np.unique(triangles)
    remap = np.full(len(mesh.vertices), -1, dtype=np.int32)
    remap[used] = np.arange(len(used), dtype=np.int32)
    return (np.ascontiguousarray(mesh.vertices_wo()[used]),
            np.ascontiguousarray(remap[triangles], dtype=np.int32), used)


def length_map(settings, groom, head, scalp_vertices_wo, scalp_head_vertices):
    """The length map L(u, v) of Bando 2003 §3.2 as the sampler takes it: (per scalp vertex
    weights or None, a grey image (H, W) or None, L_max in m). From the groom (the longest
    strand is L_max), or an image or the head's vertex weights scaled by Max Length."""
    source = settings.lcp_length_source
    if source == 'GROOM':
        weights, longest = length_weights(groom, scalp_vertices_wo)
        return weights, None, longest
    if source == 'IMAGE':
        return None, length_image(settings.lcp_length_image), settings.lcp.max_length
    return (group_length_weights(head, settings.lcp_length_group, scalp_head_vertices), None,
            settings.lcp.max_length)


def length_image(image):
    """The grey values of the length-map image, rows from v = 0; a HairdynError when it
    would grow no hair."""
    if image is None:
        raise HairdynError("Empty length map: no Length Image is set (choose a grey image in "
                           "the LCP panel; white grows hair of Max Length, black none)")
    grey = bridge.image_grey(image)
    if grey.size == 0:
        raise HairdynError(f"Empty length map: the image '{image.name}' has no pixels (is its "
                           "file missing?)")
    if not (grey > 0.0).any():
        raise HairdynError(f"Empty length map: the image '{image.name}' is black everywhere, "
                           "so no hair would grow (white grows hair of Max Length)")
    return grey


def group_length_weights(head, group_name, scalp_head_vertices):
    """Per scalp vertex, its weight in the head's vertex group `group_name`; a HairdynError
    when the group is missing or zero over the whole scalp."""
    weights = bridge.vertex_group_weights(head, {group_name},
                                          int(scalp_head_vertices.max()) + 1).get(group_name)
    if weights is None:
        raise HairdynError(f"Empty length map: '{head.name}' has no vertex group '{group_name}' "
                           "(set Length Group in the LCP panel to the group whose weights are "
                           "the hair lengths)")
    weights = weights[scalp_head_vertices]
    if not (weights > 0.0).any():
        raise HairdynError(f"Empty length map: the weights of the group '{group_name}' are zero "
                           f"over the whole scalp of '{head.name}', so no hair would grow")
    return np.ascontiguousarray(weights, dtype=np.float32)


def segment_lengths(groom):
    """Per point, the length of the segment that ends at it (0 at the roots), float64."""
    lengths = np.zeros(len(groom.positions_wo))
    lengths[1:] = np.linalg.norm(np.diff(groom.positions_wo.astype(np.float64), axis=0), axis=1)
    lengths[groom.curve_offsets[:-1]] = 0.0  # no segment from one strand's tip to the next root
    return lengths


def length_weights(groom, scalp_vertices_wo):
    """The length map of Bando 2003 §3.2 from a groom: per scalp vertex, the length of the
    strand rooted nearest to it, over the longest strand; and that longest length (m)."""
    lengths = np.add.reduceat(segment_lengths(groom), groom.curve_offsets[:-1])
    closest = nearest(scalp_vertices_wo, groom.positions_wo[groom.curve_offsets[:-1]])[0][:, 0]
    longest = float(lengths.max())
    return np.ascontiguousarray(lengths[closest] / longest, dtype=np.float32), longest


class ParticleSkin:
    """LCP's motion on real strands (Bando 2003 §4): every strand point moves with the
    particles near its (u, v, s), in the distance of eq. 3 (scalp points apart, and arc
    length). A strand point's scalp point is its root and s its arc length; a particle's
    scalp point is where its hair leaves the scalp: x − s t for the fixed root particles, and
    for the others that of the root particles nearest in (u, v). In the head's frame, the
    point is displaced by the inverse-distance blend of the displacements of the
    `neighbours_num` nearest particles since rest, so the groom keeps its shape at rest and
    takes the particles' motion, and the head's own motion is carried exactly. Roots follow the
    head rigidly; then, root to tip, each point is put at its rest distance from the previous
    one toward where it was carried, or where the body's surface is when that is inside a
    collider, so strands never stretch nor go through the body."""

    def __init__(self, groom, solver, head_matrix, neighbours_num=4):
        offsets = groom.curve_offsets
        counts = np.diff(offsets)
        self.roots = offsets[:-1]
        points = groom.positions_wo.astype(np.float64)
        self.rest_lengths = segment_lengths(groom)
        arc = np.cumsum(self.rest_lengths)
        arc -= np.repeat(arc[self.roots], counts)
        strand_points = np.column_stack([np.repeat(points[self.roots], counts, axis=0), arc])

        x = np.asarray(solver.positions, dtype=np.float64)
        t = np.asarray(solver.directions, dtype=np.float64)
        s = np.asarray(solver.s, dtype=np.float64)
        scalp = x - s[:, None] * t
        root = s < 0.0
        if root.any() and not root.all():
            uv = np.column_stack([solver.u, solver.v]).astype(np.float64)
            near, distances = nearest(uv[~root], uv[root], 3)
            scalp[~root] = (blend_weights(distances)[:, :, None] * scalp[root][near]).sum(axis=1)
        self.neighbours, distances = nearest(strand_points, np.column_stack([scalp, s]),
                                             neighbours_num)
        self.weights = blend_weights(distances)
        self.rest_head = bridge.to_local(head_matrix, points)
        self.particles_rest_head = bridge.to_local(head_matrix, x)
        # Point k of every strand long enough to have one.
        self.layers = [self.roots[counts > k] + k for k in range(1, int(counts.max()))]

    def apply(self, particles_wo, head_matrix, colliders=None):
        """Strand positions (N, 3) float32 for the particles' current positions; `colliders`
        (a native ColliderSet, or None) keeps the points out of the body."""
        moved = bridge.to_local(head_matrix, np.asarray(particles_wo, dtype=np.float64))
        moved -= self.particles_rest_head
        targets = bridge.to_world(head_matrix, self.rest_head + (
            self.weights[:, :, None] * moved[self.neighbours]).sum(axis=1))
        positions = np.empty_like(targets)
        positions[self.roots] = bridge.to_world(head_matrix, self.rest_head[self.roots])

        def toward(layer, target):
            step = target - positions[layer - 1]
            length = np.maximum(np.linalg.norm(step, axis=1, keepdims=True), 1e-12)
            return positions[layer - 1] + step * (self.rest_lengths[layer, None] / length)

        for layer in self.layers:  # root to tip, all strands at once
            positions[layer] = toward(layer, targets[layer])
            for _ in range(0 if colliders is None else 2):  # swung out where it went inside
                contacts = colliders.find_contacts(positions[layer])
                inside = contacts["hit"] & (contacts["depth"] > 0.0)
                if not inside.any():
                    break
                surface = contacts["surface_point"][inside] + 1e-4 * contacts["normal"][inside]
                positions[layer[inside]] = toward(layer[inside], surface)
        return positions


class Simulation:
    """Build at the rest frame (the scene on the first frame to simulate), then step() and
    frame_arrays() once per frame."""

    def __init__(self, hair_obj, depsgraph, scene):
        from . import colliders

        self.native = native.load()
        self.hair_obj = hair_obj
        self.settings = settings = hair_obj.hairdyn
        self.groom = bridge.read_groom(hair_obj, depsgraph)
        self.head = head_object(hair_obj, self.groom)
        self.method = settings.method
        head_matrix = bridge.object_matrix(self.head, depsgraph)
        self.colliders = None
        self.children = None
        self.skin = None  # LCP: how the strands follow the particles
        self.strand_positions = None
        try:
            if self.method == 'FOLLOW':
                self.solver = self.native.FollowSolver(
                    self.groom.curve_offsets, self.groom.positions_wo, head_matrix)
            elif self.method == 'STRANDS':
                params = properties.native_params(settings.strands, self.native.StrandParams)
                head_mesh = bridge.read_mesh(self.head, depsgraph)
                self.solver = self.native.StrandSolver(
                    self.groom.curve_offsets, self.groom.positions_wo, head_matrix,
                    root_normals(self.groom, head_mesh), params)
                self.children = self._make_children(params, head_mesh)
            elif self.method == 'LCP':
                self.solver = self._make_lcp(depsgraph, head_matrix)
            else:
                raise HairdynError(f"Unknown method '{self.method}'")
        except ValueError as error:
            raise HairdynError(f"'{hair_obj.name}': {error}") from None
        if settings.use_collision:  # Follow Head only reports penetration
            self.colliders = colliders.Colliders(hair_obj, self.head, scene, depsgraph)
            if self.method == 'STRANDS':
                self.solver.set_colliders(self.colliders.set, self.colliders.params)
            elif self.method == 'LCP':  # moves rest particles out of the body: skin after it
                self.solver.set_colliders(self.colliders.set)
        if self.method == 'LCP':
            self.skin = ParticleSkin(self.groom, self.solver, head_matrix)
            self.strand_positions = self.skin.apply(self.solver.positions, head_matrix,
                                                    self._collider_set())
        self.previous_positions = np.array(self.positions)
        self.velocities = np.zeros_like(self.previous_positions)
        self.collision_ms = 0.0

    def _make_lcp(self, depsgraph, head_matrix):
        """Bando 2003 §3.2: particles sampled over the scalp of the head up to the length map,
        or along the groom's strands."""
        settings = self.settings
        params = properties.native_params(settings.lcp, self.native.LcpParams)
        if settings.lcp_init == 'GROOM':
            particles = self.native.lcp_particles_from_groom(
                params, self.groom.curve_offsets, self.groom.positions_wo, self.groom.root_uvs)
        else:
            scalp_vertices, scalp_triangles, scalp_head_vertices = scalp_patch(
                self.head, depsgraph, settings)
            weights, image, params.max_length = length_map(
                settings, self.groom, self.head, scalp_vertices, scalp_head_vertices)
            particles = self.native.sample_lcp_particles(params, scalp_vertices, scalp_triangles,
                                                         weights, image)
        return self.native.LcpSolver(params, particles["positions"], particles["directions"],
                                     particles["u"], particles["v"], particles["s"], head_matrix)

    def _make_children(self, params, head_mesh):
        """Kurihara 1993 §4: child hairs clustered around the guides, or spread over the
        scalp between them; None when there are none."""
        count = params.children_per_guide
        if count == 0:
            return None
        if params.child_mode == 0:  # cluster
            return self.native.ChildHairs.around_guides(
                self.groom.curve_offsets, count, params.child_spread, params.seed)
        roots = scalp_points(self.groom, head_mesh, count * self.groom.curves_num, params.seed)
        return self.native.ChildHairs.between_guides(
            self.groom.curve_offsets, self.groom.positions_wo, self.solver.root_frames, roots)

    def _collider_set(self):
        return None if self.colliders is None else self.colliders.set

    @property
    def positions(self):
        """World-space strand positions (N, 3) float32: the solver's buffer (zero-copy), or
        for LCP the strands carried by the particles."""
        return self.solver.positions if self.skin is None else self.strand_positions

    def step(self, depsgraph, frame_dt):
        """Advance to the scene's current frame; returns the native stepping time in ms
        (collision queries included; collider updates are in self.collision_ms)."""
        head_matrix = bridge.object_matrix(self.head, depsgraph)
        if self.colliders is not None:
            start = time.perf_counter()
            self.colliders.update(depsgraph)
            self.collision_ms = (time.perf_counter() - start) * 1000.0
        start = time.perf_counter()
        self.solver.step(frame_dt, head_matrix)
        elapsed_ms = (time.perf_counter() - start) * 1000.0
        if self.skin is not None:
            self.strand_positions = self.skin.apply(self.solver.positions, head_matrix,
                                                    self._collider_set())
        positions = self.positions
        self.velocities = (positions - self.previous_positions) / np.float32(frame_dt)
        self.previous_positions[:] = positions
        if self.children is not None:
            self.children.update(positions, self.solver.root_frames)
        return elapsed_ms

    def stretch(self):
        return self.native.max_relative_stretch(self.groom.curve_offsets,
                                                self.groom.positions_wo, self.positions)

    def nonfinite_points(self):
        return self.native.count_nonfinite(self.positions)

    def penetration(self):
        """Exact penetration of the strands into the colliders' real triangles, or None."""
        if self.colliders is None:
            return None
        return self.colliders.penetration(self.positions)

    def frame_arrays(self):
        """Everything a frame produces, by name: what the cache stores and the outputs show.
        Never NaN: a broken frame raises instead."""
        broken = self.nonfinite_points()
        if broken:
            raise HairdynError(f"The simulation of '{self.hair_obj.name}' produced {broken} "
                               "points that are not finite numbers")
        positions = self.positions
        return {
            "position": positions,
            "velocity": self.velocities,
            "direction": point_tangents(self.groom.curve_offsets, positions),
        }

    @staticmethod
    def frame_columns():
        """Width of each array of frame_arrays(), in order."""
        return {"position": 3, "velocity": 3, "direction": 3}

    def children_arrays(self):
        """(curve_offsets, positions) of the child hairs, or None."""
        if self.children is None:
            return None
        return np.asarray(self.children.curve_offsets), self.children.positions

    def frame_streams(self):
        """The point sets besides the strands that a frame produces, by stream name: "children"
        (child hairs) and "particles" (LCP), as the cache stores them."""
        streams = {}
        if self.children is not None:
            streams["children"] = {"position": self.children.positions}
        particles = self.particle_arrays()
        if particles is not None:
            streams["particles"] = particles
        return streams

    def stream_layouts(self):
        """What Cache.create needs to know of frame_streams()."""
        layouts = {}
        if self.children is not None:
            offsets = np.asarray(self.children.curve_offsets)
            layouts["children"] = {"points": int(offsets[-1]), "columns": {"position": 3},
                                   "offsets": offsets}
        if self.skin is not None:
            layouts["particles"] = {"points": self.solver.particles_num, "columns": {
                "position": 3, "direction": 3, "velocity": 3, "density": 1, "u": 1, "v": 1,
                "s": 1}}
        return layouts

    def particle_arrays(self):
        """LCP: the particles and their attributes (Bando 2003 §4: direction t, density, u, v,
        s), or None for the strand methods."""
        if self.skin is None:
            return None
        solver = self.solver
        return {"position": solver.positions, "direction": solver.directions,
                "velocity": solver.velocities, "density": solver.density,
                "u": solver.u, "v": solver.v, "s": solver.s}

    def write(self, arrays):
        """A frame's arrays, and the child hairs, into the output objects; for LCP the point
        output shows the particles instead of the strand points."""
        write_outputs(self.hair_obj, self.groom.curve_offsets, arrays, self.children_arrays(),
                      self.particle_arrays())


def write_outputs(hair_obj, curve_offsets, arrays, children=None, points=None):
    """A frame's arrays into the hair object's output objects (created when missing):
    positions into the output Curves, all arrays as point attributes of the output mesh, and
    children=(curve_offsets, positions) into the child-hair Curves. `points` (arrays of
    other points, LCP's particles) replace the strand points in the point output."""
    settings, name = hair_obj.hairdyn, hair_obj.name
    if children is not None:
        settings.output_children = bridge.ensure_curves_output(
            settings.output_children, f"{name}_hairdyn_children", children[0], like=hair_obj)
        bridge.write_curves(settings.output_children, children[1])
    settings.output_curves = bridge.ensure_curves_output(
        settings.output_curves, f"{name}_hairdyn", curve_offsets, like=hair_obj)
    settings.output_points = bridge.ensure_points_output(
        settings.output_points, f"{name}_hairdyn_points", like=hair_obj)
    bridge.write_curves(settings.output_curves, arrays["position"])
    shown = arrays if points is None else points
    bridge.write_points(settings.output_points, shown["position"],
                        {key: value for key, value in shown.items() if key != "position"})
    if points is not None and settings.use_billboards:
        billboards.ensure(settings.output_points, bpy.context.scene.camera)


def frame_dt(scene):
    """Seconds per frame of the scene."""
    return scene.render.fps_base / scene.render.fps


class Runner:
    """Steps a Simulation through a frame range, frame by frame: writes each frame to the
    output objects and, when given one, to a cache. The headless entry point, the operators
    and the bake all drive this; `advance()` does one frame so a modal operator can stay
    responsive between frames.

    With `resume_from` (a cached frame and its arrays) the simulation continues after that
    frame instead of starting at frame_start (the rest shape is still read at frame_start).
    """

    def __init__(self, context, hair_obj, frame_start, frame_end, cache=None, resume_from=None):
        """resume_from: the last frame already baked (its successors are simulated)."""
        if frame_end < frame_start:
            raise HairdynError(f"The frame range {frame_start}..{frame_end} is empty")
        self.context, self.hair_obj, self.cache = context, hair_obj, cache
        self.object_name = hair_obj.name  # for the report, even if the object goes away
        self.frame_start, self.frame_end = frame_start, frame_end
        self.start_time = time.perf_counter()
        with playback.suspended():
            context.scene.frame_set(frame_start)
        self.simulation = Simulation(hair_obj, context.evaluated_depsgraph_get(), context.scene)
        if cache is not None:
            cache.check_topology(self.simulation.groom.curve_offsets,
                                 self.simulation.groom.positions_wo)
        self.dt = frame_dt(context.scene)
        self.next_frame = frame_start
        self.step_ms, self.collision_ms, self.nan_frames, self.stretch_max = [], [], 0, 0.0
        self.penetration_max, self.deeper_num, self.checked_num = 0.0, 0, 0
        if resume_from is not None:
            # Solvers carry state the cache does not hold (angles, the head's motion), so a
            # resumed bake re-simulates the frames it keeps, without writing them: the same
            # inputs give the same state, bit for bit.
            while self.next_frame <= resume_from:
                self._step_frame()

    @property
    def done(self):
        return self.next_frame > self.frame_end

    def _step_frame(self):
        """Move the scene to the next frame and step the simulation there; returns its ms."""
        with playback.suspended():
            self.context.scene.frame_set(self.next_frame)
        ms = self.simulation.step(self.context.evaluated_depsgraph_get(), self.dt)
        self.next_frame += 1
        return ms

    def advance(self):
        """Simulate, measure, write and cache the next frame; returns (frame, native ms).
        A hair object or collider deleted meanwhile is a HairdynError; the frames already
        written stay."""
        try:
            return self._advance()
        except ReferenceError:
            raise HairdynError("The hair object or its head was deleted during the simulation; "
                               "the frames written before are kept") from None

    def _advance(self):
        frame = self.next_frame
        ms = self._step_frame()
        self.step_ms.append(ms)
        self.collision_ms.append(self.simulation.collision_ms)
        if self.simulation.nonfinite_points():
            self.nan_frames += 1
            return frame, ms
        self.stretch_max = max(self.stretch_max, self.simulation.stretch())
        penetration = self.simulation.penetration()
        if penetration is not None:
            self.penetration_max = max(self.penetration_max, penetration["penetration_max"])
            self.deeper_num += penetration["deeper_num"]
            self.checked_num += penetration["points_num"]
        arrays = self.simulation.frame_arrays()
        if self.cache is not None:
            self.cache.write_frame(frame, arrays, self.simulation.frame_streams())
        self.simulation.write(arrays)
        return frame, ms

    def report(self):
        """The figures every solver reports (see README, "Headless runs")."""
        simulation = self.simulation
        try:
            settings = self.hair_obj.hairdyn
            outputs = [settings.output_curves.name if settings.output_curves else None,
                       settings.output_points.name if settings.output_points else None]
        except ReferenceError:  # the object was deleted: the figures still stand
            outputs = [None, None]
        return {
            "object": self.object_name,
            "solver": simulation.method.lower(),
            "strands": simulation.groom.curves_num,
            "points": simulation.groom.points_num,
            "frames": len(self.step_ms),
            "frame_start": self.frame_start,
            "frame_end": self.frame_end,
            "ms_per_frame": float(np.median(self.step_ms)) if self.step_ms else 0.0,
            "total_s": time.perf_counter() - self.start_time,
            "nan_frames": self.nan_frames,
            "stretch_max": float(self.stretch_max),
            **({"particles": simulation.solver.particles_num,
                "pairs": simulation.solver.pairs_num,
                "interpenetrating_pairs": simulation.solver.interpenetrating_pairs_num}
               if simulation.skin is not None else {}),
            "collision": simulation.colliders is not None,
            "colliders": simulation.colliders.names if simulation.colliders else [],
            "penetration_max": float(self.penetration_max),
            "penetration_share": self.deeper_num / self.checked_num if self.checked_num else 0.0,
            "penetration_tolerance": simulation.colliders.tolerance_wo() if simulation.colliders else None,
            "collision_build_ms": simulation.colliders.build_ms if simulation.colliders else 0.0,
            "collision_ms": float(np.median(self.collision_ms)) if self.collision_ms else 0.0,
            "blender_version": bpy.app.version_string,
            "native_version": simulation.native.__version__,
            "output_curves": outputs[0],
            "output_points": outputs[1],
        }


def run(context, hair_obj, frame_start, frame_end, on_frame=None):
    """Simulate hair_obj over [frame_start, frame_end] into the output objects; returns the
    report. on_frame(frame, ms) is called after each frame (progress)."""
    runner = Runner(context, hair_obj, frame_start, frame_end)
    while not runner.done:
        frame, ms = runner.advance()
        if on_frame is not None:
            on_frame(frame, ms)
    return runner.report()


def cache_directory(hair_obj):
    """The object's bake folder: <cache_directory>/<object name>, `//` relative to the .blend."""
    base = hair_obj.hairdyn.cache_directory
    if not base:
        raise HairdynError("Set a cache folder in the hairdyn panel")
    if base.startswith("//") and not bpy.data.filepath:
        raise HairdynError(f"Save the .blend file first: the cache folder '{base}' is relative "
                           "to it")
    return Path(bpy.path.abspath(base)) / bpy.path.clean_name(hair_obj.name)


def start_bake(context, hair_obj, resume_after=None):
    """A Runner that bakes the object's frame range into its cache.

    resume_after=None bakes from the start (an older bake is replaced). resume_after=frame
    keeps the cached frames up to that frame and continues after it; this needs an unbroken
    run of cached frames from the start to there, baked with the same parameters.
    """
    settings = hair_obj.hairdyn
    directory = cache_directory(hair_obj)
    parameters = properties.settings_dict(settings)
    settings.enabled = True  # a baked object plays its bake back
    if resume_after is not None:
        cache = Cache.open(directory)
        if cache.manifest["parameters"] != parameters:
            raise HairdynError("The parameters changed since this bake started: bake from the "
                               "start, or restore them")
        last = cache.prepare_resume(resume_after)
        return Runner(context, hair_obj, cache.manifest["frame_start"], cache.manifest["frame_end"],
                      cache=cache, resume_from=last)
    runner = Runner(context, hair_obj, settings.frame_start, settings.frame_end)
    runner.cache = Cache.create(
        directory, solver=settings.method.lower(), parameters=parameters,
        curve_offsets=runner.simulation.groom.curve_offsets,
        columns=runner.simulation.frame_columns(), frame_start=settings.frame_start,
        frame_end=settings.frame_end, fps=1.0 / runner.dt,
        streams=runner.simulation.stream_layouts(),
        extra={"object": hair_obj.name}, rest_positions=runner.simulation.groom.positions_wo)
    playback.forget(directory)
    return runner


def finish_bake(runner):
    """Records the bake's figures in its manifest; returns the report."""
    report = runner.report()
    manifest = runner.cache.manifest
    manifest["complete"] = runner.cache.last_contiguous_frame() == manifest["frame_end"]
    manifest["report"] = report
    manifest["timings"] = {"ms_per_frame": report["ms_per_frame"], "total_s": report["total_s"],
                           "frames": report["frames"]}
    runner.cache.save_manifest()
    playback.forget(runner.cache.directory)
    return report
