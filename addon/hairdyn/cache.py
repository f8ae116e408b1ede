"""The bake cache on disk: one .npy per frame and a manifest.json.

    <directory>/manifest.json        format, version, solver, parameters, topology, columns,
                                     frame range, timings
    <directory>/curve_offsets.npy    (C + 1,) int32: the topology, so playback can rebuild the
                                     output objects
    <directory>/children_offsets.npy (K + 1,) int32 and children_000012.npy (M, 3) float32:
                                     child hairs, when the solver makes them (written before
                                     the frame file, so a frame file means a complete frame)
    <directory>/frame_000012.npy     (N, C) float32: position, velocity and every output
                                     attribute side by side, as the manifest's "columns" says

A frame file appears only complete: it is written to a temporary file, flushed to disk and
renamed, so a crash never leaves a torn frame, and the frames present are the frames baked.
A frame with a value that is not finite is refused before anything is written.
"""
import hashlib
import json
import os
import re
from pathlib import Path

import numpy as np

from .errors import HairdynError

FORMAT = "hairdyn-cache"
VERSION = 1
_FRAME_FILE = re.compile(r"^frame_(-?\d{6,})\.npy$")


class CacheError(HairdynError):
    pass


def topology_hash(curve_offsets):
    """Identifies a groom's topology: the curve offsets (and so the point count)."""
    offsets = np.ascontiguousarray(curve_offsets, dtype=np.int32)
    return hashlib.sha256(offsets.tobytes()).hexdigest()[:16]


def _write_atomic(path, write):
    """write(file) into path.tmp, flush it to disk, then rename over path."""
    temporary = path.with_name(path.name + ".tmp")
    try:
        with open(temporary, "wb") as file:
            write(file)
            file.flush()
            os.fsync(file.fileno())
        os.replace(temporary, path)
    except OSError as error:
        temporary.unlink(missing_ok=True)
        raise CacheError(f"Cannot write the cache file '{path}': {error.strerror or error}") from None


class Cache:
    """A cache directory. Create with Cache.create() or open with Cache.open()."""

    def __init__(self, directory, manifest):
        self.directory = Path(directory)
        self.manifest = manifest
        self.columns = {name: tuple(span) for name, span in manifest["columns"].items()}
        self.width = max(stop for _, stop in self.columns.values())
        self.points_num = manifest["topology"]["points"]

    # -- manifest ------------------------------------------------------------------------------

    @staticmethod
    def manifest_path(directory):
        return Path(directory) / "manifest.json"

    @classmethod
    def create(cls, directory, *, solver, parameters, curve_offsets, columns, frame_start,
               frame_end, fps, children_offsets=None, extra=None):
        """A new cache (frames of an older bake in `directory` are removed)."""
        directory = Path(directory)
        try:
            directory.mkdir(parents=True, exist_ok=True)
        except OSError as error:
            raise CacheError(f"Cannot create the cache directory '{directory}': "
                             f"{error.strerror or error}") from None
        if not os.access(directory, os.W_OK):
            raise CacheError(f"The cache directory '{directory}' is not writable")
        offset = 0
        spans = {}
        for name, width in columns.items():
            spans[name] = [offset, offset + width]
            offset += width
        manifest = {
            "format": FORMAT,
            "version": VERSION,
            "solver": solver,
            "parameters": parameters,
            "topology": {"curves": int(len(curve_offsets) - 1), "points": int(curve_offsets[-1]),
                         "hash": topology_hash(curve_offsets)},
            "columns": spans,
            "frame_start": int(frame_start),
            "frame_end": int(frame_end),
            "fps": fps,
            "timings": {},
            "children": None if children_offsets is None else {
                "curves": int(len(children_offsets) - 1), "points": int(children_offsets[-1])},
            **(extra or {}),
        }
        cache = cls(directory, manifest)
        cache.free()
        offsets = np.ascontiguousarray(curve_offsets, dtype=np.int32)
        _write_atomic(directory / "curve_offsets.npy", lambda file: np.save(file, offsets))
        if children_offsets is not None:
            children = np.ascontiguousarray(children_offsets, dtype=np.int32)
            _write_atomic(directory / "children_offsets.npy", lambda file: np.save(file, children))
        cache.save_manifest()
        return cache

    @classmethod
    def open(cls, directory):
        """The cache in `directory`, or CacheError naming what is wrong."""
        path = cls.manifest_path(directory)
        if not path.is_file():
            raise CacheError(f"There is no hairdyn cache in '{directory}' (no manifest.json)")
        try:
            manifest = json.loads(path.read_text())
        except (OSError, ValueError) as error:
            raise CacheError(f"The cache manifest '{path}' cannot be read: {error}") from None
        if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
            raise CacheError(f"'{path}' is not a hairdyn cache manifest")
        if manifest.get("version") != VERSION:
            raise CacheError(f"The cache '{path}' has format version {manifest.get('version')}; "
                             f"this hairdyn reads version {VERSION}: bake again")
        try:
            return cls(directory, manifest)
        except (KeyError, TypeError, ValueError) as error:
            raise CacheError(f"The cache manifest '{path}' is incomplete ({error})") from None

    def free(self):
        """Removes every file of this cache (frames, topology, manifest)."""
        for frame in self.frames():
            self.frame_path(frame).unlink(missing_ok=True)
        for path in self.directory.glob("children_*.npy"):
            path.unlink(missing_ok=True)
        (self.directory / "curve_offsets.npy").unlink(missing_ok=True)
        self.manifest_path(self.directory).unlink(missing_ok=True)

    def _load(self, path, what):
        try:
            return np.load(path, allow_pickle=False)
        except FileNotFoundError:
            raise CacheError(f"The cache {what} '{path}' is missing") from None
        except (OSError, ValueError, EOFError) as error:
            raise CacheError(f"The cache {what} '{path}' is corrupted or truncated ({error})") from None

    def curve_offsets(self):
        path = self.directory / "curve_offsets.npy"
        offsets = self._load(path, "topology")
        if offsets.dtype != np.int32 or topology_hash(offsets) != self.manifest["topology"]["hash"]:
            raise CacheError(f"The cache topology '{path}' does not match its manifest")
        return offsets

    @property
    def has_children(self):
        return bool(self.manifest.get("children"))

    def children_offsets(self):
        path = self.directory / "children_offsets.npy"
        offsets = self._load(path, "child topology")
        expected = self.manifest["children"]
        if offsets.dtype != np.int32 or len(offsets) != expected["curves"] + 1 or \
                offsets[-1] != expected["points"]:
            raise CacheError(f"The cache child topology '{path}' does not match its manifest")
        return offsets

    def children_path(self, frame):
        return self.directory / f"children_{int(frame):06d}.npy"

    def read_children(self, frame):
        """(M, 3) float32 child hair positions of a frame."""
        path = self.children_path(frame)
        positions = self._load(path, "child frame")
        if positions.dtype != np.float32 or positions.shape != (self.manifest["children"]["points"], 3):
            raise CacheError(f"The cache child frame '{path}' holds {positions.dtype} "
                             f"{positions.shape}, the manifest says float32 "
                             f"({self.manifest['children']['points']}, 3)")
        return positions

    def last_contiguous_frame(self):
        """The last frame of the unbroken run of frames from frame_start, or None."""
        present = set(self.frames())
        frame = self.manifest["frame_start"]
        if frame not in present:
            return None
        while frame + 1 in present and frame + 1 <= self.manifest["frame_end"]:
            frame += 1
        return frame

    def save_manifest(self):
        text = json.dumps(self.manifest, indent=2, sort_keys=True).encode()
        _write_atomic(self.manifest_path(self.directory), lambda file: file.write(text))

    def check_topology(self, curve_offsets):
        """CacheError unless the cache was baked from a groom of this topology."""
        expected = self.manifest["topology"]
        if expected["hash"] != topology_hash(curve_offsets):
            raise CacheError(
                f"The cache in '{self.directory}' was baked from another groom "
                f"({expected['curves']} strands, {expected['points']} points; this one has "
                f"{len(curve_offsets) - 1} strands, {int(curve_offsets[-1])} points): bake again")

    # -- frames --------------------------------------------------------------------------------

    def frame_path(self, frame):
        return self.directory / f"frame_{int(frame):06d}.npy"

    def frames(self):
        """Frames on disk, sorted."""
        if not self.directory.is_dir():
            return []
        found = (_FRAME_FILE.match(p.name) for p in self.directory.iterdir())
        return sorted(int(m.group(1)) for m in found if m)

    def has_frame(self, frame):
        return self.frame_path(frame).is_file()

    def write_frame(self, frame, arrays, children_positions=None):
        """arrays: name -> (N,) or (N, k) array for every column of the manifest; the child
        hairs' (M, 3) positions when the cache has children."""
        table = np.empty((self.points_num, self.width), dtype=np.float32)
        for name, (start, stop) in self.columns.items():
            values = np.asarray(arrays[name], dtype=np.float32)
            table[:, start:stop] = values.reshape(self.points_num, stop - start)
        if not np.isfinite(table).all():
            bad = sorted(name for name, (start, stop) in self.columns.items()
                         if not np.isfinite(table[:, start:stop]).all())
            raise CacheError(f"Frame {frame} has values that are not finite numbers in "
                             f"{', '.join(bad)}; it was not written to the cache")
        if self.has_children:
            children = np.ascontiguousarray(children_positions, dtype=np.float32)
            if children.shape != (self.manifest["children"]["points"], 3) or \
                    not np.isfinite(children).all():
                raise CacheError(f"Frame {frame} has child hairs of the wrong size or not "
                                 "finite; it was not written to the cache")
            _write_atomic(self.children_path(frame), lambda file: np.save(file, children))
        _write_atomic(self.frame_path(frame), lambda file: np.save(file, table))

    def read_frame(self, frame):
        """name -> array for one frame, or CacheError naming the file."""
        path = self.frame_path(frame)
        if not path.is_file():
            raise CacheError(f"Frame {frame} is not in the cache ('{path}' is missing)")
        table = self._load(path, "frame")
        if table.dtype != np.float32 or table.shape != (self.points_num, self.width):
            raise CacheError(f"The cache frame '{path}' holds {table.dtype} {table.shape}, the "
                             f"manifest says float32 ({self.points_num}, {self.width})")
        return {name: (table[:, start] if stop - start == 1 else table[:, start:stop])
                for name, (start, stop) in self.columns.items()}
