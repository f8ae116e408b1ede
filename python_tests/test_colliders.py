"""Colliders in Blender: which meshes collide, parts by vertex group, rigid motion by
transform, deforming meshes rebuilt every frame."""
import bpy
import numpy as np
import pytest

from hairdyn import colliders, simulation
from hairdyn.errors import HairdynError


def depsgraph():
    return bpy.context.evaluated_depsgraph_get()


def test_default_colliders_and_parts(open_fixture):
    scene = open_fixture("head_curves.blend")
    hair, body = bpy.data.objects["Hair"], bpy.data.objects["Body"]
    chair = bpy.data.objects.new("Chair", bpy.data.meshes.new("Chair"))
    chair.data.from_pydata([(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)], [],
                           [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)])
    scene.collection.objects.link(chair)
    assert colliders.collider_objects(hair, body, scene) == [body]
    chair.modifiers.new("Collision", 'COLLISION')  # Blender's convention: a collider
    assert colliders.collider_objects(hair, body, scene) == [body, chair]
    hair.hairdyn.use_default_colliders = False
    assert colliders.collider_objects(hair, body, scene) == []
    hair.hairdyn.colliders.add().object = chair
    assert colliders.collider_objects(hair, body, scene) == [chair]
    hair.hairdyn.use_default_colliders = True
    built = colliders.Colliders(hair, body, scene, depsgraph())
    assert built.names == ["Body", "Chair"]
    # Body has the vertex groups head, neck and torso (scalp is not a listed part).
    assert built.colliders[0].parts_num == 3 and built.colliders[1].parts_num == 1
    assert built.build_ms > 0


def test_particle_hair_collides_with_the_emitter_it_grows_from(open_fixture):
    """Legacy particle hair: the hair object is the head mesh itself, and the run collides
    with it (it had been left out as the hair object, so such hair passed through its head)."""
    scene = open_fixture("head_particles.blend")
    body = bpy.data.objects["Body"]
    assert colliders.collider_objects(body, body, scene) == [body]
    # Its particle system modifier does not change its shape: it follows by its transform.
    assert colliders.Colliders(body, body, scene, depsgraph()).deforming == [False]
    body.modifiers.new("Collision", 'COLLISION')
    assert colliders.Colliders(body, body, scene, depsgraph()).deforming == [False]
    body.hairdyn.method = 'STRANDS'
    report = simulation.run(bpy.context, body, 1, 2)
    assert report["colliders"] == ["Body"]


def test_rigid_motion_moves_the_maps_without_rebuilding(open_fixture):
    scene = open_fixture("head_shake.blend")
    hair, body = bpy.data.objects["Hair"], bpy.data.objects["Body"]
    built = colliders.Colliders(hair, body, scene, depsgraph())
    assert built.deforming == [False]
    head_center_local = np.array([0.0, 0.0, 0.2])
    scene.frame_set(30)
    built.update(depsgraph())
    matrix = np.array(body.matrix_world)
    center_wo = (matrix @ np.append(head_center_local, 1.0))[:3].astype(np.float32)
    hits = built.set.find_contacts(center_wo[None, :])
    assert hits["hit"][0] and hits["depth"][0] > 0.05  # the moved head's centre is inside


def test_deforming_collider_is_rebuilt_each_frame(open_fixture):
    scene = open_fixture("head_curves.blend")
    hair, body = bpy.data.objects["Hair"], bpy.data.objects["Body"]
    displace = body.modifiers.new("Inflate", 'DISPLACE')
    displace.mid_level = 0.0
    displace.strength = 0.0
    displace.keyframe_insert("strength", frame=1)
    displace.strength = 0.05
    displace.keyframe_insert("strength", frame=10)
    scene.frame_set(1)
    built = colliders.Colliders(hair, body, scene, depsgraph())
    assert built.deforming == [True]
    # 2 cm above the crown: outside the rest head, inside the head inflated by 5 cm.
    crown = (np.array(body.matrix_world) @ np.array([0.0, 0.0, 0.2 + 0.112 + 0.02, 1.0]))[:3]
    point = crown.astype(np.float32)[None, :]
    assert not built.set.find_contacts(point)["hit"][0]
    scene.frame_set(10)
    rebuild_ms = built.update(depsgraph())
    assert rebuild_ms > 0
    assert built.set.find_contacts(point)["hit"][0]


@pytest.mark.parametrize("method", ['STRANDS', 'LCP', 'FOLLOW'])
def test_a_collider_scaled_to_nothing_mid_run_stops_it_with_its_name_and_frame(
        open_fixture, method):
    """The body's scale keyed to 0 at frame 3: the run stops there with a sentence naming the
    collider and the frame (the native module's refusal of a transform with no inverse), not
    a bare ValueError; the frames before were written."""
    open_fixture("head_shake.blend")
    hair, body = bpy.data.objects["Hair"], bpy.data.objects["Body"]
    hair.hairdyn.method = method
    if method == 'LCP':
        hair.hairdyn.lcp.particle_num = 500
    body.keyframe_insert("scale", frame=1)
    body.scale = (0.0, 0.0, 0.0)
    body.keyframe_insert("scale", frame=3)
    with pytest.raises(HairdynError, match="Collider 'Body' at frame 3: .*singular"):
        simulation.run(bpy.context, hair, 1, 4)


def test_a_frame_rate_slower_than_ten_seconds_a_frame_is_refused(open_fixture):
    """Blender lets a frame last 1,000 s (1 frame a second over a base of 1,000); the solvers
    step at most 10 s a frame, and the run says so before it starts."""
    open_fixture("head_shake.blend")
    hair = bpy.data.objects["Hair"]
    hair.hairdyn.method = 'STRANDS'
    render = bpy.context.scene.render
    render.fps, render.fps_base = 1, 1000.0
    with pytest.raises(HairdynError, match="makes a frame 1000 s long"):
        simulation.run(bpy.context, hair, 1, 2)
