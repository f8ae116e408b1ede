"""Benchmark: cached playback of 10,000 strands x 16 segments (issue 6). Bakes nothing: it
writes a synthetic cache of that size, then times loading frames into the output objects the
way the frame-change handler does, and the parts: reading the frame, writing it into the output
objects, Blender evaluating them. Prints figures; asserts nothing. Runs in the blender binary
and under the bpy module (python scripts/bench_playback.py -- OUT.json).

    blender -b --factory-startup --python scripts/bench_playback.py -- [OUT.json]
"""
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

import bpy
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "addon"))
import hairdyn  # noqa: E402
from hairdyn import bridge, playback  # noqa: E402
from hairdyn.cache import Cache  # noqa: E402

STRANDS, POINTS_PER_STRAND, FRAMES = 10_000, 17, 24


def main(out_path):
    if not hasattr(bpy.types.Object, "hairdyn"):
        hairdyn.register()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    offsets = np.arange(STRANDS + 1, dtype=np.int32) * POINTS_PER_STRAND
    hair = bpy.data.objects.new("Hair", bridge.new_curves_data("Hair", np.diff(offsets)))
    bpy.context.scene.collection.objects.link(hair)
    # A groom to play back onto: straight strands 16 cm long on a 1 m square (playback reads
    # the rest groom, which must be valid).
    strand = np.arange(STRANDS)
    rest = np.zeros((STRANDS, POINTS_PER_STRAND, 3), dtype=np.float32)
    rest[:, :, 0] = (strand % 100)[:, None] * 0.01
    rest[:, :, 1] = (strand // 100)[:, None] * 0.01
    rest[:, :, 2] = -0.01 * np.arange(POINTS_PER_STRAND)[None, :]
    bridge.write_curves(hair, rest.reshape(-1, 3))
    with tempfile.TemporaryDirectory() as folder:
        hair.hairdyn.cache_directory = folder
        directory = Path(folder) / "Hair"
        cache = Cache.create(directory, solver="strands", parameters={}, curve_offsets=offsets,
                             columns={"position": 3, "velocity": 3, "direction": 3},
                             frame_start=1, frame_end=FRAMES, fps=24.0)
        rng = np.random.default_rng(0)
        points = int(offsets[-1])
        for frame in range(1, FRAMES + 1):
            cache.write_frame(frame, {name: rng.normal(size=(points, 3)).astype(np.float32)
                                      for name in ("position", "velocity", "direction")})
        playback.load_frame(hair, 1)  # creates the output objects
        seconds, loading, evaluating = [], [], []
        for frame in list(range(2, FRAMES + 1)) * 2:
            start = time.perf_counter()
            playback.load_frame(hair, frame)
            loaded = time.perf_counter()
            bpy.context.evaluated_depsgraph_get().update()
            seconds.append(time.perf_counter() - start)
            loading.append(loaded - start)
            evaluating.append(seconds[-1] - loading[-1])
        opened = playback.open_cache(directory)[0]
        reading = []
        for frame in list(range(2, FRAMES + 1)) * 2:  # the read alone, as playback reads
            start = time.perf_counter()
            opened.read_frame(frame, reuse=True)
            reading.append(time.perf_counter() - start)
    ms = 1000 * statistics.median(seconds)
    parts = {"read": reading, "load": loading, "evaluate": evaluating}
    parts = {name: 1000 * statistics.median(values) for name, values in parts.items()}
    result = {"blender_version": bpy.app.version_string, "strands": STRANDS,
              "points": points, "playback_ms_per_frame": ms, "playback_fps": 1000 / ms,
              "read_ms": parts["read"], "write_ms": parts["load"] - parts["read"],
              "evaluate_ms": parts["evaluate"]}
    print(f"bench: cached playback of {STRANDS} strands x {POINTS_PER_STRAND - 1} segments "
          f"({points} points, 3 attributes): {ms:.1f} ms per frame ({1000 / ms:.0f} frames/s), "
          f"Blender {bpy.app.version_string}")
    print(f"bench: of which about {parts['read']:.1f} ms reading the frame, "
          f"{parts['load'] - parts['read']:.1f} ms writing it into the two output objects, "
          f"{parts['evaluate']:.1f} ms Blender evaluating them (medians of each part)")
    if out_path:
        Path(out_path).parent.mkdir(parents=True, exist_ok=True)
        Path(out_path).write_text(json.dumps(result, indent=2) + "\n")


main(sys.argv[sys.argv.index("--") + 1] if "--" in sys.argv and
     len(sys.argv) > sys.argv.index("--") + 1 else None)
