"""The kinematic baseline: roots stay on the animated head, every strand follows rigidly."""
import bpy
import numpy as np

from hairdyn import bridge, simulation


def depsgraph():
    return bpy.context.evaluated_depsgraph_get()


def test_follow_head_keeps_roots_on_the_moving_scalp(open_fixture):
    """The fixture's groom is parented to the head, so Blender itself moves the source curves
    rigidly with the head: at every frame the simulated strands must coincide with them."""
    scene = open_fixture("head_shake.blend")
    hair = bpy.data.objects["Hair"]
    report = simulation.run(bpy.context, hair, 1, 72)
    assert report["frames"] == 72 and report["nan_frames"] == 0
    assert report["stretch_max"] < 5e-5  # rigid: only float rounding
    seen_turn = False
    for frame in (1, 12, 30, 48, 72):
        scene.frame_set(frame)
        simulation.run(bpy.context, hair, 1, frame)
        out = bridge.read_curves(hair.hairdyn.output_curves, depsgraph())
        expected = bridge.read_curves(hair, depsgraph())
        error = np.abs(out.positions_wo - expected.positions_wo).max()
        assert error < 2e-6, (frame, error)
        roots = out.positions_wo[out.curve_offsets[:-1]]
        # The roots are on the scalp: in the head's frame they are where they were at rest.
        head = np.array(bpy.data.objects["Body"].matrix_world)
        roots_head = (np.linalg.inv(head) @ np.c_[roots, np.ones(len(roots))].T).T[:, :3]
        body_mesh = bridge.read_mesh(bpy.data.objects["Body"], depsgraph())
        nearest = np.min(np.linalg.norm(
            body_mesh.vertices[None, :, :] - roots_head[:, None, :], axis=2), axis=1)
        assert nearest.max() < 0.02  # within a face of the 3 cm-wide scalp mesh
        seen_turn |= not np.allclose(head, np.eye(4), atol=1e-3) and frame != 1
    assert seen_turn


def test_follow_output_objects_are_created_once(open_fixture):
    open_fixture("head_curves.blend")
    hair = bpy.data.objects["Hair"]
    simulation.run(bpy.context, hair, 1, 3)
    curves_out, points_out = hair.hairdyn.output_curves, hair.hairdyn.output_points
    assert curves_out.type == 'CURVES' and points_out.type == 'MESH'
    assert np.allclose(np.array(curves_out.matrix_world), np.eye(4))
    objects = len(bpy.data.objects)
    simulation.run(bpy.context, hair, 1, 3)
    assert len(bpy.data.objects) == objects
    assert hair.hairdyn.output_curves == curves_out
    mesh = points_out.data
    assert len(mesh.vertices) == 2700
    assert {"direction", "velocity"} <= set(mesh.attributes.keys())


def test_follow_particle_hair(open_fixture):
    scene = open_fixture("head_particles.blend")
    body = bpy.data.objects["Body"]
    body.rotation_euler = (0.0, 0.0, 0.5)
    body.keyframe_insert("rotation_euler", frame=10)
    body.rotation_euler = (0.0, 0.0, 0.0)
    body.keyframe_insert("rotation_euler", frame=1)
    report = simulation.run(bpy.context, body, 1, 10)
    assert report["strands"] == 300 and report["nan_frames"] == 0
    out = bridge.read_curves(body.hairdyn.output_curves, depsgraph())
    scene.frame_set(10)
    expected = bridge.read_particle_hair(body, depsgraph())
    assert np.abs(out.positions_wo - expected.positions_wo).max() < 1e-5


def test_live_playback_steps_and_restarts_like_cloth(open_fixture):
    scene = open_fixture("head_shake.blend")
    hair = bpy.data.objects["Hair"]
    assert hair.hairdyn.enabled and hair.hairdyn.use_live
    scene.frame_set(1)  # the start frame (re)starts the simulation and creates the outputs
    assert hair.hairdyn.output_curves is not None
    for frame in range(2, 13):
        scene.frame_set(frame)
    at_12 = bridge.read_curves(hair.hairdyn.output_curves, depsgraph()).positions_wo
    expected = bridge.read_curves(hair, depsgraph()).positions_wo
    assert np.abs(at_12 - expected).max() < 2e-6
    scene.frame_set(40)  # a jump is not simulated: the outputs keep frame 12
    assert np.array_equal(
        bridge.read_curves(hair.hairdyn.output_curves, depsgraph()).positions_wo, at_12)
    scene.frame_set(41)  # nor is the frame after the jump
    assert np.array_equal(
        bridge.read_curves(hair.hairdyn.output_curves, depsgraph()).positions_wo, at_12)
    hair.hairdyn.enabled = False
    scene.frame_set(1)
    assert np.array_equal(
        bridge.read_curves(hair.hairdyn.output_curves, depsgraph()).positions_wo, at_12)
