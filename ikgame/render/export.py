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

import io
import json
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
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from ikgame._files import atomic_open, write_atomic
from ikgame._progress import progress_bar
from ikgame.render.animation import ApngWriter, GifWriter, build_palette, gif_durations, quantizer
from ikgame.render.camera import Camera
from ikgame.render.pillow import render_snapshot
from ikgame.render.theme import Theme, load_theme
from ikgame.render.video import Mp4Writer, check_video, even_size
from ikgame.snapshot import Scene, Snapshot

__all__ = ["check_out_dir", "export_run", "motion_json", "parse_size", "trail_at", "write_motion"]

MIN_SIDE = 16  # px: below this the HUD and markers cannot fit
MAX_SIDE = 3840  # px, either side
MAX_PIXELS = 3840 * 2160  # a 4K frame; more is a typo or a hostile level, not a devlog GIF
TRAIL_SECONDS = 1.5  # s of end-effector path drawn behind it
GIF_MAX_FPS = 50.0  # browsers play GIF delays under 2 cs as 10 cs, so faster runs drop frames
SHEET_THUMBS = 12
SHEET_COLUMNS = 4
SHEET_THUMB_WIDTH = 320  # px, at most
CHUNK = 8  # frames per worker task: large enough to amortise the round trip, small to balance
PARALLEL_MIN_FRAMES = 48  # shorter runs finish before worker processes would have started
MAX_AUTO_WORKERS = 8
WORKER_PARENT_POLL_S = 0.5  # how soon a worker notices its parent is gone, s
_FRAME_NAME = re.compile(r"\d{6}\.png")
_SIZE = re.compile(r"(-?\d+)\s*[xX]\s*(-?\d+)")


# -- input checks --------------------------------------------------------------------------------


def parse_size(text: str) -> tuple[int, int]:
    """Parse ``"WIDTHxHEIGHT"`` into ``(width, height)``, within the export size limits.

    >>> parse_size("960x540")
    (960, 540)
    """
    match = _SIZE.fullmatch(text.strip()) if isinstance(text, str) else None
    if match is None:
        raise ValueError(f"size must be WIDTHxHEIGHT in pixels, like 960x540; got {text!r}")
    return _check_export_size((int(match[1]), int(match[2])))


def _check_export_size(size: object) -> tuple[int, int]:
    try:
        width, height = size  # type: ignore[misc]
    except (TypeError, ValueError) as exc:
        raise ValueError(f"size must be a pair (width, height), got {size!r}") from exc
    if any(isinstance(v, bool) or not isinstance(v, int | np.integer) for v in (width, height)):
        raise ValueError(f"size must be whole pixels (width, height), got {size!r}")
    if not (
        MIN_SIDE <= width <= MAX_SIDE
        and MIN_SIDE <= height <= MAX_SIDE
        and width * height <= MAX_PIXELS
    ):
        raise ValueError(
            f"size {width}x{height} is out of range: each side must be {MIN_SIDE}..{MAX_SIDE} px "
            f"and the frame at most {MAX_PIXELS} pixels (3840x2160)"
        )
    return int(width), int(height)


def check_out_dir(path: str | os.PathLike[str], force: bool) -> Path:
    """Return ``path`` as a Path if an export may write there, or raise ``ValueError``.

    A missing or empty folder is fine; a folder with files in it only with ``force``.

    >>> check_out_dir("runs/not-there-yet", force=False).name
    'not-there-yet'
    """
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise ValueError(f"output path {out} exists and is not a folder")
    if out.is_dir() and not force and any(out.iterdir()):
        raise ValueError(f"output folder {out} is not empty; use --force to overwrite its files")
    return out


def _check_run(scene: Scene, snapshots: Sequence[Snapshot]) -> None:
    if not snapshots:
        raise ValueError("no snapshots to export")
    if not (math.isfinite(scene.fps) and scene.fps > 0):
        raise ValueError(f"scene.fps must be a positive number, got {scene.fps!r}")


# -- baked motion --------------------------------------------------------------------------------


def motion_json(scene: Scene, snapshots: Sequence[Snapshot]) -> dict[str, Any]:
    """The run as keyframes a game engine can import: one entry per recorded frame.

    Each frame has every joint's local angle (radians and degrees), every link's world angle,
    the world positions of the joints (base first, end effector last), the target and the
    solver's status. Positions are world px with y up; NaN errors become null.

    >>> scene = Scene("demo", np.zeros((0, 5)), np.zeros((0, 3)), np.full(1, 8.0), 100.0)
    >>> snap = Snapshot(0.0, 0, np.array([[0.0, 0.0], [0.0, 100.0]]), np.array([1.5708]),
    ...                 np.array([1.5708]))
    >>> motion = motion_json(scene, [snap])
    >>> motion["link_lengths"], motion["frames"][0]["angles_deg"]
    ([100.0], [90.0002])
    """
    return _motion_header(scene, snapshots) | {
        "frames": [_motion_frame(snap) for snap in snapshots]
    }


def _motion_header(scene: Scene, snapshots: Sequence[Snapshot]) -> dict[str, Any]:
    _check_run(scene, snapshots)
    first = np.asarray(snapshots[0].joints, dtype=float)
    lengths = np.linalg.norm(np.diff(first, axis=0), axis=1)
    return {
        "format": "ikgame-motion",
        "version": 1,
        "level": scene.level_name,
        "fps": float(scene.fps),
        "frame_count": len(snapshots),
        "duration": _round(len(snapshots) / scene.fps, 6),
        "units": {"length": "px", "angle": "rad, and deg in *_deg", "time": "s", "y_axis": "up"},
        "conventions": {
            "angles": "local joint angle of each link relative to its parent link, counter-clockwise",
            "world_angles": "each link's direction relative to +x, counter-clockwise",
            "joints": "world positions: the base, each following joint, then the end effector",
        },
        "link_count": len(lengths),
        "link_lengths": [_round(v, 3) for v in lengths],
        "link_widths": [_round(v, 3) for v in np.asarray(scene.link_widths, dtype=float)],
    }


def _motion_frame(snap: Snapshot) -> dict[str, Any]:
    angles = np.asarray(snap.angles, dtype=float)
    error = float(snap.error)
    return {
        "time": _round(snap.time, 6),
        "tick": int(snap.tick),
        "step_index": int(snap.step_index),
        "angles_rad": [_round(a, 6) for a in angles],
        "angles_deg": [_round(a, 4) for a in np.degrees(angles)],
        "world_angles_rad": [_round(a, 6) for a in np.asarray(snap.world_angles, dtype=float)],
        "joints": [[_round(x, 3), _round(y, 3)] for x, y in np.asarray(snap.joints, dtype=float)],
        "target": None if snap.target is None else [_round(v, 3) for v in snap.target],
        "error": _round(error, 3) if math.isfinite(error) else None,
        "solver_status": str(snap.solver_status),
        "torque_limited": [bool(v) for v in np.asarray(snap.torque_limited, dtype=bool)],
    }


def _round(value: float, digits: int) -> float:
    # +0.0 turns -0.0 into 0.0, which would otherwise print as "-0.0" in the keyframes.
    return round(float(value), digits) + 0.0


def _write_motion(handle: IO[bytes], scene: Scene, snapshots: Sequence[Snapshot]) -> None:
    """The motion as JSON: an indented header, then one line per frame so runs diff well.

    Streamed a frame at a time: the whole document of a long run of many links would take
    gigabytes as Python objects.
    """
    head = json.dumps(_motion_header(scene, snapshots), indent=2, allow_nan=False)
    handle.write(f'{head[:-2]},\n  "frames": [\n'.encode())
    for i, snap in enumerate(snapshots):
        line = json.dumps(_motion_frame(snap), allow_nan=False)
        handle.write((",\n    " if i else "    ").encode() + line.encode())
    handle.write(b"\n  ]\n}\n")


# -- one frame -----------------------------------------------------------------------------------


def trail_at(snapshots: Sequence[Snapshot], index: int, fps: float) -> np.ndarray:
    """The end effector's path over the last ``TRAIL_SECONDS`` up to frame ``index``, (k, 2).

    Read from the snapshot list alone, so any frame can be drawn without drawing the others.

    >>> snaps = [Snapshot(i / 30, i, np.array([[0.0, 0.0], [i, 1.0]]), np.zeros(1), np.zeros(1))
    ...          for i in range(3)]
    >>> trail_at(snaps, 2, 30.0).tolist()
    [[0.0, 1.0], [1.0, 1.0], [2.0, 1.0]]
    """
    start = max(0, index - max(1, round(TRAIL_SECONDS * fps)))
    return np.array([snap.joints[-1] for snap in snapshots[start : index + 1]], dtype=float)


@dataclass(frozen=True)
class _Job:
    """Everything needed to draw any frame of a run; sent once to each worker process."""

    scene: Scene
    snapshots: tuple[Snapshot, ...]
    camera: Camera
    theme: Theme
    png: bool  # encode PNG bytes (frames or APNG)
    gif_stride: int  # every gif_stride-th frame goes into the GIF; 0 without a GIF
    mp4: bool = False  # raw RGB of the even-sided frame, for the MP4 encoder

    def render(self, index: int, hud: bool = True) -> Image.Image:
        trail = trail_at(self.snapshots, index, self.scene.fps)
        return render_snapshot(
            self.scene,
            self.snapshots[index],
            self.camera,
            self.theme,
            trail=trail,
            hud=hud,
        )

    def payload(self, index: int, palette: bytes | None) -> tuple[bytes | None, ...]:
        """Frame ``index`` as PNG bytes, as GIF palette indices and as the MP4's RGB bytes
        (None where not wanted)."""
        image = self.render(index)
        png = _png_bytes(image) if self.png else None
        indices = None
        if palette is not None and index % self.gif_stride == 0:
            indices = quantizer(palette).indices(image)
        rgb = None
        if self.mp4:
            rgb = image.crop((0, 0, *even_size(image.size))).tobytes()
        return png, indices, rgb


def _png_bytes(image: Image.Image) -> bytes:
    buffer = io.BytesIO()
    image.save(buffer, format="PNG")
    return buffer.getvalue()


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
    start: int, stop: int, palette: bytes | None
) -> list[tuple[bytes | None, ...]]:
    assert _WORKER_JOB is not None, "worker used without _init_worker"
    payloads = [_WORKER_JOB.payload(i, palette) for i in range(start, stop)]
    # Palette indices are a byte per pixel but mostly runs: compressed they are ~5% of the
    # size, both in the pipe to the main process and in results queued for their turn.
    return [
        (png, None if idx is None else zlib.compress(idx, 1), rgb) for png, idx, rgb in payloads
    ]


def _worker_rgb(index: int) -> bytes:
    assert _WORKER_JOB is not None, "worker used without _init_worker"
    return _WORKER_JOB.render(index).tobytes()


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
        return max(1, min(os.cpu_count() or 1, MAX_AUTO_WORKERS))
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
        initargs=(job, os.getpid()),
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
            pending.append(pool.submit(_worker_payloads, start, min(start + CHUNK, count), palette))

    # A couple of chunks queued per worker keeps them busy while bounding frames held in memory.
    for _ in range(2 * workers):
        submit()
    while pending:
        results = pending.popleft().result()
        submit()
        for png, packed, rgb in results:
            yield png, None if packed is None else zlib.decompress(packed), rgb


def _sample_images(
    job: _Job, pool: ProcessPoolExecutor | None, indices: Sequence[int]
) -> list[Image.Image]:
    if pool is None:
        return [job.render(i) for i in indices]
    return [Image.frombytes("RGB", job.camera.size, raw) for raw in pool.map(_worker_rgb, indices)]


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
) -> list[Path]:
    """Write a run's files into ``out_dir`` (created if missing) and return their paths.

    ``frames/000000.png``... one per snapshot; ``run.gif`` looping, with one shared adaptive
    palette and delays that add up to the run's length (runs above 50 fps keep every 2nd, 3rd...
    frame, as browsers slow faster GIFs down); ``run.png`` an APNG at the exact frame rate;
    ``run.mp4`` H.264 at the run's fps (needs the ``video`` extra; see :mod:`ikgame.render.video`);
    ``sheet.png`` a contact sheet of about 12 frames; ``motion.json`` (see :func:`motion_json`).
    ``workers`` processes draw the frames (None: one per CPU for long runs, else 1); the files
    are the same byte for byte whatever the count. Workers are spawned, so, as always with
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
    _check_run(scene, snapshots)
    size = _check_export_size(size)
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
        mp4=mp4,
    )
    samples = _sample_indices(len(snapshots), SHEET_THUMBS)
    show_progress = progress and sys.stderr.isatty()
    try:
        written = _write_frames(out, job, workers, samples, frames, gif, apng, mp4, show_progress)
    finally:
        # The colour table is 32 MB: keep it no longer than the export that needed it.
        quantizer.cache_clear()
    if sheet:
        written.append(write_atomic(out / "sheet.png", _png_bytes(_contact_sheet(job, samples))))
    if motion:
        written.append(write_motion(out, scene, snapshots))
    return written


def write_motion(
    out_dir: str | os.PathLike[str], scene: Scene, snapshots: Sequence[Snapshot]
) -> Path:
    """Write ``motion.json`` (see :func:`motion_json`) into ``out_dir`` and return its path:
    the baked motion on its own, for a run that draws no pictures."""
    snapshots = tuple(snapshots)
    _check_run(scene, snapshots)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    with atomic_open(out / "motion.json") as handle:
        _write_motion(handle, scene, snapshots)
    return out / "motion.json"


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
            palette = build_palette(_sample_images(job, pool, samples), job.theme)
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
