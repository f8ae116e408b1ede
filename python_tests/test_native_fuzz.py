"""Hostile input into every binding of the native module: random and bad arrays, matrices and
parameters. Each call either works or raises ValueError / TypeError with a message; nothing may
crash the process. The fuzz runs in a child process so that a crash is a failure naming the
call, not the end of the test run."""

import subprocess
import sys
import textwrap

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


FUZZ = textwrap.dedent('''
    import sys
    import numpy as np
    sys.path.insert(0, sys.argv[1])
    from hairdyn import native

    n = native.load()
    rng = np.random.default_rng(int(sys.argv[2]))
    nan, inf = float("nan"), float("inf")

    def arrays():
        shapes = [(0, 3), (1, 3), (4, 3), (3,), (4, 4), (2, 3, 3), (5,), (0,), (3, 2)]
        shape = shapes[rng.integers(len(shapes))]
        dtype = [np.float32, np.float64, np.int32, np.int64, np.uint8][rng.integers(5)]
        kind = rng.integers(6)
        if kind == 0:
            values = rng.normal(size=shape)
        elif kind == 1:
            values = rng.integers(-3, 8, size=shape)
        elif kind == 2:
            values = np.full(shape, [nan, inf, -inf, 1e30, 0.0][rng.integers(5)])
        elif kind == 3:
            values = np.zeros(shape)
        elif kind == 4:
            values = rng.normal(size=shape) * 1e19
        else:
            values = rng.integers(0, 4, size=shape)
        with np.errstate(all="ignore"):
            array = np.asarray(values).astype(dtype)
        return array if rng.random() < 0.9 else np.asfortranarray(array)[::-1]

    def value():
        pool = [None, 0, -1, 1, 2**40, -2**40, nan, inf, -inf, 1e-30, 0.5, "x", [], [1, 2],
                np.eye(4), np.zeros((4, 4)), np.diag([1, 1, 0, 1.0]), np.full((4, 4), nan)]
        return arrays() if rng.random() < 0.5 else pool[rng.integers(len(pool))]

    offsets = np.array([0, 3, 6], np.int32)
    rest = np.array([[0, 0, 0], [0, 0, .1], [0, 0, .2], [.1, 0, 0], [.1, 0, .1], [.1, 0, .2]],
                    np.float32)
    vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], np.float32)
    triangles = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], np.int32)
    objects = []
    for make in (lambda: n.FollowSolver(offsets, rest, np.eye(4)),
                 lambda: n.Collider(vertices, triangles),
                 lambda: n.ColliderSet([n.Collider(vertices, triangles)]),
                 lambda: n.ColliderMesh(vertices, triangles),
                 lambda: n.StrandSolver(offsets, rest, np.eye(4),
                                        np.tile(np.float32([0, 0, 1]), (2, 1)), n.StrandParams()),
                 lambda: n.ChildHairs.around_guides(offsets, 2, 0.01, 1)):
        try:
            objects.append(make())
        except Exception as error:  # a fixture the fuzz cannot build is no crash
            print("fixture:", type(error).__name__, error)

    callables = [getattr(n, name) for name in dir(n)
                 if not name.startswith("_") and name not in ("set_thread_num",)]
    for obj in objects:
        callables += [getattr(obj, name) for name in dir(obj)
                      if not name.startswith("_") and callable(getattr(obj, name))]
    for trial in range(int(sys.argv[3])):
        target = callables[rng.integers(len(callables))]
        args = [value() for _ in range(rng.integers(0, 7))]
        if rng.random() < 0.5 and len(args) >= 2:  # plausible first arguments, hostile rest
            args[0], args[1] = (offsets, rest) if rng.random() < 0.5 else (vertices, triangles)
        label = f"{getattr(target, '__qualname__', target)}({', '.join(type(a).__name__ for a in args)})"
        print(label, flush=True)
        try:
            result = target(*args)
        except (ValueError, TypeError) as error:
            assert str(error), label
        except RuntimeError as error:
            assert str(error), label
        else:
            for item in (result.values() if isinstance(result, dict) else
                         result if isinstance(result, tuple) else [result]):
                if isinstance(item, np.ndarray) and item.dtype.kind == "f" and item.size:
                    assert np.isfinite(item).all(), f"{label} returned values that are not finite"
    print("fuzz done")
''')


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_every_binding_survives_hostile_input(seed, tmp_path):
    script = tmp_path / "fuzz.py"
    script.write_text(FUZZ)
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
