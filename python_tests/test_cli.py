"""The headless entry point, in the host that runs the tests (blender binary or bpy module)."""
import json
import subprocess
import sys

import bpy
import numpy as np
import pytest

from conftest import FIXTURES, ROOT, host_name

CLI = ROOT / "addon" / "hairdyn" / "cli.py"
REPORT_KEYS = {"solver", "strands", "points", "frames", "ms_per_frame", "total_s",
               "nan_frames", "stretch_max", "blender_version"}


def run_cli(fixture, *args):
    """The documented command line for this host, as a subprocess."""
    if host_name() == "blender":
        command = [bpy.app.binary_path, "-b", "--factory-startup", str(FIXTURES / fixture),
                   "--python", str(CLI), "--", *args]
    else:
        command = [sys.executable, str(CLI), "--blend", str(FIXTURES / fixture), *args]
    return subprocess.run(command, capture_output=True, text=True, timeout=300)


def test_run_writes_report(tmp_path):
    report_path = tmp_path / "out.json"
    result = run_cli("head_shake.blend", "run", "--object", "Hair", "--frames", "1", "24",
                     "--set", "method=follow", "--report", str(report_path))
    assert result.returncode == 0, result.stderr + result.stdout
    report = json.loads(report_path.read_text())
    assert REPORT_KEYS <= set(report)
    assert report["solver"] == "follow"
    assert (report["strands"], report["points"], report["frames"]) == (300, 2700, 24)
    assert report["nan_frames"] == 0 and report["stretch_max"] < 5e-5
    assert report["ms_per_frame"] > 0 and report["total_s"] >= report["ms_per_frame"] / 1000
    assert report["blender_version"] == bpy.app.version_string
    assert result.stdout.count("hairdyn: frame ") == 24


@pytest.mark.parametrize("args, message", [
    (["--set", "no_such_parameter=1"], "unknown parameter 'no_such_parameter'"),
    (["--set", "method=banana"], "method must be one of follow"),
    (["--set", "frame_start=abc"], "frame_start must be an integer"),
    (["--set", "head=NoSuchObject"], "no object named 'NoSuchObject'"),
    (["--set", "method"], "--set needs NAME=VALUE"),
])
def test_bad_parameters_exit_2(args, message, tmp_path):
    from hairdyn import cli

    code = cli.main(["--blend", str(FIXTURES / "head_curves.blend"), "run", "--object", "Hair",
                     "--frames", "1", "2", "--report", str(tmp_path / "r.json"), *args])
    assert code == 2
    assert not (tmp_path / "r.json").exists()


def test_a_documented_minimum_typed_as_printed_is_accepted_and_a_wind_too_fine_refused(capsys):
    """The tooltip's minimum, 0.001 m, typed as such is in range (a FLOAT property holds it in
    single precision); LCP with the implicit pressure at that air spacing would need millions of
    air particles: the frame is refused with the reason and the run exits 1."""
    from hairdyn import cli

    code = cli.main(["--blend", str(FIXTURES / "head_curves.blend"), "run", "--object", "Hair",
                     "--frames", "1", "2", "--set", "method=lcp",
                     "--set", "lcp.implicit_pressure=1", "--set", "wind.speed=2",
                     "--set", "lcp.wind_particle_spacing=0.001"])
    err = capsys.readouterr().err
    assert code == 1, err
    assert "error: LCP refused the frame: the wind needs" in err, err
    assert "Raise the wind particle spacing" in err


def test_bad_parameter_message_and_exit_code_in_a_real_process():
    result = run_cli("head_curves.blend", "run", "--object", "Hair", "--set", "bendiness=3")
    assert result.returncode == 2
    assert "hairdyn: error: unknown parameter 'bendiness'" in result.stderr


def test_unknown_object_exit_2(capsys):
    from hairdyn import cli

    code = cli.main(["--blend", str(FIXTURES / "head_curves.blend"), "run", "--object", "Nope"])
    assert code == 2
    assert "no object named 'Nope'; hair objects: Hair" in capsys.readouterr().err


def test_simulation_failure_exits_1(capsys):
    from hairdyn import cli

    code = cli.main(["--blend", str(FIXTURES / "head_curves.blend"), "run", "--object", "Hair",
                     "--frames", "5", "1"])
    assert code == 1
    assert "frame range 5..1 is empty" in capsys.readouterr().err


def test_any_exception_ends_in_one_line_and_exit_1(monkeypatch, capsys):
    """Whatever raises (here a bug stand-in), the command line says so in one last line (after
    the traceback of a bug) and exits 1: under the blender binary an escaping exception would
    end the process with code 0."""
    from hairdyn import cli, simulation

    def broken(*_args, **_kwargs):
        raise ZeroDivisionError("float division by zero")

    monkeypatch.setattr(simulation, "run", broken)
    code = cli.main(["--blend", str(FIXTURES / "head_curves.blend"), "run", "--object", "Hair",
                     "--frames", "1", "2"])
    assert code == 1
    err = capsys.readouterr().err.strip().splitlines()  # the traceback, then one line
    assert err[-1].startswith("hairdyn: error: Internal error in hairdyn (ZeroDivisionError")


def bake_args(cache, *more):
    return ["--blend", str(FIXTURES / "head_curves.blend"), "bake", "--object", "Hair",
            "--frames", "1", "6", "--cache", str(cache), "--report", str(cache.parent / "r.json"),
            *more]


def test_resume_into_a_read_only_cache_exits_1(tmp_path, monkeypatch, capsys):
    """Root ignores file modes, so the read-only cache is simulated: removing or replacing a
    file fails with EACCES, as it would on a read-only mount."""
    import os
    from pathlib import Path

    from hairdyn import cli
    from hairdyn.cache import Cache

    cache_dir = tmp_path / "cache"
    assert cli.main(bake_args(cache_dir)) == 0
    Cache.open(cache_dir / "Hair").frame_path(6).unlink()
    Cache.open(cache_dir / "Hair").frame_path(5).write_bytes(b"torn")

    def refuse(*_args, **_kwargs):
        raise PermissionError(13, "Permission denied", str(cache_dir))

    monkeypatch.setattr(Path, "unlink", refuse)
    monkeypatch.setattr(os, "replace", refuse)
    capsys.readouterr()
    assert cli.main(bake_args(cache_dir, "--resume")) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert err and err[-1].startswith("hairdyn: error:") and "Permission denied" in err[-1]


def test_absurd_manifest_point_count_exits_1(tmp_path, capsys):
    from hairdyn import cli
    from hairdyn.cache import Cache

    cache_dir = tmp_path / "cache"
    assert cli.main(bake_args(cache_dir)) == 0
    manifest_path = Cache.manifest_path(cache_dir / "Hair")
    manifest = json.loads(manifest_path.read_text())
    manifest["topology"]["points"] = 10**30
    manifest_path.write_text(json.dumps(manifest))
    capsys.readouterr()
    assert cli.main(bake_args(cache_dir, "--resume")) == 1
    assert "point count" in capsys.readouterr().err


def test_resume_over_a_directory_frame_exits_1_in_a_real_process(tmp_path):
    cache_dir = tmp_path / "cache"
    args = bake_args(cache_dir)[2:]  # run_cli gives the .blend itself
    result = run_cli("head_curves.blend", *args)
    assert result.returncode == 0, result.stderr
    frame = cache_dir / "Hair" / "frame_000003.npy"
    frame.unlink()
    frame.mkdir()
    result = run_cli("head_curves.blend", *args, "--resume")
    assert result.returncode == 1, result.stderr + result.stdout
    assert "frame_000003.npy' is a directory" in result.stderr
    assert "Traceback" not in result.stderr


def output_positions(hair):
    """The positions written into the hair object's output curves and output points."""
    settings = hair.hairdyn
    curves, mesh = settings.output_curves.data, settings.output_points.data
    curve_positions = np.empty((len(curves.points), 3), np.float32)
    curves.points.foreach_get("position", curve_positions.ravel())
    point_positions = np.empty((len(mesh.vertices), 3), np.float32)
    mesh.vertices.foreach_get("co", point_positions.ravel())
    return curve_positions, point_positions


@pytest.mark.parametrize("method", ["STRANDS", "LCP"])
def test_a_headless_run_writes_only_its_last_frame_the_one_a_shown_run_ends_on(open_fixture,
                                                                               method):
    """show_frames off (cli.py run and bake): the output objects appear at the last frame, with
    the positions that writing every frame ends on, and Blender's evaluated copy follows."""
    from hairdyn import bridge, simulation

    open_fixture("head_shake.blend")
    hair = bpy.data.objects["Hair"]
    hair.hairdyn.method = method
    assert hair.hairdyn.output_curves is None
    runner = simulation.Runner(bpy.context, hair, 1, 4, show_frames=False)
    for _ in range(3):
        runner.advance()
    assert hair.hairdyn.output_curves is None and hair.hairdyn.output_points is None
    runner.advance()
    assert runner.done
    headless = output_positions(hair)
    evaluated = bridge.read_curves(hair.hairdyn.output_curves,
                                   bpy.context.evaluated_depsgraph_get()).positions_wo
    np.testing.assert_allclose(evaluated, headless[0], atol=1e-6)

    simulation.run(bpy.context, hair, 1, 4)  # every frame shown
    for written, shown in zip(headless, output_positions(hair)):
        assert written.shape == shown.shape and np.array_equal(written, shown)


@pytest.mark.parametrize("failure", ["raises", "not finite"])
def test_a_headless_run_that_ends_early_shows_its_last_finite_frame(open_fixture, monkeypatch,
                                                                    failure):
    """Frame 3 fails (an error, or points that are not finite numbers): the outputs show
    frame 2, as a run of frames 1-2 writes it."""
    from hairdyn import simulation
    from hairdyn.errors import HairdynError

    open_fixture("head_shake.blend")
    simulation.run(bpy.context, bpy.data.objects["Hair"], 1, 2)
    expected = output_positions(bpy.data.objects["Hair"])

    open_fixture("head_shake.blend")
    hair = bpy.data.objects["Hair"]
    step, steps = simulation.Simulation.step, []

    def failing_from_frame_3(self, *args):
        steps.append(step(self, *args))
        if len(steps) >= 3:
            if failure == "raises":
                raise HairdynError("a stand-in failure")
            self.nonfinite_num = 1
        return steps[-1]

    monkeypatch.setattr(simulation.Simulation, "step", failing_from_frame_3)
    if failure == "raises":
        with pytest.raises(HairdynError, match="stand-in"):
            simulation.run(bpy.context, hair, 1, 4, show_frames=False)
    else:
        assert simulation.run(bpy.context, hair, 1, 4, show_frames=False)["nan_frames"] == 2
    for written, frame_2 in zip(output_positions(hair), expected):
        assert np.array_equal(written, frame_2)
