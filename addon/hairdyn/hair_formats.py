"""Readers for hair files, apart from Blender: bytes in, numpy arrays out.

- TressFX .tfx, versions 3.0 and 4.0 (AMD TressFX; little-endian);
- Cem Yuksel's .hair (HAIR header of 128 bytes).

Both give strands as `curve_offsets` + `positions` (the layout hairdyn uses everywhere) in the
file's own coordinates. Layouts: ../shared/data/README.md. A damaged file raises
HairFileError naming the file and what is wrong; nothing is guessed.
"""
import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .errors import HairdynError


class HairFileError(HairdynError):
    pass


@dataclass
class HairFile:
    positions: np.ndarray  # (N, 3) float32, the file's coordinates
    curve_offsets: np.ndarray  # (C + 1,) int32
    fixed: np.ndarray  # (N,) bool: vertices the file marks immovable (TressFX w == 0)
    thickness: object = None  # (N,) float32 when the file has it, else None


def _array(data, path, offset, dtype, count, what):
    end = offset + np.dtype(dtype).itemsize * count
    if offset < 0 or end > len(data):
        raise HairFileError(f"'{path}' is truncated: its {what} need bytes {offset}..{end} "
                            f"but the file has {len(data)}")
    return np.frombuffer(data, dtype=dtype, count=count, offset=offset)


def _uniform_offsets(strands_num, points_per_strand):
    return np.arange(strands_num + 1, dtype=np.int32) * np.int32(points_per_strand)


def read_tfx(path):
    """A TressFX .tfx file (version 3.0 or 4.0)."""
    path = Path(path)
    data = path.read_bytes()
    if len(data) < 12:
        raise HairFileError(f"'{path}' is too short to be a TressFX file")
    version, strands_num, points_per_strand = struct.unpack_from("<fII", data, 0)
    if strands_num == 0 or points_per_strand < 2:
        raise HairFileError(f"'{path}' has {strands_num} strands of {points_per_strand} "
                            "vertices; hair needs strands of at least 2")
    points_num = strands_num * points_per_strand
    if abs(version - 4.0) < 1e-6:
        if len(data) < 160:
            raise HairFileError(f"'{path}' is truncated: a TressFX 4.0 header has 160 bytes")
        positions_offset, _strand_uvs, _vertex_uvs, thickness_offset, _colors = \
            struct.unpack_from("<5I", data, 12)
        xyzw = _array(data, path, positions_offset, "<f4", points_num * 4, "positions")
        xyzw = xyzw.reshape(points_num, 4)
        positions = np.ascontiguousarray(xyzw[:, :3], dtype=np.float32)
        fixed = xyzw[:, 3] == 0.0
    elif abs(version - 3.0) < 1e-6:
        if len(data) < 296:
            raise HairFileError(f"'{path}' is truncated: a TressFX 3.0 header has 296 bytes")
        _follow_per_guide, both_ends_immovable = struct.unpack_from("<2I", data, 12)
        offsets = struct.unpack_from("<6I", data, 12 + 2 * 4 + 31 * 4)
        positions_offset, thickness_offset = offsets[0], offsets[1]
        positions = np.array(_array(data, path, positions_offset, "<f4", points_num * 3,
                                    "positions").reshape(points_num, 3), dtype=np.float32)
        fixed = np.zeros(points_num, dtype=bool)
        fixed[::points_per_strand] = True  # TressFX 3 pins the root of every strand
        if both_ends_immovable:
            fixed[points_per_strand - 1::points_per_strand] = True
    else:
        raise HairFileError(f"'{path}' is TressFX version {version:g}; hairdyn reads 3.0 and 4.0")
    thickness = None
    if thickness_offset:
        thickness = np.array(_array(data, path, thickness_offset, "<f4", points_num,
                                    "thickness"), dtype=np.float32)
    if not np.isfinite(positions).all():
        raise HairFileError(f"'{path}' has vertex positions that are not finite numbers")
    return HairFile(positions, _uniform_offsets(strands_num, points_per_strand), fixed, thickness)


def read_cem_hair(path):
    """A .hair file in Cem Yuksel's format (HAIR signature)."""
    path = Path(path)
    data = path.read_bytes()
    if len(data) < 128 or data[:4] != b"HAIR":
        raise HairFileError(f"'{path}' is not a .hair file (no HAIR header)")
    hair_count, point_count, arrays, default_segments = struct.unpack_from("<4I", data, 4)
    default_thickness = struct.unpack_from("<f", data, 20)[0]
    if not arrays & 2:
        raise HairFileError(f"'{path}' has no point array")
    offset = 128
    if arrays & 1:
        segments = _array(data, path, offset, "<u2", hair_count, "segments").astype(np.int64)
        offset += 2 * hair_count
    else:
        segments = np.full(hair_count, default_segments, dtype=np.int64)
    counts = segments + 1
    if hair_count == 0 or counts.sum() != point_count:
        raise HairFileError(f"'{path}' says {point_count} points but its {hair_count} strands "
                            f"have {int(counts.sum())}")
    positions = np.array(_array(data, path, offset, "<f4", point_count * 3, "points")
                         .reshape(point_count, 3), dtype=np.float32)
    offset += 12 * point_count
    thickness = None
    if arrays & 4:
        thickness = np.array(_array(data, path, offset, "<f4", point_count, "thickness"),
                             dtype=np.float32)
    elif default_thickness > 0:
        thickness = np.full(point_count, default_thickness, dtype=np.float32)
    if not np.isfinite(positions).all():
        raise HairFileError(f"'{path}' has points that are not finite numbers")
    curve_offsets = np.zeros(hair_count + 1, dtype=np.int32)
    np.cumsum(counts, out=curve_offsets[1:])
    fixed = np.zeros(point_count, dtype=bool)
    fixed[curve_offsets[:-1]] = True  # roots
    return HairFile(positions, curve_offsets, fixed, thickness)
