"""The bake cache on disk: one .npy per frame and stream, and a manifest.json.

    <directory>/manifest.json         format, version, solver, parameters, topology, streams,
                                      frame range, timings
    <directory>/curve_offsets.npy     (C + 1,) int32: the groom's topology, so playback can
                                      rebuild the output objects
    <directory>/frame_000012.npy      (N, C) float32: the strands' position, velocity and every
                                      output attribute side by side, as the manifest's
                                      "columns" says
    <directory>/<stream>_000012.npy   the same for the other point sets a solver makes:
                                      "children" (child hairs, with children_offsets.npy) and
                                      "particles" (LCP's particles and their attributes)

Every file appears only complete: it is written to a temporary file, flushed to disk and
renamed. A frame's stream files are written before its frame file, so the frame files present
are the frames baked, whole. A frame with a value that is not finite is refused before
anything is written.

Nothing read back is trusted: the manifest's counts and column spans are checked when it is
opened, and every table read is checked for its dtype, shape and finite values before it is
handed out (CacheError naming the file otherwise). A table is read through a memory map of its
file and its columns copied straight out of the map, in one native pass that also checks every
value (into the cache's own buffers for playback: no allocation per frame); the map goes with
the table's last view. A file is never changed in place (it is replaced by a rename), so a map
sees one whole file. A resumed bake checks the frames it keeps (prepare_resume) and refuses a
groom whose rest positions moved since the bake started (the manifest keeps a hash of them).
"""
import hashlib
import json
import mmap
import os
import re
from pathlib import Path

import numpy as np

from . import native
from .errors import HairdynError

FORMAT = "hairdyn-cache"
VERSION = 1
MAIN = "frame"  # file prefix of the strands' table
_FRAME_FILE = re.compile(r"^frame_(-?\d{6,})\.npy$")


class CacheError(HairdynError):
    pass


_INT32_MAX = 2**31 - 1


def topology_hash(curve_offsets):
    """Identifies a groom's topology: the curve offsets (and so the point count)."""
    offsets = np.ascontiguousarray(curve_offsets, dtype=np.int32)
    return hashlib.sha256(offsets.tobytes()).hexdigest()[:16]


def rest_hash(positions):
    """Identifies a groom's rest shape: the exact bits of its (N, 3) float32 positions."""
    values = np.ascontiguousarray(positions, dtype=np.float32)
    return hashlib.sha256(values.tobytes()).hexdigest()[:16]


def _count(value, what, limit=_INT32_MAX):
    """An int 0 <= value <= limit from a manifest, or ValueError naming it."""
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= limit:
        raise ValueError(f"{what} is {value!r}, not a count between 0 and {limit}")
    return value


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


def _spans(columns):
    """{name: width} in order -> {name: [start, stop]} of a table's columns."""
    spans, offset = {}, 0
    for name, width in columns.items():
        spans[name] = [offset, offset + width]
        offset += width
    return spans


class _Layout:
    """One table per frame: points_num rows, named column spans."""

    def __init__(self, prefix, points_num, spans):
        self.prefix = prefix
        self.points_num = _count(points_num, f"the {prefix} point count")
        if not isinstance(spans, dict) or not spans:
            raise ValueError(f"the {prefix} columns are {spans!r}")
        self.columns = {}
        for name, span in spans.items():
            if not isinstance(span, (list, tuple)) or len(span) != 2:
                raise ValueError(f"the {prefix} column '{name}' spans {span!r}")
            start = _count(span[0], f"the start of column '{name}'", 4096)
            stop = _count(span[1], f"the end of column '{name}'", 4096)
            if stop <= start:
                raise ValueError(f"the {prefix} column '{name}' spans {span!r}")
            self.columns[name] = (start, stop)
        self.width = max(stop for _, stop in self.columns.values())
        if self.points_num * self.width > _INT32_MAX:
            raise ValueError(f"{self.points_num} {prefix} points of {self.width} values are "
                             "more than a cache frame can hold")

    def pack(self, frame, arrays):
        table = np.empty((self.points_num, self.width), dtype=np.float32)
        for name, (start, stop) in self.columns.items():
            if name not in arrays:
                raise CacheError(f"Frame {frame}: the {self.prefix} data has no '{name}'; it was "
                                 "not written")
            values = np.asarray(arrays[name], dtype=np.float32)
            if values.size != self.points_num * (stop - start):
                raise CacheError(f"Frame {frame}: {self.prefix} '{name}' has {values.size} "
                                 f"values, the cache holds {self.points_num * (stop - start)}; "
                                 "it was not written")
            table[:, start:stop] = values.reshape(self.points_num, stop - start)
        if not np.isfinite(table).all():
            bad = sorted(name for name, (start, stop) in self.columns.items()
                         if not np.isfinite(table[:, start:stop]).all())
            raise CacheError(f"Frame {frame} has values that are not finite numbers in "
                             f"{', '.join(bad)}; it was not written to the cache")
        return table

    def read(self, path, what, buffers=None):
        """The named columns of the table in the .npy file `path`, after checking its dtype,
        shape and values: CacheError naming the file otherwise. The file is memory-mapped and
        its columns copied out of the map in one native pass that checks every value, into
        `buffers` ({name: array} that read fills in and returns, so nothing is allocated per
        frame) or into new arrays."""
        table = _mapped_table(path, what)
        if table.dtype != np.float32 or table.shape != (self.points_num, self.width) or \
                not table.flags.c_contiguous:
            order = "" if table.flags.c_contiguous else " in Fortran order"
            raise CacheError(f"The cache frame '{path}' holds {table.dtype} {table.shape}"
                             f"{order}, the manifest says float32 ({self.points_num}, "
                             f"{self.width})")
        buffers = {} if buffers is None else buffers
        if not buffers:
            buffers.update({name: np.empty((len(table),) if stop - start == 1 else
                                           (len(table), stop - start), np.float32)
                            for name, (start, stop) in self.columns.items()})
        outputs = [(buffers[name].reshape(-1), start)
                   for name, (start, _) in self.columns.items()]
        if not native.load().split_columns(table, outputs):
            finite = np.isfinite(table)
            bad = sorted(name for name, (start, stop) in self.columns.items()
                         if not finite[:, start:stop].all())
            point = int(np.flatnonzero(~finite.all(axis=1))[0])
            raise CacheError(f"The cache frame '{path}' has values that are not finite numbers "
                             f"in {', '.join(bad) or 'a column no attribute uses'} (point "
                             f"{point}): bake again")
        return buffers


def _read_header(file):
    """(shape, fortran order, dtype) of the .npy file open at its start, leaving the file at
    its data; ValueError when the header is not one numpy writes (versions 1.0 and 2.0)."""
    try:
        read_header = {(1, 0): np.lib.format.read_array_header_1_0,
                       (2, 0): np.lib.format.read_array_header_2_0}.get(
                           np.lib.format.read_magic(file))
        if read_header is None:
            raise ValueError("an unknown .npy format version")
        return read_header(file)
    except Exception as error:  # a garbled header: numpy's parser may raise anything
        raise ValueError(str(error) or type(error).__name__) from None  # (numpy 2 on
        # Python 3.13: tokenize.TokenError)


def _mapped_table(path, what):
    """The .npy file's array over a read-only memory map of the file. Nothing else keeps the
    map: it is unmapped as soon as the array and its views are gone. CacheError naming the file
    when it is missing, a directory, not a plain .npy array, or shorter than its header says."""
    if path.is_dir():
        raise CacheError(f"The cache {what} '{path}' is a directory, not a file")
    try:
        with open(path, "rb") as file:
            try:
                shape, fortran, dtype = _read_header(file)
                if dtype.hasobject or not all(isinstance(n, int) and n >= 0 for n in shape):
                    raise ValueError(f"an array of {dtype} {shape}")
            except ValueError as error:
                raise CacheError(f"The cache {what} '{path}' is corrupted or truncated "
                                 f"({error})") from None
            offset = file.tell()
            count = int(np.prod(shape, dtype=np.int64))
            size = os.fstat(file.fileno()).st_size
            if size < offset + count * dtype.itemsize:
                raise CacheError(f"The cache {what} '{path}' is corrupted or truncated ({size} "
                                 f"bytes, its header says {offset + count * dtype.itemsize})")
            if count == 0:
                return np.empty(shape, dtype)
            values = np.frombuffer(_map(file), dtype=dtype, count=count, offset=offset)
    except FileNotFoundError:
        raise CacheError(f"The cache {what} '{path}' is missing") from None
    except OSError as error:
        raise CacheError(f"The cache {what} '{path}' cannot be read: "
                         f"{error.strerror or error}") from None
    return values.reshape(shape, order="F" if fortran else "C")


def _map(file):
    """A read-only memory map of a whole open file; its pages are read in by the one call
    where the system can (MAP_POPULATE), rather than one page fault at a time."""
    if hasattr(mmap, "MAP_POPULATE"):
        return mmap.mmap(file.fileno(), 0, flags=mmap.MAP_SHARED | mmap.MAP_POPULATE,
                         prot=mmap.PROT_READ)
    return mmap.mmap(file.fileno(), 0, access=mmap.ACCESS_READ)


class Cache:
    """A cache directory. Create with Cache.create() or open with Cache.open()."""

    def __init__(self, directory, manifest):
        self.directory = Path(directory)
        self.manifest = manifest
        self._buffers = {}  # stream name -> {column: array} that reads with reuse fill
        self.main = _Layout(MAIN, manifest["topology"]["points"], manifest["columns"])
        _count(manifest["topology"]["curves"], "the strand count")
        self.streams = {name: _Layout(name, stream["points"], stream["columns"])
                        for name, stream in manifest.get("streams", {}).items()}
        for key in ("frame_start", "frame_end"):
            if isinstance(manifest[key], bool) or not isinstance(manifest[key], int):
                raise ValueError(f"{key} is {manifest[key]!r}")

    @property
    def columns(self):
        return self.main.columns

    # -- manifest ------------------------------------------------------------------------------

    @staticmethod
    def manifest_path(directory):
        return Path(directory) / "manifest.json"

    @classmethod
    def create(cls, directory, *, solver, parameters, curve_offsets, columns, frame_start,
               frame_end, fps, streams=None, extra=None, rest_positions=None):
        """A new cache (an older bake in `directory` is removed). streams: name ->
        {"points": M, "columns": {name: width}, "offsets": (K + 1,) int32 or None};
        rest_positions: the groom's (N, 3) positions the bake starts from (a resume checks
        them)."""
        directory = Path(directory)
        try:
            directory.mkdir(parents=True, exist_ok=True)
        except OSError as error:
            raise CacheError(f"Cannot create the cache directory '{directory}': "
                             f"{error.strerror or error}") from None
        if not os.access(directory, os.W_OK):
            raise CacheError(f"The cache directory '{directory}' is not writable")
        streams = streams or {}
        manifest = {
            "format": FORMAT,
            "version": VERSION,
            "solver": solver,
            "parameters": parameters,
            "topology": {"curves": int(len(curve_offsets) - 1), "points": int(curve_offsets[-1]),
                         "hash": topology_hash(curve_offsets),
                         **({"rest_hash": rest_hash(rest_positions)}
                            if rest_positions is not None else {})},
            "columns": _spans(columns),
            "streams": {name: {"points": int(stream["points"]),
                               "columns": _spans(stream["columns"]),
                               "has_offsets": stream.get("offsets") is not None}
                        for name, stream in streams.items()},
            "frame_start": int(frame_start),
            "frame_end": int(frame_end),
            "fps": fps,
            "timings": {},
            **(extra or {}),
        }
        cache = cls(directory, manifest)
        cache.free()
        cache._save_array("curve_offsets.npy", curve_offsets)
        for name, stream in streams.items():
            if stream.get("offsets") is not None:
                cache._save_array(f"{name}_offsets.npy", stream["offsets"])
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
        except (KeyError, TypeError, ValueError, AttributeError) as error:
            raise CacheError(f"The cache manifest '{path}' is incomplete or damaged "
                             f"({error})") from None

    def free(self):
        """Removes every file of this cache (frames, streams, topology, manifest) and the
        bake's frame record beside them (frame_record.csv and .png)."""
        if not self.directory.is_dir():
            return
        for pattern in ("*.npy", "frame_record.*"):
            for path in self.directory.glob(pattern):
                path.unlink(missing_ok=True)
        self.manifest_path(self.directory).unlink(missing_ok=True)

    def _save_array(self, name, array):
        values = np.ascontiguousarray(array, dtype=np.int32)
        _write_atomic(self.directory / name, lambda file: np.save(file, values))

    def _load(self, path, what):
        """One array from a .npy file: CacheError naming the file when it is missing, a
        directory, not a plain .npy array, corrupted or truncated."""
        if path.is_dir():
            raise CacheError(f"The cache {what} '{path}' is a directory, not a file")
        try:
            array = np.load(path, allow_pickle=False)
        except FileNotFoundError:
            raise CacheError(f"The cache {what} '{path}' is missing") from None
        except Exception as error:  # a garbled file: numpy's parser may raise anything
            raise CacheError(f"The cache {what} '{path}' is corrupted or truncated ({error})") from None
        if not isinstance(array, np.ndarray):  # an .npz archive under a .npy name
            if hasattr(array, "close"):
                array.close()
            raise CacheError(f"The cache {what} '{path}' is not a single array")
        return array

    def curve_offsets(self):
        path = self.directory / "curve_offsets.npy"
        offsets = self._load(path, "topology")
        if offsets.dtype != np.int32 or offsets.ndim != 1 or \
                topology_hash(offsets) != self.manifest["topology"]["hash"]:
            raise CacheError(f"The cache topology '{path}' does not match its manifest")
        return offsets

    def stream_offsets(self, name):
        """The curve offsets of a stream of curves (e.g. "children")."""
        path = self.directory / f"{name}_offsets.npy"
        offsets = self._load(path, f"{name} topology")
        if offsets.dtype != np.int32 or offsets.ndim != 1 or len(offsets) < 2 or \
                offsets[0] != 0 or offsets[-1] != self.streams[name].points_num or \
                (np.diff(offsets) < 0).any():
            raise CacheError(f"The cache {name} topology '{path}' does not match its manifest")
        return offsets

    def last_contiguous_frame(self):
        """The last frame of the unbroken run of frames from frame_start, or None. A frame
        counts when its file is a .npy table of the manifest's dtype and shape (its values are
        checked by read_frame and frame_problem)."""
        present = set(self.frames())
        frame = self.manifest["frame_start"]
        if frame not in present or not self._frame_file_ok(frame):
            return None
        while frame + 1 in present and frame + 1 <= self.manifest["frame_end"] and \
                self._frame_file_ok(frame + 1):
            frame += 1
        return frame

    def _frame_file_ok(self, frame):
        """Whether the frame's files hold tables of the manifest's dtype and shape (headers
        and file sizes only; the values are not read)."""
        layouts = [(self.frame_path(frame), self.main)]
        layouts += [(self.path(name, frame), layout) for name, layout in self.streams.items()]
        for path, layout in layouts:
            try:
                with open(path, "rb") as file:
                    shape, fortran, dtype = _read_header(file)
                    header_end = file.tell()
                size = path.stat().st_size
            except (OSError, ValueError):
                return False
            expected = (layout.points_num, layout.width)
            if dtype != np.float32 or fortran or tuple(shape) != expected or \
                    size != header_end + 4 * layout.points_num * layout.width:
                return False
        return True

    def frame_problem(self, frame):
        """None when the frame and its streams read back whole (dtype, shape, finite values),
        otherwise the sentence read_frame would raise."""
        try:
            self.read_frame(frame)
            for name in self.streams:
                self.read_stream(name, frame)
        except CacheError as error:
            return str(error)
        return None

    def prepare_resume(self, resume_after):
        """Checks the frames a resumed bake keeps and removes the others; returns the last
        frame kept. Frames are kept from frame_start up to resume_after while each reads back
        whole; the first missing, truncated, garbled or non-finite frame and everything after
        it are baked again (a directory in the way is refused: it is not ours to remove). The
        manifest says the bake is incomplete until finish."""
        start, end = self.manifest["frame_start"], self.manifest["frame_end"]
        last = None
        for frame in range(start, min(end, resume_after) + 1):
            if self.frame_problem(frame) is not None:
                break
            last = frame
        if last is None:
            problem = self.frame_problem(start)
            raise CacheError(f"There is no baked frame to continue from in '{self.directory}' "
                             f"({problem})")
        if last >= end:
            raise CacheError(f"The bake in '{self.directory}' is already complete")
        self.manifest["complete"] = False
        self.save_manifest()
        self.discard_frames_after(last)
        return last

    def discard_frames_after(self, last):
        """Removes the frame and stream files of the frames after `last`."""
        prefixes = [MAIN, *self.streams]
        doomed = [self.path(prefix, frame) for frame in self.frames() if frame > last
                  for prefix in prefixes]
        for path in doomed:
            if path.is_dir():
                raise CacheError(f"'{path}' is a directory where the cache keeps a frame: "
                                 "remove it, then bake again")
        for path in doomed:
            try:
                path.unlink(missing_ok=True)
            except OSError as error:
                raise CacheError(f"Cannot remove the cache file '{path}': "
                                 f"{error.strerror or error}") from None

    def save_manifest(self):
        text = json.dumps(self.manifest, indent=2, sort_keys=True).encode()
        _write_atomic(self.manifest_path(self.directory), lambda file: file.write(text))

    def check_topology(self, curve_offsets, rest_positions=None):
        """CacheError unless the cache was baked from a groom of this topology (and, given
        rest_positions and a manifest that recorded them, from this rest shape)."""
        expected = self.manifest["topology"]
        if expected["hash"] != topology_hash(curve_offsets):
            raise CacheError(
                f"The cache in '{self.directory}' was baked from another groom "
                f"({expected['curves']} strands, {expected['points']} points; this one has "
                f"{len(curve_offsets) - 1} strands, {int(curve_offsets[-1])} points): bake again")
        if rest_positions is not None and "rest_hash" in expected and \
                expected["rest_hash"] != rest_hash(rest_positions):
            raise CacheError(
                f"The groom's points moved since the bake in '{self.directory}' started (same "
                "strands, another rest shape): bake from the start")

    # -- frames --------------------------------------------------------------------------------

    def path(self, prefix, frame):
        return self.directory / f"{prefix}_{int(frame):06d}.npy"

    def frame_path(self, frame):
        return self.path(MAIN, frame)

    def frames(self):
        """Frames on disk, sorted."""
        if not self.directory.is_dir():
            return []
        found = (_FRAME_FILE.match(p.name) for p in self.directory.iterdir())
        return sorted(int(m.group(1)) for m in found if m)

    def has_frame(self, frame):
        return self.frame_path(frame).is_file()

    def write_frame(self, frame, arrays, streams=None):
        """arrays: name -> (N,) or (N, k) array for every column of the manifest; streams:
        stream name -> its arrays, for every stream of the manifest."""
        tables = {name: layout.pack(frame, (streams or {}).get(name, {}))
                  for name, layout in self.streams.items()}
        table = self.main.pack(frame, arrays)
        for name, stream_table in tables.items():
            _write_atomic(self.path(name, frame), lambda file, t=stream_table: np.save(file, t))
        _write_atomic(self.frame_path(frame), lambda file: np.save(file, table))

    def read_frame(self, frame, reuse=False):
        """name -> array for one frame, or CacheError naming the file. reuse: the arrays are
        this Cache's own, the same ones each time and overwritten by the next such read (for
        playback, which hands them to Blender at once: nothing allocated per frame)."""
        path = self.frame_path(frame)
        if not path.exists():
            raise CacheError(f"Frame {frame} is not in the cache ('{path}' is missing)")
        return self.main.read(path, "frame", self._buffers.setdefault(MAIN, {}) if reuse else None)

    def read_stream(self, name, frame, reuse=False):
        """name -> array of one stream for one frame, or CacheError naming the file (reuse:
        as read_frame)."""
        path = self.path(name, frame)
        return self.streams[name].read(path, f"{name} frame",
                                       self._buffers.setdefault(name, {}) if reuse else None)
