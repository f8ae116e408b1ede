"""Loads hairdyn._native lazily and says in one sentence why it is unusable, if it is."""
import sys
from pathlib import Path

from .errors import HairdynError

_PACKAGE_DIR = Path(__file__).resolve().parent


def _python_tag():
    return f"cpython-{sys.version_info.major}{sys.version_info.minor}"


def status():
    """(True, version) when the native module loads, else (False, one-sentence reason)."""
    try:
        module = _import()
    except ImportError as error:
        built = sorted(p.name for p in _PACKAGE_DIR.glob("_native*.so"))
        built += sorted(p.name for p in _PACKAGE_DIR.glob("_native*.pyd"))
        if not built:
            return False, ("The hairdyn native module is not built: run 'make build' in the "
                           "hairdyn source folder, or install a release package.")
        if not any(_python_tag() in name for name in built):
            return False, (f"The hairdyn native module was built for another Python "
                           f"({', '.join(built)}); this Blender runs Python "
                           f"{sys.version_info.major}.{sys.version_info.minor}: rebuild it.")
        return False, f"The hairdyn native module failed to load: {error}."
    return True, module.__version__


def _import():
    from . import _native

    return _native


def load():
    """The native module, or HairdynError with the reason it cannot be used."""
    ok, message = status()
    if not ok:
        raise HairdynError(message)
    return _import()
