"""Noticing a jammed chain: the solver has not given the target up, the end effector stops
getting closer, and the chain is pushing (a motor at its torque limit, or a link against an
obstacle or a prop).

A solver that re-solves from the measured pose every tick keeps reporting ``success`` (or
``processing``) for an answer the chain can never move to when something is in the way; this
watch turns that into the ``blocked`` state. Its documented response (see :class:`~ikgame.control.controller.Controller`)
is to stop pushing and hold the pose until the target moves.

Times are s, distances px.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from itertools import pairwise
from typing import Final

__all__ = ["BlockWatch"]

WINDOW: Final = 0.5
"""How long the end effector must have made no progress, s."""

PROGRESS: Final = 1.0
"""An error that stays within a band this wide over the window makes no progress, px."""

NEAR: Final = 2.0
"""Within this many arrival distances of the target nothing counts as blocked."""

FADING: Final = 0.5
"""A chain whose progress is dying out is blocked once the progress still to come, projected
from the window's last two thirds, is under this share of its way to go..."""

SLOW: Final = 0.1
"""...and it closed less than this share of its way to go over the window: a chain still
closing fast may yet round what it slides along."""

RISE: Final = 0.05
"""A dying fall's error rises by at most this much from one tick to the next, px: more is a
swing, not a slide coming to rest."""


class BlockWatch:
    """Watches one chain's progress toward its target, tick by tick.

    >>> watch = BlockWatch(dt=0.1, arrival=0.5)
    >>> [watch.observe(error=40.0, reachable=True, pushing=lambda: True) for _ in range(7)][-1]
    True
    >>> watch.observe(error=20.0, reachable=True, pushing=lambda: True)  # getting closer again
    False
    """

    def __init__(self, *, dt: float, arrival: float) -> None:
        if not dt > 0:
            raise ValueError(f"dt must be a positive number of seconds, got {dt!r}")
        self._errors: deque[float] = deque(maxlen=max(2, round(WINDOW / dt) + 1))
        self._near = max(NEAR * arrival, 1.0)

    def reset(self) -> None:
        """Forget the history: the target moved, so progress is measured afresh."""
        self._errors.clear()

    def observe(
        self,
        *,
        error: float,
        reachable: bool,
        pushing: Callable[[], bool],
        touching: Callable[[], bool] | None = None,
    ) -> bool:
        """Record one tick and say whether the chain is blocked now.

        ``error`` is the end effector's distance to the target (px), ``reachable`` whether the
        solver has not given the target up as out of reach; ``pushing()`` says whether a motor
        is at its torque limit or a link touches something, and ``touching()`` (if given)
        whether a link touches something. Each is asked only once the error has stopped
        moving, or its fall is dying out (a contact query on every tick would cost more than
        the rest).
        """
        self._errors.append(error)
        if not reachable or error <= self._near or len(self._errors) < self._errors.maxlen:
            return False
        # Stuck means the error has stayed within one band for the whole window (a target that
        # has just jumped away, or a chain bouncing off something, moves the error a lot).
        errors = self._errors
        if max(errors) - min(errors) < PROGRESS:
            return pushing()
        # Or its fall is dying out far from the target against something it touches. Not for
        # a motor at its torque limit: a weak arm lifting itself slows down and speeds up again
        # as the load on it changes.
        return touching is not None and self._fading(error) and touching()

    def _fading(self, error: float) -> bool:
        """Whether the error still falls but is coming to rest well short of the target: a
        chain sliding along an obstacle it presses on, slower and slower.

        The falls over the window's thirds, ``early``, ``middle`` and ``late``, must shrink;
        the last two are taken as terms of a geometric series, whose rest,
        ``late**2 / (middle - late)``, is the progress still to come. An approach that brakes
        to a stop on the target (at a constant deceleration, or exponentially) projects at
        least the way it has left; a chain sliding on at a steady pace projects far more.
        """
        errors = self._errors
        # Thirds of equal length, ending now: the window's ticks need not divide by three.
        third = (len(errors) - 1) // 3
        start, one, two = (errors[-1 - k * third] for k in (3, 2, 1))
        early, middle, late = start - one, one - two, two - error
        if not 0.0 < late < middle < early:
            return False
        way = error - self._near
        if start - error >= SLOW * way or late * late / (middle - late) >= FADING * way:
            return False
        return all(b - a <= RISE for a, b in pairwise(errors))
