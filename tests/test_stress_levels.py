"""The stress levels of the motion-quality suite load, validate, and mean what they say.

The suite itself (benchmarks/quality.py) is a benchmark and is not run here; these tests check
its inputs: every reach target the suite counts as reachable has a witness pose inside the
limits, clear of the obstacles and within the torque budget (for a tree, one pose meeting every
target aimed at then, together), every target it expects to fail is out of reach for the reason
it names, and a creature's legs can reach the ground under them wherever the script carries it.
"""

import dataclasses
import importlib
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from ikgame.control.gait import Terrain
from ikgame.level.loader import load_level
from ikgame.level.model import ReachStep, SetStep, follow_duration
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


def _aimed(path: Path) -> list[tuple[int, ReachStep, str, dict[str, tuple[float, float]]]]:
    """Each reach step as :func:`_reach_steps` gives it, with every target aimed at while it
    runs: its own, and the ones earlier steps left on the other effectors (targets persist)."""
    level = load_level(path)
    steps = [step for _, step in expand_script(level.script)]
    reach = {i: (step, kind) for i, step, kind in _reach_steps(path)}
    aimed: dict[str, tuple[float, float]] = {}
    out = []
    for i, step in enumerate(steps):
        if i in reach:
            aimed |= quality.step_targets(level, step)
            out.append((i, step, reach[i][1], dict(aimed)))
        elif hasattr(step, "follow"):
            # A follow step leaves its effector somewhere along its path: not a fixed point.
            aimed.pop(step.effector or level.script_effectors[0], None)
    return out


def _links(path: Path, names) -> list[int]:
    chain = load_level(path).chain
    return [chain.effector_links[chain.effector_names.index(name)] for name in names]


def test_the_suite_covers_every_kind_of_stress():
    assert len(LEVELS) >= 17
    kinds = {kind for path in LEVELS for _, _, kind in _reach_steps(path)}
    assert kinds == {
        quality.REACHABLE,
        quality.OUT_OF_REACH,
        quality.TORQUE_BOUND,
        quality.JAMMED,
        quality.CONFLICT,
    }
    counts = {len(load_level(p).chain.expanded_links) for p in LEVELS}
    assert {1, 30, 200} <= counts
    # Trees: two hands aimed at once, and a creature on six legs.
    assert any(
        len(quality.step_targets(load_level(p), step)) >= 2
        for p in LEVELS
        for _, step, _ in _reach_steps(p)
    )
    assert any(len(getattr(load_level(p).gait, "legs", ())) == 6 for p in LEVELS)


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
    for index, step, kind, aimed in _aimed(path):
        if kind == quality.REACHABLE:
            links = _links(path, aimed)
            points = list(aimed.values())
            pose = metrics.find_witness(spec, points, step.tolerance, links=links)
            assert pose is not None, (path.name, index, aimed)
            assert np.all(pose >= spec.lower) and np.all(pose <= spec.upper)


@pytest.mark.parametrize("path", LEVELS, ids=IDS)
def test_every_unreachable_target_is_unreachable_for_the_reason_given(path):
    level = load_level(path)
    spec = quality.chain_spec(level)
    for index, step, kind in _reach_steps(path):
        where = (path.name, index)
        if kind == quality.OUT_OF_REACH:
            distance = math.dist(step.reach, level.chain.base)
            assert spec.reach + step.tolerance < distance < spec.reach + 4 * step.tolerance, where
        elif kind == quality.JAMMED:
            clear = dataclasses.replace(spec, segments=np.zeros((0, 5)), circles=np.zeros((0, 3)))
            assert metrics.find_witness(clear, step.reach, step.tolerance) is not None, where
            assert metrics.find_witness(spec, step.reach, step.tolerance) is None, where
        elif kind == quality.TORQUE_BOUND:
            _assert_no_pose_reaches_within_the_torque_budget(spec, step, where)
        elif kind == quality.CONFLICT:
            _assert_each_target_alone_but_not_all_together(path, spec, step, where)


def _assert_each_target_alone_but_not_all_together(path, spec, step, where) -> None:
    """A conflict: every target of the step has a witness of its own, and two of them lie
    farther apart than their branches can span (no pose meets both: a proof)."""
    aimed = quality.step_targets(load_level(path), step)
    assert len(aimed) >= 2, where
    links = _links(path, aimed)
    points = np.array(list(aimed.values()))
    for link, point in zip(links, points, strict=True):
        alone = metrics.find_witness(spec, point, step.tolerance, links=[link])
        assert alone is not None, (*where, link)
    apart = [
        math.dist(points[i], points[j]) - metrics.span(spec, links[i], links[j])
        for i in range(len(links))
        for j in range(i + 1, len(links))
    ]
    assert max(apart) > 2 * step.tolerance, where


def _assert_no_pose_reaches_within_the_torque_budget(spec, step, where) -> None:
    """Within the chain's length, yet every pose with its tip on the target needs more than the
    base's torque to hold against gravity.

    Under vertical gravity ``g`` the base holds ``|g| sum(w_i y_i)``, where ``y_i`` is link
    ``i``'s horizontal extent (from ``-L_i`` to ``L_i``) and ``w_i`` half its own mass plus all
    the mass beyond it. A tip within tolerance of the target puts ``sum(y_i)`` at least ``X``,
    the target's horizontal distance from the base less the tolerance. The least such torque is
    a linear programme answered greedily: every link starts folded back (``y_i = -L_i``), and
    the extent still missing comes from the links whose unit costs least, which are the outer
    ones (``w`` falls along the chain).
    """
    assert spec.gravity[0] == 0.0, where
    assert math.dist(step.reach, spec.base) < spec.reach, where  # only the torque is in the way
    lengths, masses = np.asarray(spec.lengths), np.asarray(spec.masses)
    weights = masses / 2 + (masses.sum() - np.cumsum(masses))
    missing = abs(step.reach[0] - spec.base[0]) - step.tolerance + lengths.sum()
    assert missing > 0.0, where
    extents = -lengths.copy()
    for i in reversed(range(len(lengths))):
        raised = min(2 * lengths[i], missing)
        extents[i] += raised
        missing -= raised
    assert missing <= 0.0, where
    least = abs(spec.gravity[1]) * float(weights @ extents)
    assert least > spec.max_torque[0], (where, least)


def _creatures() -> list[Path]:
    return [p for p in LEVELS if load_level(p).gait is not None]


@pytest.mark.parametrize("path", _creatures(), ids=[p.stem for p in _creatures()])
def test_a_creatures_feet_can_reach_the_ground_wherever_its_body_goes(path):
    """Along the body's path (each set step moves it straight) the ground, grown by the foot's
    radius, lies under every foot's landing spots (its rest spot and half a stride either side,
    the rest spot where the start pose puts the foot): within the gait's reach below the rest
    spot (the leg's length less the rest spot's distance from the hip), and from the hip no
    farther than the leg stretched, no closer than the leg folded as far as its limits allow."""
    level = load_level(path)
    spec = quality.chain_spec(level)
    chain = level.chain
    start = np.clip(
        np.radians([link.angle for link in chain.expanded_links]), spec.lower, spec.upper
    )
    starts, ends = metrics.link_segments(spec, start)
    stops = [np.array(chain.base, dtype=float)]
    for _, step in expand_script(level.script):
        if isinstance(step, SetStep) and step.set.base is not None:
            stops.append(np.array(step.set.base, dtype=float))
    assert math.dist(stops[0], stops[-1]) >= 800.0
    mask = metrics.ancestors(spec)
    legs = _links(path, level.gait.legs)
    ground = Terrain(*_grown(spec, float(spec.widths[legs].max()) / 2.0))
    base = np.array(chain.base, dtype=float)
    for link in legs:
        branch = np.flatnonzero(mask[link])
        hip, rest = starts[branch[0]] - base, ends[link] - base
        stretched = spec.lengths[branch].sum()
        spare = stretched - math.dist(hip, rest)
        folded = _shortest_reach(spec.lengths[branch], spec.lower[branch], spec.upper[branch])
        for a, b in zip(stops[:-1], stops[1:], strict=True):
            for body in np.linspace(a, b, 200):
                for ahead in (-level.gait.stride / 2, 0.0, level.gait.stride / 2):
                    x = body[0] + rest[0] + ahead
                    below = ground.ground_below(x, body[1])
                    where = (path.name, level.chain.expanded_links[link].name, round(x, 1))
                    assert below is not None, where
                    assert body[1] + rest[1] - below < spare, where
                    reach = math.dist(body + hip, (x, below))
                    assert folded < reach < stretched, where


def _grown(spec, by: float) -> tuple[np.ndarray, np.ndarray]:
    segments, circles = spec.segments.copy(), spec.circles.copy()
    segments[:, 4] += by
    circles[:, 2] += by
    return segments, circles


def _shortest_reach(lengths: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> float:
    """The closest a two-link leg's foot comes to its hip, bent as far as the knee allows."""
    assert len(lengths) == 2
    bend = max(abs(lower[1]), abs(upper[1]))
    return float(math.sqrt(lengths[0] ** 2 + lengths[1] ** 2 + 2 * lengths.prod() * math.cos(bend)))


def test_a_level_loads_at_another_tick_rate():
    level = quality.load(LEVELS[0], tick_rate=480)
    assert level.world.tick_rate == 480
    assert level.script == load_level(LEVELS[0]).script
