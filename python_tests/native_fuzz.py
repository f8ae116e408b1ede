"""Hostile input into every binding of the native module, in a process of its own:

    python native_fuzz.py ADDON_FOLDER SEED TRIALS

Each call is printed before it is made, and either works (its float arrays finite) or raises
ValueError, TypeError or RuntimeError with a message; the last line is "fuzz done". Run by
test_native_fuzz.py, and by scripts/test.sh against the module built with the sanitizers.
"""

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
    pool = [
        None,
        0,
        -1,
        1,
        2**40,
        -(2**40),
        nan,
        inf,
        -inf,
        1e-30,
        0.5,
        "x",
        [],
        [1, 2],
        np.eye(4),
        np.zeros((4, 4)),
        np.diag([1, 1, 0, 1.0]),
        np.full((4, 4), nan),
    ]
    return arrays() if rng.random() < 0.5 else pool[rng.integers(len(pool))]


offsets = np.array([0, 3, 6], np.int32)
rest = np.array(
    [[0, 0, 0], [0, 0, 0.1], [0, 0, 0.2], [0.1, 0, 0], [0.1, 0, 0.1], [0.1, 0, 0.2]], np.float32
)
vertices = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], np.float32)
triangles = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], np.int32)


def step_arguments():
    """A frame step's (frame_dt, head_to_world), either of them sometimes hostile: the solvers'
    step() then runs rather than stopping at its first argument."""
    dts = [1 / 24, 1 / 24, 1 / 24, 0.0, -1.0, nan, inf, 1e30, 1e-30]
    turn = np.eye(4)
    turn[:2, :2] = [[0.0, -1.0], [1.0, 0.0]]
    heads = [np.eye(4), np.eye(4), turn, np.full((4, 4), nan), np.diag([1e30, 1e30, 1e30, 1.0])]
    return dts[rng.integers(len(dts))], heads[rng.integers(len(heads))]


def lcp_solver():
    params = n.LcpParams(particle_num=0)
    particles = n.lcp_particles_from_groom(params, offsets, rest)
    fields = ("positions", "directions", "u", "v", "s")
    return n.LcpSolver(params, *(particles[f] for f in fields), np.eye(4))


objects = []
for make in (
    lambda: n.FollowSolver(offsets, rest, np.eye(4)),
    lambda: n.Collider(vertices, triangles),
    lambda: n.ColliderSet([n.Collider(vertices, triangles)]),
    lambda: n.ColliderMesh(vertices, triangles),
    lambda: n.StrandSolver(
        offsets, rest, np.eye(4), np.tile(np.float32([0, 0, 1]), (2, 1)), n.StrandParams()
    ),
    lambda: n.ChildHairs.around_guides(offsets, 2, 0.01, 1),
    lambda: n.LodSolver(offsets, rest, np.eye(4)),
    lcp_solver,
    n.VolumePass,
    n.HairHairPass,
    lambda: n.SsvObjectPass(n.ColliderSet([n.Collider(vertices, triangles)])),
):
    try:
        objects.append(make())
    except Exception as error:  # a fixture the fuzz cannot build is no crash
        print("fixture:", type(error).__name__, error)

callables = [
    getattr(n, name)
    for name in dir(n)
    if not name.startswith("_") and name not in ("set_thread_num",)
]
for obj in objects:
    callables += [
        getattr(obj, name)
        for name in dir(obj)
        if not name.startswith("_") and callable(getattr(obj, name))
    ]
# First, sequences whose items are made as they are read (a numpy array's rows): a binding
# must own each item while it reads it. A plain run seldom crashes when one does not; under
# the sanitizers (scripts/test.sh) the read of the freed item stops the run here.
table = np.zeros((4, 3), np.float32)
for outputs in (np.zeros((4, 3), np.int32), np.zeros((4, 2), np.float32)):
    print(f"split_columns(table, {outputs.dtype} array {outputs.shape})", flush=True)
    try:
        n.split_columns(table, outputs)
    except (ValueError, TypeError) as error:
        assert str(error)
for _ in range(int(sys.argv[3])):
    target = callables[rng.integers(len(callables))]
    args = [value() for _ in range(rng.integers(0, 7))]
    if rng.random() < 0.5 and len(args) >= 2:  # plausible first arguments, hostile rest
        plausible = [(offsets, rest), (vertices, triangles), step_arguments()]
        args[0], args[1] = plausible[rng.integers(len(plausible))]
    label = (
        f"{getattr(target, '__qualname__', target)}({', '.join(type(a).__name__ for a in args)})"
    )
    print(label, flush=True)
    try:
        result = target(*args)
    except (ValueError, TypeError) as error:
        assert str(error), label
    except RuntimeError as error:
        assert str(error), label
    else:
        for item in (
            result.values()
            if isinstance(result, dict)
            else result
            if isinstance(result, tuple)
            else [result]
        ):
            if isinstance(item, np.ndarray) and item.dtype.kind == "f" and item.size:
                assert np.isfinite(item).all(), f"{label} returned values that are not finite"
print("fuzz done")
