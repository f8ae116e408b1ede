"""LCP (Bando 2003) in Blender: particles over the scalp, strands carried by them, the report's
particle figures, the particle output's attributes, bad input; the initialisation options of
§3.2 (scalp from a vertex group or selected faces, length map from the groom, an image or
vertex weights, particles along an existing groom)."""
import bpy
import numpy as np
import pytest

from hairdyn import bridge, cli, native, simulation
from hairdyn.methods import lcp
from hairdyn.errors import HairdynError


def depsgraph():
    return bpy.context.evaluated_depsgraph_get()


def lcp_hair(open_fixture, fixture="head_shake.blend"):
    """The fixture's groom on LCP, with particles coarse enough for a quick test."""
    open_fixture(fixture)
    hair = bpy.data.objects["Hair"]
    cli.apply_settings(hair.hairdyn, ["method=lcp", "particle_num=0", "particle_spacing=0.02",
                                      "h1=0.027", "h2=0.018"])
    return hair


def test_lcp_defaults_run_the_shipped_example(open_fixture):
    """The defaults (about 2,000 particles, as Bando 2003 used) on the fixture: a sane run."""
    open_fixture("head_shake.blend")
    hair = bpy.data.objects["Hair"]
    hair.hairdyn.method = 'LCP'
    report = simulation.run(bpy.context, hair, 1, 6)
    assert report["particles"] == 2000 and report["nan_frames"] == 0
    assert report["pairs"] > 4 * report["particles"]
    assert report["penetration_share"] <= 0.005


def test_lcp_runs_on_the_head_and_carries_the_strands(open_fixture):
    hair = lcp_hair(open_fixture)
    report = simulation.run(bpy.context, hair, 1, 24)
    assert report["solver"] == "lcp" and report["nan_frames"] == 0
    assert report["particles"] > 500 and report["pairs"] > 3 * report["particles"]
    assert report["interpenetrating_pairs"] >= 0
    assert report["penetration_share"] <= 0.005  # the body collision holds
    out = bridge.read_curves(hair.hairdyn.output_curves, depsgraph())
    follow = bridge.read_curves(hair, depsgraph())  # the groom parented to the head
    roots = out.curve_offsets[:-1]
    assert np.abs(out.positions_wo[roots] - follow.positions_wo[roots]).max() < 1e-5
    moved = np.linalg.norm(out.positions_wo - follow.positions_wo, axis=1)
    assert moved.max() > 0.005  # the particles carried the strands, not a rigid copy
    assert report["stretch_max"] < 1e-4  # strands keep their length while the volume deforms


def test_lcp_strands_lie_in_the_volume_of_scalp_particles(open_fixture):
    """Particles sampled over the scalp (the default) hang in the cantilever shape of §3.2,
    while the fixture's groom sticks out sideways: the output strands take the volume's shape
    (every point within about a particle spacing of a particle) instead of keeping the
    groom's shape beside it."""
    open_fixture("head_shake.blend")
    hair = bpy.data.objects["Hair"]
    hair.hairdyn.method = 'LCP'
    simulation.run(bpy.context, hair, 1, 1)
    out = bridge.read_curves(hair.hairdyn.output_curves, depsgraph())
    groom = bridge.read_curves(hair, depsgraph())
    mesh = hair.hairdyn.output_points.data
    particles = np.empty((len(mesh.vertices), 3), np.float32)
    mesh.vertices.foreach_get("co", particles.ravel())
    free = np.ones(len(out.positions_wo), bool)
    free[out.curve_offsets[:-1]] = False

    def nearest_particle(points):
        gaps = points[:, None, :] - particles[None, :, :]
        return np.sqrt(np.min(np.einsum("ijk,ijk->ij", gaps, gaps), axis=1))

    spacing = hair.hairdyn.lcp.particle_spacing
    assert np.median(nearest_particle(groom.positions_wo[free])) > 5 * spacing  # beside it
    inside = nearest_particle(out.positions_wo[free])
    assert np.percentile(inside, 95) < spacing and inside.max() < 2 * spacing


def test_lcp_particles_reach_the_point_output(open_fixture):
    hair = lcp_hair(open_fixture, "head_curves.blend")
    report = simulation.run(bpy.context, hair, 1, 3)
    mesh = hair.hairdyn.output_points.data
    assert len(mesh.vertices) == report["particles"]
    for name in ("direction", "density", "u", "v", "s", "velocity"):
        assert name in mesh.attributes, name
    density = np.empty(len(mesh.vertices), np.float32)
    mesh.attributes["density"].data.foreach_get("value", density)
    assert density.max() > 0.0
    direction = np.empty((len(mesh.vertices), 3), np.float32)
    mesh.attributes["direction"].data.foreach_get("vector", direction.ravel())
    assert np.allclose(np.linalg.norm(direction, axis=1), 1.0, atol=1e-3)


def test_lcp_needs_a_scalp(open_fixture):
    hair = lcp_hair(open_fixture, "head_curves.blend")
    hair.hairdyn.lcp_init.scalp_group = "no_such_group"
    with pytest.raises(HairdynError, match="no vertex group 'no_such_group' marking the scalp"):
        simulation.run(bpy.context, hair, 1, 2)


def test_lcp_bad_values_are_refused(open_fixture):
    hair = lcp_hair(open_fixture, "head_curves.blend")
    with pytest.raises(cli.UsageError, match="h2 must be between 1e-05 and 1 m, not 0"):
        cli.apply_settings(hair.hairdyn, ["h2=0"])
    # A value the panel shows in another unit than the solver's is refused in the panel's.
    with pytest.raises(cli.UsageError, match="thickness must be between 0 and 100 mm, not -1"):
        cli.apply_settings(hair.hairdyn, ["swept_spheres.thickness=-1"])
    with pytest.raises(cli.UsageError, match="there is no image named 'Nope'"):
        cli.apply_settings(hair.hairdyn, ["length_image=Nope"])
    hair.hairdyn.lcp.particle_spacing = 0.9  # larger than the head: no particle fits
    with pytest.raises(HairdynError, match="No particles"):
        simulation.run(bpy.context, hair, 1, 2)


@pytest.mark.parametrize("setting, names", [
    ("particle_spacing", "raise the spacing"),  # the panel's smallest: billions of particles
    ("particle_num", "lower h₁ and h₂"),  # the panel's largest, with the default h₁ and h₂
])
def test_lcp_sizes_beyond_what_memory_holds_are_refused_before_sampling(
        open_fixture, setting, names):
    """The panel's extreme particle spacing and count ask for more particles, or neighbours
    within 2h, than a simulation can hold: refused at once with the setting to change (the
    sampling alone would take hours)."""
    open_fixture("head_shake.blend")
    hair = bpy.data.objects["Hair"]
    settings = hair.hairdyn
    settings.method = 'LCP'
    prop = settings.lcp.bl_rna.properties[setting]
    if setting == "particle_spacing":
        settings.lcp.particle_num = 0
        settings.lcp.particle_spacing = prop.hard_min
    else:
        settings.lcp.particle_num = prop.hard_max
    with pytest.raises(HairdynError, match=f"Too many particles: .*{names}"):
        simulation.run(bpy.context, hair, 1, 2)


def test_lcp_bakes_and_plays_back_its_particles(open_fixture, tmp_path):
    hair = lcp_hair(open_fixture, "head_curves.blend")
    hair.hairdyn.cache_directory = str(tmp_path)
    hair.hairdyn.frame_end = 6
    bpy.context.view_layer.objects.active = hair
    assert bpy.ops.hairdyn.bake() == {'FINISHED'}
    from hairdyn.cache import Cache

    cache = Cache.open(tmp_path / "Hair")
    assert cache.manifest["solver"] == "lcp" and set(cache.streams) == {"particles"}
    assert cache.frames() == list(range(1, 7))
    bpy.context.scene.frame_set(4)
    mesh = hair.hairdyn.output_points.data
    particles = cache.read_stream("particles", 4)
    assert len(mesh.vertices) == len(particles["position"])
    seen = np.empty_like(particles["density"])
    mesh.attributes["density"].data.foreach_get("value", seen)
    assert np.array_equal(seen, particles["density"])
    strands = bridge.read_curves(hair.hairdyn.output_curves, depsgraph()).positions_wo
    assert np.array_equal(strands, cache.read_frame(4)["position"])


def test_billboards_follow_the_hair_direction(open_fixture):
    """Bando 2003 §4: one card per particle, its long axis along the particle's direction t,
    its width across the view."""
    hair = lcp_hair(open_fixture, "head_curves.blend")
    simulation.run(bpy.context, hair, 1, 2)
    points = hair.hairdyn.output_points
    assert points.modifiers.get("hairdyn Billboards") is not None
    mesh = points.data
    direction = np.empty((len(mesh.vertices), 3), np.float32)
    mesh.attributes["direction"].data.foreach_get("vector", direction.ravel())
    positions = np.empty_like(direction)
    mesh.vertices.foreach_get("co", positions.ravel())
    graph = depsgraph()
    cards = [np.array(instance.matrix_world) for instance in graph.object_instances
             if instance.is_instance and instance.parent is not None
             and instance.parent.original == points]
    assert len(cards) == len(mesh.vertices)
    camera = np.array(bpy.context.scene.camera.matrix_world.translation)
    for matrix in cards[::25]:
        index = np.argmin(np.linalg.norm(positions - matrix[:3, 3], axis=1))
        along = matrix[:3, 2] / np.linalg.norm(matrix[:3, 2])
        across = matrix[:3, 0] / np.linalg.norm(matrix[:3, 0])
        assert abs(np.dot(along, direction[index])) > 0.999
        to_camera = camera - matrix[:3, 3]
        assert abs(np.dot(across, to_camera / np.linalg.norm(to_camera))) < 1e-3


# Initialisation options of Bando 2003 §3.2: where the scalp is, the length map, the groom.


def rest_particles(hair):
    """The particles LCP starts from (the solver built at the rest frame), by attribute."""
    built = simulation.Simulation(hair, depsgraph(), bpy.context.scene)
    return {name: np.array(values) for name, values in built.method.particle_arrays().items()}


def body_local(points):
    """World points in the Body's object space (the head's centre is at (0, 0, 0.2))."""
    inverse = np.linalg.inv(bridge.object_matrix(bpy.data.objects["Body"], depsgraph()))
    return points @ inverse[:3, :3].T + inverse[:3, 3]


def grey_image(name, left, right, size=(16, 4)):
    """An image whose left half (u < 0.5) is grey `left` and right half `right`."""
    width, height = size
    image = bpy.data.images.new(name, width, height)
    pixels = np.ones((height, width, 4), np.float32)
    pixels[:, :, :3] = np.where(np.arange(width) < width // 2, left, right)[None, :, None]
    image.pixels.foreach_set(pixels.ravel())
    return image


def weight_group(name, left, right):
    """A vertex group of the Body weighting its -X half `left` and its +X half `right`."""
    body = bpy.data.objects["Body"]
    vertices = np.empty((len(body.data.vertices), 3), np.float32)
    body.data.vertices.foreach_get("co", vertices.ravel())
    x = vertices[:, 0]
    group = body.vertex_groups.new(name=name)
    group.add([int(i) for i in np.flatnonzero(x < 0.0)], left, 'REPLACE')
    group.add([int(i) for i in np.flatnonzero(x >= 0.0)], right, 'REPLACE')


def select_faces(where):
    """Select the Body's faces whose centre (object space) satisfies where(centres)."""
    polygons = bpy.data.objects["Body"].data.polygons
    centres = np.empty((len(polygons), 3), np.float32)
    polygons.foreach_get("center", centres.ravel())
    polygons.foreach_set("select", where(centres))


def test_lcp_scalp_from_selected_faces(open_fixture):
    """Only the selected faces grow hair: the top of the head on its +X side."""
    hair = lcp_hair(open_fixture, "head_curves.blend")
    select_faces(lambda c: (c[:, 0] > 0.01) & (c[:, 2] > 0.2))
    cli.apply_settings(hair.hairdyn, ["scalp_source=faces", "scalp_group=no_such_group"])
    particles = rest_particles(hair)
    roots = body_local(particles["position"][particles["s"] < 0.0])
    assert len(roots) > 20
    assert roots[:, 0].min() > -0.005 and roots[:, 0].max() > 0.05  # the +X side, spread over it
    assert roots[:, 2].min() > 0.2 - 0.015


def test_lcp_length_map_from_an_image(open_fixture):
    """L(u, v) from a grey image times L_max: hair on the image's bright half is longer."""
    hair = lcp_hair(open_fixture, "head_curves.blend")
    grey_image("Lengths", 0.25, 1.0)
    cli.apply_settings(hair.hairdyn, ["length_source=image", "length_image=Lengths",
                                      "max_length=0.2"])
    assert hair.hairdyn.lcp_init.length_image.name == "Lengths"
    particles = rest_particles(hair)
    u, s = particles["u"], particles["s"]
    assert s[u < 0.4].max() < 0.25 * 0.2 + 0.002
    assert s[u > 0.6].max() > 0.15


def test_lcp_length_map_from_vertex_weights(open_fixture):
    """L(u, v) from the head's vertex weights times L_max: the heavy side's hair is longer."""
    hair = lcp_hair(open_fixture, "head_curves.blend")
    weight_group("length", 0.25, 1.0)
    cli.apply_settings(hair.hairdyn, ["length_source=weights", "length_group=length",
                                      "max_length=0.2"])
    particles = rest_particles(hair)
    # Where each particle grows from: the scalp vertex nearest to its (u, v) on the scalp map.
    vertices, triangles, _ = lcp.scalp_patch(bpy.data.objects["Body"], depsgraph(),
                                             hair.hairdyn.lcp_init)
    scalp_uv = native.load().harmonic_scalp_map(vertices, triangles)
    uv = np.stack([particles["u"], particles["v"]], axis=1)
    nearest = ((uv[:, None, :] - scalp_uv[None, :, :]) ** 2).sum(axis=2).argmin(axis=1)
    x, s = body_local(vertices)[nearest, 0], particles["s"]
    assert s[x < -0.04].max() < 0.25 * 0.2 + 0.002
    assert s[x > 0.04].max() > 0.15


def missing_file_image():
    image = bpy.data.images.new("Missing", 4, 4)
    image.source = 'FILE'
    image.filepath = "//no_such_length_map.png"


@pytest.mark.parametrize("prepare, assignments, message", [
    (None, ["length_source=image"], "Empty length map: no Length Image is set"),
    (lambda: grey_image("Black", 0.0, 0.0), ["length_source=image", "length_image=Black"],
     "Empty length map: the image 'Black' is black everywhere"),
    (missing_file_image, ["length_source=image", "length_image=Missing"],
     "Empty length map: the image 'Missing' has no pixels"),
    (lambda: weight_group("length", 0.0, 0.0), ["length_source=weights"],
     "Empty length map: the weights of the group 'length' are zero over the whole scalp"),
    (None, ["length_source=weights", "length_group=nope"],
     "Empty length map: 'Body' has no vertex group 'nope'"),
    (lambda: select_faces(lambda c: np.zeros(len(c), bool)), ["scalp_source=faces"],
     "No face of 'Body' is selected: select the scalp's faces"),
], ids=["no image", "black image", "image without pixels", "zero weights", "missing group",
        "no face selected"])
def test_lcp_bad_initialisation_is_explained(open_fixture, prepare, assignments, message):
    hair = lcp_hair(open_fixture, "head_curves.blend")
    if prepare is not None:
        prepare()
    cli.apply_settings(hair.hairdyn, assignments)
    with pytest.raises(HairdynError, match=message):
        simulation.run(bpy.context, hair, 1, 1)


def distances_to_segments(points, starts, ends, chunk=256):
    """Distance from each point to its nearest segment starts[k]-ends[k]."""
    result = np.empty(len(points))
    along = ends - starts
    lengths2 = np.maximum((along ** 2).sum(axis=1), 1e-30)
    for first in range(0, len(points), chunk):
        block = points[first:first + chunk, None, :]
        t = np.clip(((block - starts) * along).sum(axis=2) / lengths2, 0.0, 1.0)
        nearest = starts + t[:, :, None] * along
        result[first:first + chunk] = np.sqrt(((block - nearest) ** 2).sum(axis=2).min(axis=1))
    return result


def test_lcp_particles_from_the_groom(open_fixture):
    """Particles along the artist's strands, (u, v) the roots' surface UVs: no scalp needed."""
    hair = lcp_hair(open_fixture, "head_curves.blend")
    body = bpy.data.objects["Body"]
    body.vertex_groups.remove(body.vertex_groups["scalp"])
    cli.apply_settings(hair.hairdyn, ["particles_from=groom"])
    runner = simulation.Runner(bpy.context, hair, 1, 2)
    solver, groom = runner.simulation.method.solver, runner.simulation.groom
    positions, s = np.array(solver.positions), np.array(solver.s)
    uv = np.stack([solver.u, solver.v], axis=1)
    points, offsets = groom.positions_wo.astype(np.float64), groom.curve_offsets
    last = np.ones(len(points) - 1, bool)
    last[offsets[1:-1] - 1] = False  # no segment from one strand's tip to the next root
    strands = s >= 0.0
    assert strands.sum() > 100
    off_strand = distances_to_segments(positions[strands], points[:-1][last], points[1:][last])
    # On the strands; the few that sat closer than 0.6 h2 to a neighbour were spaced out.
    assert np.quantile(off_strand, 0.95) < 1e-4
    assert off_strand.max() < 0.3 * hair.hairdyn.lcp.h2
    from_roots = np.abs(uv[:, None, :] - groom.root_uvs[None, :, :]).sum(axis=2).min(axis=1)
    assert from_roots.max() < 1e-6
    while not runner.done:
        runner.advance()
    report = runner.report()
    assert report["nan_frames"] == 0 and report["particles"] == len(positions)
    assert np.isfinite(runner.simulation.positions).all()
