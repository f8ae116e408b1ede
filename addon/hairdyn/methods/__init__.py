"""Owns: the method registry. Each method is one adapter class (methods/<name>.py, a
`base.Method`) and one line in BUILTIN; the rest of the add-on iterates the registry and
never names a method. `register(cls)` adds one at run time (the Method enum follows).
"""

from .base import Build, Method, Section, Stream  # noqa: F401 - the adapters' interface
from .follow import Follow
from .lcp import Lcp
from .strands import Strands, register_extension
from . import lod, swept_spheres, volume

BUILTIN = (Follow, Strands, Lcp)
# Groom-wide substep passes on the Strands method, in the order they run; then level of detail,
# which replaces the strand solver (and refuses the passes: it runs none).
for _extension in (volume.EXTENSION, swept_spheres.EXTENSION, lod.EXTENSION):
    register_extension(_extension)

_registry = {}  # identifier -> Method subclass, in registration order
_listeners = []  # called with no argument when the registry changes (the Method enum)


def register(method):
    """Add a Method subclass (replacing one of the same identifier)."""
    if not method.identifier or not method.identifier.isupper():
        raise ValueError(f"{method.__name__}.identifier must be an upper-case name")
    _registry[method.identifier] = method
    for listener in _listeners:
        listener()


def unregister(method):
    if _registry.get(method.identifier) is method:
        del _registry[method.identifier]
        for listener in _listeners:
            listener()


def all_methods():
    return list(_registry.values())


def get(identifier):
    """The Method subclass for an identifier (case-insensitive), or None."""
    return _registry.get(str(identifier).upper())


def enum_items():
    """(identifier, label, description, number) for the Method EnumProperty; the numbers stay
    with their method as others are registered, so stored choices survive."""
    return [
        (
            cls.identifier,
            cls.label,
            cls.description,
            _numbers.setdefault(cls.identifier, len(_numbers)),
        )
        for cls in _registry.values()
    ]


def on_change(listener):
    if listener not in _listeners:
        _listeners.append(listener)


_numbers = {}
for _method in BUILTIN:
    register(_method)
