"""Owns: the LCP method (Bando 2003, loosely connected particles; native LcpSolver) and what
only it needs: its add-on-only initialisation options (where the particles start, the scalp,
the length map of §3.2) and the scalp patch and length map readers; the native ParticleSkin
carries the real strands with the particles (§4). It reads the shared wind (WindParams).
LCP reads the collision maps and the report tolerance; its response to the body is its own
(body_friction), not the collision response settings.
"""

import bpy
import numpy as np
from bpy.props import EnumProperty, PointerProperty, StringProperty

from .. import bridge
from ..errors import HairdynError
from .base import Method, Section, Stream, nearest


class HairdynLcpInit(bpy.types.PropertyGroup):
    """Where LCP's particles start (Bando 2003 §3.2): add-on-only options, read by the LCP
    adapter when it builds the particles."""

    particles_from: EnumProperty(
        name="Particles From",
        default='SCALP',
        items=(
            (
                'SCALP',
                "Scalp",
                "Poisson-disc samples of the hair volume over the scalp's (u, v) and the arc "
                "length s up to the length map, in a cantilever-beam shape (Bando 2003 §3.2); "
                "the strands take that shape",
            ),
            (
                'GROOM',
                "Groom",
                "Samples along the groom's strands: u, v from the root's surface position, s "
                "from arc length, directions from the tangents (Bando 2003 §3.2); needs no "
                "scalp, and the strands keep the groom's shape",
            ),
        ),
        description="Where LCP's particles start (Bando 2003 §3.2)",
    )
    scalp_source: EnumProperty(
        name="Scalp From",
        default='GROUP',
        items=(
            (
                'GROUP',
                "Vertex Group",
                "The head's faces whose corners all lie in a vertex group (Bando 2003 §3.2)",
            ),
            ('FACES', "Selected Faces", "The head mesh's selected faces (Bando 2003 §3.2)"),
        ),
        description="How the part of the head that grows hair is marked (Bando 2003 §3.2)",
    )
    scalp_group: StringProperty(
        name="Scalp",
        default="scalp",
        description="Vertex group of the head that marks the scalp LCP samples the hair volume "
        "over (Bando 2003 §3.2)",
    )
    length_source: EnumProperty(
        name="Lengths From",
        default='GROOM',
        items=(
            (
                'GROOM',
                "Groom",
                "At each scalp point the length of the groom's nearest strand; the longest "
                "strand is L_max (Bando 2003 §3.2)",
            ),
            (
                'IMAGE',
                "Image",
                "A grey image over the scalp's (u, v), scaled by Max Length L_max (Bando 2003 "
                "§3.2)",
            ),
            (
                'WEIGHTS',
                "Vertex Weights",
                "A vertex group of the head, its weights scaled by Max Length L_max (Bando "
                "2003 §3.2)",
            ),
        ),
        description="The length map L(u, v): how long the hair grows over the scalp (Bando "
        "2003 §3.2)",
    )
    length_image: PointerProperty(
        name="Length Image",
        type=bpy.types.Image,
        description="Grey image of the length map L(u, v) / L_max over the scalp's harmonic "
        "(u, v) (Bando 2003 §3.2): columns from u = 0, rows from v = 0 at the "
        "bottom; white grows hair of Max Length, black none",
    )
    length_group: StringProperty(
        name="Length Group",
        default="length",
        description="Vertex group of the head whose weights are the length map L / L_max "
        "(Bando 2003 §3.2): weight 1 grows hair of Max Length, 0 none",
    )


def draw_initialisation(layout, settings):
    """Where the particles start (Bando 2003 §3.2): only the rows the choices use."""
    init = settings.lcp_init
    layout.prop(init, "particles_from")
    if init.particles_from == 'GROOM':
        return
    obj = settings.id_data
    head = settings.head or (obj.data.surface if obj.type == 'CURVES' else obj)
    if head is not None and head.type != 'MESH':
        head = None

    def vertex_group(name):
        if head is None:
            layout.prop(init, name)
        else:
            layout.prop_search(init, name, head, "vertex_groups")

    layout.prop(init, "scalp_source")
    if init.scalp_source == 'GROUP':
        vertex_group("scalp_group")
    layout.prop(init, "length_source")
    if init.length_source == 'IMAGE':
        layout.prop(init, "length_image")
    elif init.length_source == 'WEIGHTS':
        vertex_group("length_group")


def scalp_triangles(head, mesh, init):
    """The head mesh's triangles the artist marked as scalp (Bando 2003 §3.2): those whose
    corners all lie in the scalp vertex group, or those of the selected faces."""
    if init.scalp_source == 'FACES':
        selected = bridge.selected_faces(head)
        faces_num = int(mesh.triangle_faces.max()) + 1 if len(mesh.triangle_faces) else 0
        if faces_num != len(selected):
            raise HairdynError(
                f"The modifiers of '{head.name}' change its faces, so its face "
                "selection does not mark the scalp: use a vertex group"
            )
        triangles = mesh.triangles[selected[mesh.triangle_faces]]
        if len(triangles) == 0:
            raise HairdynError(
                f"No face of '{head.name}' is selected: select the scalp's faces "
                "in Edit Mode (LCP samples the hair volume over them), or mark "
                "the scalp with a vertex group"
            )
        return triangles
    group_name = init.scalp_group
    members = bridge.vertex_group_members(head, {group_name}, len(mesh.vertices)).get(group_name)
    if members is None or len(members) == 0:
        raise HairdynError(
            f"'{head.name}' has no vertex group '{group_name}' marking the scalp: "
            "LCP samples the hair volume over it (set Scalp in the LCP panel, or "
            "take the scalp from the selected faces)"
        )
    inside = np.zeros(len(mesh.vertices), dtype=bool)
    inside[members] = True
    triangles = mesh.triangles[inside[mesh.triangles].all(axis=1)]
    if len(triangles) == 0:
        raise HairdynError(f"The scalp group '{group_name}' of '{head.name}' covers no face")
    return triangles


def scalp_patch(head, depsgraph, init):
    """The scalp as a mesh of its own (Bando 2003 §3.2): world-space vertices and triangles of
    the part of the head the artist marked, and each patch vertex's index in the head mesh."""
    mesh = bridge.read_mesh(head, depsgraph)
    triangles = scalp_triangles(head, mesh, init)
    used = np.unique(triangles)
    remap = np.full(len(mesh.vertices), -1, dtype=np.int32)
    remap[used] = np.arange(len(used), dtype=np.int32)
    return (
        np.ascontiguousarray(mesh.vertices_wo()[used]),
        np.ascontiguousarray(remap[triangles], dtype=np.int32),
        used,
    )


def length_map(init, max_length, groom, head, scalp_vertices_wo, scalp_head_vertices):
    """The length map L(u, v) of Bando 2003 §3.2 as the sampler takes it: (per scalp vertex
    weights or None, a grey image (H, W) or None, L_max in m). From the groom (the longest
    strand is L_max), or an image or the head's vertex weights scaled by Max Length."""
    source = init.length_source
    if source == 'GROOM':
        weights, longest = length_weights(groom, scalp_vertices_wo)
        return weights, None, longest
    if source == 'IMAGE':
        return None, length_image(init.length_image), max_length
    return (group_length_weights(head, init.length_group, scalp_head_vertices), None, max_length)


def length_image(image):
    """The grey values of the length-map image, rows from v = 0; a HairdynError when it
    would grow no hair."""
    if image is None:
        raise HairdynError(
            "Empty length map: no Length Image is set (choose a grey image in "
            "the LCP panel; white grows hair of Max Length, black none)"
        )
    grey = bridge.image_grey(image)
    if grey.size == 0:
        raise HairdynError(
            f"Empty length map: the image '{image.name}' has no pixels (is its file missing?)"
        )
    if not (grey > 0.0).any():
        raise HairdynError(
            f"Empty length map: the image '{image.name}' is black everywhere, "
            "so no hair would grow (white grows hair of Max Length)"
        )
    return grey


def group_length_weights(head, group_name, scalp_head_vertices):
    """Per scalp vertex, its weight in the head's vertex group `group_name`; a HairdynError
    when the group is missing or zero over the whole scalp."""
    weights = bridge.vertex_group_weights(
        head, {group_name}, int(scalp_head_vertices.max()) + 1
    ).get(group_name)
    if weights is None:
        raise HairdynError(
            f"Empty length map: '{head.name}' has no vertex group '{group_name}' "
            "(set Length Group in the LCP panel to the group whose weights are "
            "the hair lengths)"
        )
    weights = weights[scalp_head_vertices]
    if not (weights > 0.0).any():
        raise HairdynError(
            f"Empty length map: the weights of the group '{group_name}' are zero "
            f"over the whole scalp of '{head.name}', so no hair would grow"
        )
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


class Lcp(Method):
    identifier = "LCP"
    label = "LCP"
    description = (
        "Loosely connected particles (Bando 2003): particles sample the hair volume "
        "over the scalp, loose springs keep its length, SPH interactions its "
        "density; the strands follow the particles"
    )
    params = {"lcp": "LcpParams", "wind": "WindParams"}
    options = {"lcp_init": HairdynLcpInit}
    collision = ("maps", "report")
    shows = ("use_billboards",)
    sections = (
        Section(
            "Loosely Connected Particles",
            "lcp",
            (
                "particle_spacing",
                "particle_num",
                "root_depth",
                "beam_length",
                "substeps",
                "implicit_springs",
                "solver_tolerance",
                "h1",
                "a0",
                "neighbor_num",
                "young_modulus",
                "material_density",
                "spring_damping",
                "hair_density",
            ),
            active={"solver_tolerance": lambda lcp: lcp.implicit_springs},
            draw=draw_initialisation,
            open=True,
        ),
        Section(
            "Hair-Hair Interactions",
            "lcp",
            (
                "h2",
                "attraction_repulsion",
                "pressure_stiffness",
                "implicit_pressure",
                "rest_density",
                "hair_collision",
                "collision_damping",
                "hair_friction",
                "friction_damping",
            ),
            active={
                "pressure_stiffness": lambda lcp: lcp.attraction_repulsion,
                "implicit_pressure": lambda lcp: lcp.attraction_repulsion and lcp.implicit_springs,
                "rest_density": lambda lcp: lcp.attraction_repulsion,
                "collision_damping": lambda lcp: lcp.hair_collision,
                "friction_damping": lambda lcp: lcp.hair_friction,
            },
        ),
        Section(
            "Forces and Wind",
            "lcp",
            (
                "air_friction",
                "body_friction",
                "wind_particle_spacing",
                "wind_drag",
                "air_density",
            ),
        ),
        Section("Wind", "wind", rest=True),  # the shared WindParams group: the air's free stream
        Section(
            "Initial Shape",
            "lcp",
            (
                "max_length",
                "root_tangent_weight",
                "root_normal_weight",
                "whorl_u",
                "whorl_v",
                "seed",
            ),
            rest=True,
        ),
    )

    def __init__(self, build):
        self.solver = self._make_solver(build)
        self.collider_set = build.collider_set
        if self.collider_set is not None:  # moves rest particles out of the body: skin after
            self.solver.set_colliders(self.collider_set)
        # Particles sampled over the scalp have the cantilever shape of §3.2, not the groom's:
        # the strands then take the volume's shape instead of keeping the groom's beside it.
        self.skin = build.native.ParticleSkin(
            build.groom,
            self.solver,
            build.head_matrix,
            shape_from_particles=build.settings.lcp_init.particles_from == 'SCALP',
        )
        if build.groom.pins_num:  # pinned strand points ride on the head, not the particles
            self.skin.set_pinned(build.groom.fixed)
        self.strand_positions = self._skin_strands(build.head_matrix)

    def _skin_strands(self, head_matrix):
        return self.skin.apply(
            self.solver.positions,
            head_matrix,
            self.collider_set,
            directions_wo=self.solver.directions,
        )

    @staticmethod
    def _make_solver(build):
        """Bando 2003 §3.2: particles sampled over the scalp of the head up to the length map,
        or along the groom's strands."""
        init, groom, native = build.settings.lcp_init, build.groom, build.native
        params = build.params("lcp")
        if init.particles_from == 'GROOM':
            # A particle whose nearest groom point is pinned is held by the head like the
            # roots; particles sampled over the scalp stand for no groom point: the skin
            # holds the pinned points.
            particles = native.lcp_particles_from_groom(
                params,
                groom.curve_offsets,
                groom.positions_wo,
                groom.root_uvs,
                groom.fixed if groom.pins_num else None,
            )
        else:
            scalp_vertices, scalp_triangles, scalp_head_vertices = scalp_patch(
                build.head, build.depsgraph, init
            )
            weights, image, params.max_length = length_map(
                init, params.max_length, groom, build.head, scalp_vertices, scalp_head_vertices
            )
            particles = native.sample_lcp_particles(
                params, scalp_vertices, scalp_triangles, weights, image
            )
        return native.LcpSolver(
            params,
            particles["positions"],
            particles["directions"],
            particles["u"],
            particles["v"],
            particles["s"],
            build.head_matrix,
            wind=build.params("wind"),
            fixed=particles.get("fixed"),
        )

    def step(self, frame_dt, head_matrix):
        self.solver.step(frame_dt, head_matrix)  # refused or diverged: a sentence naming LCP
        self.strand_positions = self._skin_strands(head_matrix)

    @property
    def positions(self):
        return self.strand_positions

    def particle_arrays(self):
        """The particles and their attributes (Bando 2003 §4: direction t, density, u, v, s)."""
        solver = self.solver
        return {
            "position": solver.positions,
            "direction": solver.directions,
            "velocity": solver.velocities,
            "density": solver.density,
            "u": solver.u,
            "v": solver.v,
            "s": solver.s,
        }

    def streams(self):
        return {
            "particles": Stream(
                {
                    "position": 3,
                    "direction": 3,
                    "velocity": 3,
                    "density": 1,
                    "u": 1,
                    "v": 1,
                    "s": 1,
                },
                self.particle_arrays,
                self.solver.particles_num,
                outputs=("output_points",),
                billboards=True,
            )
        }

    def report(self):
        return {
            "particles": self.solver.particles_num,
            "pairs": self.solver.pairs_num,
            "interpenetrating_pairs": self.solver.interpenetrating_pairs_num,
        }
