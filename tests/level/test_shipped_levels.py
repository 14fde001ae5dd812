"""Every shipped level is valid and ends with the status it was designed for, with its own solver."""

import math

import numpy as np
import pytest

from ikgame.level.library import LEVELS_DIR, shipped_levels
from ikgame.level.loader import load_level
from ikgame.level.model import ReachStep
from ikgame.level.tools import level_rows, validate_files
from ikgame.sim import Simulation

LEVELS = shipped_levels()


def test_the_library_teaches_at_least_twelve_lessons_in_order():
    names = [p.name for p in LEVELS]
    assert len(names) >= 12
    assert names[:3] == ["01_first_reach.toml", "02_tentacle.toml", "03_elbow_limits.toml"]
    assert [int(n[:2]) for n in names] == list(range(1, len(names) + 1))


def test_every_shipped_level_is_valid():
    assert validate_files(LEVELS) == []
    assert validate_files([LEVELS_DIR]) == []


@pytest.mark.parametrize("path", LEVELS, ids=lambda p: p.stem)
def test_a_level_dumped_validates_to_the_same_level(path):
    level = load_level(path)
    assert type(level).model_validate(level.model_dump(by_alias=True, exclude_unset=True)) == level


def test_every_shipped_level_says_what_it_teaches():
    for row in level_rows():
        assert len(row["description"]) >= 80, row["file"]
        if row["expect"] == "failed":
            assert "meant to fail" in row["description"], row["file"]


def test_every_shipped_level_points_editors_at_the_schema():
    for path in LEVELS:
        assert path.read_text().startswith("#:schema ../assets/level.schema.json\n"), path.name


@pytest.mark.parametrize("path", LEVELS, ids=[p.stem for p in LEVELS])
def test_shipped_level_ends_as_designed(path):
    level = load_level(path)
    sim = Simulation(level, record=False)
    result = sim.run()
    failed = [f"{s.index}:{s.kind} {s.note}" for s in result.steps if not s.passed]
    failed += [f"goal {g.name}" for g in result.goals if not g.passed]
    assert result.status == level.level.expect, failed
    assert 0.0 <= result.score <= 100.0
    if level.level.expect == "failed":
        _assert_rests_pointing_at_the_last_target(sim, level)


def _assert_rests_pointing_at_the_last_target(sim: Simulation, level) -> None:
    """The failure state: stretched toward the unreachable target and still, not spinning."""
    target = np.array([s for s in level.script if isinstance(s, ReachStep)][-1].reach)
    points = sim.joint_positions()
    direction, wanted = points[-1] - points[0], target - points[0]
    cos = direction @ wanted / (np.linalg.norm(direction) * np.linalg.norm(wanted))
    assert cos > math.cos(math.radians(3.0))
    assert np.max(np.abs(sim.world.joint_velocities())) < 0.05
