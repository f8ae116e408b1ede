"""Runs pytest inside the blender binary:

    blender -b --factory-startup --python-exit-code 1 --python python_tests/run_in_blender.py -- [pytest args]
"""
import sys
from pathlib import Path

import pytest

args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
if not any(Path(arg.split("::")[0]).exists() for arg in args):
    args.append(str(Path(__file__).resolve().parent))  # no test path given: all of them
code = pytest.main(["-p", "no:cacheprovider", *args])
sys.exit(int(code))
