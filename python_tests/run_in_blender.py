"""Runs pytest inside the blender binary:

    blender -b --factory-startup --python-exit-code 1 --python python_tests/run_in_blender.py -- [pytest args]
"""
import sys
from pathlib import Path

import pytest

args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
code = pytest.main([str(Path(__file__).resolve().parent), "-p", "no:cacheprovider", *args])
sys.exit(int(code))
