"""Adding a method is one adapter and one registry line: a trivial method registered here runs
through the bake, playback and the command line; a Strands extension (a substep pass with its
own settings group) plugs in the same way. The error boundary: an unexpected exception in a
method cancels the operator with a report and prints its traceback once in playback."""

import bpy
import numpy as np
import pytest
from layout_recorder import Layout

import hairdyn
from conftest import FIXTURES
from hairdyn import bake, bridge, cli, methods, playback, simulation
from hairdyn.cache import Cache
from hairdyn.methods.strands import Extension, Strands


class Rising(methods.Method):
    """The groom rising 1 mm per frame; its tips as a stream of their own, shown as points."""

    identifier = "RISING"
    label = "Rising"
    description = "Test method: the rest groom moved up 1 mm per frame"

    def __init__(self, build):
        self.rest = np.array(build.groom.positions_wo)
        self.tips = build.groom.curve_offsets[1:] - 1
        self.frames = 0

    def step(self, frame_dt, head_matrix):
        self.frames += 1

    @property
    def positions(self):
        return self.rest + np.float32(0.001 * self.frames) * np.array([0, 0, 1], np.float32)

    def streams(self):
        return {
            "tips": methods.Stream(
                {"position": 3, "height": 1},
                lambda: {
                    "position": self.positions[self.tips],
                    "height": self.positions[self.tips, 2],
                },
                len(self.tips),
                outputs=("output_points",),
            )
        }

    def report(self):
        return {"rising_frames": self.frames}


class Failing(Rising):
    """Raises an unexpected exception on its third step."""

    identifier = "FAILING"
    label = "Failing"

    def step(self, frame_dt, head_matrix):
        super().step(frame_dt, head_matrix)
        if self.frames == 3:
            raise ZeroDivisionError("a bug in a method")


@pytest.fixture
def registered():
    for method in (Rising, Failing):
        methods.register(method)
    yield
    for method in (Rising, Failing):
        methods.unregister(method)


@pytest.fixture
def shake(saved_fixture):
    return saved_fixture("head_shake.blend", 5)


def output_positions(obj):
    return bridge.read_curves(obj, bpy.context.evaluated_depsgraph_get()).positions_wo


def test_a_registered_method_bakes_and_plays_back(registered, shake):
    hair = shake
    hair.hairdyn.method = 'RISING'
    assert bpy.ops.hairdyn.bake() == {'FINISHED'}
    cache = Cache.open(bake.cache_directory(hair))
    assert cache.manifest["solver"] == "rising" and set(cache.streams) == {"tips"}
    assert cache.manifest["report"]["rising_frames"] == 5  # one step per frame, 1..5
    rest = cache.read_frame(1)["position"]
    assert np.allclose(cache.read_frame(5)["position"][:, 2] - rest[:, 2], 0.004, atol=1e-6)
    bpy.context.scene.frame_set(4)
    assert playback.last_error(hair) is None
    assert np.array_equal(
        output_positions(hair.hairdyn.output_curves), cache.read_frame(4)["position"]
    )
    points = hair.hairdyn.output_points.data  # the tips stream took the point output
    assert len(points.vertices) == hair.data.curves.__len__()
    height = np.empty(len(points.vertices), np.float32)
    points.attributes["height"].data.foreach_get("value", height)
    assert np.array_equal(height, cache.read_stream("tips", 4)["height"])


def test_a_registered_method_runs_from_the_command_line(registered, tmp_path):
    report_path = tmp_path / "report.json"
    code = cli.main(
        [
            "--blend",
            str(FIXTURES / "head_shake.blend"),
            "bake",
            "--object",
            "Hair",
            "--frames",
            "1",
            "3",
            "--set",
            "method=rising",
            "--cache",
            str(tmp_path / "cache"),
            "--report",
            str(report_path),
        ]
    )
    assert code == 0
    import json

    report = json.loads(report_path.read_text())
    assert report["solver"] == "rising" and report["rising_frames"] == 3
    assert Cache.open(tmp_path / "cache" / "Hair").frames() == [1, 2, 3]


def test_an_internal_error_in_the_command_line_exits_1(registered, tmp_path, capsys):
    code = cli.main(
        [
            "--blend",
            str(FIXTURES / "head_shake.blend"),
            "run",
            "--object",
            "Hair",
            "--frames",
            "1",
            "5",
            "--set",
            "method=failing",
        ]
    )
    assert code == 1
    err = capsys.readouterr().err
    assert "hairdyn: error: Internal error in hairdyn (ZeroDivisionError: a bug in a method)" in err
    assert err.count("Traceback") == 1


def test_an_internal_error_cancels_the_bake_with_a_report(registered, shake, capsys):
    hair = shake
    hair.hairdyn.method = 'FAILING'
    with pytest.raises(RuntimeError, match=r"Internal error in hairdyn \(ZeroDivisionError"):
        bpy.ops.hairdyn.bake()
    assert "ZeroDivisionError: a bug in a method" in capsys.readouterr().err  # the traceback
    cache = Cache.open(bake.cache_directory(hair))
    assert cache.frames() == [1, 2] and cache.manifest["complete"] is False  # recorded
    with pytest.raises(RuntimeError, match="Internal error"):
        bpy.ops.hairdyn.simulate()


def test_an_internal_error_in_playback_prints_its_traceback_once(registered, shake, capsys):
    hair = shake
    hair.hairdyn.method = 'FAILING'
    hair.hairdyn.enabled = True
    capsys.readouterr()
    for frame in range(1, 6):  # fails on frame 4 (the third step), frames after stay quiet
        bpy.context.scene.frame_set(frame)
    assert "Internal error in hairdyn (ZeroDivisionError" in playback.last_error(hair)
    assert capsys.readouterr().err.count("Traceback") == 1
    for frame in range(4, 7):  # the same error again: no second traceback
        bpy.context.scene.frame_set(frame)
    assert capsys.readouterr().err.count("Traceback") == 0


def test_a_strands_extension_adds_its_settings_and_pass(shake, monkeypatch):
    """How a substep pass (volume, hair-hair collision) joins Strands: its settings group is
    registered on the hair settings, its section is in the panel, attach() gets the solver."""

    class HairdynTestPassOptions(bpy.types.PropertyGroup):
        strength: bpy.props.FloatProperty(name="Strength", default=0.5)

    attached = []
    extension = Extension(
        "test_pass",
        lambda solver, build: attached.append((solver, build.settings.test_pass.strength)),
        options={"test_pass": HairdynTestPassOptions},
        sections=(methods.Section("Test Pass", "test_pass", ("strength",)),),
    )
    for name in ("extensions", "params", "options", "sections"):
        monkeypatch.setattr(
            Strands,
            name,
            list(getattr(Strands, name)) if name == "extensions" else getattr(Strands, name),
        )
    from hairdyn.methods import strands

    strands.register_extension(extension)
    hairdyn.unregister()
    hairdyn.register()
    try:
        hair = bpy.data.objects["Hair"]
        hair.hairdyn.method = 'STRANDS'
        hair.hairdyn.strands.children_per_guide = 0
        hair.hairdyn.test_pass.strength = 0.25
        assert hasattr(bpy.types, "HAIRDYN_PT_strands_4")  # its panel section
        simulation.run(bpy.context, hair, 1, 2)
        assert len(attached) == 1 and attached[0][1] == pytest.approx(0.25)
        assert hasattr(attached[0][0], "step")
    finally:
        monkeypatch.undo()
        hairdyn.unregister()
        hairdyn.register()
    assert not hasattr(bpy.data.objects["Hair"].hairdyn, "test_pass")


@pytest.mark.parametrize(
    "method, collision",
    [
        ('FOLLOW', ["penetration_tolerance"]),
        ('STRANDS', ["stiffness", "damping", "friction", "projection_tolerance"]),
        ('LCP', ["azimuth_num", "penetration_tolerance"]),
    ],
)
def test_panels_show_what_each_method_reads(method, collision, open_fixture):
    """Each method's sections are drawn for it alone; the collision settings by kind (LCP
    reads the maps but not the response); gravity comes from the scene and is never shown."""
    from hairdyn import ui

    open_fixture("head_curves.blend")
    hair = bpy.data.objects["Hair"]
    hair.hairdyn.method = method

    class Context:
        object = hair

    shown = {}
    for panel in ui.panel_classes():
        if issubclass(panel, ui._SubPanel) and panel.poll(Context):
            names = []
            if hasattr(panel, "draw_header"):  # a section's on/off switch
                header = type("Header", (), {"layout": Layout(names)})()
                panel.draw_header(header, Context)
            panel.draw_settings(None, Layout(names), hair.hairdyn)
            shown[panel.bl_label] = names
    sections = [s.label for s in methods.get(method).sections]
    assert set(shown) - {"Collision", "Cache", "Output"} <= set(sections)
    everything = [name for names in shown.values() for name in names]
    assert "gravity" not in everything
    for name in collision:
        assert name in shown["Collision"], (method, name)
    if method == 'LCP':
        assert "stiffness" not in shown["Collision"] and "friction" not in shown["Collision"]
        assert {"particles_from", "h1", "h2", "body_friction"} <= set(everything)
    from hairdyn import native, parameters

    for struct_name in methods.get(method).params.values():  # every field but gravity shows
        fields = parameters.shown_fields(getattr(native.load(), struct_name))
        assert {f["name"] for f in fields} <= set(everything), struct_name


@pytest.mark.parametrize("points_num, targets_num, k", [(2500, 300, 1), (700, 50, 4), (3, 1, 2)])
def test_nearest_finds_each_points_nearest_targets_as_a_full_distance_table_does(
    points_num, targets_num, k
):
    """methods.base.nearest (root normals, scalp masks) against the whole table of squared
    distances, in chunks of 1,024 points: the same targets and the same distance bits, ties
    of equal distance included (duplicated targets)."""
    from hairdyn.methods.base import nearest

    rng = np.random.default_rng(points_num)
    points = rng.normal(size=(points_num, 3))
    targets = rng.normal(size=(targets_num, 3))
    targets[targets_num // 2 :] = targets[: targets_num - targets_num // 2]  # exact ties
    table = ((points[:, None, :] - targets[None, :, :]) ** 2).sum(axis=2)
    k = min(k, targets_num)
    indices, distances = nearest(points, targets, k)
    assert indices.shape == distances.shape == (points_num, k)
    expected = np.sort(table, axis=1)[:, :k]
    got = np.sort(np.take_along_axis(table, indices, axis=1), axis=1)
    assert np.array_equal(got, expected)
    assert np.array_equal(np.sort(distances, axis=1), np.sqrt(expected))
    if k == 1:
        assert np.array_equal(indices[:, 0], table.argmin(axis=1))  # the first of tied ones
