"""Write a recorded run to disk: PNG frames, a looping GIF, an APNG, an MP4, a contact sheet, and
the baked motion as JSON keyframes.

Frames are independent of each other (each frame's trail is read from the snapshot list), so they
can be drawn in worker processes; every byte that ends up in a file comes from the same
deterministic functions either way, so a parallel export is identical to a serial one. Files are
written to a temporary name in their folder and renamed into place, so a reader never sees half a
file, and an interrupted export leaves no stray temporaries. The GIF and APNG are streamed one
frame at a time, so a long run does not hold its frames in memory; their file formats are written
by :mod:`ikgame.render.animation` (and the MP4 by :mod:`ikgame.render.video`), while this module
decides what goes into them.
"""

from __future__ import annotations

import math
import multiprocessing
import os
import re
import signal
import sys
import threading
import time
import zlib
from collections import deque
from collections.abc import Iterator, Sequence
from concurrent.futures import Future, ProcessPoolExecutor
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from ikgame._files import atomic_open, write_atomic
from ikgame._progress import progress_bar
from ikgame.render.animation import (
    ApngWriter,
    GifWriter,
    build_palette,
    color_counts,
    gif_durations,
    quantizer,
)
from ikgame.render.camera import Camera
from ikgame.render.motion import check_run, motion_json, write_motion
from ikgame.render.output import check_export_size, check_out_dir, parse_size
from ikgame.render.pillow import render_snapshot
from ikgame.render.png import check_compress_level, png_bytes
from ikgame.render.theme import RGB, Theme, load_theme
from ikgame.render.video import Mp4Writer, check_video, even_size
from ikgame.snapshot import Scene, Snapshot, effector_positions

__all__ = ["check_out_dir", "export_run", "motion_json", "parse_size", "trail_at", "write_motion"]

TRAIL_SECONDS = 1.5  # s of each end effector's path drawn behind it
GIF_MAX_FPS = 50.0  # browsers play GIF delays under 2 cs as 10 cs, so faster runs drop frames
SHEET_THUMBS = 12
SHEET_COLUMNS = 4
SHEET_THUMB_WIDTH = 320  # px, at most
CHUNK = 8  # frames per worker task: large enough to amortise the round trip, small to balance
PARALLEL_MIN_FRAMES = 48  # shorter runs finish before worker processes would have started
MAX_AUTO_WORKERS = 8
WORKER_PARENT_POLL_S = 0.5  # how soon a worker notices its parent is gone, s
PNG_COMPRESSION = 1  # zlib level of PNG files: fast; 9 makes them about a third smaller
_FRAME_NAME = re.compile(r"\d{6}\.png")


# -- input checks --------------------------------------------------------------------------------


# -- one frame -----------------------------------------------------------------------------------


def trail_at(scene: Scene, snapshots: Sequence[Snapshot], index: int) -> np.ndarray:
    """The end effectors' paths over the last ``TRAIL_SECONDS`` up to frame ``index``, (m, k, 2):
    a column per effector.

    Read from the snapshot list alone, so any frame can be drawn without drawing the others.

    >>> scene = Scene("demo", np.zeros((0, 5)), np.zeros((0, 3)), np.full(1, 8.0), 10.0)
    >>> snaps = [Snapshot(i / 30, i, np.array([[0.0, 0.0], [i, 1.0]]), np.zeros(1), np.zeros(1))
    ...          for i in range(3)]
    >>> trail_at(scene, snaps, 2).tolist()
    [[[0.0, 1.0]], [[1.0, 1.0]], [[2.0, 1.0]]]
    """
    start = max(0, index - _trail_frames(scene.fps))
    window = snapshots[start : index + 1]
    return np.array([effector_positions(scene, snap) for snap in window], dtype=float)


def _trail_frames(fps: float) -> int:
    """How many frames back a frame's trail reaches."""
    return max(1, round(TRAIL_SECONDS * fps))


@dataclass(frozen=True)
class _Job:
    """Everything needed to draw the frames of a run, or of a window of it: ``snapshots`` are
    the frames from index ``first`` on. Worker processes get the job once without snapshots,
    then each task the window it draws (see :meth:`window`), so a worker never holds the run."""

    scene: Scene
    snapshots: tuple[Snapshot, ...]
    camera: Camera
    theme: Theme
    png: bool  # encode PNG bytes (frames or APNG)
    gif_stride: int  # every gif_stride-th frame goes into the GIF; 0 without a GIF
    mp4: bool = False  # raw RGB of the even-sided frame, for the MP4 encoder
    png_compression: int = PNG_COMPRESSION  # zlib level: 1 fast .. 9 small
    first: int = 0  # frame index of snapshots[0]

    def window(self, start: int, stop: int) -> _Job:
        """The job for frames ``start`` to ``stop`` only: their snapshots and their trails'."""
        first = max(0, start - _trail_frames(self.scene.fps))
        window = self.snapshots[first - self.first : stop - self.first]
        return replace(self, snapshots=window, first=first)

    def render(self, index: int, hud: bool = True) -> Image.Image:
        local = index - self.first
        trail = trail_at(self.scene, self.snapshots, local)
        return render_snapshot(
            self.scene,
            self.snapshots[local],
            self.camera,
            self.theme,
            trail=trail,
            hud=hud,
        )

    def payload(self, index: int, palette: bytes | None) -> tuple[bytes | None, ...]:
        """Frame ``index`` as PNG bytes, as GIF palette indices and as the MP4's RGB bytes
        (None where not wanted)."""
        image = self.render(index)
        png = png_bytes(image, self.png_compression) if self.png else None
        indices = None
        if palette is not None and index % self.gif_stride == 0:
            indices = quantizer(palette).indices(image)
        rgb = None
        if self.mp4:
            rgb = image.crop((0, 0, *even_size(image.size))).tobytes()
        return png, indices, rgb


# -- worker processes ------------------------------------------------------------------------------

_WORKER_JOB: _Job | None = None


def _init_worker(job: _Job, parent: int) -> None:
    global _WORKER_JOB
    _WORKER_JOB = job
    # Ctrl-C reaches the whole process group: the parent stops the pool, workers must not die
    # half-way through a chunk and break it.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    threading.Thread(target=_exit_with, args=(parent,), daemon=True).start()


def _exit_with(parent: int) -> None:
    """Exit as soon as the parent process is gone, even if it was killed (SIGKILL leaves no
    chance to shut the pool down): an orphaned worker would draw on for nobody."""
    while os.getppid() == parent:
        time.sleep(WORKER_PARENT_POLL_S)
    os._exit(1)


def _worker_payloads(
    snapshots: tuple[Snapshot, ...], first: int, start: int, stop: int, palette: bytes | None
) -> list[tuple[bytes | None, ...]]:
    assert _WORKER_JOB is not None, "worker used without _init_worker"
    job = replace(_WORKER_JOB, snapshots=snapshots, first=first)
    payloads = [job.payload(i, palette) for i in range(start, stop)]
    # Palette indices are a byte per pixel but mostly runs: compressed they are ~5% of the
    # size, both in the pipe to the main process and in results queued for their turn.
    return [
        (png, None if idx is None else zlib.compress(idx, 1), rgb) for png, idx, rgb in payloads
    ]


def _worker_colors(
    snapshots: tuple[Snapshot, ...], first: int, index: int
) -> list[tuple[int, RGB]]:
    assert _WORKER_JOB is not None, "worker used without _init_worker"
    job = replace(_WORKER_JOB, snapshots=snapshots, first=first)
    return color_counts(job.render(index))


def _main_importable() -> bool:
    """Whether spawned workers can import ``__main__`` again, as multiprocessing requires: yes
    for a module, a script file or an interactive session; no for code piped to ``python -``."""
    main = sys.modules.get("__main__")
    if main is None or getattr(main, "__spec__", None) is not None:
        return True
    path = getattr(main, "__file__", None)
    return path is None or os.path.isfile(path)


def _worker_count(workers: int | None, frames: int) -> int:
    if workers is None:
        if frames < PARALLEL_MIN_FRAMES or not _main_importable():
            return 1
        # This process is a stage of the pipeline too (GIF, file writes): one core stays its own.
        return max(1, min((os.cpu_count() or 1) - 1, MAX_AUTO_WORKERS))
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ValueError(f"workers must be a positive int or None, got {workers!r}")
    if workers > 1 and not _main_importable():
        raise ValueError(
            "worker processes must import the main module, and code read from stdin has none: "
            "run a script file (with an `if __name__ == '__main__':` guard) or pass workers=1"
        )
    return workers


@contextmanager
def _pool(job: _Job, workers: int) -> Iterator[ProcessPoolExecutor | None]:
    if workers == 1:
        yield None
        return
    # "spawn", not fork: the progress bar runs a thread, and forking a threaded process can
    # deadlock; spawn also behaves the same on every OS.
    pool = ProcessPoolExecutor(
        workers,
        mp_context=multiprocessing.get_context("spawn"),
        initializer=_init_worker,
        initargs=(replace(job, snapshots=()), os.getpid()),
    )
    try:
        yield pool
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _payloads(
    job: _Job, pool: ProcessPoolExecutor | None, workers: int, palette: bytes | None
) -> Iterator[tuple[bytes | None, ...]]:
    """Every frame's payload, in order, drawn here or by the pool."""
    count = len(job.snapshots)
    if pool is None:
        for index in range(count):
            yield job.payload(index, palette)
        return
    chunks = iter(range(0, count, CHUNK))
    pending: deque[Future[list[tuple[bytes | None, ...]]]] = deque()

    def submit() -> None:
        start = next(chunks, None)
        if start is not None:
            stop = min(start + CHUNK, count)
            window = job.window(start, stop)
            pending.append(
                pool.submit(_worker_payloads, window.snapshots, window.first, start, stop, palette)
            )

    # A couple of chunks queued per worker keeps them busy while bounding frames held in memory.
    for _ in range(2 * workers):
        submit()
    while pending:
        results = pending.popleft().result()
        submit()
        for png, packed, rgb in results:
            yield png, None if packed is None else zlib.decompress(packed), rgb


def _sample_colors(
    job: _Job, pool: ProcessPoolExecutor | None, indices: Sequence[int]
) -> Iterator[list[tuple[int, RGB]]]:
    """The :func:`color_counts` of frames ``indices``, one frame at a time: the frames
    themselves are let go as soon as they are counted, here or in a worker."""
    if pool is None:
        return (color_counts(job.render(i)) for i in indices)
    windows = [job.window(i, i + 1) for i in indices]
    return pool.map(
        _worker_colors, [w.snapshots for w in windows], [w.first for w in windows], indices
    )


def _sample_indices(count: int, wanted: int) -> list[int]:
    """Up to ``wanted`` evenly spaced frame indices, first and last included."""
    return sorted({round(v) for v in np.linspace(0, count - 1, min(wanted, count))})


# -- contact sheet -------------------------------------------------------------------------------


def _contact_sheet(job: _Job, indices: Sequence[int]) -> Image.Image:
    """Evenly spaced frames in a grid, each labelled with its time, under a title line."""
    theme, scene = job.theme, job.scene
    width, height = job.camera.size
    tw = min(width, SHEET_THUMB_WIDTH)
    th = max(1, round(height * tw / width))
    columns = min(SHEET_COLUMNS, len(indices))
    rows = math.ceil(len(indices) / columns)
    gap = max(6, tw // 24)
    label = max(10, tw // 22)  # font size, px
    title = round(label * 1.4)
    cell_h = th + round(label * 1.8)
    sheet_w = columns * tw + (columns + 1) * gap
    top = gap + round(title * 1.6)
    sheet = Image.new("RGB", (sheet_w, top + rows * (cell_h + gap)), theme.background)
    draw = ImageDraw.Draw(sheet)
    duration = len(job.snapshots) / scene.fps
    heading = f"{scene.level_name}  ·  {duration:.2f} s  ·  {len(job.snapshots)} frames"
    draw.text((gap, gap), heading, fill=theme.hud_text, font=ImageFont.load_default(size=title))
    font = ImageFont.load_default(size=label)
    for k, index in enumerate(indices):
        x = gap + (k % columns) * (tw + gap)
        y = top + (k // columns) * (cell_h + gap)
        # Shrunk from a full frame rather than drawn small: line widths and markers keep the
        # proportions of the real frames, so the sheet reads as their miniature.
        thumb = job.render(index, hud=False).resize((tw, th), Image.Resampling.LANCZOS)
        sheet.paste(thumb, (x, y))
        draw.rectangle((x - 1, y - 1, x + tw, y + th), outline=theme.hud_muted)
        caption = f"t = {job.snapshots[index].time:.2f} s"
        draw.text(
            (x + tw / 2, y + th + label * 0.4), caption, fill=theme.hud_text, font=font, anchor="ma"
        )
    return sheet


# -- files ---------------------------------------------------------------------------------------


def export_run(
    out_dir: str | os.PathLike[str],
    scene: Scene,
    snapshots: Sequence[Snapshot],
    *,
    size: tuple[int, int] = (960, 540),
    theme: str | os.PathLike[str] | Theme = "light",
    frames: bool = True,
    gif: bool = True,
    apng: bool = False,
    sheet: bool = False,
    mp4: bool = False,
    motion: bool = True,
    workers: int | None = None,
    progress: bool = True,
    png_compression: int = PNG_COMPRESSION,
) -> list[Path]:
    """Write a run's files into ``out_dir`` (created if missing) and return their paths.

    ``frames/000000.png``... one per snapshot; ``run.gif`` looping, with one shared adaptive
    palette and delays that add up to the run's length (runs above 50 fps keep every 2nd, 3rd...
    frame, as browsers slow faster GIFs down); ``run.png`` an APNG at the exact frame rate;
    ``run.mp4`` H.264 at the run's fps (needs the ``video`` extra; see :mod:`ikgame.render.video`);
    ``sheet.png`` a contact sheet of about 12 frames; ``motion.json`` (see :func:`motion_json`).
    ``png_compression`` is the zlib level of the PNG files, 0..9: the default 1 is fast, 9 makes
    files about a third smaller and the export slower.
    ``workers`` processes draw the frames (None: for long runs one per CPU but the one this
    process keeps busy, so none on two cores; else 1); the files are the same byte for byte
    whatever the count. Workers are spawned, so, as always with
    multiprocessing, a calling script needs an ``if __name__ == "__main__":`` guard. Frame files left from an earlier, longer run
    are removed so ``frames/`` holds this run only. Check ``out_dir`` first with
    :func:`check_out_dir`.

    >>> import tempfile
    >>> scene = Scene("demo", np.zeros((0, 5)), np.zeros((0, 3)), np.full(1, 8.0), 100.0)
    >>> snaps = [Snapshot(0.0, 0, np.array([[0.0, 0.0], [0.0, 100.0]]), np.zeros(1), np.zeros(1))]
    >>> with tempfile.TemporaryDirectory() as out:
    ...     [p.name for p in export_run(out, scene, snaps, size=(64, 48), progress=False)]
    ['000000.png', 'run.gif', 'motion.json']
    """
    snapshots = tuple(snapshots)
    check_run(scene, snapshots)
    size = check_export_size(size)
    check_compress_level(png_compression)
    if mp4:
        check_video()
    resolved_theme = theme if isinstance(theme, Theme) else load_theme(theme)
    workers = _worker_count(workers, len(snapshots))
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    stride = math.ceil(scene.fps / GIF_MAX_FPS - 1e-9) if gif else 0
    job = _Job(
        scene=scene,
        snapshots=snapshots,
        camera=Camera.fit(scene, snapshots, size),
        theme=resolved_theme,
        png=frames or apng,
        gif_stride=stride,
        png_compression=png_compression,
        mp4=mp4,
    )
    samples = _sample_indices(len(snapshots), SHEET_THUMBS)
    show_progress = progress and sys.stderr.isatty()
    try:
        written = _write_frames(out, job, workers, samples, frames, gif, apng, mp4, show_progress)
    finally:
        # The colour table takes a few MB: keep it no longer than the export that needed it.
        quantizer.cache_clear()
    if sheet:
        written.append(
            write_atomic(
                out / "sheet.png", png_bytes(_contact_sheet(job, samples), job.png_compression)
            )
        )
    if motion:
        written.append(write_motion(out, scene, snapshots))
    return written


def _write_frames(
    out: Path,
    job: _Job,
    workers: int,
    samples: Sequence[int],
    frames: bool,
    gif: bool,
    apng: bool,
    mp4: bool,
    progress: bool,
) -> list[Path]:
    """Draw every frame once and stream it to the PNG frames, the GIF and the APNG."""
    count = len(job.snapshots)
    size = job.camera.size
    frame_paths: list[Path] = []
    animations: list[Path] = []
    frames_dir = out / "frames"
    if frames:
        if frames_dir.is_symlink():
            raise ValueError(f"{frames_dir} is a symlink; frames are written only inside {out}")
        frames_dir.mkdir(exist_ok=True)
    with (
        _pool(job, workers) as pool,
        progress_bar("rendering", count, enabled=progress) as update,
        ExitStack() as files,
    ):
        palette = None
        gif_writer = apng_writer = None
        if gif:
            styles = job.theme.effector_styles(len(job.scene.effectors))
            palette = build_palette(
                _sample_colors(job, pool, samples),
                job.theme,
                [c for style in styles for c in style.colors()],
            )
            animations.append(out / "run.gif")
            gif_writer = GifWriter(files.enter_context(atomic_open(animations[-1])), size, palette)
            durations = gif_durations(
                math.ceil(count / job.gif_stride), job.scene.fps, job.gif_stride
            )
        if apng:
            animations.append(out / "run.png")
            apng_file = files.enter_context(atomic_open(animations[-1]))
            apng_writer = ApngWriter(apng_file, count, size, job.scene.fps)
        video = None
        if mp4:
            animations.append(out / "run.mp4")
            video = files.enter_context(Mp4Writer(animations[-1], even_size(size), job.scene.fps))
        for index, (png, indices, rgb) in enumerate(_payloads(job, pool, workers, palette)):
            if frames:
                assert png is not None
                frame_paths.append(write_atomic(frames_dir / f"{index:06d}.png", png))
            if gif_writer is not None and indices is not None:
                gif_writer.add(indices, durations[index // job.gif_stride])
            if apng_writer is not None:
                assert png is not None
                apng_writer.add(png)
            if video is not None:
                assert rgb is not None
                video.add(rgb)
            update(index + 1)
        # Trailers last, inside the block: the atomic files are renamed into place on its exit.
        if gif_writer is not None:
            gif_writer.close()
        if apng_writer is not None:
            apng_writer.close()
    if frames:
        _remove_stale_frames(frames_dir, count)
    return frame_paths + animations


def _remove_stale_frames(frames_dir: Path, count: int) -> None:
    for path in frames_dir.iterdir():
        if _FRAME_NAME.fullmatch(path.name) and int(path.stem) >= count:
            path.unlink()
