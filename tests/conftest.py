"""Shared test helpers: small levels built in code, a video probe, a level file for the live
tools, and a numba that cannot compile."""

from __future__ import annotations

import copy
import re
import signal
import subprocess
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

from ikgame.level.model import Level

# Property tests draw the same examples on every run and machine (derandomized, unless a test
# asks otherwise, as the deep fuzzing does); the one health check that times the drawing fails
# only when a shared machine is busy, so it is off.
settings.register_profile("ikgame", derandomize=True, suppress_health_check=[HealthCheck.too_slow])
settings.load_profile("ikgame")


@pytest.fixture
def numba_without_compiler(monkeypatch: pytest.MonkeyPatch) -> str:
    """numba installed but failing to compile anything (``numba.njit`` raises): the compiled
    loops must fall back to Python with a warning. Returns the warning's text to match."""
    numba = pytest.importorskip("numba")

    def broken(*signature: object, **options: object) -> object:
        raise RuntimeError("no compiler here")

    monkeypatch.setattr(numba, "njit", broken)
    return "runs in Python: no compiler here"


@pytest.fixture
def interruptible():
    """Ctrl-C reaches the commands a test starts, however the tests themselves were started.

    A shell that starts a command in the background (``cmd &``, without job control) has it
    ignore SIGINT, and a child inherits an ignored signal: a Python that starts with SIGINT
    ignored installs no KeyboardInterrupt, so the tests of Ctrl-C would see nothing. A handled
    signal is reset to its default in a child instead.
    """
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)


_BASE = {
    "level": {"name": "test", "duration": 6.0},
    "world": {"gravity": [0.0, -900.0]},
    "chain": {
        "links": [{"length": 100.0, "mass": 1.0, "max_torque": 4.0e6, "repeat": 3}],
    },
    "script": [{"reach": [150.0, 150.0]}],
}


def _merge(base: dict, changes: dict) -> dict:
    out = copy.deepcopy(base)
    for key, value in changes.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = _merge(out[key], value)
        else:
            out[key] = value
    return out


@pytest.fixture
def stress_simulation():
    """``stress_simulation(name, solver)``: a simulation of the stress level ``name``
    (``benchmarks/stress_levels/``) with ``solver``, recording nothing."""
    from ikgame.level.loader import load_level
    from ikgame.sim import Simulation

    levels = Path(__file__).resolve().parents[1] / "benchmarks" / "stress_levels"

    def simulate(name: str, solver: str) -> Simulation:
        return Simulation(load_level(levels / f"{name}.toml"), solver=solver, record=False)

    return simulate


@pytest.fixture
def make_level():
    """``make_level(chain={...}, script=[...])``: a small valid level with the given changes."""

    def make(**changes: object) -> Level:
        return Level.model_validate(_merge(_BASE, changes))

    return make


@pytest.fixture
def probe_video():
    """``probe_video(path)``: what ffprobe would say of a video (codec, pixel format, size, fps,
    frame count), read from the stream line of ``ffmpeg -i`` and a full decode, with the ffmpeg
    that imageio-ffmpeg ships; the test is skipped without the video extra."""
    imageio_ffmpeg = pytest.importorskip(
        "imageio_ffmpeg", reason="MP4 export needs the video extra: ikgame[video]"
    )

    def probe(path: Path) -> dict[str, object]:
        proc = subprocess.run(
            [imageio_ffmpeg.get_ffmpeg_exe(), "-hide_banner", "-i", str(path)],
            capture_output=True,
            text=True,
        )
        stream = next(line for line in proc.stderr.splitlines() if "Video:" in line)
        size = re.search(r", (\d+)x(\d+)", stream)
        frames, _ = imageio_ffmpeg.count_frames_and_secs(str(path))
        return {
            "codec": stream.split("Video: ")[1].split()[0],
            "pix_fmt": re.search(r"(yuv\w+)", stream).group(1),
            "size": (int(size.group(1)), int(size.group(2))),
            "fps": float(re.search(r"([\d.]+) fps", stream).group(1)),
            "frames": frames,
        }

    return probe


LIVE_LEVEL = """\
[level]
name = "{name}"
duration = 3.0

[world]
gravity = [0.0, -900.0]
tick_rate = 240
fps = 30

[chain]
base = [0.0, 0.0]
angle = 90.0

[[chain.links]]
length = 100.0
mass = 1.0
limits = [-150.0, 150.0]
max_torque = 4.0e6
repeat = 2

[[script]]
reach = [120.0, 100.0]

[[script]]
reach = [-80.0, 140.0]
"""


@pytest.fixture
def level_text():
    """``level_text(name)``: the TOML of a two-link level of at most 3 s called ``name``."""
    return lambda name="Live": LIVE_LEVEL.format(name=name)


@pytest.fixture
def level_file(tmp_path: Path, level_text) -> Path:
    """A two-link level of at most 3 s in its own folder."""
    folder = tmp_path / "levels"
    folder.mkdir()
    path = folder / "live.toml"
    path.write_text(level_text())
    return path
