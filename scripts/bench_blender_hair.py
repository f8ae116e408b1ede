"""End-to-end benchmark: Blender's built-in hair dynamics against hairdyn's strands on the
same groom (issue 3): 2,000 strands x 16 segments on the fixture's head, the head as a
collider, 48 frames, the same substeps per frame; and hairdyn's whole frame against its stepping,
headless as cli.py runs it and with every frame shown as the Bake button does (issue 18).
Prints figures and ratios; asserts nothing.

    blender -b blend_fixtures/head_particles.blend --python scripts/bench_blender_hair.py -- [OUT.json]
"""
import json
import statistics
import sys
import time
from pathlib import Path

import bpy

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "addon"))
import hairdyn  # noqa: E402
from hairdyn import simulation  # noqa: E402

STRANDS, SEGMENTS, FRAMES, SUBSTEPS = 2000, 16, 48, 4


def groom(body):
    psys = body.particle_systems[0]
    settings = psys.settings
    settings.count = STRANDS
    settings.hair_step = SEGMENTS
    settings.display_step = 4  # 2^4 = 16 segments: the path hairdyn reads equals the keys
    return psys


def time_blender_hair(scene, body, psys):
    """Seconds per frame of Blender's hair dynamics (cloth solver on the hair keys)."""
    body.modifiers.new("Collision", 'COLLISION')
    psys.use_hair_dynamics = True
    cloth = psys.cloth
    cloth.settings.quality = SUBSTEPS
    cloth.collision_settings.use_collision = True
    cloth.point_cache.frame_start, cloth.point_cache.frame_end = 1, FRAMES
    scene.frame_set(1)
    times = []
    for frame in range(2, FRAMES + 1):
        start = time.perf_counter()
        scene.frame_set(frame)
        bpy.context.evaluated_depsgraph_get()
        times.append(time.perf_counter() - start)
    psys.use_hair_dynamics = False
    body.modifiers.remove(body.modifiers["Collision"])
    scene.frame_set(1)
    return times


def run_hairdyn(body, show_frames):
    """hairdyn's strands over the frames: the report and the ms a frame takes in all, the
    run's set-up included (the report's total_s over the frames)."""
    runner = simulation.Runner(bpy.context, body, 1, FRAMES, show_frames=show_frames)
    while not runner.done:
        runner.advance()
    report = runner.report()
    return report, 1000 * report["total_s"] / report["frames"]


def main(out_path):
    if not hasattr(bpy.types.Object, "hairdyn"):
        hairdyn.register()
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, FRAMES
    body = bpy.data.objects["Body"]
    # A head turn, so that both solvers have motion and collisions to handle.
    body.rotation_euler = (0.0, 0.0, 0.0)
    body.keyframe_insert("rotation_euler", frame=1)
    body.rotation_euler = (0.0, 0.0, 0.8)
    body.keyframe_insert("rotation_euler", frame=24)
    psys = groom(body)
    blender_s = time_blender_hair(scene, body, psys)

    settings = body.hairdyn
    settings.method = 'STRANDS'
    settings.strands.substeps = SUBSTEPS
    settings.strands.children_per_guide = 0
    # Headless as cli.py runs it (the outputs get the last frame), then every frame shown as
    # the Bake button does.
    report, hairdyn_frame_ms = run_hairdyn(body, show_frames=False)
    shown_report, shown_frame_ms = run_hairdyn(body, show_frames=True)
    blender_ms = 1000 * statistics.median(blender_s)
    hairdyn_step_ms = report["ms_per_frame"]
    result = {
        "blender_version": bpy.app.version_string,
        "strands": report["strands"], "points": report["points"], "frames": FRAMES,
        "substeps": SUBSTEPS,
        "blender_hair_dynamics_ms_per_frame": blender_ms,
        "hairdyn_step_ms_per_frame": hairdyn_step_ms,
        "hairdyn_frame_ms_per_frame": hairdyn_frame_ms,
        "ratio_step": blender_ms / hairdyn_step_ms,
        "ratio_frame": blender_ms / hairdyn_frame_ms,
        "hairdyn_frame_over_step": hairdyn_frame_ms / hairdyn_step_ms,
        "hairdyn_shown_step_ms_per_frame": shown_report["ms_per_frame"],
        "hairdyn_shown_frame_ms_per_frame": shown_frame_ms,
        "hairdyn_shown_frame_over_step": shown_frame_ms / shown_report["ms_per_frame"],
        "hairdyn_colliders": report["colliders"],
        "hairdyn_penetration_share": report["penetration_share"],
    }
    print(f"bench: {report['strands']} strands x {SEGMENTS} segments, {FRAMES} frames, "
          f"{SUBSTEPS} substeps, colliding with {', '.join(report['colliders']) or 'nothing'}, "
          f"Blender {bpy.app.version_string}")
    print(f"bench: Blender hair dynamics {blender_ms:.1f} ms/frame; hairdyn strands "
          f"{hairdyn_step_ms:.2f} ms/frame stepping ({result['ratio_step']:.0f}x faster), "
          f"{hairdyn_frame_ms:.1f} ms/frame in all, set-up, reading and writing included "
          f"({result['ratio_frame']:.0f}x)")
    print(f"bench: hairdyn whole headless run {hairdyn_frame_ms:.2f} ms/frame in all (set-up "
          f"included), {result['hairdyn_frame_over_step']:.2f}x its stepping median; every "
          f"frame shown (the Bake button) {shown_frame_ms:.2f} ms/frame, "
          f"{result['hairdyn_shown_frame_over_step']:.2f}x its stepping "
          f"({shown_report['ms_per_frame']:.2f} ms)")
    if out_path:
        Path(out_path).parent.mkdir(parents=True, exist_ok=True)
        Path(out_path).write_text(json.dumps(result, indent=2) + "\n")


main(sys.argv[sys.argv.index("--") + 1] if "--" in sys.argv and
     len(sys.argv) > sys.argv.index("--") + 1 else None)
