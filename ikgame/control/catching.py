"""Catching a chain's end on its way: where the end is about to meet a still target while the
joints are still far from the solver's answer, the chain stops with the end there instead.

A solver's answer is one of the many poses that put the end on the target (a redundant chain
has a whole family of them), and the straight way in joint space from the chain's pose to it
need not keep the end on a straight way to the target. Where the joints far from the base turn
faster than those near it, the end can sweep through the target on its way and come back from
beyond: a whip. FABRIK, whose answers swing the whole chain, does this most, at 1,000 px/s and
more. Stopping where the end meets the target is what a user watching expects, and is an answer
too. :meth:`~ikgame.control.Controller.command` decides when (see ``Controller._caught``); this
module finds the pose.
"""

from __future__ import annotations

from typing import Final

import numpy as np

HEADING: Final = 0.5
"""The most an end's sideways speed may be, as a share of its speed toward the target, for it
to count as heading at the target (about 27 degrees off). An end coming in on a curve meets its
target from the side: stopped on its line of motion, it would stop short."""


def time_to_nearest(offset: tuple[float, float], velocity: tuple[float, float]) -> float | None:
    """When (s) an end at ``velocity`` (px/s) comes nearest a target ``offset`` from it (px),
    or None where it does not head at the target (see :data:`HEADING`).

    >>> time_to_nearest((0.0, 5.0), (0.0, 100.0))
    0.05
    >>> time_to_nearest((0.0, 5.0), (100.0, 10.0)) is None  # going by
    True
    """
    ox, oy = offset
    ux, uy = velocity
    toward = ox * ux + oy * uy
    if toward <= 0.0 or abs(ox * uy - oy * ux) > HEADING * toward:
        return None
    return toward / (ux * ux + uy * uy)


def catch_pose(
    angles: np.ndarray, velocities: np.ndarray, ahead: float, braking: np.ndarray, dt: float
) -> np.ndarray | None:
    """The pose (radians) where the chain stops with its end nearest the target, ``ahead``
    seconds away at the end's velocity (see :func:`time_to_nearest`), every joint braking
    evenly; None while braking can wait a tick.

    ``angles`` and ``velocities`` are the joints' (radians, rad/s), ``braking`` what each joint
    may slow by (rad/s^2) and ``dt`` the tick (s). Braking evenly from its velocity ``v`` to
    stop in ``2 ahead``, a joint turns ``v ahead``, and the end reaches that point. That asks
    ``|v| / (2 ahead)`` of a joint's braking: the pose is given on the last tick or two where
    it asks at most half of it. A joint's braking is what it has alone, and a chain brakes its
    joints at once, their reactions loading one another: planned with all of it, nine links
    limited to +-11 deg (`67_tight_limits_nine`, FABRIK) came in to their caught pose still
    turning at 70 deg/s and swung 10% of the approach past the target; with half, 0.1%.

    One joint turning at 1 rad/s that can brake at 10 rad/s^2: 0.1 s from the target, it
    stops there by turning 0.1 rad more; 0.2 s away, braking can wait.

    >>> catch_pose(np.zeros(1), np.ones(1), 0.1, np.full(1, 10.0), 0.004)
    array([0.1])
    >>> catch_pose(np.zeros(1), np.ones(1), 0.2, np.full(1, 10.0), 0.004)
    """
    speeds = np.abs(velocities)
    # A turning joint that can barely brake (a motor of next to no torque) needs for ever to
    # stop: caught now. One at rest needs no time at all.
    with np.errstate(divide="ignore", over="ignore"):
        stopping = np.divide(speeds, braking, out=np.zeros_like(speeds), where=speeds > 0.0)
    if ahead > float(np.max(stopping)) + 2.0 * dt:
        return None
    return angles + velocities * ahead
