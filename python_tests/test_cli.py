"""The headless entry point, in the host that runs the tests (blender binary or bpy module)."""
import json
import subprocess
import sys

import bpy
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
