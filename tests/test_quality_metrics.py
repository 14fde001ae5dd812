"""The motion-quality measures (benchmarks/_quality_metrics.py) on synthetic trajectories."""

import dataclasses
import doctest
import importlib
import math
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
metrics = importlib.import_module("_quality_metrics")


def test_the_module_examples_hold():
    assert doctest.testmod(metrics).failed == 0


def _approach(overshoot_px: float, distance: float = 200.0, ticks: int = 480) -> np.ndarray:
    """A tip moving along +x from 0 to ``distance``: an under-damped step response whose first
    peak passes the target by ``overshoot_px`` (none when 0), sampled at 240 ticks/s."""
    t = np.arange(1, ticks + 1) / 240.0
    if overshoot_px == 0.0:
        x = distance * (1.0 - np.exp(-12.0 * t))
    else:
        zeta = -math.log(overshoot_px / distance) / math.hypot(
            math.pi, math.log(overshoot_px / distance)
        )
        wn = 20.0
        wd = wn * math.sqrt(1.0 - zeta**2)
        envelope = np.exp(-zeta * wn * t)
        x = distance * (
            1.0 - envelope * (np.cos(wd * t) + zeta / math.sqrt(1 - zeta**2) * np.sin(wd * t))
        )
    return np.column_stack((x, np.zeros_like(x)))


def test_overshoot_is_the_first_peak_past_the_target_as_a_share_of_the_approach():
    target = np.array([200.0, 0.0])
    assert metrics.approach_overshoot(_approach(0.0), np.zeros(2), target, 6.0) == 0.0
    measured = metrics.approach_overshoot(_approach(10.0), np.zeros(2), target, 6.0)
    assert abs(measured - 5.0) < 0.05


def test_overshoot_looks_along_the_approach_only():
    # Sideways drift at the target is not overshoot; moving past it along the approach is.
    tips = np.array([[0.0, 0.0], [0.0, 95.0], [4.0, 100.0], [0.0, 103.0]])
    target = np.array([0.0, 100.0])
    assert metrics.approach_overshoot(tips, np.zeros(2), target, 6.0) == 3.0
    assert metrics.approach_overshoot(tips[:2] * 0.5, np.zeros(2), target, 6.0) is None
    assert metrics.approach_overshoot(tips, np.array([0.0, 97.0]), target, 6.0) is None


def test_a_tip_curving_in_from_the_side_does_not_overshoot():
    # Along a quarter circle round the target's side, closing in all the way: its last ticks lie
    # beyond the target on the line from the start, yet the tip never went past it.
    angle = np.linspace(0.0, math.pi / 2, 241)
    radius = np.linspace(60.0, 0.0, 241)
    target = np.array([100.0, 0.0])
    tips = target + np.column_stack((radius * np.sin(angle), radius * np.cos(angle)))
    start = np.array([100.0 - 60.0, 0.0])
    assert np.all(np.diff(np.hypot(*(tips - target).T)) < 0.0)
    assert metrics.approach_overshoot(tips, start, target, 6.0) == 0.0
    # The same arc swinging on through the target and 8 px out the other side overshoots.
    through = np.vstack((tips, target + np.linspace(0.1, 8.0, 20)[:, None] * [-1.0, 0.0]))
    measured = metrics.approach_overshoot(through, start, target, 6.0)
    assert measured is not None and measured > 5.0


def test_rest_jitter_is_the_spread_about_the_mean():
    t = np.linspace(0.0, 0.5, 120, endpoint=False)
    still = np.tile([30.0, 40.0], (120, 1))
    assert metrics.rest_jitter(still) == 0.0
    circle = np.column_stack((30 + 2 * np.cos(8 * np.pi * t), 40 + 2 * np.sin(8 * np.pi * t)))
    assert abs(metrics.rest_jitter(circle) - 2.0) < 1e-6


def test_limit_excursion_counts_only_what_lies_past_a_limit():
    angles = np.radians([[0.0, 170.0, -50.0], [12.5, -200.0, 60.0], [-9.0, 0.0, 61.0]])
    lower = np.radians([-10.0, -math.inf, -60.0])
    upper = np.radians([10.0, math.inf, 60.0])
    assert abs(metrics.limit_excursion_deg(angles, lower, upper) - 2.5) < 1e-9
    assert metrics.limit_excursion_deg(angles[:, 1:2], lower[1:2], upper[1:2]) == 0.0


def test_a_joint_spins_when_it_turns_through_more_than_half_a_turn():
    t = np.linspace(0.0, 1.0, 241)[:, None]
    wobble = 0.3 * np.sin(20 * t)
    assert metrics.spin_joints(np.hstack((wobble, wobble))) == 0
    assert metrics.spin_joints(np.hstack((wobble, 2 * np.pi * t, -3.3 * t))) == 2


def test_stretched_toward_wants_the_tip_at_the_nearest_point_of_reach():
    base, target = np.array([10.0, 0.0]), np.array([310.0, 400.0])
    nearest = base + np.array([0.6, 0.8]) * 360.0
    assert metrics.stretched_toward(base, nearest, target, 360.0, 6.0)
    assert not metrics.stretched_toward(base, nearest - [0.0, 20.0], target, 360.0, 6.0)
    assert not metrics.stretched_toward(
        base, base + np.array([0.8, 0.6]) * 360.0, target, 360.0, 6.0
    )


def _spec(n: int = 4) -> object:
    rng = np.random.default_rng(3)
    return metrics.ChainSpec(
        lengths=rng.uniform(20.0, 80.0, n),
        masses=rng.uniform(0.5, 2.0, n),
        widths=np.full(n, 10.0),
        max_torque=np.full(n, 1e6),
        lower=np.full(n, -np.pi),
        upper=np.full(n, np.pi),
        base=np.array([5.0, -3.0]),
        base_angle=0.7,
        gravity=np.array([120.0, -900.0]),
        segments=np.zeros((0, 5)),
        circles=np.zeros((0, 3)),
    )


@pytest.mark.parametrize("shape", ["chain", "tree"])
def test_gravity_torque_is_the_slope_of_the_potential_energy(shape):
    spec = _spec() if shape == "chain" else _fork()
    n = len(spec.lengths)
    pose = np.random.default_rng(4).uniform(-2.0, 2.0, n)

    def energy(angles: np.ndarray) -> float:
        starts, ends = metrics.link_segments(spec, angles)
        com = (starts + ends) / 2.0
        return float(-(spec.masses[:, None] * com * spec.gravity).sum())

    h = 1e-6
    slope = [(energy(pose + h * e) - energy(pose - h * e)) / (2 * h) for e in np.eye(n)]
    torques = metrics.gravity_torques(spec, *metrics.link_segments(spec, pose))
    np.testing.assert_allclose(torques, np.abs(slope), rtol=1e-5, atol=1e-3)


def test_clearance_sees_a_link_crossing_an_obstacle():
    spec = dataclasses.replace(
        _spec(1), base=np.zeros(2), base_angle=0.0, lengths=np.array([100.0])
    )
    links = metrics.link_segments(spec, np.zeros(1))
    wall = dataclasses.replace(spec, segments=np.array([[50.0, -40.0, 50.0, 40.0, 2.0]]))
    assert metrics.obstacle_clearance(wall, *links) < 0.0
    beside = dataclasses.replace(spec, segments=np.array([[0.0, 20.0, 100.0, 20.0, 2.0]]))
    assert abs(metrics.obstacle_clearance(beside, *links) - 13.0) < 1e-9
    disc = dataclasses.replace(spec, circles=np.array([[120.0, 0.0, 10.0]]))
    assert abs(metrics.obstacle_clearance(disc, *links) - 5.0) < 1e-9


def test_a_witness_respects_limits_torque_and_obstacles():
    spec = dataclasses.replace(
        _spec(3), gravity=np.zeros(2), lower=np.full(3, -0.5), upper=np.full(3, 0.5)
    )
    reachable = metrics.chain_points(spec, np.array([0.4, -0.3, 0.2]))[-1]
    pose = metrics.find_witness(spec, reachable, 4.0)
    assert pose is not None and np.all(np.abs(pose) <= 0.5)
    # Beyond the limits (the chain would have to bend back on itself) there is none.
    behind = metrics.chain_points(spec, np.array([2.5, 0.0, 0.0]))[-1]
    assert metrics.find_witness(spec, behind, 4.0) is None
    weak = dataclasses.replace(spec, gravity=np.array([0.0, -900.0]), max_torque=np.full(3, 1.0))
    assert metrics.find_witness(weak, reachable, 4.0) is None


def _fork() -> object:
    """A trunk of 60 px straight up with two arms of two links each on its tip, under
    gravity, every joint free."""
    n = 5
    return dataclasses.replace(
        _spec(n),
        lengths=np.array([60.0, 50.0, 40.0, 50.0, 40.0]),
        base=np.zeros(2),
        base_angle=math.pi / 2,
        parents=np.array([-1, 0, 1, 0, 3]),
    )


def test_a_tree_hangs_each_link_from_its_parents_end():
    spec = _fork()
    pose = np.random.default_rng(5).uniform(-2.0, 2.0, 5)
    starts, ends = metrics.link_segments(spec, pose)
    np.testing.assert_allclose(starts[[1, 3]], [ends[0], ends[0]])
    np.testing.assert_allclose(starts[[2, 4]], [ends[1], ends[3]])
    # Each arm is a chain hanging from the trunk's tip.
    arm = dataclasses.replace(spec, lengths=spec.lengths[[0, 3, 4]], parents=None)
    np.testing.assert_allclose(metrics.chain_points(arm, pose[[0, 3, 4]])[-1], ends[4])
    # A root off the base sits at its offset in the base frame (x up, y to the left here).
    offsets = np.zeros((5, 2))
    offsets[2] = (0.0, 30.0)
    legs = dataclasses.replace(spec, parents=np.array([-1, 0, -1, 2, 3]), offsets=offsets)
    np.testing.assert_allclose(metrics.link_segments(legs, pose)[0][2], [-30.0, 0.0], atol=1e-9)


def test_two_hands_are_never_farther_apart_than_their_span():
    spec = _fork()
    assert metrics.span(spec, 2, 4) == 180.0
    assert metrics.span(spec, 1, 4) == 140.0
    poses = np.random.default_rng(7).uniform(-np.pi, np.pi, (500, 5))
    apart = [np.hypot(*np.subtract(*metrics.link_segments(spec, p)[1][[2, 4]])) for p in poses]
    assert max(apart) <= 180.0
    # The arms stretched out to either side meet it.
    wide = np.array([0.0, np.pi / 2, 0.0, -np.pi / 2, 0.0])
    ends = metrics.link_segments(spec, wide)[1]
    assert np.hypot(*(ends[2] - ends[4])) == pytest.approx(180.0)


def test_a_witness_meets_several_targets_at_once_or_none_is_found():
    spec = dataclasses.replace(_fork(), max_torque=np.full(5, 1e7))
    pose = np.array([0.3, 1.0, 0.4, -1.2, -0.5])
    ends = metrics.link_segments(spec, pose)[1]
    found = metrics.find_witness(spec, ends[[2, 4]], 4.0, links=[2, 4])
    assert found is not None
    reached = metrics.link_segments(spec, found)[1][[2, 4]]
    assert np.hypot(*(reached - ends[[2, 4]]).T).max() <= 2.0
    # Each of two points 190 px apart alone, but not both: the hands span 180 px at most.
    apart = np.array([[-95.0, 60.0], [95.0, 60.0]])
    assert metrics.find_witness(spec, apart[0], 4.0, links=[2]) is not None
    assert metrics.find_witness(spec, apart, 4.0, links=[2, 4]) is None
