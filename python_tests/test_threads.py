"""The native thread pool in a forked process: Python's multiprocessing forks by default on
Linux, and a child forked after the solver ran has none of the pool's threads (fork copies
only the calling thread). The child must still compute, alone, rather than wait forever for
workers that are not there."""

import subprocess
import sys
import textwrap

from conftest import ROOT

FORK = textwrap.dedent('''
    import os, sys, time
    import numpy as np
    sys.path.insert(0, sys.argv[1])
    from hairdyn import native

    module = native.load()
    module.set_thread_num(2)
    strands, points = 4000, 4
    offsets = np.arange(0, strands * points + 1, points, dtype=np.int32)
    rest = np.random.default_rng(1).normal(size=(strands * points, 3)).astype(np.float32)
    solver = module.FollowSolver(offsets, rest, np.eye(4))
    moved = np.eye(4)
    moved[0, 3] = 0.1
    solver.step(1 / 24, moved)  # the pool's threads start here
    parent = np.array(solver.positions, copy=True)
    pid = os.fork()
    if pid == 0:
        child = module.FollowSolver(offsets, rest, np.eye(4))
        child.step(1 / 24, moved)
        os._exit(0 if np.array_equal(np.asarray(child.positions), parent) else 3)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            print("child exit", os.waitstatus_to_exitcode(status))
            sys.exit(0)
        time.sleep(0.05)
    os.kill(pid, 9)
    print("child hung")
''')


def test_a_forked_child_computes(tmp_path):
    script = tmp_path / "fork.py"
    script.write_text(FORK)
    venv = ROOT / ".venv" / "bin" / "python"
    python = str(venv) if venv.exists() else sys.executable
    result = subprocess.run(
        [python, str(script), str(ROOT / "addon")], capture_output=True, text=True, timeout=120
    )
    assert result.stdout.strip().splitlines()[-1:] == ["child exit 0"], (
        f"{result.stdout[-500:]}\n{result.stderr[-2000:]}"
    )
