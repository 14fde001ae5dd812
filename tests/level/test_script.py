"""The script at run time: follow paths, easing, lead-in, scoring, set and sequence steps."""

import math

import numpy as np
import pytest

from ikgame.level.model import (
    FOLLOW_SHAPES,
    ReachStep,
    SequenceStep,
    SetStep,
    WaitStep,
)
from ikgame.level.script import EASINGS, ScriptRunner, expand_script, follow_path


def _follow(shape: str, **fields):
    data = {"follow": shape, **fields}
    if "from_" in data:
        data["from"] = data.pop("from_")
    return FOLLOW_SHAPES[shape].model_validate(data)


def _play(runner: ScriptRunner, effector, seconds: float, dt: float = 0.01) -> list:
    """Observe ``effector(time, target)`` every ``dt`` until done or ``seconds`` pass."""
    time, targets = 0.0, []
    while not runner.done and time < seconds - 1e-9:
        target = runner.target
        time = round(time + dt, 9)
        targets.append(None if target is None else target.copy())
        runner.observe(time, dt, np.asarray(effector(time, target), dtype=float))
    return targets


def test_easings_map_zero_to_zero_and_one_to_one_and_never_go_back():
    u = np.linspace(0.0, 1.0, 101)
    for name, ease in EASINGS.items():
        values = np.array([ease(x) for x in u])
        assert values[0] == 0.0 and values[-1] == 1.0, name
        assert np.all(np.diff(values) >= 0), name


def test_circle_goes_round_in_its_direction_from_its_start_angle():
    ccw = follow_path(_follow("circle", center=(10, 20), radius=5, period=4, duration=4))
    cw = follow_path(
        _follow("circle", center=(10, 20), radius=5, period=4, duration=4, direction="cw", start=90)
    )
    assert ccw(0.0) == pytest.approx((15.0, 20.0))
    assert ccw(1.0) == pytest.approx((10.0, 25.0))
    assert cw(0.0) == pytest.approx((10.0, 25.0))
    assert cw(1.0) == pytest.approx((15.0, 20.0))


def test_line_runs_from_its_start_to_its_end_in_its_duration():
    path = follow_path(_follow("line", from_=(0, 0), to=(100, 50), duration=2))
    assert path(0.0) == pytest.approx((0.0, 0.0))
    assert path(1.0) == pytest.approx((50.0, 25.0))
    assert path(2.0) == pytest.approx((100.0, 50.0))


def test_lissajous_one_to_two_is_a_figure_eight_through_its_centre():
    step = _follow(
        "lissajous", center=(0, 100), amplitude=(40, 20), frequency=(0.25, 0.5), duration=4
    )
    path = follow_path(step)
    points = np.array([path(s) for s in np.linspace(0.0, 4.0, 401)])
    assert path(0.0) == pytest.approx((0.0, 100.0))
    assert path(2.0) == pytest.approx((0.0, 100.0), abs=1e-9)
    assert points[:, 0].max() == pytest.approx(40.0, abs=0.1)
    assert points[:, 1].min() == pytest.approx(80.0, abs=0.1)


def test_polyline_moves_at_its_speed_round_corners_and_waits_at_the_end():
    step = _follow("polyline", points=[(0, 0), (30, 0), (30, 40)], speed=10)
    path = follow_path(step)
    assert path(2.0) == pytest.approx((20.0, 0.0))
    assert path(3.0) == pytest.approx((30.0, 0.0))
    assert path(5.0) == pytest.approx((30.0, 20.0))
    assert path(99.0) == pytest.approx((30.0, 40.0))


def test_follow_aims_at_the_start_during_the_lead_in_then_moves_and_scores():
    step = _follow("line", from_=(0, 0), to=(100, 0), duration=1.0, lead_in=0.5, tolerance=5)
    runner = ScriptRunner([step])
    targets = _play(runner, lambda t, target: target + (0.0, 3.0), 5.0)
    assert all(np.allclose(t, (0.0, 0.0)) for t in targets[:51])
    assert targets[-1][0] == pytest.approx(99.0)
    (outcome,) = runner.outcomes
    assert outcome.passed and outcome.kind == "follow"
    assert outcome.ended == pytest.approx(1.5)
    assert outcome.max_error >= outcome.mean_error > 3.0
    assert outcome.score == pytest.approx(100 * (0.5 + 0.5 * (1 - outcome.mean_error / 5)))


def test_easing_reparametrises_time_but_ends_on_the_same_point():
    linear = _follow("line", from_=(0, 0), to=(100, 0), duration=1.0, lead_in=0.0)
    eased = linear.model_copy(update={"easing": "in"})
    seen, final = {}, {}
    for step in (linear, eased):
        runner = ScriptRunner([step, WaitStep(wait=1.0)])
        seen[step.easing] = _play(runner, lambda t, target: target, 1.0)
        final[step.easing] = runner.target.tolist()
    assert seen["in"][50][0] < seen["linear"][50][0]
    assert final["in"] == final["linear"] == [100.0, 0.0]


def test_a_follow_step_fails_when_its_mean_error_is_above_tolerance():
    runner = ScriptRunner([_follow("line", from_=(0, 0), to=(10, 0), duration=0.5, tolerance=2)])
    _play(runner, lambda t, target: target + (0.0, 3.0), 5.0)
    (outcome,) = runner.outcomes
    assert not outcome.passed and outcome.score == 0.0
    assert outcome.note == "mean tracking error above tolerance"


def test_a_follow_step_cut_short_by_the_level_fails():
    runner = ScriptRunner([_follow("line", from_=(0, 0), to=(10, 0), duration=2.0)])
    _play(runner, lambda t, target: target, 1.5)
    (outcome,) = runner.finish(1.5)
    assert not outcome.passed and outcome.note == "level ended first"


def test_a_sequence_runs_as_reach_steps_each_scored_and_traced_to_its_source():
    runner = ScriptRunner(
        [WaitStep(wait=0.1), SequenceStep(sequence=[(1.0, 0.0), (2.0, 0.0)], hold=0.0)]
    )
    _play(runner, lambda t, target: np.zeros(2) if target is None else target, 2.0)
    assert [(o.index, o.source, o.kind, o.passed) for o in runner.outcomes] == [
        (0, 0, "wait", True),
        (1, 1, "reach", True),
        (2, 1, "reach", True),
    ]
    assert [o.score for o in runner.outcomes][1:] == pytest.approx([99.875, 99.875])


def test_set_steps_take_no_time_and_leave_their_changes_for_the_simulation():
    script = [
        ReachStep(reach=(5.0, 5.0), hold=0.0),
        SetStep.model_validate({"set": {"gravity": [0, 0]}}),
        SetStep.model_validate({"set": {"gain": 3.0}}),
        WaitStep(wait=1.0),
    ]
    runner = ScriptRunner(script)
    assert runner.take_changes() == []
    runner.observe(0.1, 0.1, np.array([5.0, 5.0]))
    changes = runner.take_changes()
    assert [c.gravity for c in changes] == [(0.0, 0.0), None]
    assert [c.gain for c in changes] == [None, 3.0]
    assert runner.take_changes() == []
    assert [(o.kind, o.passed, o.started, o.ended) for o in runner.outcomes[1:]] == [
        ("set", True, 0.1, 0.1),
        ("set", True, 0.1, 0.1),
    ]
    assert runner.target.tolist() == [5.0, 5.0]


def test_set_steps_the_level_never_reached_fail_and_change_nothing():
    runner = ScriptRunner(
        [WaitStep(wait=5.0), SetStep.model_validate({"set": {"gravity": [0, 0]}})]
    )
    outcomes = runner.finish(1.0)
    assert [(o.kind, o.passed, o.note) for o in outcomes] == [
        ("wait", False, "level ended first"),
        ("set", False, "level ended first"),
    ]
    assert runner.take_changes() == []


def test_expand_script_keeps_other_steps_as_they_are():
    wait = WaitStep(wait=1.0)
    assert expand_script([wait]) == ((0, wait),)


def test_outcome_keys_are_in_a_stable_order():
    runner = ScriptRunner([ReachStep(reach=(0.0, 1.0), hold=0.0)])
    runner.observe(0.5, 0.5, np.array([0.0, 1.0]))
    assert list(runner.outcomes[0].as_dict()) == [
        "index",
        "source",
        "kind",
        "passed",
        "score",
        "reached",
        "time_to_reach",
        "final_error",
        "mean_error",
        "max_error",
        "started",
        "ended",
        "note",
    ]
    assert math.isclose(runner.outcomes[0].as_dict()["score"], 100 * (0.5 + 0.5 * 0.875))


def _play_tree(runner: ScriptRunner, positions, seconds: float, dt: float = 0.01) -> list:
    """Observe ``positions(time, targets) -> {name: point}`` every ``dt`` until done or
    ``seconds`` pass; returns the targets seen before each tick."""
    time, seen = 0.0, []
    while not runner.done and time < seconds - 1e-9:
        targets = runner.targets
        time = round(time + dt, 9)
        seen.append({name: point.copy() for name, point in targets.items()})
        runner.observe(
            time, dt, {n: np.asarray(p, float) for n, p in positions(time, targets).items()}
        )
    return seen


def test_a_reach_of_several_effectors_passes_when_all_are_within_tolerance_together():
    step = ReachStep(reach={"left": (0.0, 0.0), "right": (10.0, 0.0)}, hold=0.1, tolerance=1.0)
    runner = ScriptRunner([step], effectors=("left", "right"))

    def positions(time, targets):  # the left hand arrives at 0.2 s, the right one at 0.5 s
        return {
            "left": (0.0, 0.0) if time >= 0.2 - 1e-9 else (0.0, 5.0),
            "right": (10.0, 0.5) if time >= 0.5 - 1e-9 else (10.0, 3.0),
        }

    _play_tree(runner, positions, 2.0)
    (outcome,) = runner.outcomes
    assert outcome.reached and outcome.time_to_reach == pytest.approx(0.5)
    assert outcome.ended == pytest.approx(0.6)
    assert outcome.effectors == ("left", "right")
    assert outcome.final_errors == pytest.approx((0.0, 0.5))
    assert outcome.final_error == pytest.approx(0.5)
    data = outcome.as_dict()
    assert list(data)[-2:] == ["effectors", "final_errors"]
    assert data["effectors"] == ["left", "right"] and data["final_errors"] == [0.0, 0.5]


def test_a_reach_of_several_effectors_times_out_with_the_largest_error():
    step = ReachStep(reach={"a": (0.0, 0.0), "b": (0.0, 0.0)}, timeout=0.5)
    runner = ScriptRunner([step], effectors=("a", "b"))
    _play_tree(runner, lambda t, _: {"a": (0.0, 1.0), "b": (3.0, 4.0)}, 1.0)
    (outcome,) = runner.outcomes
    assert not outcome.reached and outcome.note == "timed out"
    assert outcome.final_error == pytest.approx(5.0)
    assert outcome.final_errors == pytest.approx((1.0, 5.0))


def test_targets_are_sticky_until_a_later_step_sets_them_again():
    script = [
        ReachStep(reach={"a": (1.0, 0.0), "b": (2.0, 0.0)}, hold=0.0),
        _follow("line", from_=(0, 5), to=(10, 5), duration=0.5, lead_in=0.0, effector="b"),
        ReachStep(reach={"a": (7.0, 7.0)}, hold=0.0),
        WaitStep(wait=0.2),
    ]
    runner = ScriptRunner(script, effectors=("a", "b", "c"))
    seen = _play_tree(runner, lambda t, targets: targets, 3.0)
    # "c" is never aimed: it holds its pose.
    assert {n: p.tolist() for n, p in seen[0].items()} == {"a": [1.0, 0.0], "b": [2.0, 0.0]}
    during_follow = seen[5]
    assert during_follow["a"].tolist() == [1.0, 0.0] and during_follow["b"][1] == 5.0
    assert {n: p.tolist() for n, p in runner.targets.items()} == {"a": [7.0, 7.0], "b": [10.0, 5.0]}
    assert [o.passed for o in runner.outcomes] == [True, True, True, True]
    assert [o.effectors for o in runner.outcomes] == [("a", "b"), ("b",), ("a",), ()]


def test_a_sequence_naming_its_effector_reaches_with_that_one():
    script = [SequenceStep(sequence=[(1.0, 0.0), (2.0, 0.0)], hold=0.0, effector="b")]
    runner = ScriptRunner(script, effectors=("a", "b"))
    _play_tree(runner, lambda t, targets: {"a": (9.0, 9.0), **targets}, 1.0)
    assert [(o.kind, o.passed, o.effectors) for o in runner.outcomes] == [
        ("reach", True, ("b",)),
        ("reach", True, ("b",)),
    ]


def test_a_chain_observed_by_name_or_by_its_tip_alone_scores_the_same():
    def script():
        return [
            ReachStep(reach=(3.0, 4.0), hold=0.2),
            _follow("circle", center=(0, 0), radius=5, period=1, duration=1, lead_in=0.1),
            SequenceStep(sequence=[(1.0, 1.0)], hold=0.0, effector="tip"),
        ]

    def tip(time):
        return np.array([5.0 * math.cos(3.0 * time), 5.0 * math.sin(2.0 * time)])

    by_point, by_name = ScriptRunner(script()), ScriptRunner(script())
    time = 0.0
    while not by_point.done and time < 10.0:
        assert np.array_equal(by_point.target, by_name.targets["tip"])
        time = round(time + 0.01, 9)
        by_point.observe(time, 0.01, tip(time))
        by_name.observe(time, 0.01, {"tip": tip(time)})
    outcomes = [o.as_dict() for o in by_point.finish(time)]
    assert outcomes == [o.as_dict() for o in by_name.finish(time)]
    assert all("effectors" not in o for o in outcomes)


def test_a_tree_with_one_effector_has_a_chain_shaped_target_and_names_it_in_outcomes():
    runner = ScriptRunner([ReachStep(reach=(0.0, 10.0), hold=0.0)], effectors=("foot",))
    assert runner.target.tolist() == [0.0, 10.0]
    runner.observe(0.1, 0.1, np.array([0.0, 9.0]))
    assert runner.outcomes[0].effectors == ("foot",)


def test_a_script_of_several_effectors_needs_them_named():
    runner = ScriptRunner([ReachStep(reach={"a": (0.0, 1.0)})], effectors=("a", "b"))
    assert runner.target is None
    with pytest.raises(ValueError, match="observe them by name"):
        runner.observe(0.1, 0.1, np.zeros(2))
    with pytest.raises(ValueError, match="this chain has several"):
        ScriptRunner([ReachStep(reach=(0.0, 1.0))], effectors=("a", "b"))
    with pytest.raises(ValueError, match='name it: effector = "name"'):
        ScriptRunner([_follow("line", from_=(0, 0), to=(1, 0), duration=1.0)], effectors=("a", "b"))


def _upcoming_along(runner: ScriptRunner, seconds: float, dt: float = 0.01) -> list:
    """:attr:`ScriptRunner.upcoming` at every tick (by name, as lists) of a play whose
    effectors are always on their targets."""
    seen, time = [], 0.0
    while not runner.done and time < seconds:
        upcoming = runner.upcoming
        seen.append(None if upcoming is None else {n: p.tolist() for n, p in upcoming.items()})
        time = round(time + dt, 9)
        runner.observe(time, dt, runner.targets)
    return seen


def test_the_upcoming_targets_are_known_while_a_reach_or_a_wait_holds_its_own():
    script = [
        ReachStep(reach={"a": (1.0, 0.0)}, hold=0.0),
        WaitStep(wait=0.05),
        ReachStep(reach={"b": (2.0, 0.0)}, hold=0.0),
        ReachStep(reach={"a": (3.0, 3.0)}, hold=0.0),
        SetStep.model_validate({"set": {"gain": 3.0}}),
        ReachStep(reach={"a": (4.0, 4.0)}, hold=0.0),
        _follow("line", from_=(0, 5), to=(10, 5), duration=0.05, lead_in=0.0, effector="b"),
        ReachStep(reach={"a": (5.0, 5.0)}, hold=0.0),
    ]
    runner = ScriptRunner(script, effectors=("a", "b"))
    seen = _upcoming_along(runner, 2.0)
    changes = [seen[0]] + [
        now for before, now in zip(seen, seen[1:], strict=False) if now != before
    ]
    assert changes == [
        # Reaching "a": the next step is a wait, no new target.
        None,
        # Waiting: the next reach aims "b" too, and "a" keeps its target.
        {"a": [1.0, 0.0], "b": [2.0, 0.0]},
        {"a": [3.0, 3.0], "b": [2.0, 0.0]},
        # The reach after a set step (which can change the solver) is not known ahead, nor a
        # path's moving targets, nor what follows them.
        None,
    ]
    assert runner.done and runner.upcoming is None
