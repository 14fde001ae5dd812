"""FABRIK: forward and backward reaching inverse kinematics (Aristidou & Lasenby 2011), in 2D.

FABRIK moves joint positions rather than angles. The backward pass pins the end effector to the
target and walks toward the base, putting each joint back at its link's length from the one
after it; the forward pass pins joint 0 back to the base and walks out again. The angles are
read off the forward pass, which places link after link, so each joint limit is applied there
exactly, with no conversion afterwards. The backward pass respects the limits too (it turns a
link no further from the next link's direction than the next joint allows) so that the two
passes fight less. They can still fight: with joints pressed against their limits the passes
crawl or stall short of a target that is in reach (FABRIK's known weakness with constraints).
So on a chain with limits a pass that gains little hands the rest of the solve to damped least
squares, which leaves the joints pressing into their limits alone and moves the others: the
passes make the big moves, the polish slides the chain along its limits to the target.

A limited joint's angle is read as the representative nearest its previous angle before it is
clamped, so a joint never jumps round through its limit; a free joint is wrapped to [-pi, pi].

Angles are radians, lengths and positions pixels.
"""

from __future__ import annotations

import math
from itertools import accumulate
from typing import Final

import numpy as np

from ikgame.kinematics._floats import FloatChain
from ikgame.kinematics.ccd import TRIVIAL_ARC_LENGTH, wrap_angle
from ikgame.kinematics.jacobian import (
    _check_solve_inputs,
    _escape_saddle,
    _solution,
    solve_dls,
)
from ikgame.kinematics.skeleton import Skeleton
from ikgame.kinematics.solver import Solution, SolveStatus

__all__ = ["solve_fabrik", "POLISH_PROGRESS"]

POLISH_PROGRESS: Final = 0.1
"""On a chain with limits, a pass that gains less than this fraction of the error hands over to
damped least squares (dimensionless).

Against a limit the two passes pull against each other and crawl (a median of 50 passes on
chains limited to +-10 deg) or stop; damped least squares drops the joints pressing into their
limits and moves the others, and needs a median of 3 iterations from there."""


def solve_fabrik(
    skeleton: Skeleton,
    angles: np.ndarray,
    target: np.ndarray,
    *,
    max_iterations: int = 10,
    tolerance: float = 1.0,
) -> Solution:
    """Repeat backward and forward reaching passes until success, failure or ``max_iterations``.

    A target out of reach is answered at once with the chain stretched straight toward it and
    ``FAILURE``, when the limits allow that pose; otherwise the passes pull the chain as
    straight as the limits let it be. On a chain with limits, once a pass gains less than
    ``POLISH_PROGRESS`` of the error, damped least squares takes over for the iterations left.
    On a free chain a pass that gains less than ``TRIVIAL_ARC_LENGTH`` is a stall: a straight
    chain with the target on its own line is bent out of it (FABRIK alone would never leave that
    line); anything else ends in ``FAILURE``. A pass that would raise the error is not taken.
    ``angles`` (radians) warm-starts the solve; ``tolerance`` is in px.

    >>> sol = solve_fabrik(Skeleton.chain([100, 100]), np.zeros(2), (0, 150))
    >>> sol.status.value, sol.error <= 1.0
    ('success', True)
    """
    start, target, tolerance = _check_solve_inputs(
        skeleton, angles, target, max_iterations, tolerance
    )
    links = _Links(skeleton)
    tx, ty = float(target[0]), float(target[1])
    current = start.tolist()
    xs, ys = links.joints(current)
    error = math.hypot(xs[-1] - tx, ys[-1] - ty)
    if error <= tolerance:
        return _solution(skeleton, start, SolveStatus.SUCCESS, 0, error)
    if math.hypot(tx - links.base_x, ty - links.base_y) >= skeleton.reach:
        stretched = _stretched_toward(links, tx, ty)
        if np.array_equal(skeleton.clamp(stretched), stretched):
            xs, ys = links.joints(stretched.tolist())
            error = math.hypot(xs[-1] - tx, ys[-1] - ty)
            status = SolveStatus.SUCCESS if error <= tolerance else SolveStatus.FAILURE
            return _solution(skeleton, stretched, status, 1, error)
    has_limits = bool(skeleton.limited.any())
    used = 0
    while error > tolerance:
        if used == max_iterations:
            return _solution(skeleton, np.array(current), SolveStatus.PROCESSING, used, error)
        used += 1
        reached = _backward_pass(links, current, xs, ys, tx, ty)
        trial, trial_xs, trial_ys = _forward_pass(links, current, reached)
        trial_error = math.hypot(trial_xs[-1] - tx, trial_ys[-1] - ty)
        progress = error - trial_error
        slow = progress < POLISH_PROGRESS * error
        if progress > 0.0:
            current, xs, ys, error = trial, trial_xs, trial_ys, trial_error
        if has_limits and slow:
            return _polish(
                skeleton, np.array(current), target, tolerance, max_iterations - used, used, error
            )
        if progress >= TRIVIAL_ARC_LENGTH:
            continue
        escaped = _escape_saddle(
            skeleton, np.array(current), np.column_stack((xs, ys)), target, error
        )
        if escaped is None:
            return _solution(skeleton, np.array(current), SolveStatus.FAILURE, used, error)
        current = escaped[0].tolist()
        xs, ys = escaped[1][:, 0].tolist(), escaped[1][:, 1].tolist()
        error = escaped[2]
    return _solution(skeleton, np.array(current), SolveStatus.SUCCESS, used, error)


def _polish(
    skeleton: Skeleton,
    angles: np.ndarray,
    target: np.ndarray,
    tolerance: float,
    remaining: int,
    used: int,
    error: float,
) -> Solution:
    """Damped least squares from where the passes slowed down, for the ``remaining`` iterations."""
    if remaining < 1:
        return _solution(skeleton, angles, SolveStatus.PROCESSING, used, error)
    sol = solve_dls(skeleton, angles, target, max_iterations=remaining, tolerance=tolerance)
    return Solution(sol.angles, sol.status, used + sol.iterations, sol.error)


class _Links(FloatChain):
    """A chain as floats, with FABRIK's way of fitting an angle into a joint's limits."""

    def limited(self, i: int, angle: float, previous: float) -> float:
        """``angle`` as joint ``i``'s angle (see :func:`fit_angle`)."""
        return fit_angle(angle, previous, self.free[i], self.lower[i], self.upper[i])


def fit_angle(angle: float, previous: float, free: bool, lower: float, upper: float) -> float:
    """``angle`` as a joint's angle: wrapped if the joint is free, else clamped into its limits
    from the representative nearest ``previous`` (so never round the long way)."""
    if free:
        return wrap_angle(angle)
    nearest = previous + wrap_angle(angle - previous)
    return min(max(nearest, lower), upper)


def _stretched_toward(links: _Links, tx: float, ty: float) -> np.ndarray:
    """Local angles of the straight chain pointing from the base at the target, radians."""
    stretched = np.zeros(len(links.lengths))
    stretched[0] = wrap_angle(math.atan2(ty - links.base_y, tx - links.base_x) - links.base_angle)
    return stretched


def _backward_pass(
    links: _Links, angles: list[float], xs: list[float], ys: list[float], tx: float, ty: float
) -> tuple[list[float], list[float], list[float]]:
    """Joint positions with the end pinned to the target, walking back toward the base.

    Returns the joints' x and y (n + 1 each, px) and each link's world direction (radians).
    """
    n = len(angles)
    world = list(accumulate(angles, initial=links.base_angle))[1:]
    xs = list(xs)
    ys = list(ys)
    headings = [0.0] * n
    xs[n], ys[n] = tx, ty
    for i in range(n - 1, -1, -1):
        heading = _direction(xs[i + 1] - xs[i], ys[i + 1] - ys[i], world[i])
        if i < n - 1:
            bend = links.limited(i + 1, headings[i + 1] - heading, angles[i + 1])
            heading = headings[i + 1] - bend
        headings[i] = heading
        xs[i] = xs[i + 1] - links.lengths[i] * math.cos(heading)
        ys[i] = ys[i + 1] - links.lengths[i] * math.sin(heading)
    return xs, ys, headings


def _forward_pass(
    links: _Links,
    angles: list[float],
    reached: tuple[list[float], list[float], list[float]],
) -> tuple[list[float], list[float], list[float]]:
    """Joint 0 back on the base, each link aimed at the next joint of the backward pass.

    Returns the new local angles (radians, within the limits) and the joints' x and y (px),
    which are the forward kinematics of those angles.
    """
    reached_xs, reached_ys, headings = reached
    x, y = links.base_x, links.base_y
    new = []
    xs = [x]
    ys = [y]
    parent = links.base_angle
    for i, length in enumerate(links.lengths):
        heading = _direction(reached_xs[i + 1] - x, reached_ys[i + 1] - y, headings[i])
        angle = links.limited(i, heading - parent, angles[i])
        new.append(angle)
        parent += angle
        x += length * math.cos(parent)
        y += length * math.sin(parent)
        xs.append(x)
        ys.append(y)
    return new, xs, ys


def _direction(dx: float, dy: float, fallback: float) -> float:
    """Direction of (dx, dy), radians; two joints on top of each other keep ``fallback``."""
    return math.atan2(dy, dx) if dx or dy else fallback
