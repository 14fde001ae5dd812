"""Data-driven level files: each broken file with its exact messages, each valid one with its
fully-defaulted model (tomli's habit: the fixtures are files, the expectations are pinned)."""

import json
from pathlib import Path

import pytest

from ikgame.level.loader import LevelError, load_level
from ikgame.sim import Simulation

DATA = Path(__file__).resolve().parents[1] / "data" / "levels"
INVALID = sorted((DATA / "invalid").glob("*.toml"))
VALID = sorted((DATA / "valid").glob("*.toml"))


def _messages(path: Path) -> list[str]:
    with pytest.raises(LevelError) as exc:
        load_level(path)
    return [str(p).replace(str(path), path.name) for p in exc.value.problems]


@pytest.mark.parametrize("path", INVALID, ids=[p.stem for p in INVALID])
def test_invalid_level_reports_exactly_its_problems(path):
    expected = path.with_suffix(".txt").read_text(encoding="utf-8").splitlines()
    assert _messages(path) == expected


def test_every_invalid_file_has_its_expectation_and_every_expectation_its_file():
    stems = {p.stem for p in INVALID}
    assert stems == {p.stem for p in (DATA / "invalid").glob("*.txt")}


def test_a_file_with_many_problems_reports_all_of_them_each_on_its_line():
    lines = _messages(DATA / "invalid" / "many_problems.toml")
    assert len(lines) == 9
    assert all(line.split(":")[1].isdigit() for line in lines)


@pytest.mark.parametrize("path", VALID, ids=[p.stem for p in VALID])
def test_valid_level_loads_to_its_pinned_model(path):
    expected = json.loads(path.with_suffix(".expected.json").read_text(encoding="utf-8"))
    assert load_level(path).model_dump(mode="json", by_alias=True) == expected


@pytest.mark.parametrize("path", VALID, ids=[p.stem for p in VALID])
def test_valid_level_runs_to_a_pass(path):
    result = Simulation(load_level(path), record=False).run()
    assert result.status == "passed", [s.note for s in result.steps if not s.passed]
