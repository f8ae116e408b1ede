"""The volume (Petrovic 2006) in the add-on: velocity smoothing, targeting and shell normals
through the Strands method, its report fields, the shell_normal attribute in outputs and
cache, and the Cycles pictures of Sintel's groom shaded by the shell against the default hair
shader (Fig. 3(b) against 3(c)), kept as files."""

import bpy
import numpy as np
from mathutils import Vector

from hairdyn import bake, simulation
from render_check import cycles_pixels
from test_sintel import sintel_scene


def test_volume_options_report_and_shell_normal_attribute(open_fixture, tmp_path):
    open_fixture("head_shake.blend")
    hair = bpy.data.objects["Hair"]
    settings = hair.hairdyn
    settings.method = 'STRANDS'
    settings.strands.children_per_guide = 0
    settings.volume_options.use_smoothing = True
    settings.volume_options.use_shell_normals = True
    settings.frame_start, settings.frame_end = 1, 6
    settings.cache_directory = str(tmp_path)
    bpy.context.view_layer.objects.active = hair
    assert bpy.ops.hairdyn.bake() == {'FINISHED'}
    from hairdyn.cache import Cache

    cache = Cache.open(bake.cache_directory(hair))
    report = cache.manifest["report"]
    assert report["volume_ms"] > 0.0 and report["density_max"] > 0.0
    normals = cache.read_frame(6)["shell_normal"]
    assert normals.shape == (settings.output_curves.data.points.__len__(), 3)
    assert np.allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-3)
    attribute = settings.output_curves.data.attributes["shell_normal"]
    shown = np.empty(len(attribute.data) * 3, dtype=np.float32)
    attribute.data.foreach_get("vector", shown)
    assert np.isfinite(shown).all() and np.abs(shown).max() > 0.5


def test_sintel_shell_normals_against_the_default_hair_shader(artifacts):
    hair, bust = sintel_scene()
    settings = hair.hairdyn
    settings.use_collision = False
    settings.volume_options.use_shell_normals = True
    simulation.run(bpy.context, hair, 1, 2)
    output = settings.output_curves
    scene = bpy.context.scene
    camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(camera)
    scene.camera = camera
    box = np.array([bust.matrix_world @ Vector(corner) for corner in bust.bound_box])
    centre, size = box.mean(axis=0), np.ptp(box, axis=0).max()
    camera.location = centre + np.array([0.0, -1.6 * size, 0.25 * size])
    camera.rotation_euler = (np.radians(83), 0.0, 0.0)
    light = bpy.data.objects.new("Sun", bpy.data.lights.new("Sun", 'SUN'))
    light.rotation_euler = (np.radians(50), 0.0, np.radians(40))
    scene.collection.objects.link(light)
    hair.hide_render = True
    default = bpy.data.materials.new("default_hair")
    default.use_nodes = True
    images = {}
    for name, material in (
        ("shell_normals", bpy.data.materials["hairdyn_shell_normals"]),
        ("default_hair", default),
    ):
        output.data.materials.clear()
        output.data.materials.append(material)
        path = artifacts / f"sintel_{name}_{bpy.app.version_string.split()[0]}.png"
        images[name] = cycles_pixels(scene, path, 160)
        assert path.is_file()
    assert np.abs(images["shell_normals"] - images["default_hair"]).mean() > 0.002
