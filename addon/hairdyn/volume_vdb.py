"""The hair density grid (Petrovic 2006, eq. 1) as an OpenVDB file, for a Blender Volume object.

Neither host's Python ships an OpenVDB writer. Debian's ``python3-openvdb`` (``pyopenvdb`` for
CPython 3.11, built against NumPy 1.x) serves Blender 3.4's Python directly, and the bpy
wheel's 3.11 venv (NumPy 1.26) when loaded from its file: that is what ``find_writer`` does.
Where nothing can write VDB, ``find_writer`` says why and ``write_density_vdb`` raises with that
sentence, so the option can show it.

    density, grid_to_world = hairdyn._native.density_grid(offsets, positions, head, cell)
    volume_vdb.write_density_vdb(path, density, grid_to_world)

The file holds one float grid named ``density`` (nodes per grid vertex, a fog volume) whose
transform maps voxel (i, j, k) to world space, so a Volume object with the identity matrix
shows it where the hair is.
"""

import importlib.util
import os
import sys

import numpy as np

# Debian's python3-openvdb; found on Blender 3.4's sys.path, loaded by path in other 3.11 venvs.
DEBIAN_PYOPENVDB = "/usr/lib/python3/dist-packages/pyopenvdb.cpython-311-x86_64-linux-gnu.so"

_writer = None
_reason = None


def find_writer():
    """(pyopenvdb module, "") when an OpenVDB writer can be used, else (None, why not)."""
    global _writer, _reason
    if _writer is not None or _reason is not None:
        return _writer, _reason or ""
    try:
        import pyopenvdb as module
    except ImportError:
        module = None
    if module is None and sys.version_info[:2] == (3, 11) and os.path.isfile(DEBIAN_PYOPENVDB):
        try:
            spec = importlib.util.spec_from_file_location("pyopenvdb", DEBIAN_PYOPENVDB)
            module = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(module)
        except Exception as error:  # a module built for another NumPy or Python
            _reason = f"Debian's pyopenvdb could not be loaded here ({error})"
            return None, _reason
    if module is None:
        _reason = (
            "No OpenVDB writer for this Python: install Debian's python3-openvdb "
            "(apt-get install python3-openvdb) for Python 3.11"
        )
        return None, _reason
    try:  # NumPy interop is what the writer needs; a NumPy 2 host cannot use a NumPy 1 build.
        module.FloatGrid().copyFromArray(np.zeros((2, 2, 2), np.float32))
    except Exception as error:
        _reason = f"pyopenvdb cannot take NumPy arrays here ({error})"
        return None, _reason
    _writer = module
    return _writer, ""


def write_density_vdb(path, density, grid_to_world, name="density"):
    """Write `density` (float32 indexed [i, j, k]) with the 4x4 row-major `grid_to_world` as a
    VDB file at `path`, atomically (a temporary file renamed). Raises RuntimeError with the
    reason when no writer exists, ValueError for bad arrays."""
    writer, reason = find_writer()
    if writer is None:
        raise RuntimeError(reason)
    density = np.asarray(density)
    if density.ndim != 3 or density.dtype != np.float32 or not np.isfinite(density).all():
        raise ValueError("density must be a finite float32 array indexed [i, j, k]")
    matrix = np.asarray(grid_to_world, dtype=np.float64)
    if matrix.shape != (4, 4) or not np.isfinite(matrix).all():
        raise ValueError("grid_to_world must be a finite 4x4 matrix")
    grid = writer.FloatGrid()
    grid.name = name
    grid.gridClass = writer.GridClass.FOG_VOLUME
    grid.copyFromArray(np.ascontiguousarray(density), ijk=(0, 0, 0), tolerance=0.0)
    # OpenVDB multiplies row vectors: its matrix is the transpose of Blender's.
    grid.transform = writer.createLinearTransform(matrix.T.tolist())
    temporary = f"{path}.tmp{os.getpid()}"
    writer.write(temporary, grids=[grid])
    os.replace(temporary, path)
