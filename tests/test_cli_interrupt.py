"""``ikgame run`` stopped during its export: by Ctrl-C, SIGTERM, or SIGKILL as a supervisor
sends it. No orphan worker, no temporary file after the next run, no folder mixing two runs,
and every frame on disk a whole PNG."""

from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import threading
from pathlib import Path

import pytest
from PIL import Image

ROOT = Path(__file__).resolve().parents[1]
pytestmark = pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads /proc")


# Long enough (900 frames) that the export is still running when the signal comes; small frames
# so that the whole export takes a few seconds when it is not stopped.
LEVEL = """
[level]
name = "long"
duration = 30.0
[chain]
[[chain.links]]
length = 80.0
repeat = 3
[[script]]
reach = [120.0, 100.0]
[[script]]
wait = 30.0
"""
# The same level cut to one frame (five ticks at 240 Hz, at 30 fps): a rerun of it over a
# killed run, which had written at least two frames, leaves a frame too many unless the earlier
# run is cleared first.
ONE_FRAME = LEVEL.replace("duration = 30.0", "duration = 0.02", 1)


def _start(out: Path, *extra: str, level_text: str = LEVEL) -> subprocess.Popen[str]:
    level = out.parent / "long.toml"
    level.write_text(level_text)
    return subprocess.Popen(
        [sys.executable, "-m", "ikgame", "run", str(level), "--out", str(out), "--quiet"]
        + ["--size", "160x90", *extra],
        cwd=ROOT,
        env=os.environ | {"PYTHONPATH": str(ROOT)},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def _wait_for(condition, what: str, limit: float = 120.0) -> None:
    """Poll ``condition`` until it holds; fail after ``limit`` s (a hung run, not a slow one)."""
    pause = threading.Event()
    for _ in range(int(limit / 0.05)):
        if condition():
            return
        pause.wait(0.05)
    pytest.fail(f"gave up waiting for {what}")


def _children(pid: int) -> set[int]:
    found = set()
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            found.add(int(stat.parent.name))
    return found


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def _frames(out: Path) -> list[Path]:
    return sorted((out / "frames").glob("*.png")) if (out / "frames").is_dir() else []


def _temps(out: Path) -> list[Path]:
    return [p for p in out.rglob(".*.tmp")]


# Where in the export the signal lands: right at the start and at a seeded random later frame.
STOP_AT = (2, random.Random(12).randrange(3, 80))


@pytest.mark.parametrize("at", STOP_AT)
@pytest.mark.parametrize(
    "sig, code, word", [(signal.SIGTERM, 143, "terminated"), (signal.SIGINT, 130, "interrupted")]
)
def test_a_stopped_export_exits_cleanly_and_keeps_whole_frames(
    tmp_path, sig, code, word, at, interruptible
):
    out = tmp_path / "out"
    proc = _start(out, "--workers", "2")
    _wait_for(lambda: len(_frames(out)) >= at, f"{at} frames")
    workers = _children(proc.pid)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == code, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"{word}")
    assert "the run was cut short" in lines[0] and "no results.json" in lines[0]
    assert not (out / "results.json").exists()
    assert not _temps(out)
    for frame in _frames(out):
        with Image.open(frame) as image:
            image.verify()
    # Workers and multiprocessing's resource tracker leave on their own, within a second or so.
    _wait_for(lambda: not [pid for pid in workers if _alive(pid)], "the workers to exit", 60)


@pytest.mark.parametrize("at", STOP_AT)
def test_after_sigkill_the_workers_die_and_a_forced_rerun_leaves_one_whole_run(tmp_path, at):
    out = tmp_path / "out"
    proc = _start(out, "--workers", "2")
    _wait_for(lambda: len(_frames(out)) >= at, f"{at} frames")
    workers = _children(proc.pid)
    assert workers, "the export runs in worker processes"
    proc.kill()
    proc.communicate(timeout=60)
    _wait_for(lambda: not [pid for pid in workers if _alive(pid)], "orphaned workers to exit", 60)
    rerun = _start(out, "--force", "--no-gif", level_text=ONE_FRAME)
    _, err = rerun.communicate(timeout=300)
    assert rerun.returncode == 0, err
    assert not _temps(out)
    assert not (out / "run.gif").exists(), "a file of the killed run survived the rerun"
    results = (out / "results.json").read_text()
    frames = _frames(out)
    assert len(frames) == 1 and '"count": 1' in results
