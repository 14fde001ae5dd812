"""Level files for the live tools: small enough to run to the end in a test."""

from __future__ import annotations

from pathlib import Path

import pytest

LEVEL = """\
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
    return lambda name="Live": LEVEL.format(name=name)


@pytest.fixture
def level_file(tmp_path: Path, level_text) -> Path:
    """A two-link level of at most 3 s in its own folder."""
    folder = tmp_path / "levels"
    folder.mkdir()
    path = folder / "live.toml"
    path.write_text(level_text())
    return path
