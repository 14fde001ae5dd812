"""The Jacobian, and the Jacobian-transpose and damped-least-squares solvers on worked cases."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ikgame.kinematics import (
    Skeleton,
    SolveStatus,
    forward_kinematics,
    solve_dls,
    solve_jacobian_transpose,
    wrap_angle,
)
from ikgame.kinematics.jacobian import (
    GAIN_GROW,
    GAIN_MAX,
    GAIN_SHRINK,
    MAX_STEP,
    _escape_saddle,
    _next_gain,
    _wrap_free,
    jacobian,
)

PI = math.pi
JACOBIAN_SOLVERS = [solve_jacobian_transpose, solve_dls]


def _end(skeleton: Skeleton, angles: np.ndarray) -> np.ndarray:
    return forward_kinematics(skeleton, angles)[0][-1]


# -- the Jacobian -------------------------------------------------------------------------------


def test_jacobian_of_a_straight_chain_is_the_lever_arm_of_each_joint():
    chain = Skeleton.chain([10.0, 20.0, 30.0], base=(5.0, -5.0))
    np.testing.assert_allclose(jacobian(chain, np.zeros(3)), [[0, 0, 0], [60, 50, 30]], atol=1e-12)


@settings(derandomize=True, max_examples=60, deadline=None)
@given(
    st.lists(st.floats(1.0, 100.0), min_size=1, max_size=12),
    st.lists(st.floats(-PI, PI), min_size=12, max_size=12),
    st.floats(-PI, PI),
)
def test_jacobian_matches_finite_differences(lengths, angles, base_angle):
    chain = Skeleton.chain(lengths, base=(3.0, 4.0), base_angle=base_angle)
    theta = np.array(angles[: len(lengths)])
    h = 1e-6
    numeric = np.column_stack(
        [
            (_end(chain, theta + h * unit) - _end(chain, theta - h * unit)) / (2 * h)
            for unit in np.eye(len(lengths))
        ]
    )
    assert jacobian(chain, theta).shape == (2, len(lengths))
    np.testing.assert_allclose(jacobian(chain, theta), numeric, atol=1e-5 * sum(lengths))


def test_jacobian_rejects_a_tree_and_wrong_angles():
    tree = Skeleton(
        lengths=np.ones(3), parents=np.array([-1, 0, 0]), lower=-np.inf, upper=np.inf, base=(0, 0)
    )
    with pytest.raises(ValueError, match="serial chain"):
        jacobian(tree, np.zeros(3))
    with pytest.raises(ValueError, match=r"angles must have shape \(2,\)"):
        jacobian(Skeleton.chain([1.0, 1.0]), np.zeros(3))


# -- worked cases -------------------------------------------------------------------------------


@pytest.mark.parametrize("solve", JACOBIAN_SOLVERS)
@pytest.mark.parametrize(
    "target",
    [(0.0, 150.0), (150.0, 0.0), (-150.0, 0.0), (0.0, 0.0), (199.0, 0.0)],
    ids=["above", "on-the-line-in-front", "behind-the-base", "on-the-base", "almost-stretched"],
)
def test_reaches_targets_including_saddles_of_a_straight_chain(solve, target):
    # From the straight pose, a target on the chain's own line is a saddle: zero gradient.
    chain = Skeleton.chain([100.0, 100.0])
    sol = solve(chain, np.zeros(2), target, max_iterations=100, tolerance=0.5)
    assert sol.status is SolveStatus.SUCCESS
    assert sol.error <= 0.5
    assert np.hypot(*(_end(chain, sol.angles) - target)) == pytest.approx(sol.error)


@pytest.mark.parametrize("solve", JACOBIAN_SOLVERS)
def test_a_stretched_chain_pointing_at_an_unreachable_target_fails_at_once(solve):
    chain = Skeleton.chain([100.0, 100.0])
    sol = solve(chain, np.zeros(2), (500.0, 0.0), max_iterations=50)
    assert sol.status is SolveStatus.FAILURE
    assert sol.iterations == 1
    assert sol.angles.tolist() == [0.0, 0.0]
    assert sol.error == pytest.approx(300.0)


@pytest.mark.parametrize("solve", JACOBIAN_SOLVERS)
def test_a_one_link_chain_cannot_reach_its_own_base(solve):
    # Every angle is as good as any other: a flat minimum, not a saddle.
    sol = solve(Skeleton.chain([100.0]), np.zeros(1), (0.0, 0.0), max_iterations=50)
    assert sol.status is SolveStatus.FAILURE
    assert sol.error == pytest.approx(100.0)


@pytest.mark.parametrize("solve", JACOBIAN_SOLVERS)
def test_the_error_never_rises_from_one_iteration_to_the_next(solve):
    chain = Skeleton.chain([60.0, 50.0, 40.0, 30.0], base_angle=0.3)
    start = np.array([2.0, -2.5, 2.8, -1.0])
    errors = [
        solve(chain, start, (-40.0, -90.0), max_iterations=k, tolerance=0.0).error
        for k in range(1, 30)
    ]
    assert all(later <= earlier for earlier, later in zip(errors, errors[1:], strict=False))
    assert errors[-1] < 0.02 * errors[0]


@pytest.mark.parametrize("solve", JACOBIAN_SOLVERS)
def test_a_locked_joint_stays_put_and_the_others_make_up_for_it(solve):
    chain = Skeleton.chain([100.0, 100.0, 100.0], limits=[None, (0.4, 0.4), None])
    sol = solve(chain, np.zeros(3), (50.0, 200.0), max_iterations=100, tolerance=0.5)
    assert sol.status is SolveStatus.SUCCESS
    assert sol.angles[1] == 0.4


@pytest.mark.parametrize("solve", JACOBIAN_SOLVERS)
def test_a_limited_joint_is_clamped_not_wrapped(solve):
    # Reaching the target behind the base would take the root the long way round through -pi.
    chain = Skeleton.chain([100.0, 100.0], limits=[(-3.0, 3.0), None])
    sol = solve(chain, np.array([2.9, 0.0]), (-150.0, -60.0), max_iterations=200, tolerance=0.5)
    assert -3.0 <= sol.angles[0] <= 3.0


# -- the adaptive step of the Jacobian transpose ------------------------------------------------


def test_the_gain_grows_while_the_error_falls_and_shrinks_when_it_rises():
    assert _next_gain(0.25, improved=True) == 0.25 * GAIN_GROW
    assert _next_gain(GAIN_MAX, improved=True) == GAIN_MAX
    assert _next_gain(1.0, improved=False) == GAIN_SHRINK
    gain = 1.0
    for _ in range(5):
        gain = _next_gain(gain, improved=False)
    for _ in range(10):
        gain = _next_gain(gain, improved=True)
    assert gain == GAIN_MAX


def _line_search_step(chain: Skeleton, angles: np.ndarray, target: np.ndarray) -> np.ndarray:
    j = jacobian(chain, angles)
    e = target - _end(chain, angles)
    g = j.T @ e
    v = j @ g
    return (e @ v) / (v @ v) * g


def test_an_overshooting_step_is_rejected_and_the_next_one_halved():
    chain = Skeleton.chain([44.0, 54.0])
    start = np.array([-2.8, -2.3])
    target = np.array([68.0, 59.0])
    first = solve_jacobian_transpose(chain, start, target, max_iterations=1, tolerance=0.5)
    assert first.status is SolveStatus.PROCESSING
    np.testing.assert_allclose(first.angles, start)
    second = solve_jacobian_transpose(chain, start, target, max_iterations=2, tolerance=0.5)
    halved = start + GAIN_SHRINK * _line_search_step(chain, start, target)
    np.testing.assert_allclose(_end(chain, second.angles), _end(chain, halved), atol=1e-9)
    assert second.error < first.error


def _fixed_step_iterations(chain: Skeleton, target: np.ndarray, alpha: float, tol: float) -> int:
    angles = np.zeros(chain.count)
    for used in range(1, 10_000):
        angles = angles + alpha * jacobian(chain, angles).T @ (target - _end(chain, angles))
        if np.hypot(*(target - _end(chain, angles))) <= tol:
            return used
    return 10_000


def test_the_adaptive_step_needs_far_fewer_iterations_than_a_fixed_small_one():
    chain = Skeleton.chain([80.0, 70.0, 60.0, 50.0])
    target = np.array([-60.0, 150.0])
    first = _line_search_step(chain, np.zeros(4), target)
    j = jacobian(chain, np.zeros(4))
    alpha = float(np.linalg.norm(first) / np.linalg.norm(j.T @ target)) / 10.0
    fixed = _fixed_step_iterations(chain, target, alpha, tol=1.0)
    adaptive = solve_jacobian_transpose(chain, np.zeros(4), target, max_iterations=500)
    assert adaptive.status is SolveStatus.SUCCESS
    assert adaptive.iterations * 3 < fixed


# -- damped least squares -----------------------------------------------------------------------


def test_dls_changes_no_joint_by_more_than_max_step_per_iteration():
    # Nearly straight and aimed just off its own line: the undamped step would be enormous.
    chain = Skeleton.chain([100.0] * 5)
    start = np.full(5, 1e-4)
    sol = solve_dls(chain, start, (480.0, 5.0), max_iterations=1, tolerance=0.0)
    assert np.max(np.abs(sol.angles - start)) <= MAX_STEP + 1e-12


def test_dls_converges_in_a_few_iterations_near_the_target():
    chain = Skeleton.chain([50.0] * 8, base_angle=1.0)
    start = np.linspace(-0.5, 0.5, 8)
    target = _end(chain, start + 0.05)
    sol = solve_dls(chain, start, target, max_iterations=10, tolerance=0.01)
    assert sol.status is SolveStatus.SUCCESS
    assert sol.iterations <= 4


# -- helpers ------------------------------------------------------------------------------------


@settings(derandomize=True, max_examples=200, deadline=None)
@given(st.lists(st.floats(-1e6, 1e6), min_size=1, max_size=8))
def test_free_joints_wrap_exactly_as_wrap_angle_and_limited_ones_not_at_all(angles):
    n = len(angles)
    free = Skeleton.chain([1.0] * n)
    limited = Skeleton.chain([1.0] * n, limits=[(-1e7, 1e7)] * n)
    arr = np.array(angles)
    assert _wrap_free(free, arr).tolist() == [wrap_angle(a) for a in angles]
    assert _wrap_free(limited, arr).tolist() == angles


def test_no_escape_from_a_true_minimum_but_one_from_a_saddle():
    chain = Skeleton.chain([100.0, 100.0])
    straight = np.zeros(2)
    points = forward_kinematics(chain, straight)[0]
    beyond = np.array([300.0, 0.0])
    assert _escape_saddle(chain, straight, points, beyond, 100.0) is None
    inside = np.array([150.0, 0.0])
    escaped = _escape_saddle(chain, straight, points, inside, 50.0)
    assert escaped is not None
    angles, escaped_points, error = escaped
    assert error < 50.0
    np.testing.assert_allclose(escaped_points, forward_kinematics(chain, angles)[0])
