"""The per-frame record beside a bake: rows by frame, a CSV and a PNG plot; its summary
equals the bake report's figures when fed by the bake's own figures."""

from pathlib import Path

import bpy
import numpy as np
import pytest

from hairdyn import frame_record


def test_record_round_trip_and_plot(tmp_path):
    record = frame_record.start(tmp_path)
    rows = {
        f: {
            "ms": 1.0 + f,
            "penetration_share": 0.01 * f,
            "stretch": 1e-5 * f,
            "kinetic_energy": 0.5 * f * f,
            "contacts": 3 * f,
        }
        for f in range(1, 11)
    }
    for frame in (3, 1, 2, *range(4, 11)):  # order of arrival does not matter
        record.add(frame, rows[frame])
    png = record.finish()
    assert png == tmp_path / "frame_record.png" and png.is_file()
    assert frame_record.read(tmp_path / "frame_record.csv") == {
        f: {k: float(v) for k, v in row.items()} for f, row in rows.items()
    }
    summary = record.summary()
    # median of 2..11 is 6.5; the largest stretch is frame 10's; the mean share of 0.01..0.1
    assert summary == {
        "frames": 10,
        "ms_per_frame": 6.5,
        "stretch_max": pytest.approx(1e-4),
        "penetration_share": pytest.approx(0.055),
    }
    image = frame_record.read_png_rgb(png)
    assert image.shape == (28 + 5 * 150, 800, 3)
    blue = np.all(image == frame_record._LINE, axis=2)
    # each of the five panels has its curve drawn in it
    for index in range(5):
        top = 28 + index * 150
        assert blue[top : top + 111].sum() > 200, index
    # a rising figure: the curve's left end is lower in the panel (larger row) than its right
    rows_ms = np.nonzero(blue[28 : 28 + 111])
    left = rows_ms[0][rows_ms[1] < rows_ms[1].min() + 5].mean()
    right = rows_ms[0][rows_ms[1] > rows_ms[1].max() - 5].mean()
    assert left > right + 80


def test_resume_keeps_earlier_rows_and_a_fresh_start_drops_them(tmp_path):
    record = frame_record.start(tmp_path)
    figures = dict.fromkeys(frame_record.FIGURES, 1.0)
    for frame in (1, 2, 3):
        record.add(frame, figures)
    record.finish()
    resumed = frame_record.start(tmp_path, resume=True)
    resumed.add(4, figures)
    resumed.finish()
    assert sorted(frame_record.read(tmp_path / "frame_record.csv")) == [1, 2, 3, 4]
    assert sorted(frame_record.start(tmp_path).rows) == []


def test_bad_figures_are_refused(tmp_path):
    record = frame_record.start(tmp_path)
    with pytest.raises(ValueError, match="frame 1: the record needs contacts"):
        record.add(1, {k: 1.0 for k in frame_record.FIGURES if k != "contacts"})
    with pytest.raises(ValueError, match="frame 2: stretch is not a finite number"):
        record.add(2, {**dict.fromkeys(frame_record.FIGURES, 1.0), "stretch": float("nan")})
    assert record.rows == {}


def test_kinetic_energy_is_half_the_sum_of_squared_speeds():
    velocities = np.array([[3.0, 4.0, 0.0], [0.0, 0.0, 2.0]], dtype=np.float32)
    assert frame_record.kinetic_energy(velocities) == pytest.approx(0.5 * (25.0 + 4.0))


def test_record_of_a_bake_matches_its_report(open_fixture, tmp_path):
    """The bake loop records every frame beside the cache: the record's summary equals the
    report's ms_per_frame, stretch_max and penetration_share, and a resumed bake keeps the
    rows of the frames it keeps."""
    from hairdyn import bake, cli

    open_fixture("head_shake.blend")
    hair = bpy.data.objects["Hair"]
    hair.hairdyn.cache_directory = str(tmp_path)
    hair.hairdyn.frame_start, hair.hairdyn.frame_end = 1, 8
    cli.apply_settings(hair.hairdyn, ["method=strands"])
    runner = bake.start_bake(bpy.context, hair)
    while not runner.done:
        runner.advance()
    report = bake.finish_bake(runner)
    png = Path(report["frame_record"])
    assert png.parent == runner.cache.directory and png.is_file()
    record = frame_record.start(runner.cache.directory, resume=True)
    summary = record.summary()
    assert summary["frames"] == report["frames"] == 8
    assert summary["ms_per_frame"] == pytest.approx(report["ms_per_frame"])
    assert summary["stretch_max"] == pytest.approx(report["stretch_max"])
    assert summary["penetration_share"] == pytest.approx(report["penetration_share"], abs=1e-12)
    table = record.table()
    assert table["kinetic_energy"].max() > 0.0  # the head shakes the hair
    assert np.array_equal(table["contacts"], np.round(table["contacts"]))  # counts
    runner = bake.start_bake(bpy.context, hair, resume_after=5)
    while not runner.done:
        runner.advance()
    bake.finish_bake(runner)
    resumed = frame_record.read(runner.cache.directory / frame_record.CSV_NAME)
    assert sorted(resumed) == list(range(1, 9))
    assert all(resumed[f] == record.rows[f] for f in range(1, 6))  # kept, not re-recorded
    bpy.context.view_layer.objects.active = hair
    assert bpy.ops.hairdyn.open_frame_record.poll()
