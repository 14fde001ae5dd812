"""The stress levels of the motion-quality suite load, validate, and mean what they say.

The suite itself (benchmarks/quality.py) is a benchmark and is not run here; these tests check
its inputs: every reach target the suite counts as reachable has a witness pose inside the
limits, clear of the obstacles and within the torque budget, and every target it expects to
fail is out of reach for the reason it names.
"""

import dataclasses
import importlib
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from ikgame.level.loader import load_level
from ikgame.level.model import ReachStep, follow_duration
from ikgame.level.script import expand_script
from ikgame.level.tools import validate_files

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"
sys.path.insert(0, str(BENCHMARKS))
quality = importlib.import_module("quality")
metrics = importlib.import_module("_quality_metrics")

LEVELS = quality.stress_levels()
IDS = [p.stem for p in LEVELS]


def _reach_steps(path: Path) -> list[tuple[int, ReachStep, str]]:
    """(index as the run counts steps, step, expected kind) of each reach step of a level."""
    expect = quality.EXPECTATIONS.get(path.name, {})
    steps = expand_script(load_level(path).script)
    return [
        (i, step, expect.get(i, quality.REACHABLE))
        for i, (_, step) in enumerate(steps)
        if isinstance(step, ReachStep)
    ]


def test_the_suite_covers_every_kind_of_stress():
    assert len(LEVELS) >= 15
    kinds = {kind for path in LEVELS for _, _, kind in _reach_steps(path)}
    assert kinds == {quality.REACHABLE, quality.OUT_OF_REACH, quality.TORQUE_BOUND, quality.JAMMED}
    counts = {len(load_level(p).chain.expanded_links) for p in LEVELS}
    assert {1, 30, 200} <= counts


def test_every_stress_level_is_valid():
    assert validate_files(LEVELS) == []
    assert validate_files([quality.STRESS_DIR]) == []


def test_every_stress_level_says_what_it_tests_and_points_editors_at_the_schema():
    for path in LEVELS:
        assert path.read_text().startswith("#:schema ../../assets/level.schema.json\n"), path.name
        assert "reachable" in load_level(path).level.description, path.name


def test_the_quick_set_and_the_expectations_name_stress_levels():
    names = {p.name for p in LEVELS}
    assert set(quality.QUICK) <= names
    assert set(quality.EXPECTATIONS) <= names
    for name, table in quality.EXPECTATIONS.items():
        reach = {i for i, _, _ in _reach_steps(quality.STRESS_DIR / name)}
        assert set(table) <= reach, name


def test_each_level_lasts_long_enough_for_every_step_to_time_out():
    for path in LEVELS:
        level = load_level(path)
        steps = [s for _, s in expand_script(level.script)]
        needed = sum(getattr(s, "timeout", 0.0) + getattr(s, "wait", 0.0) for s in steps)
        needed += sum(s.lead_in + follow_duration(s) for s in steps if hasattr(s, "follow"))
        assert level.level.duration >= needed, path.name


@pytest.mark.parametrize("path", LEVELS, ids=IDS)
def test_every_reachable_target_has_a_witness_pose(path):
    spec = quality.chain_spec(load_level(path))
    for index, step, kind in _reach_steps(path):
        if kind == quality.REACHABLE:
            pose = metrics.find_witness(spec, step.reach, step.tolerance)
            assert pose is not None, (path.name, index, step.reach)
            assert np.all(pose >= spec.lower) and np.all(pose <= spec.upper)


@pytest.mark.parametrize("path", LEVELS, ids=IDS)
def test_every_unreachable_target_is_unreachable_for_the_reason_given(path):
    level = load_level(path)
    spec = quality.chain_spec(level)
    for index, step, kind in _reach_steps(path):
        where = (path.name, index)
        distance = math.dist(step.reach, level.chain.base)
        if kind == quality.OUT_OF_REACH:
            assert spec.reach + step.tolerance < distance < spec.reach + 4 * step.tolerance, where
        elif kind == quality.JAMMED:
            clear = dataclasses.replace(spec, segments=np.zeros((0, 5)), circles=np.zeros((0, 3)))
            assert metrics.find_witness(clear, step.reach, step.tolerance) is not None, where
            assert metrics.find_witness(spec, step.reach, step.tolerance) is None, where
        elif kind == quality.TORQUE_BOUND:
            _assert_no_pose_reaches_within_the_torque_budget(spec, step, where)


def _assert_no_pose_reaches_within_the_torque_budget(spec, step, where) -> None:
    """Exhaustive over a 0.25 deg grid of a two-link chain's joint space."""
    assert len(spec.lengths) == 2, where
    grid = np.radians(np.arange(-180.0, 180.0, 0.25))
    a, b = (g.ravel() for g in np.meshgrid(grid, grid))
    inside = (a >= spec.lower[0]) & (a <= spec.upper[0]) & (b >= spec.lower[1])
    inside &= b <= spec.upper[1]
    a, b = a[inside], b[inside]
    first = spec.base_angle + a
    elbow = spec.base + spec.lengths[0] * np.column_stack((np.cos(first), np.sin(first)))
    tip = elbow + spec.lengths[1] * np.column_stack((np.cos(first + b), np.sin(first + b)))
    near = np.hypot(*(tip - step.reach).T) <= step.tolerance
    assert near.any(), where  # within the chain's length: only the torque stands in the way
    assert spec.gravity[0] == 0.0, where
    gravity_y = spec.gravity[1]
    com_x = np.column_stack(((spec.base[0] + elbow[:, 0]) / 2, (elbow[:, 0] + tip[:, 0]) / 2))
    base_torque = np.abs(gravity_y * (spec.masses * (com_x - spec.base[0])).sum(axis=1))
    assert base_torque[near].min() > spec.max_torque[0], where


def test_a_level_loads_at_another_tick_rate():
    level = quality.load(LEVELS[0], tick_rate=480)
    assert level.world.tick_rate == 480
    assert level.script == load_level(LEVELS[0]).script
