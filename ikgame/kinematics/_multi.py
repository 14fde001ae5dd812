"""What every multi-target solver shares: the checked problem, its objective, and the way out of
a saddle.

A :class:`Problem` is one skeleton with one :class:`~ikgame.kinematics.targets.TargetSet`: the
arrays a solve reads on every iteration, worked out once. Error vectors are ``point - end``
(k, 2), px; the objective is ``F = 1/2 sum_j w_j |e_j|^2``, px^2. Progress is measured in the
weighted root-mean-square error ``sqrt(2 F / sum_j w_j)``, px, which for one target is its
distance, so the chain solvers' thresholds in px carry over.
"""

from __future__ import annotations

import math
from typing import Final

import numpy as np

from ikgame.kinematics.jacobian import (
    ERROR_CLAMP,
    ESCAPE_ANGLE,
    NEGATIVE_CURVATURE,
    _check_settings,
    _wrap_free,
)
from ikgame.kinematics.skeleton import Skeleton, check_angles, tree_points
from ikgame.kinematics.solver import Solution, Solver, SolveStatus
from ikgame.kinematics.targets import TargetSet, columns

__all__ = ["Layout", "Problem", "layout", "prepare", "as_chain_solve", "STALL_GAIN"]

STALL_GAIN: Final = 1e-9
"""An iteration that lowers the weighted RMS error by less than this (px) has stalled.

Far finer than the chain solvers' ``TRIVIAL_ARC_LENGTH``: targets that cannot all be reached
leave a large error whose last approach to the compromise is slow (each step gains a little),
and stopping at the first small gain would stop well short of the weighted optimum."""

_ROUNDING: Final = 1e-12
"""Relative slack on the objective when deciding that a bend out of a saddle lowered it."""


class Layout:
    """What a solve reads that depends only on the skeleton's links and limits and on which
    links the targets name, with which weights: worked out once per skeleton and kept in its
    memo (see :func:`layout`), so every array here is read-only."""

    def __init__(self, skeleton: Skeleton, links: np.ndarray, weights: np.ndarray) -> None:
        self.total_weight = float(weights.sum())
        # Rows of the stacked Jacobian and error, each scaled by the square root of its weight:
        # the weighted least-squares problem as a plain one.
        self.row_scale = _read_only(np.repeat(np.sqrt(weights), 2))
        self.mask = _read_only(skeleton.ancestors[links])
        self.active = _read_only(self.mask.any(axis=0))
        self.subtree_weight = _read_only(weights @ self.mask)
        self.error_clamp = ERROR_CLAMP * skeleton.reach
        self.has_limits = bool(skeleton.limited[self.active].any())
        # The same as Python values, for the solvers that visit one joint at a time (where
        # numpy's per-call overhead costs more than the arithmetic).
        self.below: tuple[list[int], ...] = tuple(
            np.flatnonzero(self.mask[:, i]).tolist() for i in range(skeleton.count)
        )
        self.free: list[bool] = (~skeleton.limited).tolist()
        self.lower: list[float] = skeleton.lower.tolist()
        self.upper: list[float] = skeleton.upper.tolist()
        self.weight_list: list[float] = weights.tolist()


_LAYOUTS_KEPT: Final = 32
"""Target sets whose layouts a skeleton keeps; a script that keeps changing which effectors it
aims at, or their weights, starts afresh past this many."""


def layout(skeleton: Skeleton, targets: TargetSet) -> Layout:
    """The :class:`Layout` of ``targets`` on ``skeleton``, from the skeleton's memo if there;
    ``ValueError`` unless every targeted link is one of the skeleton's (checked once per
    layout: the memo holds only links that passed)."""
    key = ("layout", targets.links.tobytes(), targets.weights.tobytes())
    memo = skeleton._memo
    found = memo.get(key)
    if found is None:
        targets.check(skeleton)
        if len(memo) >= _LAYOUTS_KEPT:
            memo.clear()
        found = memo[key] = Layout(skeleton, targets.links, targets.weights)
    return found  # type: ignore[return-value]  # the memo holds a Layout under this key


def _read_only(array: np.ndarray) -> np.ndarray:
    array.setflags(write=False)
    return array


class Problem:
    """A skeleton and its targets, as the arrays a solve reads every iteration."""

    def __init__(self, skeleton: Skeleton, targets: TargetSet, tolerance: float) -> None:
        self.layout = shared = layout(skeleton, targets)  # checks the links, too
        self.skeleton = skeleton
        self.tolerance = tolerance
        self.links = targets.links
        self.points = targets.points
        self.weights = targets.weights
        self.total_weight = shared.total_weight
        self.row_scale = shared.row_scale
        self.mask = shared.mask
        self.active = shared.active
        self.subtree_weight = shared.subtree_weight
        self.root_points = skeleton.root_points()
        self.error_clamp = shared.error_clamp
        self.has_limits = shared.has_limits

    def pose(self, angles: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Link starts (n, 2), link ends (n, 2), px, and world angles (n,), radians."""
        return tree_points(self.skeleton, angles, self.root_points)

    def errors(self, ends: np.ndarray) -> np.ndarray:
        """(k, 2) error vectors ``point - end``, px."""
        return self.points - ends[self.links]

    def objective(self, errors: np.ndarray) -> float:
        """``1/2 sum_j w_j |e_j|^2``, px^2."""
        return 0.5 * float(self.weights @ np.einsum("ij,ij->i", errors, errors))

    def rms(self, objective: float) -> float:
        """The weighted root-mean-square error for an objective, px."""
        return math.sqrt(2.0 * objective / self.total_weight)

    def arrived(self, errors: np.ndarray) -> bool:
        """Whether every targeted end is within the tolerance."""
        return bool((np.einsum("ij,ij->i", errors, errors) <= self.tolerance**2).all())

    def jacobian(self, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
        """(2k, n) stacked Jacobian with each target's rows scaled by sqrt(weight)."""
        stacked = columns(ends[self.links], starts, self.mask).reshape(-1, self.skeleton.count)
        return stacked * self.row_scale[:, None]

    def weighted(self, errors: np.ndarray, clamp: bool) -> np.ndarray:
        """(2k,) error vectors stacked and scaled by sqrt(weight); with ``clamp`` each one
        shortened to at most ``ERROR_CLAMP`` of the reach first."""
        if clamp:
            lengths = np.hypot(errors[:, 0], errors[:, 1])
            scale = np.minimum(1.0, self.error_clamp / np.maximum(lengths, 1e-300))
            errors = errors * scale[:, None]
        return errors.reshape(-1) * self.row_scale

    def solution(
        self, angles: np.ndarray, status: SolveStatus, used: int, errors: np.ndarray
    ) -> Solution:
        """The answer: free joints wrapped, the largest and every distance, px."""
        distances = np.hypot(errors[:, 0], errors[:, 1])
        return Solution(
            _wrap_free(self.skeleton, angles), status, used, float(distances.max()), distances
        )

    def escape(
        self, angles: np.ndarray, starts: np.ndarray, ends: np.ndarray, objective: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, float] | None:
        """Bend along the objective's most negative curvature, if that lowers it.

        The Hessian is the sum of each target's, as for a chain: ``w (J_a . J_b + e . (P -
        p_c))`` for joints ``a``, ``b`` that both move the target's end, ``c`` the later of
        the two. Returns ``(angles, starts, ends, objective)`` of the better bend, or None at a
        true minimum (the weighted compromise of targets that cannot all be reached, say) or
        when limits block both bends.
        """
        n = self.skeleton.count
        effectors = ends[self.links]
        arms = (effectors[:, None, :] - starts[None, :, :]) * self.mask[:, :, None]
        errors = self.points - effectors
        stacked = self.jacobian(starts, ends)
        pulls = np.einsum("kni,ki->kn", arms, errors) * self.weights[:, None]
        later = np.maximum.outer(np.arange(n), np.arange(n))
        both = self.mask[:, :, None] & self.mask[:, None, :]
        hessian = stacked.T @ stacked + (pulls[:, later] * both).sum(axis=0)
        eigenvalues, eigenvectors = np.linalg.eigh(hessian)
        scale = self.total_weight * self.skeleton.reach**2
        if eigenvalues[0] >= -NEGATIVE_CURVATURE * scale:
            return None
        direction = eigenvectors[:, 0] * self.active
        bend = direction * (ESCAPE_ANGLE / float(np.abs(direction).max()))
        best = None
        for trial in (self.skeleton.clamp(angles + bend), self.skeleton.clamp(angles - bend)):
            trial_starts, trial_ends, _ = self.pose(trial)
            trial_objective = self.objective(self.errors(trial_ends))
            better = trial_objective < objective * (1.0 - _ROUNDING)
            if better and (best is None or trial_objective < best[3]):
                best = (trial, trial_starts, trial_ends, trial_objective)
        return best


def prepare(
    skeleton: Skeleton,
    angles: object,
    targets: object,
    max_iterations: object,
    tolerance: object,
) -> tuple[Problem, np.ndarray]:
    """The checked problem and the start angles clamped to the limits (a new array)."""
    if not isinstance(targets, TargetSet):
        raise ValueError(f"targets must be a TargetSet, got {type(targets).__name__}")
    tol = _check_settings(max_iterations, tolerance)
    start = skeleton.clamp(check_angles(angles, skeleton.count))
    return Problem(skeleton, targets, tol), start


def as_chain_solve(
    solve: Solver,
    skeleton: Skeleton,
    angles: np.ndarray,
    targets: object,
    max_iterations: int,
    tolerance: float,
) -> Solution | None:
    """The chain solver's own answer when the problem is a chain's tip and one target, else None.

    That case is the chain solvers' whole job, so it is theirs exactly, not an approximation.
    """
    if not (
        isinstance(targets, TargetSet)
        and len(targets) == 1
        and skeleton.is_chain
        and not skeleton.has_root_offsets
        and int(targets.links[0]) == skeleton.count - 1
    ):
        return None
    sol = solve(
        skeleton, angles, targets.points[0], max_iterations=max_iterations, tolerance=tolerance
    )
    return Solution(sol.angles, sol.status, sol.iterations, sol.error, np.array([sol.error]))
