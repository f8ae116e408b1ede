"""Owns: the one exception type users see, and the one error boundary every entry point
(operators, the frame-change handler, the command line) goes through.

A HairdynError is something the user can fix; its message is a sentence meant for the artist
and is shown as it is (a Blender report, one console line). Anything else is an internal error:
its traceback is printed once on the console and the user sees one line saying so.
"""

import traceback


class HairdynError(Exception):
    """Something the user can fix (bad input, missing object, missing native module)."""


def message(error):
    """The one line a user sees for any exception."""
    if isinstance(error, HairdynError):
        return str(error)
    if isinstance(error, OSError) and error.filename is not None:  # the disk, not a bug
        return f"Cannot access '{error.filename}': {error.strerror or error}"
    if isinstance(error, MemoryError):
        return "Out of memory: bake fewer strands or frames at once"
    return (
        f"Internal error in hairdyn ({type(error).__name__}: {error}); the traceback is on "
        "the console, please report it"
    )


def is_internal(error):
    """A bug of hairdyn's (its traceback is printed), not something the user can fix."""
    return not isinstance(error, (HairdynError, OSError, MemoryError))


def print_traceback(error, where="hairdyn"):
    """The traceback of an internal error, on the console (stderr)."""
    print(f"{where}: internal error:")
    traceback.print_exception(type(error), error, error.__traceback__)


def operator_boundary(function):
    """Decorates an operator's execute / invoke / modal: a HairdynError becomes an ERROR report,
    anything else an internal-error report with its traceback on the console; both cancel. The
    operator's `cleanup(context)` (if any) runs first, so nothing is left half-done."""

    def guarded(self, context, *event):
        try:
            return function(self, context, *event)
        except Exception as error:  # noqa: BLE001 - this is the boundary
            cleanup = getattr(self, "cleanup", None)
            if cleanup is not None:
                try:
                    cleanup(context)
                except Exception as cleanup_error:  # noqa: BLE001
                    print_traceback(cleanup_error, f"hairdyn: {self.bl_idname} cleanup")
            if is_internal(error):
                print_traceback(error, f"hairdyn: {self.bl_idname}")
            self.report({'ERROR'}, message(error))
            return {'CANCELLED'}

    if function.__code__.co_argcount == 3:  # invoke / modal: Blender counts the arguments

        def with_event(self, context, event):
            return guarded(self, context, event)

        result = with_event
    else:

        def without_event(self, context):
            return guarded(self, context)

        result = without_event
    result.__name__, result.__doc__ = function.__name__, function.__doc__
    return result


class Once:
    """Remembers the last error per key, so a handler called every frame says each distinct
    error once: a console line for a user error, the traceback for an internal one."""

    def __init__(self):
        self.last = {}

    def report(self, key, label, error):
        text = message(error)
        if self.last.get(key) != text:
            if is_internal(error):
                print_traceback(error, f"hairdyn: {label}")
            else:
                print(f"hairdyn: {label}: {text}")
        self.last[key] = text

    def clear(self, key=None):
        if key is None:
            self.last.clear()
        else:
            self.last.pop(key, None)

    def get(self, key):
        return self.last.get(key)
