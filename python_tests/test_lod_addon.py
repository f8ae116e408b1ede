"""Level of detail (Ward & Lin 2003 §4, §6) in the add-on: the Strands method's section, a bake
through the LodSolver that keeps the groom's topology and writes `lod_level`, the camera that
chooses the levels (the scene's, or the section's own), lod_error against a fine simulation,
the report, and the combinations it refuses."""

import bpy
import numpy as np
import pytest
from mathutils import Vector

from conftest import scale_radius_attribute
from hairdyn import bake, cli, native, simulation, ui
from hairdyn.errors import HairdynError
from layout_recorder import Layout
from render_check import cycles_pixels

SECTION = "Level of Detail (Ward & Lin 2003)"


def lod_hair(open_fixture, name="head_curves.blend"):
    """The fixture's hair on the Strands method with level of detail on, no child hairs."""
    open_fixture(name)
    hair = bpy.data.objects["Hair"]
    settings = hair.hairdyn
    settings.method = 'STRANDS'
    settings.strands.children_per_guide = 0
    settings.lod.enabled = True
    return hair


def camera_facing_hair(hair, distance, name="LodCamera"):
    """A camera `distance` metres from the hair's centre along the fixture camera's view axis."""
    positions = np.array([p.position for p in hair.data.points])
    centre = hair.matrix_world @ Vector(positions.mean(axis=0).tolist())
    scene_camera = bpy.data.objects["Camera"]
    forward = scene_camera.matrix_world.to_3x3() @ Vector((0.0, 0.0, -1.0))
    camera = bpy.data.objects.new(name, bpy.data.cameras.new(name))
    camera.data.clip_end = 1000.0
    camera.matrix_world = scene_camera.matrix_world.copy()
    camera.location = centre - forward.normalized() * distance
    bpy.context.scene.collection.objects.link(camera)
    return camera


def levels(hair):
    """The output curves' lod_level point attribute."""
    attribute = hair.hairdyn.output_curves.data.attributes["lod_level"]
    values = np.empty(len(attribute.data), dtype=np.float32)
    attribute.data.foreach_get("value", values)
    return values


def test_section_shows_the_lod_fields_with_enabled_in_its_header(open_fixture):
    open_fixture("head_curves.blend")
    hair = bpy.data.objects["Hair"]
    settings = hair.hairdyn
    assert not settings.lod.enabled  # off until asked for: it needs a camera
    panel = next(p for p in ui.panel_classes() if getattr(p, "bl_label", "") == SECTION)

    class Context:
        object = hair

    settings.method = 'LCP'
    assert not panel.poll(Context)
    settings.method = 'STRANDS'
    assert panel.poll(Context)

    class Section(Layout):  # rows of their own, so the section's own `active` stays
        def row(self, **_):
            return Layout(self.shown)

    header, rows = [], []
    panel.draw_header(type("Header", (), {"layout": Layout(header)})(), Context)
    layout = Section(rows)
    panel.draw_settings(None, layout, settings)
    assert header == ["enabled"]
    assert not layout.active  # greyed out while off
    settings.lod.enabled = True
    panel.draw_settings(None, layout, settings)
    assert layout.active
    fields = {f["name"] for f in native.load().LodParams.fields()} - {"enabled"}
    assert fields <= set(rows) and "enabled" not in rows
    assert {"camera", "measure_error", "distance_near", "merge_threshold"} <= set(rows)
    assert rows.index("camera") < rows.index("distance_near")


def test_bake_keeps_the_topology_and_writes_lod_level(saved_fixture):
    hair = saved_fixture("head_shake.blend", 3)
    settings = hair.hairdyn
    settings.method = 'STRANDS'
    settings.strands.children_per_guide = 0
    settings.lod.enabled = True
    settings.lod.skeleton_points = 1000  # more than the strands have: theirs
    assert bpy.ops.hairdyn.bake() == {'FINISHED'}
    from hairdyn.cache import Cache

    cache = Cache.open(bake.cache_directory(hair))
    report = cache.manifest["report"]
    assert report["frames"] == 3 and report["nan_frames"] == 0
    per_level = report["skeletons_per_level"]
    assert len(per_level["min"]) == len(per_level["mean"]) == len(per_level["max"]) >= 2
    assert all(
        a <= b <= c for a, b, c in zip(per_level["min"], per_level["mean"], per_level["max"])
    )
    assert report["lod_switches"] > 0  # the first frame splits to the levels the camera asks
    assert report["lod_ms"] > 0.0 and report["lod_camera"] == "Camera"
    assert "lod_error" not in report  # not measured unless asked for
    output = settings.output_curves.data
    sizes = [len(curve.points) for curve in hair.data.curves]
    assert [len(curve.points) for curve in output.curves] == sizes
    assert report["lod_skeleton_points"] == max(sizes)
    bpy.context.scene.frame_set(3)  # the bake plays back: frame 3's levels on the output
    shown = levels(hair)
    cached = cache.read_frame(3)["lod_level"]
    np.testing.assert_array_equal(shown, cached.ravel())
    assert np.isfinite(shown).all() and (shown == np.round(shown)).all()
    finest = len(per_level["min"]) - 1
    assert shown.min() >= 0 and shown.max() <= finest


def test_far_camera_keeps_the_coarsest_level_and_a_close_one_refines(open_fixture):
    hair = lod_hair(open_fixture)
    settings = hair.hairdyn
    settings.lod.velocity_slow, settings.lod.velocity_fast = 50.0, 100.0  # distance decides
    far = camera_facing_hair(hair, 40.0)
    settings.lod_options.camera = far  # the section's camera over the scene's (≈1 m away)
    report = simulation.run(bpy.context, hair, 1, 2)
    assert (levels(hair) == report["lod_coarsest_level"]).all()
    assert report["skeletons_per_level"]["max"][0] == report["lod_strips"]
    assert sum(report["skeletons_per_level"]["max"][1:]) == 0
    settings.lod_options.camera = camera_facing_hair(hair, 0.3, "Close")
    report = simulation.run(bpy.context, hair, 1, 2)
    close = levels(hair)
    assert close.max() == report["lod_finest_level"] > report["lod_coarsest_level"]
    assert len(np.unique(close)) >= 2


def test_lod_error_is_measured_against_the_fine_strands(open_fixture):
    hair = lod_hair(open_fixture, "head_shake.blend")
    hair.hairdyn.lod_options.measure_error = True
    report = simulation.run(bpy.context, hair, 1, 4)
    assert 0.0 < report["lod_error"] <= report["lod_error_max"] < 0.05  # of the hair length
    assert report["lod_fine_ms"] > 0.0


def test_volume_passes_and_no_camera_are_refused_with_a_sentence(open_fixture):
    hair = lod_hair(open_fixture)
    settings = hair.hairdyn
    cli.apply_settings(settings, ["lod.enabled=true", "volume_options.use_smoothing=true"])
    with pytest.raises(
        HairdynError,
        match="runs only the swept spheres' substep passes, so it cannot be combined with Volume",
    ):
        simulation.run(bpy.context, hair, 1, 1)
    settings.volume_options.use_smoothing = False
    bpy.context.scene.camera = None
    with pytest.raises(HairdynError, match="needs a camera"):
        simulation.run(bpy.context, hair, 1, 1)
    cli.apply_settings(settings, ["lod_options.camera=Camera"])  # by name, as --set takes it
    assert simulation.run(bpy.context, hair, 1, 1)["lod_camera"] == "Camera"


def test_colour_by_level_shades_the_output_and_gives_the_groom_back(open_fixture, artifacts):
    hair = lod_hair(open_fixture)
    settings = hair.hairdyn
    settings.lod.velocity_slow, settings.lod.velocity_fast = 50.0, 100.0  # distance decides
    camera = camera_facing_hair(hair, 0.3, "Close")
    settings.lod_options.camera = camera
    settings.lod_options.color_by_level = True  # no output yet: the run puts it on
    report = simulation.run(bpy.context, hair, 1, 2)
    output = settings.output_curves
    slot = output.material_slots[0]
    assert slot.link == 'OBJECT' and slot.material.name == "hairdyn_lod_level"
    groom = [m.name for m in hair.data.materials if m is not None]
    assert [m.name for m in output.data.materials if m is not None] == groom  # untouched
    tree = slot.material.node_tree
    reader = next(n for n in tree.nodes if n.bl_idname == "ShaderNodeAttribute")
    assert reader.attribute_name == "lod_level" and "lod_level" in output.data.attributes
    finest = report["lod_finest_level"]
    assert tree.nodes["finest_level"].inputs[1].default_value == max(1, finest)
    assert len(np.unique(levels(hair))) >= 2  # a coarse and a fine colour to see

    # What a render shows: the coarse strands red, the finest blue.
    scene = bpy.context.scene
    scene.camera = camera
    for other in list(scene.objects):
        if other not in (output, camera):
            other.hide_render = True
    scene.world = scene.world or bpy.data.worlds.new("World")
    path = artifacts / f"lod_levels_{bpy.app.version_string.split()[0]}.png"
    rgb = cycles_pixels(scene, path, 120)[:, :3]
    red = (rgb[:, 0] > 2.0 * rgb[:, 2] + 0.02).sum()
    blue = (rgb[:, 2] > 2.0 * rgb[:, 0] + 0.02).sum()
    assert red > 20 and blue > 20, (red, blue)

    settings.lod_options.color_by_level = False  # the groom's materials again, at once
    assert output.material_slots[0].link == 'DATA'
    settings.lod_options.color_by_level = True
    assert output.material_slots[0].material.name == "hairdyn_lod_level"


def test_colour_by_level_shows_from_the_first_frame_written(open_fixture):
    hair = lod_hair(open_fixture)
    hair.hairdyn.lod_options.color_by_level = True
    simulation.run(bpy.context, hair, 1, 1)  # a one-frame run: the output is made by it
    slot = hair.hairdyn.output_curves.material_slots[0]
    assert slot.link == 'OBJECT' and slot.material.name == "hairdyn_lod_level"


def test_swept_spheres_run_on_the_skeletons_of_every_level(open_fixture):
    """Hair-hair and segment-exact body collision under level of detail (Ward & Lin 2003 §5.2
    with §6): the report carries both passes' figures, a close camera still refines, and the
    fine reference of lod_error runs the same passes."""
    hair = lod_hair(open_fixture, "head_shake.blend")
    settings = hair.hairdyn
    settings.lod_options.camera = camera_facing_hair(hair, 0.3, "Close")
    settings.lod_options.measure_error = True
    cli.apply_settings(settings, ["hair_hair=true", "body_collision=swept_spheres"])
    report = simulation.run(bpy.context, hair, 1, 4)
    assert report["nan_frames"] == 0
    assert report["hair_hair_ms"] > 0.0 and report["hair_hair_pairs"] >= 0
    assert report["crossings"] >= 0
    assert 0.0 <= report["segment_penetration_share"] <= 0.001
    # The placed strands stay out of the head too (LodSolver.set_bodies): measured 0.15 mm
    # deep at most; 2.3 mm when only the skeletons were kept out.
    assert report["penetration_max"] < 0.001
    assert report["lod_finest_level"] > report["lod_coarsest_level"]
    assert len(np.unique(levels(hair))) >= 2
    # Measured (stop 47): 1.02% of the hair length with both passes, 0.43% without either.
    assert 0.0 < report["lod_error"] < 0.04


def test_the_curves_radius_attribute_sizes_the_group_volumes(open_fixture):
    """Under level of detail the groups' swept spheres take their strands' Curves radius
    attribute (the widest strand's radius at each skeleton point, plus the group's spread), as
    plain strands do; Strand Thickness stands in where there is none."""

    def run_with(scale):
        hair = lod_hair(open_fixture, "head_shake.blend")
        settings = hair.hairdyn
        settings.lod_options.camera = camera_facing_hair(hair, 0.3, "Close")
        scale_radius_attribute(hair, scale)
        cli.apply_settings(settings, ["hair_hair=true", "swept_spheres.thickness=0.5"])  # mm
        return simulation.run(bpy.context, hair, 1, 3)

    none, thin, thick = run_with(None), run_with(0.25), run_with(4.0)
    assert thin["hair_hair_pairs"] < none["hair_hair_pairs"] < thick["hair_hair_pairs"]


def ribbon_vertices(strips_obj):
    """(ribbons, 2 n, 3): the strips mesh's vertices, ribbon by ribbon (faces of 4)."""
    mesh = strips_obj.data
    positions = np.empty((len(mesh.vertices), 3), dtype=np.float32)
    mesh.vertices.foreach_get("co", positions.ravel())
    corners = np.empty(4 * len(mesh.polygons), dtype=np.int32)
    mesh.polygons.foreach_get("vertices", corners)
    return positions, corners.reshape(-1, 4)


def test_ribbon_faces_join_each_pair_of_vertices_to_the_next():
    from hairdyn import bridge

    assert bridge.ribbon_faces([0, 4, 10]).tolist() == [
        [0, 1, 3, 2],
        [4, 5, 7, 6],
        [6, 7, 9, 8],
    ]


def test_strips_show_as_ribbons_when_asked_and_play_back(saved_fixture):
    """Every strip of the hierarchy is a ribbon of the Output Strips mesh (a quad between each
    skeleton point's pair of vertices and the next), made hidden and shown while Strips as
    Ribbons is on; the strips not driving hair have no area; a bake plays them back."""
    hair = saved_fixture("head_curves.blend", 2)
    settings = hair.hairdyn
    settings.method = 'STRANDS'
    settings.strands.children_per_guide = 0
    settings.lod.enabled = True
    settings.lod.velocity_slow, settings.lod.velocity_fast = 50.0, 100.0  # distance decides
    settings.lod_options.camera = camera_facing_hair(hair, 40.0)  # the top strips alone
    report = simulation.run(bpy.context, hair, 1, 2)
    strips = settings.output_strips
    assert strips.name == "Hair_hairdyn_strips" and strips.users_scene
    assert report["output_strips"] == strips.name and report["output_children"] is None
    assert strips.hide_render and strips.hide_viewport  # until asked for
    positions, faces = ribbon_vertices(strips)
    n = report["lod_skeleton_points"]
    ribbons = len(positions) // (2 * n)
    assert len(positions) == 2 * n * ribbons and len(faces) == (n - 1) * ribbons
    assert ribbons > report["lod_strips"]  # the top strips and their halves

    def shown(positions):
        per_ribbon = positions.reshape(ribbons, 2 * n, 3)
        return (np.ptp(per_ribbon, axis=1).max(axis=1) > 0).sum()

    assert shown(positions) == report["lod_strips"]  # the far camera: the top strips drive
    attribute = strips.data.attributes["lod_level"]
    level = np.empty(len(attribute.data), dtype=np.float32)
    attribute.data.foreach_get("value", level)
    assert (level[: 2 * n * report["lod_strips"]] == 0).all() and level.max() >= 1
    assert strips.data.materials[0].name == "hairdyn_lod_level"  # coloured by level

    settings.lod_options.show_strips = True
    assert not strips.hide_render and not strips.hide_viewport
    settings.lod_options.camera = camera_facing_hair(hair, 0.3, "Close")
    assert bpy.ops.hairdyn.bake() == {'FINISHED'}
    from hairdyn.cache import Cache

    cache = Cache.open(bake.cache_directory(hair))
    baked = cache.read_stream("strips", 2)["position"]
    assert 0 < shown(baked) < report["lod_strips"] * 2  # strips split into clusters
    bpy.context.scene.frame_set(1)
    bpy.context.scene.frame_set(2)  # played back from the cache
    np.testing.assert_array_equal(ribbon_vertices(strips)[0], baked)
    assert not strips.hide_render
    settings.lod_options.show_strips = False
    assert strips.hide_render and strips.hide_viewport


def test_outputs_made_again_by_playback_are_dressed_as_simulated_ones(saved_fixture):
    """Outputs the artist deleted come back from the bake as a simulated frame shows them: the
    curves coloured by level, the ribbons in the level material (also when its slot was
    emptied); a frame without level of detail gives the curves the groom's material back."""
    hair = saved_fixture("head_curves.blend", 2)
    settings = hair.hairdyn
    settings.method = 'STRANDS'
    settings.strands.children_per_guide = 0
    settings.lod.enabled = True
    settings.lod_options.color_by_level = settings.lod_options.show_strips = True
    assert bpy.ops.hairdyn.bake() == {'FINISHED'}
    bpy.data.objects.remove(settings.output_curves)
    bpy.data.objects.remove(settings.output_strips)
    bpy.context.scene.frame_set(1)
    bpy.context.scene.frame_set(2)  # played back into new outputs
    curves, strips = settings.output_curves, settings.output_strips
    assert curves is not None and strips is not None and not strips.hide_render
    assert curves.material_slots[0].link == 'OBJECT'
    assert curves.material_slots[0].material.name == "hairdyn_lod_level"
    assert strips.data.materials[0].name == "hairdyn_lod_level"
    strips.data.materials[0] = None
    bpy.context.scene.frame_set(1)
    assert strips.data.materials[0].name == "hairdyn_lod_level"
    settings.lod.enabled = False
    simulation.run(bpy.context, hair, 1, 1)
    assert curves.material_slots[0].link == 'DATA'
    assert curves.material_slots[0].material == hair.data.materials[0]


def test_ribbons_of_an_earlier_run_hide_once_level_of_detail_is_off(open_fixture):
    hair = lod_hair(open_fixture)
    settings = hair.hairdyn
    settings.lod_options.show_strips = True
    simulation.run(bpy.context, hair, 1, 1)
    strips = settings.output_strips
    assert not strips.hide_render
    settings.lod.enabled = False
    report = simulation.run(bpy.context, hair, 1, 1)
    assert strips.hide_render and strips.hide_viewport  # no ribbons in this run: none shown
    assert report["output_strips"] is None and report["output_curves"] == "Hair_hairdyn"
    settings.lod_options.show_strips = False
    settings.lod_options.show_strips = True
    assert strips.hide_render  # still none to show
