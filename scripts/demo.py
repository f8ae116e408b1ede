"""The main job (`make demo`): bake the shipped head-shake example and show it.

    blender -b blend_fixtures/head_shake.blend --python scripts/demo.py -- OUT_DIR [METHOD]
        [--color speed] [--size W H] [--samples N] [--frames START END]

METHOD is STRANDS (the default) or LCP (loosely connected particles, shown as billboards,
with the groom's strands carried by them). Writes into OUT_DIR:
  demo.mp4                every baked frame, rendered fast (Workbench) with the frame number
                          and that frame's native milliseconds burnt in; `--color speed`
                          colours the hair by its speed where the host's Workbench shows
                          curve attributes
  demo_still.png          the middle frame at 1280 x 720 in Cycles: Principled Hair BSDF,
                          child hairs thin and tapering, denoised where the host can
  demo_follow_vs_sim.png  that frame twice side by side: left the rest groom carried rigidly
                          by the head (what Follow Head gives), right the simulation
  demo_report.json        the bake's report
"""
import argparse
import json
import sys
import time
from pathlib import Path

import bpy
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "addon"))

import hairdyn  # noqa: E402


def enum_items(owner, name):
    return {item.identifier for item in owner.bl_rna.properties[name].enum_items}


def bake(hair, out_dir, method, frames=None):
    """Bakes the hair object into out_dir/cache; returns (report, {frame: native ms})."""
    from hairdyn import bake as baking

    settings = hair.hairdyn
    settings.method = method
    if method == 'STRANDS':
        # The shake throws a few tips onto the torso's flat top, where the cylindrical map
        # sees the body edge-on (14 mm deep with maps alone); the swept spheres' exact
        # hair-object pass after the maps keeps every segment out (under 1 mm).
        settings.swept_spheres.body_collision = 'BOTH'
    settings.cache_directory = str(out_dir / "cache")
    if frames is not None:
        settings.frame_start, settings.frame_end = frames
    bpy.context.view_layer.objects.active = hair
    runner = baking.start_bake(bpy.context, hair, show_frames=False)  # headless: see Runner
    frame_ms = {}
    while not runner.done:
        frame, ms = runner.advance()
        frame_ms[frame] = ms
        print(f"hairdyn demo: baked frame {frame} ({ms:.1f} ms)", flush=True)
    return baking.finish_bake(runner), frame_ms


def hair_material():
    """The Principled Hair BSDF (Chiang 2016 where the host has the choice), brown by
    melanin: one material for the groom and everything made from it."""
    from hairdyn.methods.base import node_material

    def build(nodes, links):
        hair = nodes.new("ShaderNodeBsdfHairPrincipled")
        if "parametrization" in hair.bl_rna.properties:
            hair.parametrization = 'MELANIN'
        if "model" in hair.bl_rna.properties and 'CHIANG' in enum_items(hair, "model"):
            hair.model = 'CHIANG'
        hair.inputs["Melanin"].default_value = 0.55
        hair.inputs["Roughness"].default_value = 0.35
        output = nodes.new("ShaderNodeOutputMaterial")
        links.new(hair.outputs[0], output.inputs["Surface"])

    return node_material("hairdyn_demo_hair", build)


def use_material(obj, material):
    obj.data.materials.clear()
    obj.data.materials.append(material)


def output_format(settings, media, file_format):
    """Image or movie output; Blender 5 chooses the media type before the format."""
    if "media_type" in settings.bl_rna.properties:
        settings.media_type = media
    settings.file_format = file_format


def has_denoiser():
    """Whether this host's Cycles was built with OpenImageDenoise (Debian's 3.4 was not)."""
    import _cycles

    return bool(getattr(_cycles, "with_openimagedenoise", False))


def render_still(scene, path, size, samples):
    """The current frame in Cycles: denoised where the host has a denoiser."""
    scene.render.engine = 'CYCLES'
    scene.render.use_stamp = False
    scene.render.resolution_x, scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    output_format(scene.render.image_settings, 'IMAGE', 'PNG')
    scene.cycles.samples = samples
    scene.cycles.use_denoising = has_denoiser()
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    return path


def read_png(path):
    image = bpy.data.images.load(str(path))
    width, height = image.size
    pixels = np.empty(width * height * 4, dtype=np.float32)
    image.pixels.foreach_get(pixels)
    bpy.data.images.remove(image)
    return pixels.reshape(height, width, 4)


def save_png(pixels, path):
    height, width, _ = pixels.shape
    image = bpy.data.images.new(path.stem, width, height, alpha=True)
    image.pixels.foreach_set(pixels.ravel())
    image.filepath_raw = str(path)
    image.file_format = 'PNG'
    image.save()
    bpy.data.images.remove(image)


def render_follow_vs_sim(scene, hair, path, size, samples):
    """The current frame twice, same camera: left the Follow Head baseline (the rest groom and
    its children carried rigidly by the head), right the simulation."""
    from hairdyn import simulation

    settings = hair.hairdyn
    frame, method = scene.frame_current, settings.method
    half = (size[0] // 2, size[1])
    halves = []
    for name in ('FOLLOW', method):
        if name == 'FOLLOW':  # simulated live, not loaded from the bake
            settings.method, settings.use_cache, settings.use_live = 'FOLLOW', False, False
            simulation.run(bpy.context, hair, settings.frame_start, frame)
        else:
            settings.method, settings.use_cache = method, True
            scene.frame_set(frame)  # playback loads the baked frame again
        halves.append(read_png(render_still(scene, path.with_suffix(".half.png"), half, samples)))
    path.with_suffix(".half.png").unlink()
    save_png(np.concatenate(halves, axis=1), path)
    return path


def color_by_speed(hair):
    """Colours the output strands by their speed (m/s, blue still to red fast) through a
    colour attribute, for hosts whose Workbench shows curve attributes; returns whether this
    host does."""
    shading = bpy.context.scene.display.shading
    kind = next((k for k in ('ATTRIBUTE', 'VERTEX') if k in enum_items(shading, "color_type")), None)
    curves_obj = hair.hairdyn.output_curves
    if kind != 'ATTRIBUTE' or curves_obj is None:
        return False  # Blender 3.4's Workbench ignores attributes on curves

    def update(scene, _depsgraph=None):
        points = hair.hairdyn.output_points
        velocity = points.data.attributes.get("velocity") if points is not None else None
        curves = curves_obj.data
        if velocity is None or len(velocity.data) != len(curves.points):
            return
        values = np.empty(len(velocity.data) * 3, dtype=np.float32)
        velocity.data.foreach_get("vector", values)
        speed = np.linalg.norm(values.reshape(-1, 3), axis=1)
        t = np.clip(speed / 1.5, 0.0, 1.0)
        colors = np.column_stack([t, 0.25 * np.ones_like(t), 1.0 - t, np.ones_like(t)])
        attribute = curves.attributes.get("speed_color") or \
            curves.attributes.new("speed_color", 'FLOAT_COLOR', 'POINT')
        attribute.data.foreach_set("color", colors.astype(np.float32).ravel())
        curves.attributes.active_color = attribute

    bpy.app.handlers.frame_change_post.append(update)
    shading.color_type = 'ATTRIBUTE'
    return True


def render_video(scene, path_stem, frame_ms, size, color=None):
    """Every baked frame through Blender's own movie output (FFmpeg, H.264), in Workbench;
    the frame number and its native milliseconds burnt in. Returns the movie's path."""
    render = scene.render
    render.engine = 'BLENDER_WORKBENCH'
    render.resolution_x, render.resolution_y = size
    render.resolution_percentage = 100
    output_format(render.image_settings, 'VIDEO', 'FFMPEG')
    render.ffmpeg.format = 'MPEG4'
    render.ffmpeg.codec = 'H264'
    render.ffmpeg.constant_rate_factor = 'HIGH'
    render.use_stamp = True
    for stamp in ("date", "time", "render_time", "camera", "lens", "scene", "filename",
                  "memory", "hostname", "marker", "sequencer_strip", "frame_range"):
        if f"use_stamp_{stamp}" in render.bl_rna.properties:
            setattr(render, f"use_stamp_{stamp}", False)
    render.use_stamp_frame = True
    render.use_stamp_note = True
    render.stamp_font_size = max(12, size[1] // 24)
    colored = color == "speed" and color_by_speed(bpy.data.objects["Hair"])

    def burn_in(scene, _depsgraph=None):
        ms = frame_ms.get(scene.frame_current)
        scene.render.stamp_note_text = "hairdyn" + (f"  {ms:.1f} ms/frame" if ms else "") + \
            ("  colour: speed" if colored else "")

    bpy.app.handlers.frame_change_pre.append(burn_in)
    scene.frame_start, scene.frame_end = min(frame_ms), max(frame_ms)
    render.filepath = str(path_stem)
    try:
        bpy.ops.render.render(animation=True)
    finally:
        bpy.app.handlers.frame_change_pre.remove(burn_in)
    return Path(bpy.path.abspath(render.frame_path(frame=scene.frame_start)))


def movie_frames(path):
    """Frames in a movie file, as Blender's movie reader counts them."""
    clip = bpy.data.movieclips.load(str(path))
    try:
        return clip.frame_duration
    finally:
        bpy.data.movieclips.remove(clip)


def run(out_dir, method='STRANDS', size=(1280, 720), samples=64, video_size=(640, 360),
        frames=None, color=None):
    """Bake, then the video, the still and the side-by-side; returns what it wrote."""
    out_dir.mkdir(parents=True, exist_ok=True)
    if not hasattr(bpy.types.Object, "hairdyn"):
        hairdyn.register()
    scene = bpy.context.scene
    hair = bpy.data.objects["Hair"]
    use_material(hair, hair_material())  # the outputs take the groom's material
    start = time.perf_counter()
    report, frame_ms = bake(hair, out_dir, method, frames)
    bake_s = time.perf_counter() - start
    (out_dir / "demo_report.json").write_text(json.dumps(report, indent=2) + "\n")

    start = time.perf_counter()
    video = render_video(scene, out_dir / "demo_", frame_ms, video_size, color)
    video_s = time.perf_counter() - start
    target = video.with_name("demo.mp4")
    video.replace(target)

    still_frame = sorted(frame_ms)[len(frame_ms) // 2]
    scene.frame_set(still_frame)  # playback loads the baked frame
    start = time.perf_counter()
    still = render_still(scene, out_dir / "demo_still.png", size, samples)
    side = render_follow_vs_sim(scene, hair, out_dir / "demo_follow_vs_sim.png", size, samples)
    still_s = time.perf_counter() - start
    return {"report": report, "bake_s": bake_s, "video": target, "video_s": video_s,
            "still": still, "follow_vs_sim": side, "still_s": still_s, "still_frame": still_frame}


def main(argv):
    parser = argparse.ArgumentParser(prog="demo.py")
    parser.add_argument("out_dir", nargs="?", default=str(ROOT / "out" / "demo"))
    parser.add_argument("method", nargs="?", default="STRANDS")
    parser.add_argument("--color", choices=["speed"])
    parser.add_argument("--size", nargs=2, type=int, default=(1280, 720))
    parser.add_argument("--samples", type=int, default=64)
    parser.add_argument("--frames", nargs=2, type=int)
    args = parser.parse_args(argv)
    wrote = run(Path(args.out_dir), args.method.upper(), tuple(args.size), args.samples,
                frames=args.frames, color=args.color)
    report = wrote["report"]
    carried = (f"{report['particles']} particles, {report['pairs']} pairs"
               if "particles" in report else f"{report['strands']} guides")
    print(f"hairdyn demo: baked {report['frames']} frames ({carried}, {report['points']} points)"
          f" in {wrote['bake_s']:.1f} s: {report['ms_per_frame']:.2f} ms per frame of native "
          f"stepping (solver '{report['solver']}', Blender {report['blender_version']})")
    print(f"hairdyn demo: quality: stretch {report['stretch_max']:.1e}, penetration max "
          f"{report['penetration_max'] * 1000:.2f} mm, {report['penetration_share'] * 100:.2f}% "
          f"of nodes deeper than the tolerance, {report['nan_frames']} NaN frames")
    print(f"hairdyn demo: video ({report['frames']} frames, Workbench) in {wrote['video_s']:.1f} s"
          f" -> {wrote['video']}")
    print(f"hairdyn demo: frame {wrote['still_frame']} in Cycles in {wrote['still_s']:.1f} s -> "
          f"{wrote['still']} and {wrote['follow_vs_sim']} (left: follow head, right: simulated)")


if __name__ == "__main__":
    main(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
