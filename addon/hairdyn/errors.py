"""The one exception type users see: its message is a sentence meant for the artist."""


class HairdynError(Exception):
    """Something the user can fix (bad input, missing object, missing native module)."""
