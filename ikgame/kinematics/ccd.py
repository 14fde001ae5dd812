"""Cyclic coordinate descent (CCD) in 2D.

:func:`ccd_iteration` is Ryan Juckett's ``CalcIK_2D_CCD`` ("Cyclic Coordinate Descent in 2D",
2009) reproduced operation for operation: bones as ``(x, y, angle)`` in parent space, the last
bone is the end effector, one pass from the last joint to the root, early out on arrival, and
the article's constants for the degenerate case and for detecting that nothing moved.
:func:`solve_ccd` builds the limit-aware solve loop on top of the same per-joint rotation.
"""

from __future__ import annotations

import math
from collections.abc import MutableSequence, Sequence
from typing import Final

import numpy as np

from ikgame.kinematics._compiled import compiled_pass
from ikgame.kinematics._floats import FloatChain, float_angles, float_point, forward
from ikgame.kinematics.skeleton import Skeleton, check_angles, check_point
from ikgame.kinematics.solver import Solution, SolveStatus

__all__ = [
    "CCDResult",
    "EPSILON",
    "TRIVIAL_ARC_LENGTH",
    "wrap_angle",
    "ccd_iteration",
    "ccd_iteration_limited",
    "solve_ccd",
]

EPSILON: Final = 1e-4
"""Below this product of distances (px^2) a joint is left alone: no division by tiny numbers."""

TRIVIAL_ARC_LENGTH: Final = 1e-5
"""An end-effector arc shorter than this (px) counts as no motion, which signals failure."""

CCDResult = SolveStatus
"""The article's name for the three iteration states: ``SUCCESS``, ``PROCESSING``, ``FAILURE``."""

_TWO_PI: Final = 2.0 * math.pi
_NUDGE: Final = 0.05
"""Bend (radians per joint) that gets a stalled, straight chain off its own line."""


def wrap_angle(angle: float) -> float:
    """The equivalent rotation in [-pi, pi], radians (the article's ``SimplifyAngle``).

    C#'s ``%`` keeps the sign of the dividend, as :func:`math.fmod` does.

    >>> round(wrap_angle(3 * math.pi / 2), 12) == round(-math.pi / 2, 12)
    True
    """
    angle = math.fmod(angle, _TWO_PI)
    if angle < -math.pi:
        angle += _TWO_PI
    elif angle > math.pi:
        angle -= _TWO_PI
    return angle


def _rotation_toward(
    jx: float, jy: float, ex: float, ey: float, tx: float, ty: float
) -> tuple[float, float, float, float]:
    """Rotation about joint (jx, jy) that puts the end (ex, ey) on the line to the target.

    Returns ``(cos, sin, angle, joint_to_end_distance)``, as the article computes them.
    """
    cur_to_end_x = ex - jx
    cur_to_end_y = ey - jy
    cur_to_end_mag = math.sqrt(cur_to_end_x * cur_to_end_x + cur_to_end_y * cur_to_end_y)
    cur_to_target_x = tx - jx
    cur_to_target_y = ty - jy
    cur_to_target_mag = math.sqrt(
        cur_to_target_x * cur_to_target_x + cur_to_target_y * cur_to_target_y
    )
    end_target_mag = cur_to_end_mag * cur_to_target_mag
    if end_target_mag <= EPSILON:
        cos_rot, sin_rot = 1.0, 0.0
    else:
        cos_rot = (cur_to_end_x * cur_to_target_x + cur_to_end_y * cur_to_target_y) / end_target_mag
        sin_rot = (cur_to_end_x * cur_to_target_y - cur_to_end_y * cur_to_target_x) / end_target_mag
    # min and max written out (the same floats), so that this compiles as it is.
    clipped = cos_rot if cos_rot < 1.0 else 1.0
    rot = math.acos(clipped if clipped > -1.0 else -1.0)
    if sin_rot < 0.0:
        rot = -rot
    return cos_rot, sin_rot, rot, cur_to_end_mag


def _check_arrival(arrival_dist: float) -> float:
    arrival = float(arrival_dist)
    if not math.isfinite(arrival) or arrival < 0:
        raise ValueError(f"arrival distance must be finite and >= 0 px, got {arrival_dist!r}")
    return arrival


def _check_bones(bones: object) -> np.ndarray:
    try:
        arr = np.asarray(bones, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"bones must be rows of numbers (x, y, angle), got {bones!r}") from exc
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"bones must have shape (n, 3) of (x, y, angle), got shape {arr.shape}")
    if arr.shape[0] == 0:
        raise ValueError("bones must hold at least one bone, got none")
    if not np.all(np.isfinite(arr)):
        raise ValueError("bones must be finite (no NaN or infinity)")
    return arr


def ccd_iteration(
    bones: object, target: object, arrival_dist: float
) -> tuple[SolveStatus, np.ndarray]:
    """One CCD iteration over ``bones``, exactly as the article's ``CalcIK_2D_CCD``.

    ``bones`` is an (n, 3) array-like of ``(x, y, angle)`` in parent space (bone 0 relative to
    the origin; the last bone is the end effector). Returns ``(result, angles)`` with the n
    updated local angles in a new array; ``bones`` is not changed.

    >>> result, angles = ccd_iteration([(0, 0, 0), (1, 0, 0), (1, 0, 0)], (1, 1), 1e-3)
    >>> result.value, np.round(angles, 6).tolist()
    ('success', [0.0, 1.570796, 0.0])
    """
    arr = _check_bones(bones)
    tx, ty = (float(v) for v in check_point(target))
    arrival_dist_sqr = _check_arrival(arrival_dist) ** 2
    rows = arr.tolist()
    num_bones = len(rows)

    world_x = [rows[0][0]]
    world_y = [rows[0][1]]
    world_angle = rows[0][2]
    cos_a = [math.cos(world_angle)]
    sin_a = [math.sin(world_angle)]
    for x, y, angle in rows[1:]:
        world_x.append(world_x[-1] + cos_a[-1] * x - sin_a[-1] * y)
        world_y.append(world_y[-1] + sin_a[-1] * x + cos_a[-1] * y)
        world_angle += angle
        cos_a.append(math.cos(world_angle))
        sin_a.append(math.sin(world_angle))

    angles = [row[2] for row in rows]
    end_x = world_x[-1]
    end_y = world_y[-1]
    modified_bones = False
    for i in range(num_bones - 2, -1, -1):
        jx, jy = world_x[i], world_y[i]
        cos_rot, sin_rot, rot, cur_to_end_mag = _rotation_toward(jx, jy, end_x, end_y, tx, ty)
        cur_to_end_x = end_x - jx
        cur_to_end_y = end_y - jy
        end_x = jx + cos_rot * cur_to_end_x - sin_rot * cur_to_end_y
        end_y = jy + sin_rot * cur_to_end_x + cos_rot * cur_to_end_y
        angles[i] = wrap_angle(angles[i] + rot)
        dx = tx - end_x
        dy = ty - end_y
        if dx * dx + dy * dy <= arrival_dist_sqr:
            return SolveStatus.SUCCESS, np.array(angles)
        if not modified_bones and abs(rot) * cur_to_end_mag > TRIVIAL_ARC_LENGTH:
            modified_bones = True
    status = SolveStatus.PROCESSING if modified_bones else SolveStatus.FAILURE
    return status, np.array(angles)


def ccd_iteration_limited(
    skeleton: Skeleton, angles: np.ndarray, target: np.ndarray, arrival_dist: float
) -> tuple[SolveStatus, np.ndarray]:
    """One CCD iteration on a chain that clamps each joint to its limits as it goes.

    Free joints are wrapped to [-pi, pi] as in the article; a limited joint is clamped without
    wrapping, so it never reaches a target by going the long way round through its limit. The
    end effector is then moved by the rotation actually applied. With no limits and
    ``base_angle == 0`` this is :func:`ccd_iteration` on the same chain.

    >>> chain = Skeleton.chain([1.0, 1.0], limits=[(-0.5, 0.5), None])
    >>> status, angles = ccd_iteration_limited(chain, np.zeros(2), np.array([0.0, 2.0]), 1e-3)
    >>> float(angles[0])
    0.5
    """
    chain = _chain(skeleton)
    tx, ty = (float(v) for v in check_point(target))
    arrival = _check_arrival(arrival_dist)
    start = check_angles(angles, skeleton.count).tolist()
    status, new = chain.iterate(start, tx, ty, arrival * arrival)
    return status, np.array(new)


_last: tuple[Skeleton, _Chain] | None = None
"""The skeleton solved last and its chain as floats: a controller solves one chain every tick,
and a :class:`Skeleton` is frozen (one that moves is a new object)."""


def _chain(skeleton: Skeleton) -> _Chain:
    """``skeleton`` as a :class:`_Chain`, reused while the same skeleton comes back."""
    global _last
    last = _last
    if last is not None and last[0] is skeleton:
        return last[1]
    chain = _Chain(skeleton)
    _last = (skeleton, chain)
    return chain


class _Chain(FloatChain):
    """A chain as floats, with the limit-aware CCD pass (compiled for a long chain, when
    :mod:`ikgame.kinematics._compiled` can)."""

    def __init__(self, skeleton: Skeleton) -> None:
        super().__init__(skeleton)
        self._compiled = compiled_pass(self)

    def iterate(
        self, angles: list[float], tx: float, ty: float, arrival_dist_sqr: float
    ) -> tuple[SolveStatus, list[float]]:
        """One limit-aware pass; returns the status and the new angles."""
        if self._compiled is not None:
            new, status = self._compiled(angles, tx, ty, arrival_dist_sqr)
            return _STATUSES[status], new
        joints = len(self.lengths) + 1
        new = list(angles)
        status = _iterate(
            self.lengths,
            self.lower,
            self.upper,
            self.free,
            self.base_x,
            self.base_y,
            self.base_angle,
            new,
            tx,
            ty,
            arrival_dist_sqr,
            [0.0] * joints,
            [0.0] * joints,
        )
        return _STATUSES[status], new


_STATUSES: Final = (SolveStatus.SUCCESS, SolveStatus.PROCESSING, SolveStatus.FAILURE)
""":func:`_iterate`'s status codes."""


def _iterate(
    lengths: Sequence[float],
    lower: Sequence[float],
    upper: Sequence[float],
    free: Sequence[bool],
    base_x: float,
    base_y: float,
    base_angle: float,
    angles: MutableSequence[float],
    tx: float,
    ty: float,
    arrival_dist_sqr: float,
    joint_x: MutableSequence[float],
    joint_y: MutableSequence[float],
) -> int:
    """One limit-aware CCD pass turning ``angles`` (radians) in place toward (tx, ty), px.

    Returns an index into :data:`_STATUSES`. Lists or numpy arrays alike (``joint_x`` and
    ``joint_y``, one longer than ``angles``, are its scratch space), so that the same code runs
    in Python and compiled.
    """
    forward(lengths, angles, base_x, base_y, base_angle, joint_x, joint_y)
    end_x, end_y = joint_x[-1], joint_y[-1]
    modified = False
    for i in range(len(angles) - 1, -1, -1):
        jx, jy = joint_x[i], joint_y[i]
        cos_rot, sin_rot, rot, cur_to_end_mag = _rotation_toward(jx, jy, end_x, end_y, tx, ty)
        wanted = angles[i] + rot
        if free[i]:
            angles[i] = wrap_angle(wanted)
        else:
            # min(max(wanted, lower), upper), written out: the same floats.
            clamped = lower[i] if lower[i] > wanted else wanted
            clamped = upper[i] if upper[i] < clamped else clamped
            if clamped != wanted:
                rot += clamped - wanted
                cos_rot, sin_rot = math.cos(rot), math.sin(rot)
            angles[i] = clamped
        cur_to_end_x = end_x - jx
        cur_to_end_y = end_y - jy
        end_x = jx + cos_rot * cur_to_end_x - sin_rot * cur_to_end_y
        end_y = jy + sin_rot * cur_to_end_x + cos_rot * cur_to_end_y
        dx = tx - end_x
        dy = ty - end_y
        if dx * dx + dy * dy <= arrival_dist_sqr:
            return 0
        if not modified and abs(rot) * cur_to_end_mag > TRIVIAL_ARC_LENGTH:
            modified = True
    return 1 if modified else 2


def solve_ccd(
    skeleton: Skeleton,
    angles: np.ndarray,
    target: np.ndarray,
    *,
    max_iterations: int = 10,
    tolerance: float = 1.0,
) -> Solution:
    """Repeat limit-aware CCD iterations until success, failure, or ``max_iterations``.

    ``angles`` (radians) warm-starts the solve; ``tolerance`` is the arrival distance, px. A
    pose already within ``tolerance`` is returned as it is, with zero iterations: a controller
    that re-solves every tick then leaves a settled chain alone.

    >>> sol = solve_ccd(Skeleton.chain([100, 100]), np.zeros(2), np.array([0.0, 150.0]))
    >>> sol.status.value, sol.error <= 1.0
    ('success', True)
    """
    if max_iterations < 1:
        raise ValueError(f"max_iterations must be >= 1, got {max_iterations}")
    tx, ty = float_point(target)
    tolerance = _check_arrival(tolerance)
    chain = _chain(skeleton)
    current = chain.clamp(float_angles(angles, skeleton.count))
    error_sqr = chain.error_sqr(current, tx, ty)
    status = SolveStatus.SUCCESS if error_sqr <= tolerance * tolerance else SolveStatus.PROCESSING
    used = 0
    nudged = False
    while used < max_iterations and status is SolveStatus.PROCESSING:
        status, current = chain.iterate(current, tx, ty, tolerance * tolerance)
        used += 1
        if status is SolveStatus.SUCCESS:
            # The pass tracks the end by rotations, which drifts from forward kinematics by
            # rounding: arrival, like the reported error, is the pose's own.
            error_sqr = chain.error_sqr(current, tx, ty)
            if error_sqr > tolerance * tolerance:
                status = SolveStatus.PROCESSING
        elif status is SolveStatus.FAILURE and not nudged and chain.within_reach(tx, ty):
            # A straight chain aimed along its own line has no rotation to make: every joint
            # sees the end and the target on one ray. Bend it once and carry on.
            current = skeleton.clamp(np.asarray(current) + _NUDGE).tolist()
            status, nudged = SolveStatus.PROCESSING, True
    if used and status is not SolveStatus.SUCCESS:
        error_sqr = chain.error_sqr(current, tx, ty)
    return Solution(np.array(current), status, used, math.sqrt(error_sqr))
