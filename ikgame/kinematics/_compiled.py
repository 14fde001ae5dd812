"""A long chain's innermost solver loop compiled by numba, when it is installed (the ``fast``
extra: ``python -m pip install 'ikgame[fast]'``).

What is compiled is the Python code itself (:func:`ikgame.kinematics.ccd._iterate` and what it
calls), not a second implementation: the same operations in the same order, no fast-math, so
the same floats, and a run gives the same results with numba or without it (tests compare the
two bit for bit). Only chains of :data:`COMPILED_LINKS` links or more use it: below that,
crossing into compiled code costs about what it saves, and a short run does not pay numba's
import (about half a second) or its compiling (a second or two, once per process: nothing is
cached on disk, since numba would refresh a cached loop only when its own module changes, not
when the helpers it calls do). ``IKGAME_COMPILED=0`` in the environment turns it off.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from types import ModuleType
from typing import TYPE_CHECKING, Final, TypeVar

import numpy as np

from ikgame._numba import compiled, turned_off

if TYPE_CHECKING:
    from ikgame.kinematics._floats import FloatChain

__all__ = ["COMPILED_END_LINKS", "COMPILED_LINKS", "compiled_end", "compiled_pass"]

COMPILED_LINKS: Final = 32
"""Chains of this many links or more run their CCD passes compiled, where numba is installed."""

COMPILED_END_LINKS: Final = 101
"""Chains of this many links or more find their end effector by compiled forward kinematics,
with any solver: shorter ones check their error for less than numba's import and compiling
cost a run whose solver does not compile its CCD pass."""

Pass = Callable[[list[float], float, float, float], tuple[list[float], int]]
"""``(angles, tx, ty, arrival_dist_sqr) -> (new angles, status code)``, radians and px."""

End = Callable[["FloatChain", list[float]], tuple[float, float]]
"""``(chain, angles) -> (x, y)``: the end effector of ``chain`` (its base as it is now) at
``angles``, radians and px."""


def compiled_pass(chain: FloatChain) -> Pass | None:
    """``chain``'s CCD pass compiled, or None: a short chain, no numba, or turned off.

    >>> from ikgame.kinematics import Skeleton
    >>> from ikgame.kinematics._floats import FloatChain
    >>> compiled_pass(FloatChain(Skeleton.chain([10.0, 10.0]))) is None  # too short to pay
    True
    """
    kernel = _built(len(chain.lengths), COMPILED_LINKS, _kernel)
    if kernel is None:
        return None
    lengths, lower, upper = (
        np.array(v, dtype=float) for v in (chain.lengths, chain.lower, chain.upper)
    )
    free = np.array(chain.free, dtype=bool)
    base_x, base_y, base_angle = chain.base_x, chain.base_y, chain.base_angle
    joint_x, joint_y = np.empty(len(lengths) + 1), np.empty(len(lengths) + 1)

    def run(
        angles: list[float], tx: float, ty: float, arrival_dist_sqr: float
    ) -> tuple[list[float], int]:
        new = np.array(angles, dtype=float)
        status = kernel(
            lengths,
            lower,
            upper,
            free,
            base_x,
            base_y,
            base_angle,
            new,
            tx,
            ty,
            arrival_dist_sqr,
            joint_x,
            joint_y,
        )
        return new.tolist(), int(status)

    return run


def compiled_end(chain: FloatChain) -> End | None:
    """``chain``'s forward kinematics to its end effector compiled, or None: a short chain, no
    numba, or turned off. The base is read from the chain given at each call (a chain copied
    for a moved base shares its lengths).

    >>> from ikgame.kinematics import Skeleton
    >>> from ikgame.kinematics._floats import FloatChain
    >>> compiled_end(FloatChain(Skeleton.chain([10.0, 10.0]))) is None  # too short to pay
    True
    """
    kernel = _built(len(chain.lengths), COMPILED_END_LINKS, _forward_kernel)
    if kernel is None:
        return None
    lengths = np.array(chain.lengths, dtype=float)
    joint_x, joint_y = np.empty(len(lengths) + 1), np.empty(len(lengths) + 1)

    def end(of: FloatChain, angles: list[float]) -> tuple[float, float]:
        kernel(
            lengths,
            np.array(angles, dtype=float),
            of.base_x,
            of.base_y,
            of.base_angle,
            joint_x,
            joint_y,
        )
        return float(joint_x[-1]), float(joint_y[-1])

    return end


K = TypeVar("K")


def _built(links: int, fewest: int, kernel: Callable[[], K | None]) -> K | None:
    """``kernel()``, or None for a chain of fewer than ``fewest`` links (compiling would not
    pay) or with the compiled loops turned off (:func:`~ikgame._numba.turned_off`)."""
    if links < fewest or turned_off():
        return None
    return kernel()


@functools.cache
def _forward_kernel() -> Callable[..., None] | None:
    """:func:`ikgame.kinematics._floats.forward` compiled, or None (see :func:`ikgame._numba.compiled`)."""
    from ikgame.kinematics import _floats

    def build(numba: ModuleType) -> Callable[..., None]:
        kernel = numba.njit(nogil=True)(_floats.forward)
        # Compiled now, on a one-link chain (see _kernel).
        kernel(np.ones(1), np.zeros(1), 0.0, 0.0, 0.0, np.zeros(2), np.zeros(2))
        return kernel

    return compiled("forward kinematics", build)


@functools.cache
def _kernel() -> Callable[..., int] | None:
    """:func:`ikgame.kinematics.ccd._iterate` compiled, or None (see :func:`ikgame._numba.compiled`)."""
    from ikgame.kinematics import ccd

    def build(numba: ModuleType) -> Callable[..., int]:
        _teach(numba)
        kernel = numba.njit(nogil=True)(ccd._iterate)
        # Compiled now, on a one-link chain, so that a numba that cannot compile it is found
        # here rather than in the middle of a solve.
        one, scratch = np.ones(1), np.zeros(2)
        free = np.ones(1, dtype=bool)
        kernel(
            one, -one, one, free, 0.0, 0.0, 0.0, np.zeros(1), 1.0, 0.0, 0.0, scratch, scratch.copy()
        )
        return kernel

    return compiled("the CCD pass", build)


@functools.cache
def _teach(numba: ModuleType) -> None:
    """Tell ``numba`` (once) how to compile what the pass calls."""
    from numba.extending import overload, register_jitable

    from ikgame.kinematics import _floats, ccd

    # numba compiles numpy's fmod but not math's; both are C's fmod, which is exact.
    overload(math.fmod)(lambda x, y: lambda x, y: np.fmod(x, y))
    # The helpers stay plain Python functions for Python callers; compiled code calls them
    # compiled.
    for helper in (_floats.forward, ccd._rotation_toward, ccd.wrap_angle):
        register_jitable(helper)
