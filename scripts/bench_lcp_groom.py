"""Benchmark: LCP on a real groom (issue 18: no frame over 3x the median). Bando 2003's
particles sampled along Sintel's strands (lcp_init.particles_from = GROOM) on Sintel's bust
turning its head, 48 frames, at the default particle count and at 20,000 asked for. Prints the
frame times (whole frames: stepping, reading and writing Blender data) and the slowest
frame's ratio to the median; asserts nothing. Skips when the Sintel assets are missing.

    blender -b --factory-startup --python scripts/bench_lcp_groom.py -- [OUT.json]
"""

import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

import bpy

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "addon"))
sys.path.insert(0, str(ROOT / "python_tests"))
import hairdyn  # noqa: E402
import sintel_assets  # noqa: E402
from hairdyn import simulation  # noqa: E402

FRAMES = 48


def run(particle_num, cache_directory):
    hair, _bust = sintel_assets.load()
    hair.hairdyn.method = 'LCP'
    hair.hairdyn.lcp_init.particles_from = 'GROOM'
    hair.hairdyn.lcp.particle_num = particle_num
    hair.hairdyn.cache_directory = cache_directory
    start = time.perf_counter()
    runner = simulation.Runner(bpy.context, hair, 1, FRAMES)
    setup_s = time.perf_counter() - start
    frame_ms = []
    while not runner.done:
        start = time.perf_counter()
        runner.advance()
        frame_ms.append(1000 * (time.perf_counter() - start))
    report = runner.report()
    median = statistics.median(frame_ms)
    return {
        "particle_num_asked": particle_num,
        "particles": report["particles"],
        "pairs": report["pairs"],
        "setup_s": setup_s,
        "median_ms": median,
        "slowest_ms": max(frame_ms),
        "slowest_frame": 1 + frame_ms.index(max(frame_ms)),
        "slowest_over_median": max(frame_ms) / median,
        "frame_ms": frame_ms,
        "nan_frames": report["nan_frames"],
    }


def main(out_path):
    if not hasattr(bpy.types.Object, "hairdyn"):
        hairdyn.register()
    results = []
    with tempfile.TemporaryDirectory() as folder:
        for particle_num in (2000, 20000):
            try:
                result = run(particle_num, folder)
            except FileNotFoundError as error:
                print(f"bench: skipped, {error}")
                return
            results.append(result)
            print(
                f"bench: LCP on Sintel's groom, {result['particles']} particles "
                f"({particle_num} asked), {FRAMES} frames: median {result['median_ms']:.1f} "
                f"ms/frame, slowest {result['slowest_ms']:.1f} ms (frame "
                f"{result['slowest_frame']}), {result['slowest_over_median']:.2f}x the "
                f"median; set-up {result['setup_s']:.2f} s"
            )
    if out_path:
        Path(out_path).parent.mkdir(parents=True, exist_ok=True)
        Path(out_path).write_text(json.dumps(results, indent=2) + "\n")


main(
    sys.argv[sys.argv.index("--") + 1]
    if "--" in sys.argv and len(sys.argv) > sys.argv.index("--") + 1
    else None
)
