"""The volume (Petrovic 2006) in the add-on: velocity smoothing, targeting and shell normals
through the Strands method, its report fields, the shell_normal attribute in outputs and
cache, and the Cycles pictures of Sintel's groom shaded by the shell against the default hair
shader (Fig. 3(b) against 3(c)), kept as files."""

import bpy
import numpy as np
import pytest
from mathutils import Vector

from hairdyn import bake, simulation
from render_check import cycles_pixels
from test_sintel import sintel_scene


def shake_hair(open_fixture, tmp_path, frames, children_per_guide=0, **options):
    """The shipped head-shake example's hair on the Strands method, active, baking frames
    1..frames into tmp_path, with these volume_options switched on."""
    open_fixture("head_shake.blend")
    hair = bpy.data.objects["Hair"]
    settings = hair.hairdyn
    settings.method = 'STRANDS'
    settings.strands.children_per_guide = children_per_guide
    for name, value in options.items():
        setattr(settings.volume_options, name, value)
    settings.frame_start, settings.frame_end = 1, frames
    settings.cache_directory = str(tmp_path)
    bpy.context.view_layer.objects.active = hair
    return hair


def test_volume_options_report_and_shell_normal_attribute(open_fixture, tmp_path):
    hair = shake_hair(open_fixture, tmp_path, 6, use_smoothing=True, use_shell_normals=True)
    settings = hair.hairdyn
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


def test_child_hairs_carry_the_shell_normals(open_fixture, tmp_path):
    """§4.1's normals on the child hairs too: each child point takes its guide's normal at its
    place along it (children beside their guides), unit length, in the output and the cache."""
    hair = shake_hair(open_fixture, tmp_path, 3, children_per_guide=2, use_shell_normals=True)
    settings = hair.hairdyn
    assert bpy.ops.hairdyn.bake() == {'FINISHED'}
    from hairdyn.cache import Cache

    cache = Cache.open(bake.cache_directory(hair))
    guides = cache.read_frame(3)["shell_normal"]
    children = cache.read_stream("children", 3)["shell_normal"]
    assert np.allclose(np.linalg.norm(children, axis=1), 1.0, atol=1e-5)
    guide_offsets = cache.curve_offsets()
    child_offsets = cache.stream_offsets("children")
    for child in range(len(child_offsets) - 1):
        guide = child // 2  # children come guide by guide
        mine = children[child_offsets[child] : child_offsets[child + 1]]
        theirs = guides[guide_offsets[guide] : guide_offsets[guide + 1]]
        assert mine.shape == theirs.shape
        np.testing.assert_allclose(mine, theirs, atol=1e-5)
    bpy.context.scene.frame_set(3)  # playback shows the baked frame
    attribute = settings.output_children.data.attributes["shell_normal"]
    shown = np.empty(len(attribute.data) * 3, dtype=np.float32)
    attribute.data.foreach_get("vector", shown)
    np.testing.assert_array_equal(shown.reshape(-1, 3), children)


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
    if default.node_tree is None:  # newer Blender gives every material its node tree
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


def test_grid_preview_bakes_the_density_as_a_volume_sequence(open_fixture, tmp_path):
    """Grid Preview: each baked frame's density (eq. 1) as density/density_<frame>.vdb beside
    the bake, played by the Volume object '<hair> density' at each file's own frame; a bake
    of fewer frames drops the older files. Where the host has no OpenVDB writer, the bake
    refuses to start and says why."""
    from hairdyn import volume_vdb
    from hairdyn.errors import HairdynError

    hair = shake_hair(open_fixture, tmp_path, 4, use_grid_preview=True)
    settings = hair.hairdyn
    writer, reason = volume_vdb.find_writer()
    if writer is None:
        with pytest.raises(HairdynError, match="Grid Preview"):
            bake.start_bake(bpy.context, hair)
        assert not any(tmp_path.rglob("*.npy"))
        pytest.skip(f"no OpenVDB writer in this host: {reason}")
    assert bpy.ops.hairdyn.bake() == {'FINISHED'}
    folder = bake.cache_directory(hair) / "density"
    assert sorted(p.name for p in folder.iterdir()) == [
        f"density_{frame:06d}.vdb" for frame in range(1, 5)
    ]
    obj = bpy.data.objects["Hair density"]
    assert obj.type == 'VOLUME' and obj.data.is_sequence
    assert (obj.data.frame_start, obj.data.frame_duration) == (1, 4)
    grid = writer.read(str(folder / "density_000003.vdb"), "density")
    assert grid.evalMinMax()[1] > 0.5  # nodes per vertex: the hair is in it
    for frame in (2, 4):
        bpy.context.scene.frame_set(frame)
        shown = obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).data.grids
        assert shown.frame_filepath.endswith(f"density_{frame:06d}.vdb")
        assert [g.name for g in shown] == ["density"]

    settings.frame_start, settings.frame_end = 2, 3
    assert bpy.ops.hairdyn.bake() == {'FINISHED'}
    assert sorted(p.name for p in folder.iterdir()) == ["density_000002.vdb", "density_000003.vdb"]
    assert (obj.data.frame_start, obj.data.frame_duration) == (2, 2)


def test_target_from_a_frame_of_the_bake(open_fixture, tmp_path):
    """Target from Bake Frame (§5.2): a snapshot of a baked frame becomes the Target, placed
    as the head at the first simulated frame carries it; it outlives a new bake, and the run
    directs toward it. A frame the bake lacks is an error that changes nothing."""
    hair = shake_hair(open_fixture, tmp_path, 8)
    settings = hair.hairdyn
    assert bpy.ops.hairdyn.bake() == {'FINISHED'}
    from hairdyn.cache import Cache

    baked = Cache.open(bake.cache_directory(hair)).read_frame(6)["position"].copy()
    with pytest.raises(RuntimeError, match="Frame 99 is not in the cache"):
        bpy.ops.hairdyn.target_from_bake(frame=99)
    assert settings.volume_options.target is None

    assert bpy.ops.hairdyn.target_from_bake(frame=6) == {'FINISHED'}
    target = settings.volume_options.target
    assert target is not None and target.name == "Hair target 6" and target.hide_render
    shown = np.empty(len(target.data.points) * 3, dtype=np.float32)
    target.data.position_data.foreach_get("vector", shown)
    # In the head's frame the snapshot is the baked frame 6.
    head = settings.head or hair.data.surface
    scene = bpy.context.scene
    heads = {}
    for frame in (1, 6):
        scene.frame_set(frame)
        heads[frame] = np.array(
            head.evaluated_get(bpy.context.evaluated_depsgraph_get()).matrix_world
        )
    assert not np.allclose(heads[1], heads[6])  # the head turns: the placement matters

    def in_head(matrix, points):
        inverse = np.linalg.inv(matrix)
        return points @ inverse[:3, :3].T + inverse[:3, 3]

    np.testing.assert_allclose(
        in_head(heads[1], shown.reshape(-1, 3)), in_head(heads[6], baked), atol=1e-5
    )
    assert bpy.ops.hairdyn.bake() == {'FINISHED'}  # a new bake keeps the snapshot
    assert settings.volume_options.target == target
    cache = Cache.open(bake.cache_directory(hair))
    report = cache.manifest["report"]
    assert np.isfinite(report["target_error"]) and report["target_error"] > 0.0
    # Directed: eq. 3's error to the snapshot falls over the run.
    runner = simulation.Runner(bpy.context, hair, 1, 8)
    errors = []
    try:
        while not runner.done:
            runner.advance()
            errors.append(runner.simulation.method.attached[0].volume_pass.target_error)
    finally:
        runner.close()
    print("eq. 3 error by frame:", [round(e) for e in errors])
    assert errors[-1] < 0.2 * errors[0]
