"""Hostile input into every binding of the native module: random and bad arrays, matrices and
parameters. Each call either works or raises ValueError / TypeError with a message; nothing may
crash the process. The fuzz (native_fuzz.py) runs in a child process so that a crash is a
failure naming the call, not the end of the test run; scripts/test.sh also runs it against the
module built with the sanitizers."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from conftest import ROOT
from hairdyn import native


def test_singular_and_huge_matrices_are_refused():
    module = native.load()
    offsets = np.array([0, 3], np.int32)
    rest = np.array([[0, 0, 0], [0, 0, 0.1], [0, 0, 0.2]], np.float32)
    zero_scale = np.diag([0.0, 0.0, 0.0, 1.0])
    flattened = np.diag([1.0, 1.0, 0.0, 1.0])  # a scale keyed to zero along z
    with pytest.raises(ValueError, match="head_to_world_rest is singular"):
        module.FollowSolver(offsets, rest, zero_scale)
    solver = module.FollowSolver(offsets, rest, np.eye(4))
    with pytest.raises(ValueError, match="head_to_world is singular"):
        solver.step(1 / 24, flattened)
    with pytest.raises(ValueError, match="beyond single precision"):
        solver.step(1 / 24, np.diag([1e39, 1e39, 1e39, 1.0]))
    solver.step(1 / 24, np.diag([1e-4, 1e-4, 1e-4, 1.0]))  # small but invertible: accepted
    for bad_dt in (-1.0, 0.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="frame_dt must be a positive number"):
            solver.step(bad_dt, np.eye(4))
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], np.float32)
    triangles = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], np.int32)
    collider = module.Collider(vertices, triangles)
    with pytest.raises(ValueError, match="object_to_world is singular"):
        collider.set_transform(zero_scale)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_every_binding_survives_hostile_input(seed):
    script = Path(__file__).with_name("native_fuzz.py")
    # A Python with numpy that can import the add-on package (bpy): the venv's, in both hosts.
    venv = ROOT / ".venv" / "bin" / "python"
    python = str(venv) if venv.exists() else sys.executable
    result = subprocess.run(
        [python, str(script), str(ROOT / "addon"), str(seed), "1500"],
        capture_output=True,
        text=True,
        timeout=600,
        env={"PATH": "/usr/bin:/bin"},
    )
    last = result.stdout.strip().splitlines()[-1:] or ["(nothing)"]
    assert result.returncode == 0 and last == ["fuzz done"], (
        f"crashed or failed after: {last[0]}\n{result.stderr[-2000:]}"
    )
