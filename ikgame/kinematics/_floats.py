"""A serial chain's arrays as Python floats, for the solvers that walk it joint by joint.

CCD and FABRIK visit one joint at a time; there numpy's per-call overhead costs more than the
arithmetic, so they work on plain lists (px, radians).
"""

from __future__ import annotations

import math
from collections.abc import MutableSequence, Sequence

import numpy as np

from ikgame.kinematics._compiled import compiled_end
from ikgame.kinematics.skeleton import Skeleton, check_angles, check_point


def check_chain(skeleton: Skeleton) -> None:
    """``ValueError`` unless ``skeleton`` is a serial chain with its joint 0 on the base."""
    if not skeleton.is_chain:
        raise ValueError("this solver needs a serial chain (parents[i] == i - 1)")
    if skeleton.has_root_offsets:
        raise ValueError(
            "this solver needs joint 0 on the base (zero root_offsets); "
            "the multi-target solvers take root offsets"
        )


def float_angles(angles: object, count: int) -> list[float]:
    """``angles`` as a list of floats, or ``ValueError`` (as :func:`check_angles` words it).

    The common case, a float array of the right shape, is checked without numpy's per-call
    overhead: this runs every tick.
    """
    if isinstance(angles, np.ndarray) and angles.shape == (count,) and angles.dtype == float:
        listed = angles.tolist()
        if all(map(math.isfinite, listed)):
            return listed
    return check_angles(angles, count).tolist()


def float_point(point: object) -> tuple[float, float]:
    """``point`` as two finite floats, px, or ``ValueError`` (as :func:`check_point` words it)."""
    if isinstance(point, np.ndarray) and point.shape == (2,) and point.dtype == float:
        x, y = point.tolist()
    elif isinstance(point, tuple) and len(point) == 2 and all(type(v) is float for v in point):
        x, y = point
    else:
        x, y = check_point(point).tolist()
    if not (math.isfinite(x) and math.isfinite(y)):
        x, y = check_point(point).tolist()
    return x, y


def forward(
    lengths: Sequence[float],
    angles: Sequence[float],
    x: float,
    y: float,
    heading: float,
    xs: MutableSequence[float],
    ys: MutableSequence[float],
) -> None:
    """Forward kinematics of a chain from its base at (``x``, ``y``) px facing ``heading``
    (radians), written into ``xs`` and ``ys``: every joint, then the end effector, px.

    Lists or numpy arrays alike, so that the same code runs in Python and compiled
    (:mod:`ikgame.kinematics._compiled`).

    >>> xs, ys = [0.0] * 3, [0.0] * 3
    >>> forward([1.0, 2.0], [0.0, 0.0], 5.0, 0.0, 0.0, xs, ys)
    >>> xs
    [5.0, 6.0, 8.0]
    """
    xs[0] = x
    ys[0] = y
    for i in range(len(lengths)):
        heading += angles[i]
        x += lengths[i] * math.cos(heading)
        y += lengths[i] * math.sin(heading)
        xs[i + 1] = x
        ys[i + 1] = y


class FloatChain:
    """A chain's lengths, limits and base as floats, with forward kinematics on lists."""

    def __init__(self, skeleton: Skeleton) -> None:
        check_chain(skeleton)
        self.lengths: list[float] = skeleton.lengths.tolist()
        self.lower: list[float] = skeleton.lower.tolist()
        self.upper: list[float] = skeleton.upper.tolist()
        self.free: list[bool] = (~skeleton.limited).tolist()
        self.base_x = float(skeleton.base[0])
        self.base_y = float(skeleton.base[1])
        self.base_angle = skeleton.base_angle
        # A long chain's end effector by compiled forward kinematics, where numba can: the
        # same floats (see ikgame.kinematics._compiled), and on most ticks the solver's checks
        # of a tracking chain's error are what a solve costs.
        self._end = compiled_end(self)

    def clamp(self, angles: list[float]) -> list[float]:
        """:meth:`Skeleton.clamp` over lists: the same floats as ``np.clip`` against the limit
        arrays gives (where an angle equals a limit, the limit, whichever zero it is)."""
        out = []
        for angle, low, high in zip(angles, self.lower, self.upper, strict=True):
            angle = angle if angle > low else low
            out.append(angle if angle < high else high)
        return out

    def joints(self, angles: list[float]) -> tuple[list[float], list[float]]:
        """World x and y of every joint, then the end effector, px."""
        xs = [0.0] * (len(self.lengths) + 1)
        ys = [0.0] * (len(self.lengths) + 1)
        forward(self.lengths, angles, self.base_x, self.base_y, self.base_angle, xs, ys)
        return xs, ys

    def error_sqr(self, angles: list[float], tx: float, ty: float) -> float:
        """Squared distance from the end effector to the target by forward kinematics, px^2."""
        end = self._end
        if end is not None:
            x, y = end(self, angles)
            return (x - tx) ** 2 + (y - ty) ** 2
        xs, ys = self.joints(angles)
        return (xs[-1] - tx) ** 2 + (ys[-1] - ty) ** 2

    def within_reach(self, tx: float, ty: float) -> bool:
        """True when the target is strictly closer to the base than the chain's full length."""
        return math.hypot(tx - self.base_x, ty - self.base_y) < sum(self.lengths)
