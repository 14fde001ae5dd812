"""Solver comparison: one run per solver, sane metrics, deterministic JSON, the plot's data.

The drawing itself is tested on synthetic data in tests/render/test_plot.py."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from PIL import Image
from rich.console import Console

from ikgame.compare import (
    DEFAULT_SOLVERS,
    _mean_squared_jerk,
    _tracking_error,
    compare_level,
    comparison_table,
    squared_jerk,
    write_comparison,
)
from ikgame.kinematics import SOLVERS
from ikgame.level.model import Level
from ikgame.level.script import StepOutcome
from ikgame.render.plot import SOLVER_COLOURS

FIRST_TARGET = (180.0, 120.0)
TOLERANCE = 6.0

SHORT_LEVEL = {
    "level": {"name": "Compare test", "duration": 3.0},
    "world": {"gravity": [0.0, 0.0], "tick_rate": 120},
    "chain": {"links": [{"length": 80.0, "limits": [-150.0, 150.0], "repeat": 3}]},
    "script": [
        {"reach": list(FIRST_TARGET), "tolerance": TOLERANCE, "hold": 0.2, "timeout": 1.5},
        {"reach": [-120.0, 150.0], "tolerance": TOLERANCE, "hold": 0.2, "timeout": 1.5},
    ],
}


def _level(**changes: object) -> Level:
    return Level.model_validate({**SHORT_LEVEL, **changes})


@pytest.fixture(scope="module")
def comparison():
    return compare_level(_level())


def _without_wall_clock(data: dict) -> dict:
    for run in data["solvers"].values():
        del run["wall_clock"]
    return data


def test_default_compares_every_registered_solver_seed_pair_first():
    assert sorted(DEFAULT_SOLVERS) == sorted(SOLVERS)
    assert DEFAULT_SOLVERS[:2] == ("ccd", "jacobian_transpose")


def test_one_run_per_solver_in_the_order_asked(comparison):
    assert [run.solver for run in comparison.runs] == list(DEFAULT_SOLVERS)
    assert comparison.run("dls").solver == "dls"


def test_targets_and_tolerance_are_read_off_the_level(comparison):
    np.testing.assert_allclose(comparison.reach_points, [FIRST_TARGET, (-120.0, 150.0)])
    assert comparison.tolerance == TOLERANCE


def test_metrics_are_finite_and_sensible(comparison):
    start = comparison.start_pose[-1]
    straight = math.dist(start, FIRST_TARGET)
    for run in comparison.runs:
        assert run.status in {"passed", "failed", "diverged"}
        assert 0.0 <= run.score <= 100.0
        assert len(run.steps) == 2
        assert run.ticks == len(run.times) == len(run.errors) == len(run.path) - 1
        assert run.angles.shape == (run.ticks + 1, 3)
        assert 0.0 < run.sim_time <= 3.0 + 1e-9
        assert run.path_length >= straight - TOLERANCE, run.solver
        assert math.isfinite(run.mean_squared_jerk) and run.mean_squared_jerk >= 0.0
        assert run.tracking_error is None  # no follow step in this level
        # A target every tick: solved on each, or on every other tick (60 Hz at 120 ticks/s)
        # while the answer has arrived near the chain.
        assert math.ceil(run.ticks / 2) <= run.solver_calls <= run.ticks
        assert run.iterations_per_tick >= 0.0
        assert 0.0 <= run.torque_limited <= 1.0
        assert run.solver_us_per_tick is not None and run.solver_us_per_tick > 0.0
        np.testing.assert_allclose(run.path[0], start)
        for step in run.steps:
            if step.reached:
                assert 0.0 <= step.time_to_reach <= 1.5
                assert step.final_error <= TOLERANCE


def test_compare_json_is_deterministic_apart_from_wall_clock(comparison, tmp_path):
    again = compare_level(_level())
    first = json.loads(write_comparison(tmp_path / "a", comparison)[0].read_text())
    second = json.loads(write_comparison(tmp_path / "b", again)[0].read_text())
    assert list(first) == ["level", "tick_rate", "note", "units", "solvers"]
    assert list(first["solvers"]) == list(DEFAULT_SOLVERS)
    assert "wall_clock" in first["note"]
    assert _without_wall_clock(first) == _without_wall_clock(second)


def test_write_comparison_writes_json_and_a_png_with_every_solver(comparison, tmp_path):
    paths = write_comparison(tmp_path / "out", comparison)
    assert [p.name for p in paths] == ["compare.json", "compare.png"]
    with Image.open(paths[1]) as image:
        assert image.size == (1200, 560)
        pixels = np.asarray(image.convert("RGB"), dtype=int).reshape(-1, 3)
    for solver in DEFAULT_SOLVERS:
        distance = np.abs(pixels - SOLVER_COLOURS[solver]).sum(axis=1)
        assert (distance < 30).sum() > 100, solver


def test_plot_data_is_the_runs_and_the_level_as_measured(comparison):
    plot = comparison.plot_data()
    assert plot.level == comparison.level and plot.tolerance == TOLERANCE
    assert [t.solver for t in plot.traces] == [r.solver for r in comparison.runs]
    for trace, run in zip(plot.traces, comparison.runs, strict=True):
        assert (trace.status, trace.sim_time, trace.path_length) == (
            run.status,
            run.sim_time,
            run.path_length,
        )
        np.testing.assert_array_equal(trace.errors, run.errors)
        np.testing.assert_array_equal(trace.path, run.path)
        assert trace.target_trails == ()  # reach steps only
    np.testing.assert_array_equal(plot.reach_points, comparison.reach_points)
    np.testing.assert_array_equal(plot.start_pose, comparison.start_pose)


def test_table_has_a_row_per_solver(comparison):
    console = Console(width=240, record=True)
    console.print(comparison_table(comparison))
    text = console.export_text()
    for solver in DEFAULT_SOLVERS:
        assert solver in text
    assert "reach 2 (s)" in text and "µs/tick" in text


def test_ticks_without_a_target_break_the_error_line_and_skip_the_solver():
    level = _level(
        level={"name": "wait first", "duration": 1.0},
        script=[{"wait": 0.25}, {"reach": list(FIRST_TARGET)}],
    )
    run = compare_level(level, ["ccd"]).runs[0]
    assert np.isnan(run.errors[:30]).all() and np.isfinite(run.errors[-1])
    # No call in the 30 ticks without a target; one every tick or every other after them.
    assert math.ceil((run.ticks - 30) / 2) <= run.solver_calls <= run.ticks - 30


def test_a_follow_step_gives_a_tracking_error_and_a_target_trail():
    level = _level(
        level={"name": "follow", "duration": 2.0},
        script=[
            {
                "follow": "circle",
                "center": [0.0, 150.0],
                "radius": 40.0,
                "period": 1.0,
                "duration": 1.0,
                "lead_in": 0.25,
            }
        ],
    )
    comparison = compare_level(level, ["ccd", "dls"])
    for run in comparison.runs:
        assert run.tracking_error is not None and 0.0 <= run.tracking_error < 40.0
    for trace in comparison.plot_data().traces:
        (trail,) = trace.target_trails
        np.testing.assert_allclose(np.hypot(trail[:, 0], trail[:, 1] - 150.0), 40.0)
    assert comparison.reach_points.shape == (0, 2)
    console = Console(width=240, record=True)
    console.print(comparison_table(comparison))
    text = console.export_text()
    assert "tracking error (px)" in text and "final error" not in text


def test_progress_rises_to_one():
    seen = []
    compare_level(_level(level={"name": "p", "duration": 0.5}), ["ccd", "fabrik"], seen.append)
    assert seen == sorted(seen) and seen[-1] == 1.0 and 0.4 < seen[len(seen) // 2] < 0.6


@pytest.mark.parametrize(
    ("solvers", "message"),
    [
        (["ccd", "newton"], "unknown solver 'newton'; valid solvers: "),
        ([], "name at least one solver"),
        ("ccd", "a list of names, not the string"),
        (["dls", "dls"], "each solver may be compared once"),
    ],
)
def test_bad_solver_lists_are_refused(solvers, message):
    with pytest.raises(ValueError, match=message) as info:
        compare_level(_level(), solvers)
    if "unknown" in message:
        assert all(name in str(info.value) for name in SOLVERS)


def test_asking_for_a_solver_not_compared_names_the_compared_ones(comparison):
    with pytest.raises(ValueError, match="has: ccd, jacobian_transpose, dls, fabrik"):
        comparison.run("newton")


def test_jerk_of_a_cubic_is_six_per_joint_squared():
    dt = 0.01
    t = np.arange(10) * dt
    angles = np.stack([t**3, -(t**3)], axis=1)  # d^3/dt^3 = +-6 rad/s^3
    assert _mean_squared_jerk(angles, dt) == pytest.approx(72.0)
    assert math.isnan(_mean_squared_jerk(angles[:3], dt))


def test_jerk_ignores_the_wrap_of_a_free_joint():
    steady = np.array([[3.12], [3.16], [3.20], [3.24]])  # 0.04 rad/tick, through pi
    angles = (steady + np.pi) % (2 * np.pi) - np.pi
    assert angles[-1, 0] < 0.0
    assert _mean_squared_jerk(angles, 1.0) == pytest.approx(0.0, abs=1e-6)


@pytest.mark.parametrize(("angles", "dt"), [(np.zeros(5), 0.1), (np.zeros((5, 2)), 0.0)])
def test_squared_jerk_refuses_bad_input(angles, dt):
    with pytest.raises(ValueError, match="must be"):
        squared_jerk(angles, dt)


def test_tracking_error_is_the_duration_weighted_mean_of_follow_steps():
    steps = [
        StepOutcome(0, "reach", True, True, 0.5, 1.0, mean_error=50.0, ended=1.0),
        StepOutcome(1, "follow", True, mean_error=2.0, started=1.0, ended=2.0),
        StepOutcome(2, "follow", True, mean_error=5.0, started=2.0, ended=5.0),
    ]
    assert _tracking_error(steps) == pytest.approx((2.0 * 1 + 5.0 * 3) / 4)
    assert _tracking_error(steps[:1]) is None


_CHAIN_RUN_KEYS = [
    "status",
    "score",
    "steps_passed",
    "steps_total",
    "ticks",
    "sim_time",
    "path_length",
    "mean_squared_jerk",
    "tracking_error",
    "iterations_per_tick",
    "torque_limited",
    "solver_calls",
    "steps",
    "wall_clock",
]

TWO_ARMS = {
    "level": {"name": "Two arms", "duration": 2.0},
    "world": {"gravity": [0.0, 0.0], "tick_rate": 120},
    "chain": {
        "angle": 90.0,
        "bones": [
            {"name": "torso", "length": 80.0, "limits": [-20.0, 20.0]},
            {"name": "left", "parent": "torso", "length": 60.0, "repeat": 2, "angle": 60.0},
            {"name": "right", "parent": "torso", "length": 60.0, "repeat": 2, "angle": -60.0},
        ],
    },
    "script": [
        {"reach": {"left": [-110.0, 130.0], "right": [110.0, 140.0]}, "hold": 0.2},
        {
            "follow": "line",
            "effector": "right",
            "from": [110.0, 140.0],
            "to": [60.0, 190.0],
            "duration": 0.5,
        },
    ],
}


def test_a_chain_compares_with_the_keys_it_always_had(comparison):
    for run in comparison.runs:
        assert list(run.as_dict()) == _CHAIN_RUN_KEYS
        assert run.effectors == ("tip",) and run.paths.shape == (run.ticks + 1, 1, 2)
        np.testing.assert_array_equal(run.paths[:, 0], run.path)


def test_a_tree_is_measured_over_every_effector_and_its_solver_timed():
    comparison = compare_level(Level.model_validate(TWO_ARMS), ["ccd", "dls"])
    for run in comparison.runs:
        assert run.effectors == ("left", "right")
        # Every tick aims both hands, through the tree's multi-target solve, which is timed.
        assert run.solver_calls == run.ticks > 0 and run.iterations_per_tick > 0.0
        assert run.solver_us_per_tick is not None and run.solver_us_per_tick > 0.0
        lengths = run.path_lengths
        assert set(lengths) == {"left", "right"} and min(lengths.values()) > 20.0
        assert run.path_length == pytest.approx(sum(lengths.values()))
        data = run.as_dict()
        assert list(data) == [*_CHAIN_RUN_KEYS[:-1], "path_lengths", "wall_clock"]
        assert data["path_lengths"] == {k: pytest.approx(v, rel=1e-5) for k, v in lengths.items()}
        np.testing.assert_allclose(run.paths[-1], run.paths[-1])  # finite
        assert np.isfinite(run.paths).all()
    # Both hands' points of the reach step, and the right hand's line as a moving target.
    np.testing.assert_allclose(comparison.reach_points, [(-110.0, 130.0), (110.0, 140.0)])
    for run, trace in zip(comparison.runs, comparison.plot_data().traces, strict=True):
        # The picture draws both hands' paths and labels their length together.
        assert len(trace.paths) == 2 and trace.path_length == run.path_length
        for j, path in enumerate(trace.paths):
            np.testing.assert_array_equal(path, run.paths[:, j])
        (trail,) = trace.target_trails
        assert trail[0] == pytest.approx((110.0, 140.0), abs=1.0)
        assert trail[-1] == pytest.approx((60.0, 190.0), abs=1.0)


def test_a_trees_start_pose_walks_every_bone_out_and_back_from_the_base():
    level = Level.model_validate(TWO_ARMS)
    pose = compare_level(level.model_copy(update={"script": level.script[:1]}), ["ccd"]).start_pose
    segments = level.chain.start_segments()
    # Base, the root's joint (at the base), each of the 5 bones out and back, the base again.
    assert len(pose) == 2 * len(segments) + 3
    assert pose[0] == pytest.approx((0.0, 0.0)) and pose[-1] == pytest.approx((0.0, 0.0))
    walked = {
        tuple(np.round(np.concatenate([a, b]), 3)) for a, b in zip(pose, pose[1:], strict=False)
    }
    for start, end in segments:
        assert tuple(np.round([*start, *end], 3)) in walked
        assert tuple(np.round([*end, *start], 3)) in walked


def test_a_creature_reports_its_footing_and_its_feet_slip_in_the_table():
    legs = [
        {
            "name": f"hip{i}",
            "at": [x, 0.0],
            "angle": -100.0,
            "length": 50.0,
            "limits": [-170.0, -10.0],
        }
        for i, x in enumerate((30.0, -30.0))
    ]
    feet = [
        {
            "name": f"foot{i}",
            "parent": f"hip{i}",
            "angle": 20.0,
            "length": 50.0,
            "limits": [0.0, 150.0],
        }
        for i in range(2)
    ]
    level = Level.model_validate(
        {
            "level": {"name": "Biped", "duration": 1.5},
            "chain": {"base": [0.0, 110.0], "angle": 0.0, "bones": [*legs, *feet]},
            "obstacles": [{"kind": "segment", "a": [-300.0, 0.0], "b": [300.0, 0.0]}],
            "gait": {"legs": ["foot0", "foot1"], "step_time": 0.2},
            "script": [{"set": {"base": [60.0, 110.0], "over": 1.0}}, {"wait": 1.4}],
        }
    )
    comparison = compare_level(level, ["dls"])
    (run,) = comparison.runs
    assert set(run.footing) == {"foot0", "foot1"}
    assert sum(leg["steps"] for leg in run.footing.values()) > 0
    assert run.as_dict()["footing"] == run.footing
    console = Console(width=240, record=True)
    console.print(comparison_table(comparison))
    text = console.export_text()
    assert "foot slip (px)" in text
    assert f"{max(leg['slip'] for leg in run.footing.values()):.2f}" in text
