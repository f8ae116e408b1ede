"""Run inside a real Blender window (xvfb-run): show the hairdyn panel, screenshot it, run
the simulate operator and the modal bake from the UI, screenshot again.

    blender --factory-startup FIXTURE --python python_tests/ui_check.py -- OBJECT OUT_JSON OUT_PNG CACHE_DIR
"""
import json
import sys
from pathlib import Path

import bpy

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "addon"))
sys.path.insert(0, str(Path(__file__).resolve().parent))
import hairdyn  # noqa: E402
from layout_recorder import Layout  # noqa: E402

object_name, out_json, out_png, cache_dir = sys.argv[sys.argv.index("--") + 1:][:4]
BAKE_FRAMES = 10
result = {"steps": []}


def finish(error=None):
    result["error"] = error
    result["draw_calls"] = hairdyn.ui.HAIRDYN_PT_main.draw_calls
    Path(out_json).write_text(json.dumps(result, indent=2))
    bpy.ops.wm.quit_blender()


def properties_area():
    window = bpy.context.window_manager.windows[0]
    areas = [a for a in window.screen.areas if a.type == 'PROPERTIES']
    return window, (areas[0] if areas else None)


def select():
    obj = bpy.data.objects[object_name]
    view_layer = bpy.context.view_layer
    for other in view_layer.objects:
        other.select_set(other == obj)
    view_layer.objects.active = obj
    for area in bpy.context.window_manager.windows[0].screen.areas:
        area.tag_redraw()  # the properties editor lists the object's tabs after a redraw
    result["steps"].append("selected")
    bpy.app.timers.register(show_panel, first_interval=0.5)


def show_panel():
    try:
        window, area = properties_area()
        if area is None:  # the file has no properties editor: turn the biggest area into one
            area = max(window.screen.areas, key=lambda a: a.width * a.height)
            area.type = 'PROPERTIES'
        area.spaces.active.context = 'PHYSICS'
        area.tag_redraw()
        result["steps"].append("panel shown")
    except Exception as error:  # reported to the test, which fails with it
        finish(f"show_panel: {error!r}")
        return None
    bpy.app.timers.register(screenshot, first_interval=1.5)
    return None


def label_width(text):
    """Pixels the properties editor's widget font draws `text` in, at this window's scale."""
    import blf

    points = bpy.context.preferences.ui_styles[0].widget_label.points
    scale = bpy.context.preferences.system.ui_scale
    try:
        blf.size(0, points * scale)
    except TypeError:  # Blender 3.x: size(fontid, size, dpi)
        blf.size(0, int(round(points * scale)), 72)
    return blf.dimensions(0, text)[0]


def cut_labels(region):
    """Labels of every method's sections that do not fit the label column of a
    use_property_split layout in this region: Blender gives that column 40% of the layout's
    width (UI_ITEM_PROP_SEP_DIVIDE), after the panel's margins and a sub-panel's indent."""
    from hairdyn import methods, ui

    scale = bpy.context.preferences.system.ui_scale
    available = 0.4 * (region.width - 2 * 20 * scale) - 8 * scale
    labels = []
    settings = bpy.data.objects[object_name].hairdyn
    for method in methods.all_methods():
        settings.method = method.identifier
        for panel in ui.panel_classes():
            if hasattr(panel, "draw_settings"):
                panel.draw_settings(None, Layout([], labels), settings)
    widths = {label: label_width(label) for label in sorted(set(labels))}
    result["label_column_px"] = available
    result["widest_label"] = max(widths.items(), key=lambda item: item[1])
    result["label_widths"] = widths
    return {label: width for label, width in widths.items() if width > available}


def screenshot():
    try:
        window, area = properties_area()
        with bpy.context.temp_override(window=window, screen=window.screen, area=area):
            bpy.ops.screen.screenshot(filepath=out_png)
        result["steps"].append("screenshot")
        region = next(r for r in area.regions if r.type == 'WINDOW')
        result["properties_width_px"] = region.width
        method = bpy.data.objects[object_name].hairdyn.method
        result["cut_labels"] = cut_labels(region)
        bpy.data.objects[object_name].hairdyn.method = method
        obj = bpy.data.objects[object_name]
        with bpy.context.temp_override(window=window, screen=window.screen, area=area,
                                       object=obj):
            result["simulate"] = sorted(bpy.ops.hairdyn.simulate())
        result["steps"].append("simulated")
        obj.hairdyn.method = 'STRANDS'
        obj.hairdyn.cache_directory = cache_dir
        obj.hairdyn.frame_end = BAKE_FRAMES
        with bpy.context.temp_override(window=window, screen=window.screen, area=area,
                                       object=obj):
            result["bake_invoke"] = sorted(bpy.ops.hairdyn.bake('INVOKE_DEFAULT'))
        result["steps"].append("bake started")
        bpy.app.timers.register(wait_for_bake, first_interval=0.2)
    except Exception as error:
        finish(f"screenshot: {error!r}")
    return None


def wait_for_bake():
    """Poll until the modal bake has written its manifest as complete (or 60 s pass)."""
    from hairdyn import bake
    from hairdyn.cache import Cache

    result.setdefault("polls", 0)
    result["polls"] += 1
    try:
        manifest = Cache.open(bake.cache_directory(bpy.data.objects[object_name])).manifest
    except Exception:  # not created yet
        manifest = {}
    if manifest.get("complete"):
        result["baked_frames"] = manifest["report"]["frames"]
        # Scrub like a user: the bake plays back, frames past it simulate live.
        from hairdyn import playback

        obj = bpy.data.objects[object_name]
        for frame in (3, 1, 2):
            bpy.context.scene.frame_set(frame)
        result["playback_error"] = playback.last_error(obj)
        window, area = properties_area()
        with bpy.context.temp_override(window=window, screen=window.screen, area=area):
            bpy.ops.screen.screenshot(filepath=out_png.replace(".png", "_baked.png"))
        result["steps"].append("baked")
        finish()
        return None
    if result["polls"] > 300:
        finish("the modal bake did not finish within 60 s")
        return None
    return 0.2


if not hasattr(bpy.types.Object, "hairdyn"):
    hairdyn.register()
bpy.app.timers.register(select, first_interval=1.0)
