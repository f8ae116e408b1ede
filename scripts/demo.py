"""The main job: simulate the shipped head-shake example headless and render a frame.

    blender -b blend_fixtures/head_shake.blend --python scripts/demo.py -- OUT_DIR
"""
import json
import sys
import time
from pathlib import Path

import bpy

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "addon"))

import hairdyn  # noqa: E402
from hairdyn import simulation  # noqa: E402


def main(out_dir):
    out_dir.mkdir(parents=True, exist_ok=True)
    if not hasattr(bpy.types.Object, "hairdyn"):
        hairdyn.register()
    hair = bpy.data.objects["Hair"]
    settings = hair.hairdyn
    report = simulation.run(bpy.context, hair, settings.frame_start, settings.frame_end)
    (out_dir / "demo_report.json").write_text(json.dumps(report, indent=2) + "\n")

    hair.hide_render = True  # the simulated output replaces the groom in the picture
    scene = bpy.context.scene
    frame = (settings.frame_start + settings.frame_end) // 2
    # Re-simulating up to the frame shown keeps the picture in step with the dynamics.
    simulation.run(bpy.context, hair, settings.frame_start, frame)
    scene.render.filepath = str(out_dir / "demo_frame.png")
    start = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    render_s = time.perf_counter() - start
    print(f"hairdyn demo: {report['strands']} strands, {report['points']} points, "
          f"{report['frames']} frames, {report['ms_per_frame']:.3f} ms per frame "
          f"(solver '{report['solver']}'), stretch {report['stretch_max']:.2e}, "
          f"{report['nan_frames']} NaN frames; Blender {report['blender_version']}")
    print(f"hairdyn demo: rendered frame {frame} in {render_s:.1f} s -> {scene.render.filepath}")
    print(f"hairdyn demo: report -> {out_dir / 'demo_report.json'}")


main(Path(sys.argv[sys.argv.index("--") + 1] if "--" in sys.argv else ROOT / "out"))
