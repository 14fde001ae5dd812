"""export_run and friends: the files a run leaves on disk, and the checks on their inputs."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os
import weakref

import numpy as np
import pytest
from PIL import Image

from ikgame.render import export
from ikgame.render.export import export_run, motion_json
from ikgame.render.theme import load_theme

SIZE = (160, 90)
LIGHT = load_theme("light")


def _export(out, scene, snaps, **kwargs):
    options = dict(size=SIZE, progress=False, workers=1) | kwargs
    return export_run(out, scene, snaps, **options)


def _digests(folder) -> dict[str, str]:
    return {
        str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(folder.rglob("*"))
        if p.is_file()
    }


def test_frames_are_numbered_pngs_one_per_snapshot(tmp_path, run):
    scene, snaps = run(5)
    written = _export(tmp_path, scene, snaps, gif=False, motion=False)
    names = sorted(p.name for p in (tmp_path / "frames").iterdir())
    assert names == [f"{i:06d}.png" for i in range(5)]
    assert written == [tmp_path / "frames" / name for name in names]
    with Image.open(tmp_path / "frames" / "000003.png") as image:
        assert image.format == "PNG" and image.size == SIZE and image.mode == "RGB"


def test_fast_runs_keep_every_other_frame_in_the_gif(tmp_path, run):
    scene, snaps = run(12, fps=60.0)
    _export(tmp_path, scene, snaps, frames=False, motion=False)
    with Image.open(tmp_path / "run.gif") as gif:
        assert gif.n_frames == 6
        durations = []
        for k in range(gif.n_frames):
            gif.seek(k)
            durations.append(gif.info["duration"])
    assert durations == [30, 40, 30, 30, 40, 30]  # 12 frames at 60 fps: 200 ms


def test_apng_without_frames_on_disk(tmp_path, run):
    scene, snaps = run(3)
    written = _export(tmp_path, scene, snaps, frames=False, gif=False, apng=True, motion=False)
    assert [p.name for p in written] == ["run.png"]
    assert not (tmp_path / "frames").exists()


def test_contact_sheet_is_a_grid_of_evenly_spaced_frames(tmp_path, run):
    scene, snaps = run(30)
    written = _export(tmp_path, scene, snaps, frames=False, gif=False, motion=False, sheet=True)
    assert [p.name for p in written] == ["sheet.png"]
    assert export._sample_indices(30, 12) == [0, 3, 5, 8, 11, 13, 16, 18, 21, 24, 26, 29]
    assert export._sample_indices(5, 12) == [0, 1, 2, 3, 4]
    with Image.open(tmp_path / "sheet.png") as sheet:
        # 4 columns of 160 px frames plus gaps; 3 rows under a title.
        assert 4 * SIZE[0] < sheet.width < 4 * SIZE[0] + 100
        assert 3 * SIZE[1] < sheet.height


def test_motion_json_holds_every_frame(tmp_path, run):
    scene, snaps = run(4)
    _export(tmp_path, scene, snaps, frames=False, gif=False)
    data = json.loads((tmp_path / "motion.json").read_text())
    assert data == json.loads(json.dumps(motion_json(scene, snaps)))
    assert data["level"] == "Synthetic" and data["fps"] == 30.0
    assert data["frame_count"] == 4 and len(data["frames"]) == 4
    assert data["link_lengths"] == pytest.approx([40.0, 40.0, 40.0])
    frame = data["frames"][2]
    snap = snaps[2]
    assert frame["time"] == pytest.approx(snap.time, abs=1e-6)
    assert frame["angles_rad"] == pytest.approx(snap.angles.tolist(), abs=1e-6)
    assert frame["angles_deg"] == pytest.approx(np.degrees(snap.angles).tolist(), abs=1e-4)
    np.testing.assert_allclose(frame["joints"], snap.joints, atol=1e-3)
    assert frame["target"] == pytest.approx(snap.target.tolist())
    assert frame["solver_status"] == snap.solver_status
    assert frame["torque_limited"] == snap.torque_limited.tolist()


def test_motion_json_is_an_indented_header_then_one_line_per_frame(tmp_path, run):
    scene, snaps = run(3)
    _export(tmp_path, scene, snaps, frames=False, gif=False)
    text = (tmp_path / "motion.json").read_text()
    motion = motion_json(scene, snaps)
    frames = motion.pop("frames")
    head = json.dumps(motion, indent=2)
    lines = [json.dumps(frame) for frame in frames]
    assert text == f'{head[:-2]},\n  "frames": [\n    ' + ",\n    ".join(lines) + "\n  ]\n}\n"


def test_png_compression_trades_time_for_size_not_pixels(tmp_path, run):
    scene, snaps = run(2)
    _export(tmp_path / "fast", scene, snaps, gif=False, motion=False)
    _export(tmp_path / "small", scene, snaps, gif=False, motion=False, png_compression=9)
    fast, small = tmp_path / "fast/frames/000001.png", tmp_path / "small/frames/000001.png"
    assert small.stat().st_size < fast.stat().st_size
    with Image.open(fast) as a, Image.open(small) as b:
        assert a.tobytes() == b.tobytes()
    with pytest.raises(ValueError, match="compress_level"):
        _export(tmp_path / "bad", scene, snaps, png_compression=10)


def test_motion_json_writes_missing_values_as_null(run):
    scene, snaps = run(2, targets=np.zeros((0, 2)))
    frame = motion_json(scene, snaps)["frames"][0]
    assert frame["target"] is None and frame["error"] is None


def test_writes_are_atomic_and_leave_no_temporaries(tmp_path, run):
    scene, snaps = run(4)
    _export(tmp_path, scene, snaps, apng=True, sheet=True)
    leftovers = [p for p in tmp_path.rglob("*") if p.name.startswith(".") or p.suffix == ".tmp"]
    assert leftovers == []
    umask = os.umask(0)
    os.umask(umask)
    assert (tmp_path / "run.gif").stat().st_mode & 0o777 == 0o666 & ~umask


def test_a_failed_export_leaves_no_partial_files(tmp_path, run):
    scene, snaps = run(4)
    broken = snaps[:2] + [dataclasses.replace(snaps[2], joints=np.zeros((1, 2)))]
    with pytest.raises(ValueError, match="joints"):
        _export(tmp_path, scene, broken, apng=True)
    names = {p.name for p in tmp_path.rglob("*")}
    assert not names & {"run.gif", "run.png", "motion.json"}
    assert not [name for name in names if name.endswith(".tmp")]


def test_re_export_removes_frames_of_a_longer_earlier_run(tmp_path, run):
    scene, snaps = run(5)
    _export(tmp_path, scene, snaps, gif=False, motion=False)
    (tmp_path / "frames" / "notes.txt").write_text("mine")
    _export(tmp_path, scene, snaps[:2], gif=False, motion=False)
    names = sorted(p.name for p in (tmp_path / "frames").iterdir())
    assert names == ["000000.png", "000001.png", "notes.txt"]


def test_bad_export_arguments_raise(tmp_path, run):
    scene, snaps = run(2)
    with pytest.raises(ValueError, match=r"^unknown theme 'x'; available: dark, light$"):
        _export(tmp_path, scene, snaps, theme="x")
    with pytest.raises(ValueError, match="out of range"):
        _export(tmp_path, scene, snaps, size=(8, 8))
    with pytest.raises(ValueError, match="workers"):
        _export(tmp_path, scene, snaps, workers=0)
    with pytest.raises(ValueError, match="no snapshots"):
        _export(tmp_path, scene, [])
    with pytest.raises(ValueError, match="fps"):
        _export(tmp_path, dataclasses.replace(scene, fps=0.0), snaps)


def test_progress_is_silent_when_stderr_is_not_a_terminal(tmp_path, run, capsys):
    scene, snaps = run(2)
    export_run(tmp_path, scene, snaps, size=SIZE, workers=1, progress=True)
    assert capsys.readouterr().err == ""


def test_parallel_export_is_byte_identical_to_serial(tmp_path, run):
    scene, snaps = run(2 * export.CHUNK + 3)
    options = dict(apng=True, sheet=True)
    _export(tmp_path / "serial", scene, snaps, workers=1, **options)
    _export(tmp_path / "parallel", scene, snaps, workers=2, **options)
    serial, parallel = _digests(tmp_path / "serial"), _digests(tmp_path / "parallel")
    assert len(serial) == len(snaps) + 4
    assert serial == parallel


def test_the_gif_palette_holds_one_sample_frame_at_a_time(tmp_path, run, monkeypatch):
    """Each sample frame is counted and let go before the next is drawn: the palette needs
    their colour counts, not a dozen frames held at once."""
    scene, snaps = run(60)
    original = export.color_counts
    alive: list[weakref.ref] = []
    counted = []

    def count(image):
        assert all(ref() is None for ref in alive), "an earlier sample frame is still held"
        alive.append(weakref.ref(image))
        counted.append(original(image))
        return counted[-1]

    monkeypatch.setattr(export, "color_counts", count)
    _export(tmp_path, scene, snaps, frames=False, motion=False)
    assert len(counted) == export.SHEET_THUMBS


def test_trail_covers_the_last_seconds(run):
    scene, snaps = run(100)
    trail = export.trail_at(scene, snaps, 80)
    assert trail.shape == (math.ceil(export.TRAIL_SECONDS * scene.fps) + 1, 1, 2)
    np.testing.assert_array_equal(trail[-1, 0], snaps[80].joints[-1])
    assert len(export.trail_at(scene, snaps, 0)) == 1


def test_code_from_stdin_exports_serially_or_says_why(tmp_path, run, monkeypatch):
    scene, snaps = run(export.PARALLEL_MIN_FRAMES)
    monkeypatch.setattr(export, "_main_importable", lambda: False)
    assert export._worker_count(None, len(snaps)) == 1
    with pytest.raises(ValueError, match="workers=1"):
        _export(tmp_path, scene, snaps, workers=2)


def test_a_window_of_a_run_draws_its_frames_as_the_whole_run_does(run):
    scene, snaps = run(120)
    job = export._Job(scene, tuple(snaps), export.Camera.fit(scene, snaps, SIZE), LIGHT, True, 1)
    window = job.window(100, 108)
    # Only the frames and the trail they need travel to a worker, not the run.
    assert window.first == 100 - round(export.TRAIL_SECONDS * scene.fps)
    assert len(window.snapshots) == 108 - window.first
    for index in (100, 107):
        assert window.render(index).tobytes() == job.render(index).tobytes()
    assert job.window(0, 8).first == 0


def test_automatic_workers_leave_this_process_a_core(run, monkeypatch):
    monkeypatch.setattr(export, "_main_importable", lambda: True)
    for cores, expected in [(1, 1), (2, 1), (4, 3), (64, export.MAX_AUTO_WORKERS)]:
        monkeypatch.setattr(export.os, "cpu_count", lambda cores=cores: cores)
        assert export._worker_count(None, export.PARALLEL_MIN_FRAMES) == expected
    assert export._worker_count(None, export.PARALLEL_MIN_FRAMES - 1) == 1
