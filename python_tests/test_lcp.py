"""LCP (Bando 2003) in Blender: particles over the scalp, strands carried by them, the report's
particle figures, the particle output's attributes, bad input."""
import bpy
import numpy as np
import pytest

from hairdyn import bridge, cli, simulation
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
    hair.hairdyn.lcp_scalp = "no_such_group"
    with pytest.raises(HairdynError, match="no vertex group 'no_such_group' marking the scalp"):
        simulation.run(bpy.context, hair, 1, 2)


def test_lcp_bad_values_are_refused(open_fixture):
    hair = lcp_hair(open_fixture, "head_curves.blend")
    with pytest.raises(cli.UsageError, match="h2 must be between"):
        cli.apply_settings(hair.hairdyn, ["h2=0"])
    hair.hairdyn.lcp.particle_spacing = 0.9  # larger than the head: no particle fits
    with pytest.raises(HairdynError, match="No particles"):
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
