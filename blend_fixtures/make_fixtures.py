"""Regenerates every .blend fixture of hairdyn. Run with Blender 3.4 (the oldest supported
Blender) so every supported host opens the files:

    blender -b --factory-startup --python blend_fixtures/make_fixtures.py

Makes, next to this script:
  head_curves.blend     Body (head + neck + torso, vertex groups head/neck/torso/scalp, UVs)
                        and "Hair": Curves grown on the scalp, surface = Body, parented to it
  head_particles.blend  the same Body carrying the same groom as legacy particle hair
  head_shake.blend      head_curves with the Body shaking its head (frames 1-72)
Units are meters, Z up, the face looks along -Y.
"""
import math
import sys
from pathlib import Path

import bmesh
import bpy
from mathutils import Matrix, Vector

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "addon"))

HEAD_CENTER = Vector((0.0, 0.0, 0.2))  # Body space; the Body origin is the neck base
HEAD_RADIUS = 0.1
STRANDS = 300
HAIR_LENGTH = 0.22
HAIR_STEP = 8  # keys per strand - 1; display_step 3 gives 9 points per strand


def add_part(name, geom_verts, groups):
    groups[name] = [v.index for v in geom_verts]


def make_body():
    bm = bmesh.new()
    bm.loops.layers.uv.new("UVMap")  # calc_uvs fills this layer
    groups = {}
    # Torso and neck: closed cylinders; head: a slightly long sphere.
    torso = bmesh.ops.create_cone(bm, cap_ends=True, segments=24, radius1=0.17, radius2=0.15,
                                  depth=0.5, matrix=Matrix.Translation((0, 0, -0.28)) @
                                  Matrix.Diagonal((1.0, 0.6, 1.0, 1.0)), calc_uvs=True)
    bm.verts.index_update()
    add_part("torso", torso["verts"], groups)
    neck = bmesh.ops.create_cone(bm, cap_ends=True, segments=16, radius1=0.055, radius2=0.05,
                                 depth=0.16, matrix=Matrix.Translation((0, 0, 0.05)),
                                 calc_uvs=True)
    bm.verts.index_update()
    add_part("neck", neck["verts"], groups)
    head = bmesh.ops.create_uvsphere(bm, u_segments=32, v_segments=16, radius=HEAD_RADIUS,
                                     matrix=Matrix.Translation(HEAD_CENTER) @
                                     Matrix.Diagonal((0.85, 1.0, 1.12, 1.0)), calc_uvs=True)
    bm.verts.index_update()
    add_part("head", head["verts"], groups)
    scalp = []
    for v in head["verts"]:
        p = v.co - HEAD_CENTER
        face = p.y < -0.03 and p.z < 0.06  # forehead and face stay bare
        if p.z > -0.03 and not face:
            scalp.append(v.index)
    groups["scalp"] = scalp
    mesh = bpy.data.meshes.new("Body")
    bm.to_mesh(mesh)
    bm.free()
    for polygon in mesh.polygons:
        polygon.use_smooth = True
    body = bpy.data.objects.new("Body", mesh)
    body.location = (0.0, 0.0, 1.4)
    for name, indices in groups.items():
        group = body.vertex_groups.new(name=name)
        group.add(indices, 1.0, 'REPLACE')
    skin = bpy.data.materials.new("Skin")
    skin.diffuse_color = (0.8, 0.6, 0.5, 1.0)
    skin.use_nodes = True
    skin.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.8, 0.6, 0.5, 1)
    mesh.materials.append(skin)
    return body


def hair_material():
    material = bpy.data.materials.new("Hair")
    material.diffuse_color = (0.35, 0.2, 0.1, 1.0)
    material.use_nodes = True
    nodes, links = material.node_tree.nodes, material.node_tree.links
    nodes.remove(nodes["Principled BSDF"])
    hair = nodes.new("ShaderNodeBsdfHairPrincipled")
    links.new(hair.outputs[0], nodes["Material Output"].inputs["Surface"])
    return material


def add_particle_hair(body):
    modifier = body.modifiers.new("Hair", 'PARTICLE_SYSTEM')
    settings = modifier.particle_system.settings
    settings.name = "Hair"
    settings.type = 'HAIR'
    settings.count = STRANDS
    settings.hair_length = HAIR_LENGTH
    settings.hair_step = HAIR_STEP
    settings.display_step = 3
    settings.render_step = 3
    settings.emit_from = 'FACE'
    settings.distribution = 'RAND'
    modifier.particle_system.seed = 7
    modifier.particle_system.vertex_group_density = "scalp"
    return modifier.particle_system


def scene_setup(scene, frame_end):
    scene.frame_start, scene.frame_end = 1, frame_end
    scene.render.fps = 24
    scene.render.engine = 'CYCLES'
    scene.cycles.samples = 16
    scene.cycles.use_denoising = False
    scene.render.resolution_x, scene.render.resolution_y = 320, 240
    scene.render.resolution_percentage = 100
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    camera.location = (0.55, -0.95, 1.75)
    camera.rotation_euler = (math.radians(82), 0.0, math.radians(30))
    camera.data.lens = 50
    scene.collection.objects.link(camera)
    scene.camera = camera
    sun = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", 'SUN'))
    sun.rotation_euler = (math.radians(40), math.radians(10), math.radians(30))
    sun.data.energy = 4.0
    scene.collection.objects.link(sun)
    world = bpy.data.worlds.new("World")
    world.color = (0.05, 0.05, 0.06)
    scene.world = world


def new_scene(frame_end):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene_setup(scene, frame_end)
    body = make_body()
    scene.collection.objects.link(body)
    return scene, body


def convert_to_curves(body):
    """The particle groom as a Curves object on the Body's surface, parented to it."""
    view_layer = bpy.context.view_layer
    view_layer.objects.active = body
    before = set(bpy.data.objects)
    with bpy.context.temp_override(object=body, active_object=body, selected_objects=[body],
                                   selected_editable_objects=[body]):
        bpy.ops.curves.convert_from_particle_system()
    hair = next(o for o in bpy.data.objects if o not in before)
    hair.name = hair.data.name = "Hair"
    hair.parent = body
    hair.matrix_parent_inverse = Matrix.Identity(4)
    hair.matrix_basis = Matrix.Identity(4)
    hair.data.surface = body
    hair.data.surface_uv_map = body.data.uv_layers[0].name
    with bpy.context.temp_override(object=hair, active_object=hair, selected_objects=[hair],
                                   selected_editable_objects=[hair]):
        bpy.ops.curves.snap_curves_to_surface(attach_mode='NEAREST')
    comb(hair.data)
    hair.data.materials.append(hair_material())
    body.modifiers.remove(body.modifiers["Hair"])
    return hair


def comb(curves):
    """Combs the straight particle strands down and outward over the head, keeping every
    segment length, and gives them a tapered radius (1.2 mm at the root to 0.4 mm)."""
    import numpy as np

    positions = np.empty((len(curves.points), 3), dtype=np.float32)
    offsets = np.empty(len(curves.curves) + 1, dtype=np.int32)
    curves.position_data.foreach_get("vector", positions.ravel())
    curves.curve_offset_data.foreach_get("value", offsets)
    radius = np.empty(len(positions), dtype=np.float32)
    center = np.array(HEAD_CENTER)
    down = np.array((0.0, 0.0, -1.0))
    for start, end in zip(offsets[:-1], offsets[1:]):
        strand = positions[start:end].astype(np.float64)
        lengths = np.linalg.norm(np.diff(strand, axis=0), axis=1)
        normal = (strand[1] - strand[0]) / lengths[0]
        radial = strand[0] - center
        radial[2] = 0.0
        radial /= max(np.linalg.norm(radial), 1e-9)
        t = np.linspace(0.0, 1.0, len(lengths))
        for k, length in enumerate(lengths):
            direction = normal + 2.5 * t[k] * (0.45 * radial + down)
            strand[k + 1] = strand[k] + length * direction / np.linalg.norm(direction)
        positions[start:end] = strand
        radius[start:end] = np.linspace(0.0012, 0.0004, end - start)
    curves.position_data.foreach_set("vector", positions.ravel())
    curves.attributes.new("radius", 'FLOAT', 'POINT').data.foreach_set("value", radius)


def configure(obj, frame_end):
    import hairdyn

    if not hasattr(bpy.types.Object, "hairdyn"):
        hairdyn.register()
    obj.hairdyn.frame_start, obj.hairdyn.frame_end = 1, frame_end
    obj.hairdyn.enabled = True


def save(name):
    path = HERE / name
    bpy.ops.wm.save_as_mainfile(filepath=str(path), compress=True)
    print(f"fixture: wrote {path}")


def shake(body, frame_end):
    """A 'no' shake with a nod and a step to the side: rotation and translation keys."""
    keys = [(1, 0, 0, 0.0), (12, 35, 8, 0.04), (24, -35, -6, 0.0), (36, 30, 10, -0.04),
            (48, -25, -4, 0.0), (60, 0, 0, 0.02), (frame_end, 0, 0, 0.0)]
    for frame, yaw, pitch, x in keys:
        body.rotation_euler = (math.radians(pitch), 0.0, math.radians(yaw))
        body.location = (x, 0.0, 1.4)
        body.keyframe_insert("rotation_euler", frame=frame)
        body.keyframe_insert("location", frame=frame)


def main():
    _, body = new_scene(48)
    add_particle_hair(body)
    configure(body, 48)
    save("head_particles.blend")

    _, body = new_scene(48)
    add_particle_hair(body)
    hair = convert_to_curves(body)
    configure(hair, 48)
    save("head_curves.blend")

    _, body = new_scene(72)
    add_particle_hair(body)
    hair = convert_to_curves(body)
    configure(hair, 72)
    shake(body, 72)
    save("head_shake.blend")


main()
