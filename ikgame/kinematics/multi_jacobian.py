"""Jacobian transpose and damped least squares for several targets on a tree.

The chain solvers' methods on the stacked Jacobian: each target contributes two rows, scaled by
the square root of its weight, and its error vector likewise, so the weighted least-squares
problem is an ordinary one. The gradient ``J^T W e`` is the sum of every target's own gradient;
joints that move no targeted end have zero columns and never move. Steps are kept only when the
weighted objective fell by a fair share of what the linear model promised, clamped to the joint
limits, and a stall ends in the same saddle test as for a chain. Targets that cannot all be
reached leave the solve at the weighted least-squares compromise, with ``FAILURE``.

A chain with one target at its tip is solved by the chain solver itself.

Angles are radians, lengths and positions pixels.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ikgame.kinematics._multi import STALL_GAIN, Problem, as_chain_solve, prepare
from ikgame.kinematics.ccd import TRIVIAL_ARC_LENGTH
from ikgame.kinematics.jacobian import (
    DAMPING_BIAS,
    MU_INITIAL,
    SUFFICIENT_DECREASE,
    _capped,
    _next_gain,
    _next_mu,
    _pressing,
    solve_dls,
    solve_jacobian_transpose,
)
from ikgame.kinematics.skeleton import Skeleton
from ikgame.kinematics.solver import Solution, SolveStatus
from ikgame.kinematics.targets import TargetSet

__all__ = ["solve_jacobian_transpose_targets", "solve_dls_targets"]


def solve_jacobian_transpose_targets(
    skeleton: Skeleton,
    angles: np.ndarray,
    targets: TargetSet,
    *,
    max_iterations: int = 10,
    tolerance: float = 1.0,
) -> Solution:
    """Steepest descent on the weighted objective: ``delta = alpha J^T W e``, adaptive alpha.

    As :func:`~ikgame.kinematics.jacobian.solve_jacobian_transpose`, with the gradient summed
    over the targets and alpha the exact line-search step of the linearised weighted problem
    times a gain; joints pushing into a limit drop out of the gradient. ``SUCCESS`` when every target is within ``tolerance`` (px); ``Solution.error``
    is the largest distance, ``Solution.errors`` each one.

    >>> tree = Skeleton.tree([100, 60, 60], [-1, 0, 0])
    >>> targets = TargetSet([1, 2], [(137.3, 72.6), (152.9, 11.8)])
    >>> sol = solve_jacobian_transpose_targets(tree, np.zeros(3), targets, max_iterations=100)
    >>> sol.status.value, bool(sol.errors.max() <= 1.0)
    ('success', True)
    """
    chain = as_chain_solve(
        solve_jacobian_transpose, skeleton, angles, targets, max_iterations, tolerance
    )
    if chain is not None:
        return chain
    problem, start = prepare(skeleton, angles, targets, max_iterations, tolerance)
    gain = 1.0

    def propose(current: np.ndarray, stacked: np.ndarray, error: np.ndarray) -> np.ndarray:
        gradient = stacked.T @ error
        if problem.has_limits:
            # Projected gradient: a joint pushing into its limit would only shorten the line
            # search for the others.
            gradient[_pressing(skeleton, current, gradient)] = 0.0
        velocity = stacked @ gradient
        speed_sq = float(velocity @ velocity)
        if speed_sq == 0.0:
            return gradient
        return gradient * (gain * float(error @ velocity) / speed_sq)

    def adapt(improved: bool) -> None:
        nonlocal gain
        gain = _next_gain(gain, improved=improved)

    return descend(problem, start, max_iterations, propose, adapt)


def solve_dls_targets(
    skeleton: Skeleton,
    angles: np.ndarray,
    targets: TargetSet,
    *,
    max_iterations: int = 10,
    tolerance: float = 1.0,
) -> Solution:
    """Damped least squares on the stacked, weighted Jacobian, Levenberg-Marquardt style.

    As :func:`~ikgame.kinematics.jacobian.solve_dls`: ``lambda^2 = mu (F + DAMPING_BIAS reach^2
    sum w)`` with ``F`` the weighted objective, joints pressing into a limit dropped from the
    step, no joint changed by more than ``MAX_STEP`` per iteration.

    >>> tree = Skeleton.tree([100, 60, 60], [-1, 0, 0])
    >>> targets = TargetSet([1, 2], [(137.3, 72.6), (152.9, 11.8)])
    >>> sol = solve_dls_targets(tree, np.zeros(3), targets, max_iterations=50)
    >>> sol.status.value, bool(sol.errors.max() <= 1.0)
    ('success', True)
    """
    chain = as_chain_solve(solve_dls, skeleton, angles, targets, max_iterations, tolerance)
    if chain is not None:
        return chain
    problem, start = prepare(skeleton, angles, targets, max_iterations, tolerance)
    bias = DAMPING_BIAS * skeleton.reach**2 * problem.total_weight
    mu = MU_INITIAL

    def propose(current: np.ndarray, stacked: np.ndarray, error: np.ndarray) -> np.ndarray:
        damping = mu * (0.5 * float(error @ error) + bias)
        step = _damped_step(stacked, error, damping)
        if problem.has_limits:
            free = ~_pressing(skeleton, current, step)
            if not free.all():
                step = _damped_step(stacked * free, error, damping)
        return _capped(step)

    def adapt(improved: bool) -> None:
        nonlocal mu
        mu = _next_mu(mu, improved=improved)

    return descend(problem, start, max_iterations, propose, adapt)


def descend(
    problem: Problem,
    current: np.ndarray,
    max_iterations: int,
    propose: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray],
    adapt: Callable[[bool], None],
) -> Solution:
    """The loop both solvers share: step, keep the step only if it helped, adapt.

    ``propose(angles, stacked, error)`` gets the weighted (2k, n) Jacobian and the weighted,
    clamped (2k,) error; ``adapt(improved)`` hears whether the step was kept. A step that moves
    no targeted end by ``TRIVIAL_ARC_LENGTH``, or gains less than ``STALL_GAIN`` in the weighted
    RMS error, is a stall: escape a saddle if there is one, else end in ``FAILURE``.
    """
    clamp = problem.skeleton.clamp
    starts, ends, _ = problem.pose(current)
    errors = problem.errors(ends)
    objective = problem.objective(errors)
    used = 0
    while not problem.arrived(errors):
        if used == max_iterations:
            return problem.solution(current, SolveStatus.PROCESSING, used, errors)
        used += 1
        stacked = problem.jacobian(starts, ends)
        step = propose(current, stacked, problem.weighted(errors, clamp=True))
        trial = clamp(current + step)
        trial_starts, trial_ends, _ = problem.pose(trial)
        trial_errors = problem.errors(trial_ends)
        trial_objective = problem.objective(trial_errors)
        moved = trial_ends[problem.links] - ends[problem.links]
        stalled = float(np.abs(moved).max()) < TRIVIAL_ARC_LENGTH
        linear = stacked @ (trial - current)
        promised = float(problem.weighted(errors, clamp=False) @ linear) - 0.5 * float(
            linear @ linear
        )
        improved = (
            trial_objective < objective
            and objective - trial_objective >= SUFFICIENT_DECREASE * promised
        )
        if improved:
            gained = problem.rms(objective) - problem.rms(trial_objective)
            stalled = stalled or gained < STALL_GAIN
            current, starts, ends = trial, trial_starts, trial_ends
            errors, objective = trial_errors, trial_objective
        if stalled:
            escaped = problem.escape(current, starts, ends, objective)
            if escaped is None:
                return problem.solution(current, SolveStatus.FAILURE, used, errors)
            current, starts, ends, objective = escaped
            errors = problem.errors(ends)
        else:
            adapt(improved)
    return problem.solution(current, SolveStatus.SUCCESS, used, errors)


def _damped_step(stacked: np.ndarray, error: np.ndarray, damping: float) -> np.ndarray:
    """``J^T (J J^T + damping I)^-1 e``, through whichever of the two systems is smaller."""
    rows, cols = stacked.shape
    if rows <= cols:
        system = stacked @ stacked.T
        system[np.diag_indices(rows)] += damping
        return stacked.T @ np.linalg.solve(system, error)
    system = stacked.T @ stacked
    system[np.diag_indices(cols)] += damping
    return np.linalg.solve(system, stacked.T @ error)
