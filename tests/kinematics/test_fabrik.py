"""FABRIK: agreement with the textbook passes on free chains, worked cases, joint limits.

The reference below is the algorithm as Aristidou & Lasenby (2011) give it, on joint positions
only, without calling ikgame.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from ikgame.kinematics import Skeleton, SolveStatus, forward_kinematics, solve_fabrik
from ikgame.kinematics.fabrik import _Links

PI = math.pi


def _textbook_fabrik(points: np.ndarray, lengths: list[float], target: np.ndarray, passes: int):
    """Backward then forward reaching, ``passes`` times, on an (n + 1, 2) array of joints."""
    p = points.copy()
    base = p[0].copy()
    for _ in range(passes):
        p[-1] = target
        for i in range(len(lengths) - 1, -1, -1):
            r = np.linalg.norm(p[i + 1] - p[i])
            p[i] = (1 - lengths[i] / r) * p[i + 1] + lengths[i] / r * p[i]
        p[0] = base
        for i in range(len(lengths)):
            r = np.linalg.norm(p[i + 1] - p[i])
            p[i + 1] = (1 - lengths[i] / r) * p[i] + lengths[i] / r * p[i + 1]
    return p


def _end(skeleton: Skeleton, angles: np.ndarray) -> np.ndarray:
    return forward_kinematics(skeleton, angles)[0][-1]


@settings(derandomize=True, max_examples=100, deadline=None)
@given(
    st.lists(st.floats(5.0, 100.0), min_size=2, max_size=12),
    st.lists(st.floats(-PI, PI), min_size=24, max_size=24),
    st.floats(-PI, PI),
    st.integers(1, 3),
)
def test_free_chain_passes_match_the_textbook_algorithm(lengths, angles, base_angle, passes):
    n = len(lengths)
    chain = Skeleton.chain(lengths, base=(10.0, -20.0), base_angle=base_angle)
    start = np.array(angles[:n])
    target = _end(chain, np.array(angles[n : 2 * n]))
    points = forward_kinematics(chain, start)[0]
    # Out of reach (or exactly at it) the solver skips the passes and stretches the chain.
    assume(np.hypot(*(target - chain.base)) < 0.999 * sum(lengths))
    assume(np.hypot(*(points[-1] - target)) > 1.0)
    expected = _textbook_fabrik(points, lengths, target, passes)
    expected_error = np.hypot(*(expected[-1] - target))
    # Stop before the solve would: at the tolerance, or where a pass gains (almost) nothing.
    previous = _textbook_fabrik(points, lengths, target, passes - 1)
    assume(np.hypot(*(previous[-1] - target)) - expected_error > 1e-3)
    sol = solve_fabrik(chain, start, target, max_iterations=passes, tolerance=0.0)
    assert sol.iterations == passes
    np.testing.assert_allclose(
        forward_kinematics(chain, sol.angles)[0], expected, atol=1e-6 * sum(lengths)
    )
    assert sol.error == pytest.approx(expected_error, abs=1e-6 * sum(lengths))


@pytest.mark.parametrize(
    "target",
    [(0.0, 150.0), (150.0, 0.0), (-150.0, 0.0), (0.0, 0.0), (100.0, 0.0)],
    ids=["above", "on-the-line-in-front", "behind-the-base", "on-the-base", "on-a-joint"],
)
def test_reaches_targets_including_ones_on_a_straight_chains_line(target):
    # Passes alone never bend a straight chain off its own line; the solver bends it out.
    chain = Skeleton.chain([100.0, 100.0])
    sol = solve_fabrik(chain, np.zeros(2), target, max_iterations=100, tolerance=0.5)
    assert sol.status is SolveStatus.SUCCESS
    assert np.hypot(*(_end(chain, sol.angles) - target)) == pytest.approx(sol.error)


def test_an_unreachable_target_gets_the_straight_chain_at_once():
    chain = Skeleton.chain([100.0, 50.0, 25.0], base=(10.0, 10.0), base_angle=PI / 2)
    sol = solve_fabrik(chain, np.array([0.3, -1.0, 2.0]), (10.0 - 400.0, 10.0), max_iterations=5)
    assert sol.status is SolveStatus.FAILURE
    assert sol.iterations == 1
    np.testing.assert_allclose(sol.angles, [PI / 2, 0.0, 0.0])
    assert sol.error == pytest.approx(225.0)


def test_an_unreachable_target_the_limits_keep_from_pointing_at():
    chain = Skeleton.chain([100.0, 100.0], limits=[(-0.5, 0.5), (-1.0, 1.0)])
    sol = solve_fabrik(chain, np.zeros(2), (0.0, 500.0), max_iterations=50)
    assert sol.status is SolveStatus.FAILURE
    assert sol.angles.tolist() == [0.5, 1.0]


@pytest.mark.parametrize("passes", range(1, 12))
def test_limits_hold_after_every_pass_and_the_error_never_rises(passes):
    limits = [(-1.0, 1.0), (0.2, 2.0), (-2.5, -0.3), (-0.5, 0.5)]
    chain = Skeleton.chain([80.0, 60.0, 50.0, 40.0], limits=limits)
    start = np.array([0.0, 1.0, -1.0, 0.0])
    target = (-30.0, 120.0)
    sol = solve_fabrik(chain, start, target, max_iterations=passes, tolerance=0.0)
    assert np.all(sol.angles >= chain.lower) and np.all(sol.angles <= chain.upper)
    if passes > 1:
        before = solve_fabrik(chain, start, target, max_iterations=passes - 1, tolerance=0.0)
        assert sol.error <= before.error


def test_a_wide_limit_reads_the_angle_nearest_the_previous_one():
    # Limits wider than a turn: 3.3 and 3.3 - 2 pi are the same direction, only one is near.
    links = _Links(Skeleton.chain([1.0], limits=[(-4.0, 4.0)]))
    assert links.limited(0, 3.3 - 2 * PI, previous=3.0) == pytest.approx(3.3)
    assert links.limited(0, 3.3, previous=-3.0) == pytest.approx(3.3 - 2 * PI)
    assert links.limited(0, 3.9, previous=3.5) == pytest.approx(3.9)
    assert links.limited(0, 4.5, previous=3.5) == 4.0


def test_a_free_joint_reads_its_angle_wrapped():
    links = _Links(Skeleton.chain([1.0]))
    assert links.limited(0, 3.3, previous=0.0) == pytest.approx(3.3 - 2 * PI)


def _curled_at_its_limits() -> tuple[Skeleton, np.ndarray, np.ndarray]:
    """A 12-link chain curled as far as its limits go, and a start one joint nudged off it."""
    chain = Skeleton.chain([5.0] * 11 + [24.0], limits=[(-1.0, 1.0)] * 11 + [(-3.125, 1.0)])
    target = _end(chain, chain.lower)
    start = chain.lower.copy()
    start[10] += 0.0625
    return chain, start, target


def test_a_chain_curled_at_its_limits_is_reached_from_near_by():
    chain, start, target = _curled_at_its_limits()
    sol = solve_fabrik(chain, start, target, max_iterations=300, tolerance=0.01 * chain.reach)
    assert sol.status is SolveStatus.SUCCESS


def _in_limits(rng: np.random.Generator, chain: Skeleton) -> np.ndarray:
    return rng.uniform(np.maximum(chain.lower, -PI), np.minimum(chain.upper, PI))


def test_tight_symmetric_limits_are_no_trap():
    # +-10 deg on every joint: the passes alone crawl along the limits (or stop); they hand
    # over to damped least squares, which slides the chain the rest of the way.
    rng = np.random.default_rng(10)
    for _ in range(40):
        n = int(rng.integers(2, 16))
        chain = Skeleton.chain(
            rng.uniform(20.0, 60.0, n),
            base_angle=rng.uniform(-PI, PI),
            limits=[(-math.radians(10), math.radians(10))] * n,
        )
        target = _end(chain, _in_limits(rng, chain))
        sol = solve_fabrik(chain, np.zeros(n), target, max_iterations=50, tolerance=0.5)
        assert sol.status is SolveStatus.SUCCESS, (n, sol.error)
        assert np.all(sol.angles >= chain.lower) and np.all(sol.angles <= chain.upper)


@pytest.mark.parametrize("side", [1.0, -1.0], ids=["bends-left", "bends-right"])
def test_one_sided_limits_are_reached_from_straight_most_of_the_time(side):
    # Every joint bends one way only, [10, 170] deg or [-170, -10] deg. A local method can
    # still end at a limit short of a target far round (RobustSolver restarts those), but
    # FABRIK must no longer stall on most: before the hand-over it reached 37 of 100.
    rng = np.random.default_rng(11)
    low, high = sorted((side * math.radians(10), side * math.radians(170)))
    reached = 0
    for _ in range(100):
        n = int(rng.integers(2, 16))
        chain = Skeleton.chain(
            rng.uniform(20.0, 60.0, n), base_angle=rng.uniform(-PI, PI), limits=[(low, high)] * n
        )
        target = _end(chain, _in_limits(rng, chain))
        sol = solve_fabrik(chain, chain.clamp(np.zeros(n)), target, max_iterations=200)
        assert np.all(sol.angles >= chain.lower) and np.all(sol.angles <= chain.upper)
        reached += sol.status is SolveStatus.SUCCESS
    assert reached >= 85


def test_a_stall_against_a_limit_ends_in_failure_no_worse_than_the_start():
    # The base on its -30 deg stop, the target behind the arm: the short way round is through
    # the stop, so every local step makes things worse (RobustSolver goes the long way).
    r = math.radians
    arm = Skeleton.chain(
        [120, 100, 80], limits=[(r(-30), r(120)), (r(10), r(170)), (r(-170), r(-10))]
    )
    target = _end(arm, np.array([r(100), r(120), r(-30)]))
    sol = solve_fabrik(arm, arm.lower, target, max_iterations=300, tolerance=0.5)
    assert sol.status is SolveStatus.FAILURE
    assert sol.error <= np.hypot(*(_end(arm, arm.lower) - target))
    assert np.all(sol.angles >= arm.lower) and np.all(sol.angles <= arm.upper)
