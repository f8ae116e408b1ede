"""The per-frame record of a bake, beside its cache, and a plot of it.

    record = frame_record.start(cache_dir)       # a bake begins (resume=True keeps old rows)
    record.add(frame, {"ms": ..., "penetration_share": ..., "stretch": ..., "kinetic_energy":
                       ..., "contacts": ...})    # after each frame
    png = record.finish()                        # writes frame_record.csv and frame_record.png

The figures, per frame: native milliseconds; the share of strand points deeper in a collider
than the penetration tolerance; the largest relative segment stretch; the kinetic energy per
unit mass, ½ Σ |v|² over the points (m²/s², see kinetic_energy()); the number of points in
contact. Over a bake, their median ms, largest stretch and mean share are the report's
ms_per_frame, stretch_max and penetration_share (the share is taken over the same points each
frame). The plot is drawn with numpy and written as PNG with zlib: no plotting library, so it
is the same in every Blender.
"""

import csv
import os
import struct
import zlib
from pathlib import Path

import numpy as np

FIGURES = ("ms", "penetration_share", "stretch", "kinetic_energy", "contacts")
CSV_NAME = "frame_record.csv"
PNG_NAME = "frame_record.png"
_TITLES = {
    "ms": "ms per frame",
    "penetration_share": "penetration share %",
    "stretch": "stretch",
    "kinetic_energy": "kinetic energy m2/s2",
    "contacts": "contacts",
}
_SHOWN_SCALE = {"penetration_share": 100.0}  # plotted as percent


def kinetic_energy(velocities):
    """½ Σ |v|² over the points' velocities (N, 3): kinetic energy per unit point mass."""
    v = np.asarray(velocities, dtype=np.float64)
    return float(0.5 * np.einsum("ij,ij->", v, v))


class FrameRecord:
    """Rows of figures by frame, for one cache folder."""

    def __init__(self, cache_dir, rows=None):
        self.directory = Path(cache_dir)
        self.rows = dict(rows or {})

    @classmethod
    def start(cls, cache_dir, resume=False):
        """A record for a bake into cache_dir; resume=True keeps the frames recorded before
        (a resumed bake), else an older record there is dropped."""
        record = cls(cache_dir)
        if resume and record.csv_path.is_file():
            record.rows = read(record.csv_path)
        return record

    @property
    def csv_path(self):
        return self.directory / CSV_NAME

    @property
    def png_path(self):
        return self.directory / PNG_NAME

    def add(self, frame, figures):
        """The figures of one frame (every name of FIGURES, finite numbers)."""
        missing = [name for name in FIGURES if name not in figures]
        if missing:
            raise ValueError(f"frame {frame}: the record needs {', '.join(missing)}")
        row = {name: float(figures[name]) for name in FIGURES}
        bad = [name for name, value in row.items() if not np.isfinite(value)]
        if bad:
            raise ValueError(f"frame {frame}: {', '.join(bad)} is not a finite number")
        self.rows[int(frame)] = row

    def summary(self):
        """The report's figures from the record: ms_per_frame (median), stretch_max,
        penetration_share (mean), and the frame count."""
        table = self.table()
        return {
            "frames": len(table["frame"]),
            "ms_per_frame": float(np.median(table["ms"])) if len(table["frame"]) else 0.0,
            "stretch_max": float(table["stretch"].max(initial=0.0)),
            "penetration_share": float(table["penetration_share"].mean())
            if len(table["frame"])
            else 0.0,
        }

    def table(self):
        """{"frame": int array, figure: float array} in frame order."""
        frames = sorted(self.rows)
        table = {"frame": np.array(frames, dtype=np.int64)}
        for name in FIGURES:
            table[name] = np.array([self.rows[f][name] for f in frames], dtype=np.float64)
        return table

    def finish(self):
        """Write the CSV and the plot beside the cache; returns the PNG's path."""
        self.directory.mkdir(parents=True, exist_ok=True)
        temporary = self.csv_path.with_name(CSV_NAME + ".tmp")
        with open(temporary, "w", newline="") as file:
            writer = csv.writer(file)
            writer.writerow(("frame", *FIGURES))
            for frame in sorted(self.rows):
                writer.writerow((frame, *(repr(self.rows[frame][name]) for name in FIGURES)))
        os.replace(temporary, self.csv_path)
        write_png(self.png_path, plot(self.table()))
        return self.png_path


start = FrameRecord.start


def read(path):
    """{frame: {figure: value}} from a frame_record.csv."""
    with open(path, newline="") as file:
        return {
            int(row["frame"]): {name: float(row[name]) for name in FIGURES}
            for row in csv.DictReader(file)
        }


# ---- drawing -----------------------------------------------------------------------------------

_GLYPHS = {  # 5 x 7, rows top to bottom
    "0": "01110 10001 10011 10101 11001 10001 01110",
    "1": "00100 01100 00100 00100 00100 00100 01110",
    "2": "01110 10001 00001 00010 00100 01000 11111",
    "3": "11110 00001 00001 01110 00001 00001 11110",
    "4": "00010 00110 01010 10010 11111 00010 00010",
    "5": "11111 10000 11110 00001 00001 10001 01110",
    "6": "00110 01000 10000 11110 10001 10001 01110",
    "7": "11111 00001 00010 00100 01000 01000 01000",
    "8": "01110 10001 10001 01110 10001 10001 01110",
    "9": "01110 10001 10001 01111 00001 00010 01100",
    ".": "00000 00000 00000 00000 00000 01100 01100",
    "-": "00000 00000 00000 11111 00000 00000 00000",
    "+": "00000 00100 00100 11111 00100 00100 00000",
    "%": "11000 11001 00010 00100 01000 10011 00011",
    "/": "00000 00001 00010 00100 01000 10000 00000",
    " ": "00000 00000 00000 00000 00000 00000 00000",
    "a": "00000 00000 01110 00001 01111 10001 01111",
    "c": "00000 00000 01110 10000 10000 10001 01110",
    "e": "00000 00000 01110 10001 11111 10000 01110",
    "f": "00110 01001 01000 11100 01000 01000 01000",
    "g": "00000 01111 10001 10001 01111 00001 01110",
    "h": "10000 10000 10110 11001 10001 10001 10001",
    "i": "00100 00000 01100 00100 00100 00100 01110",
    "k": "10000 10000 10010 10100 11000 10100 10010",
    "m": "00000 00000 11010 10101 10101 10001 10001",
    "n": "00000 00000 10110 11001 10001 10001 10001",
    "o": "00000 00000 01110 10001 10001 10001 01110",
    "p": "00000 00000 11110 10001 11110 10000 10000",
    "r": "00000 00000 10110 11001 10000 10000 10000",
    "s": "00000 00000 01110 10000 01110 00001 11110",
    "t": "01000 01000 11100 01000 01000 01001 00110",
    "x": "00000 00000 10001 01010 00100 01010 10001",
    "y": "00000 00000 10001 10001 01111 00001 01110",
}
_INK, _LINE, _FRAME_INK = (30, 30, 30), (31, 119, 180), (160, 160, 160)


def _text(image, x, y, text, scale=2, colour=_INK):
    """Draw `text` with its top-left corner at (x, y)."""
    for char in text:
        rows = _GLYPHS.get(char, _GLYPHS[" "]).split()
        mask = np.array([[bit == "1" for bit in row] for row in rows])
        mask = np.kron(mask, np.ones((scale, scale), dtype=bool))
        height, width = mask.shape
        block = image[y : y + height, x : x + width]
        block[mask[: block.shape[0], : block.shape[1]]] = colour
        x += width + scale


def _number(value):
    return f"{value:.3g}" if value == 0 or 1e-3 <= abs(value) < 1e4 else f"{value:.2e}"


def _polyline(image, xs, ys, colour=_LINE):
    """Connected segments through the pixel points (xs, ys), two pixels thick."""
    points = [(xs[0], ys[0])] if len(xs) == 1 else []
    for (x0, y0), (x1, y1) in zip(zip(xs[:-1], ys[:-1]), zip(xs[1:], ys[1:])):
        count = int(max(abs(x1 - x0), abs(y1 - y0))) + 1
        points += list(zip(np.linspace(x0, x1, count), np.linspace(y0, y1, count)))
    for x, y in points:
        x, y = int(round(x)), int(round(y))
        image[max(y - 1, 0) : y + 1, max(x - 1, 0) : x + 1] = colour


def plot(table, width=800, panel_height=110):
    """An RGB image (H, W, 3) uint8: one panel per figure over the frames, each with its
    title and value range, the frame range under the last."""
    margin_left, margin_top, gap = 112, 28, 40
    frames = table["frame"]
    height = margin_top + len(FIGURES) * (panel_height + gap)
    image = np.full((height, width, 3), 255, dtype=np.uint8)
    x0, x1 = margin_left, width - 20
    for index, name in enumerate(FIGURES):
        top = margin_top + index * (panel_height + gap)
        bottom = top + panel_height
        image[top, x0 : x1 + 1] = image[bottom, x0 : x1 + 1] = _FRAME_INK
        image[top : bottom + 1, x0] = image[top : bottom + 1, x1] = _FRAME_INK
        _text(image, x0, top - 18, _TITLES[name])
        values = table[name] * _SHOWN_SCALE.get(name, 1.0)
        if len(values) == 0:
            continue
        low, high = float(values.min()), float(values.max())
        _text(image, 4, top + 2, _number(high))
        _text(image, 4, bottom - 14, _number(low))
        span_v = high - low if high > low else 1.0
        span_f = float(frames[-1] - frames[0]) or 1.0
        xs = x0 + 4 + (frames - frames[0]) / span_f * (x1 - x0 - 8)
        ys = bottom - 4 - (values - low) / span_v * (panel_height - 8)
        _polyline(image, xs, ys)
    if len(frames):
        last = margin_top + (len(FIGURES) - 1) * (panel_height + gap) + panel_height
        _text(image, x0, last + 6, f"frame {frames[0]}")
        label = f"{frames[-1]}"
        _text(image, x1 - 12 * len(label), last + 6, label)
    return image


def write_png(path, rgb):
    """An (H, W, 3) uint8 image as an 8-bit RGB PNG, written atomically."""
    rgb = np.ascontiguousarray(rgb, dtype=np.uint8)
    height, width, _ = rgb.shape
    raw = np.concatenate([np.zeros((height, 1), dtype=np.uint8), rgb.reshape(height, -1)], axis=1)

    def chunk(kind, data):
        return (
            struct.pack(">I", len(data))
            + kind
            + data
            + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
        )

    data = (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
        + chunk(b"IDAT", zlib.compress(raw.tobytes(), 6))
        + chunk(b"IEND", b"")
    )
    path = Path(path)
    temporary = path.with_name(path.name + ".tmp")
    temporary.write_bytes(data)
    os.replace(temporary, path)


def read_png_rgb(path):
    """(H, W, 3) uint8 of a PNG that write_png wrote (filter 0 rows): for checks."""
    data = Path(path).read_bytes()
    width, height = struct.unpack(">II", data[16:24])
    position, idat = 8, b""
    while position < len(data):
        length = struct.unpack(">I", data[position : position + 4])[0]
        if data[position + 4 : position + 8] == b"IDAT":
            idat += data[position + 8 : position + 8 + length]
        position += 12 + length
    raw = np.frombuffer(zlib.decompress(idat), dtype=np.uint8).reshape(height, 1 + width * 3)
    return raw[:, 1:].reshape(height, width, 3)
