"""FABRIK for several targets on a tree, with sub-bases where branches meet.

The backward pass walks from the targeted ends toward the base, as for a chain, one link at a
time from the last index to the first. Where branches meet (a sub-base, the end of a link with
several children on the way to targets) each branch proposes its own position for that joint;
the joint goes to their centroid, each proposal weighted by the sum of the target weights in its
branch (a target on the link's own end joins in with its weight). The forward pass then pins the
roots back on their joints and places link after link aimed at the backward pass's positions,
applying each joint limit exactly as the angles are read off. Links with no targeted end below
them keep their angles: an effector without a target holds its pose.

The centroid is a compromise of its own, not the weighted least-squares one, and the passes
fight joint limits just as on a chain; so when there are several targets, or limits, a pass that
gains less than ``POLISH_PROGRESS`` of the weighted RMS error hands the rest of the solve to
damped least squares, which settles at the weighted least-squares optimum.

A chain with one target at its tip is solved by :func:`~ikgame.kinematics.fabrik.solve_fabrik`.

Angles are radians, lengths and positions pixels.
"""

from __future__ import annotations

import math

import numpy as np

from ikgame.kinematics._multi import Problem, as_chain_solve, prepare
from ikgame.kinematics.ccd import TRIVIAL_ARC_LENGTH
from ikgame.kinematics.fabrik import POLISH_PROGRESS, _direction, fit_angle, solve_fabrik
from ikgame.kinematics.multi_jacobian import solve_dls_targets
from ikgame.kinematics.skeleton import Skeleton
from ikgame.kinematics.solver import Solution, SolveStatus
from ikgame.kinematics.targets import TargetSet

__all__ = ["solve_fabrik_targets"]


def solve_fabrik_targets(
    skeleton: Skeleton,
    angles: np.ndarray,
    targets: TargetSet,
    *,
    max_iterations: int = 10,
    tolerance: float = 1.0,
) -> Solution:
    """Repeat backward and forward passes over the tree until every target is reached, a stall,
    or ``max_iterations``; hand over to damped least squares as the module notes say.

    A pass that would raise the weighted objective is not taken. ``angles`` (radians)
    warm-starts the solve; ``tolerance`` is in px.

    >>> tree = Skeleton.tree([100, 60, 60], [-1, 0, 0])
    >>> targets = TargetSet([1, 2], [(137.3, 72.6), (152.9, 11.8)])
    >>> sol = solve_fabrik_targets(tree, np.zeros(3), targets, max_iterations=50)
    >>> sol.status.value, bool(sol.errors.max() <= 1.0)
    ('success', True)
    """
    chain = as_chain_solve(solve_fabrik, skeleton, angles, targets, max_iterations, tolerance)
    if chain is not None:
        return chain
    problem, current = prepare(skeleton, angles, targets, max_iterations, tolerance)
    passes = _Passes(problem)
    polish = problem.has_limits or len(targets) > 1
    starts, ends, world = problem.pose(current)
    errors = problem.errors(ends)
    objective = problem.objective(errors)
    used = 0
    while not problem.arrived(errors):
        if used == max_iterations:
            return problem.solution(current, SolveStatus.PROCESSING, used, errors)
        used += 1
        trial = passes.run(current, starts, world)
        trial_starts, trial_ends, trial_world = problem.pose(trial)
        trial_errors = problem.errors(trial_ends)
        trial_objective = problem.objective(trial_errors)
        rms = problem.rms(objective)
        progress = rms - problem.rms(trial_objective)
        if progress > 0.0:
            current, starts, ends, world = trial, trial_starts, trial_ends, trial_world
            errors, objective = trial_errors, trial_objective
        if polish and progress < POLISH_PROGRESS * rms:
            if used == max_iterations:
                return problem.solution(current, SolveStatus.PROCESSING, used, errors)
            sol = solve_dls_targets(
                skeleton,
                current,
                targets,
                max_iterations=max_iterations - used,
                tolerance=problem.tolerance,
            )
            return Solution(sol.angles, sol.status, used + sol.iterations, sol.error, sol.errors)
        if progress >= TRIVIAL_ARC_LENGTH:
            continue
        escaped = problem.escape(current, starts, ends, objective)
        if escaped is None:
            return problem.solution(current, SolveStatus.FAILURE, used, errors)
        current, starts, ends, objective = escaped
        world = problem.pose(current)[2]
        errors = problem.errors(ends)
    return problem.solution(current, SolveStatus.SUCCESS, used, errors)


class _Passes:
    """The tree as Python floats, with one backward and forward pass."""

    def __init__(self, problem: Problem) -> None:
        skeleton = problem.skeleton
        n = skeleton.count
        self.parents: list[int] = skeleton.parents.tolist()
        self.lengths: list[float] = skeleton.lengths.tolist()
        self.free: list[bool] = (~skeleton.limited).tolist()
        self.lower: list[float] = skeleton.lower.tolist()
        self.upper: list[float] = skeleton.upper.tolist()
        self.active: list[bool] = problem.active.tolist()
        self.subtree_weight: list[float] = problem.subtree_weight.tolist()
        self.roots: list[list[float]] = problem.root_points.tolist()
        self.base_angle = skeleton.base_angle
        # Each link's own target, weighted: the seed of the backward pass's sums.
        self.own_x = [0.0] * n
        self.own_y = [0.0] * n
        self.own_w = [0.0] * n
        for link, (x, y), w in zip(
            problem.links.tolist(), problem.points.tolist(), problem.weights.tolist(), strict=True
        ):
            self.own_x[link], self.own_y[link], self.own_w[link] = w * x, w * y, w

    def run(self, angles: np.ndarray, starts: np.ndarray, world: np.ndarray) -> np.ndarray:
        """One backward and one forward pass from ``angles``; returns the new angles."""
        reached_x, reached_y = self._backward(starts, world)
        return self._forward(angles.tolist(), world.tolist(), reached_x, reached_y)

    def _backward(self, starts: np.ndarray, world: np.ndarray) -> tuple[list[float], list[float]]:
        """Where each targeted link's end should go, px, walking from the ends to the base."""
        sum_x, sum_y, sum_w = list(self.own_x), list(self.own_y), list(self.own_w)
        old_x = starts[:, 0].tolist()
        old_y = starts[:, 1].tolist()
        headings = world.tolist()
        reached_x = [0.0] * len(sum_x)
        reached_y = [0.0] * len(sum_x)
        for i in range(len(sum_x) - 1, -1, -1):
            if not self.active[i]:
                continue
            bx = sum_x[i] / sum_w[i]
            by = sum_y[i] / sum_w[i]
            reached_x[i], reached_y[i] = bx, by
            parent = self.parents[i]
            if parent < 0:
                continue
            heading = _direction(bx - old_x[i], by - old_y[i], headings[i])
            w = self.subtree_weight[i]
            sum_x[parent] += w * (bx - self.lengths[i] * math.cos(heading))
            sum_y[parent] += w * (by - self.lengths[i] * math.sin(heading))
            sum_w[parent] += w
        return reached_x, reached_y

    def _forward(
        self,
        angles: list[float],
        world: list[float],
        reached_x: list[float],
        reached_y: list[float],
    ) -> np.ndarray:
        """Roots on their joints, each targeted link aimed at its backward position."""
        n = len(angles)
        end_x = [0.0] * n
        end_y = [0.0] * n
        new = list(angles)
        for i, parent in enumerate(self.parents):
            if parent < 0:
                x, y = self.roots[i]
                parent_world = self.base_angle
            else:
                x, y = end_x[parent], end_y[parent]
                parent_world = world[parent]
            if self.active[i]:
                heading = _direction(reached_x[i] - x, reached_y[i] - y, world[i])
                new[i] = fit_angle(
                    heading - parent_world, angles[i], self.free[i], self.lower[i], self.upper[i]
                )
            world[i] = parent_world + new[i]
            end_x[i] = x + self.lengths[i] * math.cos(world[i])
            end_y[i] = y + self.lengths[i] * math.sin(world[i])
        return np.array(new)
