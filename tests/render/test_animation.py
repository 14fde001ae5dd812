"""GIF and APNG streams: frames, delays, palette and looping, read back by Pillow."""

from __future__ import annotations

import os
import tracemalloc

import numpy as np
import pytest
from PIL import Image

from ikgame.render import animation
from ikgame.render.export import export_run
from ikgame.render.theme import load_theme

SIZE = (160, 90)


def _export(out, scene, snaps, **kwargs):
    options = dict(size=SIZE, progress=False, workers=1) | kwargs
    return export_run(out, scene, snaps, **options)


def test_gif_has_every_frame_right_durations_and_loops(tmp_path, run):
    scene, snaps = run(7)
    _export(tmp_path, scene, snaps)
    with Image.open(tmp_path / "run.gif") as gif:
        assert gif.n_frames == 7
        assert gif.info["loop"] == 0
        durations = []
        for k in range(gif.n_frames):
            gif.seek(k)
            durations.append(gif.info["duration"])
            decoded = np.asarray(gif.convert("RGB"), dtype=int)
            with Image.open(tmp_path / "frames" / f"{k:06d}.png") as png:
                exact = np.asarray(png.convert("RGB"), dtype=int)
            # One shared palette, no dithering: flat colours survive exactly, edges nearly.
            assert decoded[0, -1].tolist() == list(load_theme("light").background)
            assert np.mean(np.all(decoded == exact, axis=2)) > 0.8
            assert np.abs(decoded - exact).mean() < 1.5
    assert durations == [30, 40, 30, 30, 40, 30, 30]
    assert sum(durations) == pytest.approx(7 / scene.fps * 1000, abs=5)


def test_gif_durations_add_up_to_the_run():
    for fps in (24.0, 25.0, 30.0, 29.97, 48.0):
        durations = animation.gif_durations(1000, fps, 1)
        assert all(d % 10 == 0 and d >= 20 for d in durations)
        assert sum(durations) == pytest.approx(1000 / fps * 1000, abs=5)


def test_unchanged_frames_keep_their_time_in_the_gif(tmp_path, run):
    scene, snaps = run(3)
    still = [snaps[0]] * 3
    _export(tmp_path, scene, still, frames=False, motion=False)
    with Image.open(tmp_path / "run.gif") as gif:
        assert gif.n_frames == 3


def test_apng_frames_match_the_png_frames(tmp_path, run):
    scene, snaps = run(4)
    _export(tmp_path, scene, snaps, gif=False, apng=True)
    with Image.open(tmp_path / "run.png") as apng:
        assert apng.format == "PNG" and apng.is_animated and apng.n_frames == 4
        assert apng.info["loop"] == 0
        for k in range(4):
            apng.seek(k)
            assert apng.info["duration"] == pytest.approx(1000 / 30)
            with Image.open(tmp_path / "frames" / f"{k:06d}.png") as png:
                assert apng.convert("RGB").tobytes() == png.convert("RGB").tobytes()


def test_quantizer_keeps_palette_colours_exact_and_maps_others_to_the_nearest():
    palette = bytes([10, 20, 30, 200, 200, 200, 11, 20, 30] + [0, 0, 0] * 252)
    image = Image.new("RGB", (3, 1))
    image.putdata([(10, 20, 30), (11, 20, 30), (190, 205, 199)])
    assert list(animation._Quantizer(palette).indices(image)) == [0, 2, 1]


def test_many_new_colours_map_to_the_nearest_entry_in_a_few_mb():
    """A frame full of colours not seen before (a sprite, a gradient) is matched to the
    palette a block at a time: the distances of all of them at once would take 100 MB."""
    rng = np.random.default_rng(7)
    palette = rng.integers(0, 256, 3 * animation.GIF_COLORS, dtype=np.uint8).tobytes()
    pixels = rng.integers(0, 256, (64, 128, 3), dtype=np.uint8)  # 8192 colours, nearly all new
    quantizer = animation._Quantizer(palette)
    tracemalloc.start()
    try:
        indices = np.frombuffer(quantizer.indices(Image.fromarray(pixels)), dtype=np.uint8)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 8 * 2**20
    colours = np.frombuffer(palette, dtype=np.uint8).reshape(-1, 3).astype(int)
    diff = pixels.reshape(-1, 1, 3).astype(int) - colours[None]
    nearest = np.argmin((diff * diff * [2, 4, 3]).sum(axis=2), axis=1)
    assert np.array_equal(indices, nearest)


def _resident_mb() -> float:
    with open("/proc/self/status") as status:
        return next(int(line.split()[1]) for line in status if line.startswith("VmRSS")) / 1024


@pytest.mark.skipif(not os.path.exists("/proc/self/status"), reason="reads Linux /proc")
def test_the_colour_table_takes_memory_only_where_colours_are_written():
    """A run's colours are scattered over the 16 MB table: only the small pages they land on
    may take memory, not the whole table in 2 MB pages."""
    table = animation._zeroed(1 << 24)
    scattered = np.random.default_rng(5).integers(0, 1 << 24, 600)
    before = _resident_mb()
    table[scattered] = 1
    assert _resident_mb() - before < 6
    assert table.sum() == len(np.unique(scattered))


def test_a_trees_effector_colours_are_exact_palette_entries(tmp_path, tree_run):
    theme = load_theme("light")
    blank = [animation.color_counts(Image.new("RGB", SIZE, theme.background))]
    extra = [(1, 2, 3), (250, 1, 2)]
    colours = animation.build_palette(iter(blank), theme, extra)
    entries = [tuple(colours[i : i + 3]) for i in range(0, len(colours), 3)]
    assert set(extra) <= set(entries) and set(theme.colors()) <= set(entries)
    # An exported tree's GIF keeps each effector's tip colour exact.
    scene, snaps = tree_run(3)
    _export(tmp_path, scene, snaps, frames=False, motion=False)
    with Image.open(tmp_path / "run.gif") as gif:
        gif.seek(2)
        pixels = {tuple(p) for p in np.asarray(gif.convert("RGB")).reshape(-1, 3).tolist()}
    assert {s.tip for s in theme.effector_styles(2)} <= pixels
