"""Cyclic coordinate descent for several targets on a tree.

One pass visits the joints from the last index to the first, so every joint comes after all the
joints below it, as in the chain's pass from the tip to the root. Each joint turns by the angle
that best serves the targeted ends below it: rotating the arms ``r_j`` (joint to end) by
``theta`` toward the arms ``t_j`` (joint to target) changes the weighted objective by
``-sum_j w_j (R(theta) r_j . t_j)`` plus a constant, which is largest at

    theta = atan2(sum_j w_j (r_j x t_j), sum_j w_j (r_j . t_j)),

the chain's rotation when there is one target. A limited joint is clamped without wrapping (it
never goes the long way round through its limit), a free one wrapped to [-pi, pi], and the ends
below it are moved by the rotation actually applied. Joints with no targeted end below them are
never visited: an effector without a target holds its pose. Each turn is the exact minimum
along that joint, so the objective never rises and the solve settles at a stationary point: all
targets reached, or their weighted least-squares compromise.

A chain with one target at its tip is solved by :func:`~ikgame.kinematics.ccd.solve_ccd` itself.

Angles are radians, lengths and positions pixels.
"""

from __future__ import annotations

import math

import numpy as np

from ikgame.kinematics._multi import Problem, as_chain_solve, prepare
from ikgame.kinematics.ccd import TRIVIAL_ARC_LENGTH, solve_ccd, wrap_angle
from ikgame.kinematics.skeleton import Skeleton
from ikgame.kinematics.solver import Solution, SolveStatus
from ikgame.kinematics.targets import TargetSet

__all__ = ["solve_ccd_targets"]


def solve_ccd_targets(
    skeleton: Skeleton,
    angles: np.ndarray,
    targets: TargetSet,
    *,
    max_iterations: int = 10,
    tolerance: float = 1.0,
) -> Solution:
    """Repeat multi-target CCD passes until every target is reached, a stall, or the budget.

    ``angles`` (radians) warm-starts the solve; ``tolerance`` (px) is the arrival distance of
    every target. A pass that turns nothing is a stall: a saddle (a straight branch aimed along
    its own line) is bent out of, a true minimum ends in ``FAILURE``.

    >>> tree = Skeleton.tree([100, 60, 60], [-1, 0, 0])
    >>> targets = TargetSet([1, 2], [(137.3, 72.6), (152.9, 11.8)])
    >>> sol = solve_ccd_targets(tree, np.zeros(3), targets, max_iterations=100)
    >>> sol.status.value, bool(sol.errors.max() <= 1.0)
    ('success', True)
    """
    chain = as_chain_solve(solve_ccd, skeleton, angles, targets, max_iterations, tolerance)
    if chain is not None:
        return chain
    problem, current = prepare(skeleton, angles, targets, max_iterations, tolerance)
    passes = _Passes(problem)
    starts, ends, _ = problem.pose(current)
    errors = problem.errors(ends)
    used = 0
    while not problem.arrived(errors):
        if used == max_iterations:
            return problem.solution(current, SolveStatus.PROCESSING, used, errors)
        used += 1
        turned = passes.run(current, starts, ends)
        starts, ends, _ = problem.pose(current)
        errors = problem.errors(ends)
        if not turned:
            escaped = problem.escape(current, starts, ends, problem.objective(errors))
            if escaped is None:
                return problem.solution(current, SolveStatus.FAILURE, used, errors)
            current, starts, ends, _ = escaped
            errors = problem.errors(ends)
    return problem.solution(current, SolveStatus.SUCCESS, used, errors)


class _Passes:
    """The problem as Python floats (CCD visits one joint at a time, where numpy's per-call
    overhead costs more than the arithmetic), with the pass itself."""

    def __init__(self, problem: Problem) -> None:
        shared = problem.layout
        self.below = shared.below
        self.free = shared.free
        self.lower = shared.lower
        self.upper = shared.upper
        self.tx, self.ty = (list(v) for v in zip(*problem.points.tolist(), strict=True))
        self.weights = shared.weight_list
        self.links = problem.links
        self.tolerance_sqr = problem.tolerance**2

    def run(self, angles: np.ndarray, starts: np.ndarray, ends: np.ndarray) -> bool:
        """One pass; updates ``angles`` in place and returns whether any end moved noticeably.

        Stops early once every target is within the tolerance.
        """
        tx, ty, weights = self.tx, self.ty, self.weights
        below_of, free, lower, upper = self.below, self.free, self.lower, self.upper
        effectors = ends[self.links]
        px = effectors[:, 0].tolist()
        py = effectors[:, 1].tolist()
        sx = starts[:, 0].tolist()
        sy = starts[:, 1].tolist()
        new = angles.tolist()
        turned = False
        tolerance_sqr = self.tolerance_sqr
        # Whether each target is within the tolerance; a turn only changes those below it.
        inside = [
            (tx[j] - px[j]) ** 2 + (ty[j] - py[j]) ** 2 <= tolerance_sqr for j in range(len(px))
        ]
        # Comparisons below stand for max() and min() (the same picks, without the calls).
        for i in range(len(new) - 1, -1, -1):
            below = below_of[i]
            if not below:
                continue
            jx, jy = sx[i], sy[i]
            dot = cross = longest = 0.0
            for j in below:
                rx, ry = px[j] - jx, py[j] - jy
                qx, qy = tx[j] - jx, ty[j] - jy
                dot += weights[j] * (rx * qx + ry * qy)
                cross += weights[j] * (rx * qy - ry * qx)
                arm_sqr = rx * rx + ry * ry
                if arm_sqr > longest:
                    longest = arm_sqr
            rot = math.atan2(cross, dot)
            wanted = new[i] + rot
            if free[i]:
                new[i] = wrap_angle(wanted)
            else:
                clamped = lower[i] if lower[i] > wanted else wanted
                if upper[i] < clamped:
                    clamped = upper[i]
                rot += clamped - wanted
                new[i] = clamped
            cos_rot, sin_rot = math.cos(rot), math.sin(rot)
            for j in below:
                rx, ry = px[j] - jx, py[j] - jy
                px[j] = x = jx + cos_rot * rx - sin_rot * ry
                py[j] = y = jy + sin_rot * rx + cos_rot * ry
                inside[j] = (tx[j] - x) ** 2 + (ty[j] - y) ** 2 <= tolerance_sqr
            if not turned and abs(rot) * math.sqrt(longest) > TRIVIAL_ARC_LENGTH:
                turned = True
            if all(inside):
                break
        angles[:] = new
        return turned
