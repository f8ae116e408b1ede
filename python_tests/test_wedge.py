"""cli.py wedge: parameter sets baked in parallel on a 2-worker Dask LocalCluster, each task
one headless bake of the host's Blender; a bad set fails alone, a re-run bakes only what is not
done."""

import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import bpy
import pytest

from conftest import FIXTURES, ROOT, host_name

CLI = ROOT / "addon" / "hairdyn" / "cli.py"


def _wedge_module():
    spec = importlib.util.spec_from_file_location(
        "wedge_under_test", ROOT / "addon" / "hairdyn" / "wedge.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_parameter_sets_from_a_table_and_a_product(tmp_path):
    wedge = _wedge_module()
    table = tmp_path / "sets.csv"
    table.write_text("substeps,method\n2,strands\n4,follow\n")
    sets = wedge.parameter_sets(table, ["k_theta=0.1,0.2", "seed=1"])
    assert sets == [
        {"substeps": "2", "method": "strands", "k_theta": "0.1", "seed": "1"},
        {"substeps": "2", "method": "strands", "k_theta": "0.2", "seed": "1"},
        {"substeps": "4", "method": "follow", "k_theta": "0.1", "seed": "1"},
        {"substeps": "4", "method": "follow", "k_theta": "0.2", "seed": "1"},
    ]
    as_json = tmp_path / "sets.json"
    as_json.write_text(json.dumps([{"substeps": 2, "use_wind": True}]))
    assert wedge.parameter_sets(as_json) == [{"substeps": "2", "use_wind": "true"}]
    assert len(wedge.parameter_sets(None, ["a=1,2,3", "b=x,y"])) == 6
    with pytest.raises(wedge.WedgeError, match="--vary needs NAME=V1,V2"):
        wedge.parameter_sets(None, ["k_theta"])
    with pytest.raises(wedge.WedgeError, match="no parameter sets"):
        wedge.parameter_sets(None, [])
    with pytest.raises(wedge.WedgeError, match="must be a JSON list"):
        as_json.write_text('{"substeps": 2}')
        wedge.parameter_sets(as_json)


def _driver_python():
    """A Python with Dask distributed to drive the wedge: this one when it has Dask, else
    Debian's Python 3.11 (apt's python3-distributed; for the blender binary that is the Python
    it embeds, whatever sys.executable names). The tasks run this host's Blender either way."""
    candidates = ([sys.executable] if host_name() == "bpy" else []) + ["/usr/bin/python3.11"]
    for python in candidates:
        if (
            subprocess.run([python, "-c", "import distributed"], capture_output=True).returncode
            == 0
        ):
            return python
    pytest.skip(
        f"Dask distributed is not installed for {' or '.join(candidates)} (setup.sh "
        "installs it in .venv313 and as Debian's python3-distributed)"
    )


def _wedge(python, out, table):
    command = [
        python,
        str(CLI),
        "wedge",
        str(FIXTURES / "head_shake.blend"),
        "--object",
        "Hair",
        "--out",
        str(out),
        "--table",
        str(table),
        "--frames",
        "1",
        "3",
        "--set",
        "method=strands",
        "--set",
        "children_per_guide=0",
        "--workers",
        "2",
    ]
    # the tasks bake in this host: the blender binary, or this Python's bpy module
    command += (
        ["--blender", bpy.app.binary_path]
        if host_name() == "blender"
        else ["--python", sys.executable]
    )
    process = subprocess.run(command, capture_output=True, text=True, timeout=900)
    summary = (
        json.loads((out / "summary.json").read_text()) if (out / "summary.json").is_file() else None
    )
    return process, summary


def test_two_by_two_wedge_one_bad_set_fails_alone_and_rerun_finishes_it(tmp_path):
    python = _driver_python()
    table = tmp_path / "sets.csv"
    # a 2 x 2 of substeps x damping; substeps 0 is out of range (at least 1)
    table.write_text("strands.substeps,strands.damping\n2,0.2\n2,0.8\n0,0.2\n4,0.8\n")
    out = tmp_path / "wedge"
    process, summary = _wedge(python, out, table)
    assert summary is not None, process.stdout[-3000:] + process.stderr[-3000:]
    assert process.returncode == 1  # a set failed
    status = {e["name"]: e["status"] for e in summary["sets"]}
    assert status == {
        "set_000": "done",
        "set_001": "done",
        "set_002": "failed",
        "set_003": "done",
    }, summary
    bad = summary["sets"][2]
    assert "substeps must be between 1 and 1000, not 0" in bad["message"]
    for entry in summary["sets"]:
        if entry["status"] == "done":
            assert entry["report"]["frames"] == 3 and entry["report"]["nan_frames"] == 0
            assert Path(entry["report"]["cache"]).is_dir()
            assert Path(entry["image"]).stat().st_size > 1000
    assert summary["baked_now"] == 4
    sheet = Path(summary["contact_sheet"])
    assert sheet.is_file() and sheet.stat().st_size > 1000
    done_before = {
        e["name"]: Path(e["report"]["cache"]).stat().st_mtime_ns
        for e in summary["sets"]
        if e["status"] == "done"
    }

    table.write_text("strands.substeps,strands.damping\n2,0.2\n2,0.8\n1,0.2\n4,0.8\n")  # fixed
    process, summary = _wedge(python, out, table)
    assert process.returncode == 0, process.stdout[-3000:] + process.stderr[-3000:]
    assert [e["status"] for e in summary["sets"]] == ["done"] * 4
    assert [e["skipped"] for e in summary["sets"]] == [True, True, False, True]
    assert summary["baked_now"] == 1
    for name, mtime in done_before.items():  # the finished sets were not baked again
        entry = next(e for e in summary["sets"] if e["name"] == name)
        assert Path(entry["report"]["cache"]).stat().st_mtime_ns == mtime
