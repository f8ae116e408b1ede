"""The cache never hands back what it did not verify: random bytes, truncations, wrong shapes,
wrong dtypes, non-finite values, archives and directories in place of frames, and damaged
manifests all end in a CacheError naming the file, never in another exception or in data."""

import json

import numpy as np
import pytest

from hairdyn.cache import Cache, CacheError

OFFSETS = np.array([0, 3, 6], np.int32)


def make_cache(directory, frames=(1, 2, 3)):
    cache = Cache.create(
        directory,
        solver="follow",
        parameters={"a": 1},
        curve_offsets=OFFSETS,
        columns={"position": 3, "density": 1},
        frame_start=1,
        frame_end=4,
        fps=24.0,
        streams={"particles": {"points": 5, "columns": {"position": 3}}},
        rest_positions=np.zeros((6, 3), np.float32),
    )
    rng = np.random.default_rng(0)
    for frame in frames:
        cache.write_frame(
            frame,
            {
                "position": rng.normal(size=(6, 3)).astype(np.float32),
                "density": rng.random(6).astype(np.float32),
            },
            {"particles": {"position": rng.normal(size=(5, 3)).astype(np.float32)}},
        )
    return cache


def npy_bytes(array):
    import io

    buffer = io.BytesIO()
    np.save(buffer, array)
    return buffer.getvalue()


def damaged_frames(rng, good):
    """(name, bytes or None for a directory) of ways a frame file can be wrong."""
    yield "directory", None
    yield "empty", b""
    yield "random bytes", rng.bytes(int(rng.integers(1, 400)))
    for _ in range(20):
        yield "truncated", good[: int(rng.integers(0, len(good)))]
    for _ in range(10):  # one byte flipped in the header
        data = bytearray(good)
        data[int(rng.integers(0, 128))] ^= 0xFF
        yield "header byte flipped", bytes(data)
    yield "wrong shape", npy_bytes(np.zeros((6, 3), np.float32))
    yield "too many points", npy_bytes(np.zeros((7, 4), np.float32))
    yield "1-D", npy_bytes(np.zeros(24, np.float32))
    yield "float64", npy_bytes(np.zeros((6, 4), np.float64))
    yield "big-endian", npy_bytes(np.zeros((6, 4), ">f4"))
    yield "int32", npy_bytes(np.zeros((6, 4), np.int32))
    yield "object array", npy_bytes(np.array([None] * 24, dtype=object).reshape(6, 4))
    nan = np.zeros((6, 4), np.float32)
    nan[2, 1] = np.nan
    yield "NaN", npy_bytes(nan)
    yield "infinity", npy_bytes(np.full((6, 4), np.inf, np.float32))
    yield "npz archive", _npz_bytes()


def _npz_bytes():
    import io

    buffer = io.BytesIO()
    np.savez(buffer, frame=np.zeros((6, 4), np.float32))
    return buffer.getvalue()


def plant(path, data):
    if path.is_dir():
        path.rmdir()
    else:
        path.unlink(missing_ok=True)
    if data is None:
        path.mkdir()
    else:
        path.write_bytes(data)


@pytest.mark.parametrize("which", ["frame", "particles"])
def test_damaged_frame_files_are_refused_by_every_reader(tmp_path, which):
    cache = make_cache(tmp_path)
    path = cache.frame_path(2) if which == "frame" else cache.path("particles", 2)
    good = path.read_bytes()
    rng = np.random.default_rng(1)
    for name, data in damaged_frames(rng, good):
        plant(path, data)
        reopened = Cache.open(tmp_path)
        try:
            values = (
                reopened.read_frame(2) if which == "frame" else reopened.read_stream("particles", 2)
            )
        except CacheError as error:
            assert str(path.name) in str(error), name
        else:  # a flipped header byte can leave a valid header: the data must still be right
            table = np.concatenate([np.atleast_2d(v.T).T for v in values.values()], axis=1)
            assert table.dtype == np.float32 and np.isfinite(table).all(), name
            assert table.shape[0] == (6 if which == "frame" else 5), name
        # The frames before stay readable, and the run of whole frames stops before frame 2
        # whenever frame 2 cannot be read.
        reopened.read_frame(1)
        if reopened.frame_problem(2) is not None:
            assert reopened.last_contiguous_frame() in (1, 3)
    plant(path, good)
    assert Cache.open(tmp_path).last_contiguous_frame() == 3


def test_header_check_matches_the_full_read(tmp_path):
    """last_contiguous_frame (headers and sizes) never counts a frame read_frame refuses for
    its shape, dtype or length."""
    cache = make_cache(tmp_path)
    good = cache.frame_path(2).read_bytes()
    rng = np.random.default_rng(2)
    for name, data in damaged_frames(rng, good):
        if name in ("NaN", "infinity"):
            continue  # values: only the full read sees them
        plant(cache.frame_path(2), data)
        reopened = Cache.open(tmp_path)
        if reopened.last_contiguous_frame() == 3:
            assert reopened.frame_problem(2) is None, name


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda m: m["topology"].update(points=10**30), "point count"),
        (lambda m: m["topology"].update(points=-1), "point count"),
        (lambda m: m["topology"].update(points="6"), "point count"),
        (lambda m: m["topology"].update(points=2**31 // 4 + 1), "more than a cache frame can hold"),
        (lambda m: m["topology"].update(curves=None), "strand count"),
        (lambda m: m.update(columns={"position": [3, 0]}), "column 'position'"),
        (lambda m: m.update(columns={"position": "abc"}), "column 'position'"),
        (lambda m: m.update(columns={}), "columns"),
        (lambda m: m.update(columns=[1, 2]), "columns"),
        (lambda m: m["streams"]["particles"].update(points=1.5), "particles point count"),
        (lambda m: m.update(frame_start="1"), "frame_start"),
        (lambda m: m.pop("topology"), "topology"),
        (lambda m: m.update(topology=[]), "incomplete or damaged"),
    ],
)
def test_damaged_manifest_is_refused_on_open(tmp_path, edit, message):
    make_cache(tmp_path)
    path = Cache.manifest_path(tmp_path)
    manifest = json.loads(path.read_text())
    edit(manifest)
    path.write_text(json.dumps(manifest))
    with pytest.raises(CacheError, match=message):
        Cache.open(tmp_path)


def test_random_manifests_never_raise_anything_but_cache_error(tmp_path):
    make_cache(tmp_path)
    path = Cache.manifest_path(tmp_path)
    good = path.read_bytes()
    rng = np.random.default_rng(3)
    values = [None, -1, 0, 1, 2**40, 1.5, "x", [], {}, [1], {"a": 1}, True, float("nan")]
    for trial in range(300):
        if trial % 3 == 0:  # bytes cut or flipped
            data = bytearray(good[: int(rng.integers(0, len(good)))])
            if data:
                data[int(rng.integers(0, len(data)))] = int(rng.integers(0, 256))
            path.write_bytes(bytes(data))
        else:  # one value replaced, anywhere in the tree
            manifest = json.loads(good)
            node = manifest
            while True:
                keys = list(node) if isinstance(node, dict) else list(range(len(node)))
                key = keys[int(rng.integers(0, len(keys)))]
                child = node[key]
                if isinstance(child, (dict, list)) and child and rng.random() < 0.7:
                    node = child
                    continue
                node[key] = values[int(rng.integers(0, len(values)))]
                break
            path.write_text(json.dumps(manifest))
        try:
            cache = Cache.open(tmp_path)
            cache.curve_offsets()
            for frame in cache.frames():
                cache.read_frame(frame)
                for name in cache.streams:
                    cache.read_stream(name, frame)
            cache.last_contiguous_frame()
        except CacheError:
            pass


def test_topology_files_are_verified(tmp_path):
    cache = make_cache(tmp_path)
    for data in (
        None,
        b"garbage",
        npy_bytes(np.array([0, 3, 6], np.int64)),
        npy_bytes(np.array([[0, 3, 6]], np.int32)),
    ):
        plant(tmp_path / "curve_offsets.npy", data)
        with pytest.raises(CacheError, match="curve_offsets.npy"):
            cache.curve_offsets()
