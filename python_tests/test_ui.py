"""A real Blender window under Xvfb: the panel is drawn, its operators run from the UI
(simulate, and the modal bake with its progress), screenshots are kept as artifacts."""
import json
import os
import shutil
import subprocess

import pytest

from conftest import FIXTURES, ROOT

UI_CHECK = ROOT / "python_tests" / "ui_check.py"


@pytest.mark.parametrize("fixture, obj", [("head_curves.blend", "Hair"),
                                          ("head_particles.blend", "Body")])
def test_panel_in_a_real_window(fixture, obj, artifacts, tmp_path):
    blender = shutil.which("blender")
    xvfb_run = shutil.which("xvfb-run")
    if blender is None or xvfb_run is None:
        pytest.skip("needs the 'blender' binary and 'xvfb-run' (Debian packages blender, xvfb)")
    out_json = tmp_path / "ui.json"
    screenshot = artifacts / f"ui_panel_{obj.lower()}.png"
    screenshot.unlink(missing_ok=True)
    command = [xvfb_run, "-a", "-s", "-screen 0 1920x1080x24", blender, "--factory-startup",
               str(FIXTURES / fixture), "--python", str(UI_CHECK), "--", obj, str(out_json),
               str(screenshot), str(tmp_path / "cache")]
    # Python's copy of the environment: bpy 5.2 sets OCIO to its own colour config (a format
    # Debian's Blender cannot read) in the process's C environment, which children inherit.
    process = subprocess.run(command, capture_output=True, text=True, timeout=180,
                             env=dict(os.environ))
    assert out_json.is_file(), process.stdout[-3000:] + process.stderr[-3000:]
    result = json.loads(out_json.read_text())
    assert result["error"] is None, result
    assert result["draw_calls"] > 0
    # Issue 17: every label of every method's sections fits the default properties editor.
    print("properties editor", result["properties_width_px"], "px, label column",
          round(result["label_column_px"]), "px, widest label", result["widest_label"])
    assert result["cut_labels"] == {}, result["cut_labels"]
    assert result["simulate"] == ["FINISHED"]
    assert result["bake_invoke"] == ["RUNNING_MODAL"]  # the modal bake, as from the button
    assert result["baked_frames"] == 10
    assert result["playback_error"] is None
    assert sorted(p.name for p in (tmp_path / "cache" / obj).glob("frame_*.npy"))[-1] == \
        "frame_000010.npy"
    assert screenshot.is_file() and screenshot.stat().st_size > 10_000
    assert screenshot.with_name(screenshot.stem + "_baked.png").is_file()
