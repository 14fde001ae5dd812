"""The obstacle planner's gap measure compiled by numba, when it is installed (the ``fast``
extra: ``python -m pip install 'ikgame[fast]'``), for a process that searches much.

:meth:`~ikgame.kinematics.clearance.Clearance._gaps` measures each link's smallest gap to the
obstacles over batches of poses with numpy; on the few dozen points of a batch numpy's cost per
call is most of the cost, and the gaps are about four fifths of a search's CPU time.
:func:`_gap_loop` is the same measure written as one loop over poses, links and obstacles: the
same operations on the same floats in the same order (C's ``hypot``, as numpy's), so it gives
numpy's gaps bit for bit (tests compare the two), and compiled it takes a fifth to a thirteenth
of numpy's time.

numba's import and a first call of the loop (compiling it, or loading it from numba's cache
on disk beside this module) take 0.7 to 1.5 s of CPU, more than most runs measure gaps in all.
So a process compiles it only once it has measured ``COMPILE_AFTER`` link and obstacle pairs
with numpy, and on a thread of its own, so that no tick waits for it: until it is ready the gaps
are measured with numpy, after with the loop, with the same results either way.
``IKGAME_COMPILED=0`` in the environment turns it off.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from types import ModuleType
from typing import Final

import numpy as np

from ikgame._numba import compiled, turned_off

__all__ = ["COMPILE_AFTER", "Gaps", "compiled_gaps"]

COMPILE_AFTER: Final = 3_000_000
"""Link and obstacle pairs a process measures with numpy before it compiles the loop: 0.7 to
1.5 s of numpy's gaps (2 to 4 million pairs a second on searching runs), about what compiling
costs, so that a process never spends much more on compiling than it could win. No shipped
level's run gets there (``13_conductor``'s, the most, measures about a million pairs, 0.5 s of
numpy); a search-heavy stress level's measures 5 to 13 million."""

Gaps = Callable[
    [np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    np.ndarray,
]
"""``(starts, ends, centers, round_reach, a, b, long_reach) -> (..., n) gaps``: link starts and
ends (..., n, 2), round obstacles' centres (c, 2) and the gaps at which each link touches them
(n, c), long ones' ends (s, 2) each and theirs (n, s); px."""


def _gap_loop(
    starts: np.ndarray,
    ends: np.ndarray,
    centers: np.ndarray,
    round_reach: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    long_reach: np.ndarray,
    out: np.ndarray,
) -> None:
    """Into ``out`` (m, n): each of m poses' links' smallest signed gap to any obstacle, px,
    from their ``starts`` and ``ends`` (m, n, 2) (see :data:`Gaps`): the distance between the
    link and the obstacle's core, negated where a link crosses a long obstacle, less the reach
    at which they touch. Each distance is a point's to a segment, as numpy's ``_nearest_on``
    measures it.

    >>> link = np.array([[[0.0, 0.0]]]), np.array([[[10.0, 0.0]]])  # one pose of one link
    >>> rock = np.array([[5.0, 8.0]]), np.array([[3.0]])  # 8 px above it, touching at 3 px
    >>> none, out = np.empty((0, 2)), np.empty((1, 1))
    >>> _gap_loop(*link, *rock, none, none, np.empty((1, 0)), out)
    >>> out.tolist()
    [[5.0]]
    """
    for p in range(starts.shape[0]):
        for i in range(starts.shape[1]):
            sx, sy = starts[p, i, 0], starts[p, i, 1]
            ex, ey = ends[p, i, 0], ends[p, i, 1]
            rx, ry = ex - sx, ey - sy
            rr = rx * rx + ry * ry
            rr = rr if rr > 1e-12 else 1e-12
            least = math.inf
            for j in range(centers.shape[0]):
                cx, cy = centers[j, 0], centers[j, 1]
                near_start = math.hypot(sx - cx, sy - cy)
                near_end = math.hypot(ex - cx, ey - cy)
                u = ((cx - sx) * rx + (cy - sy) * ry) / rr
                u = min(max(u, 0.0), 1.0)
                along = math.hypot(sx + u * rx - cx, sy + u * ry - cy)
                d = min(min(near_start, near_end), along) - round_reach[i, j]
                least = d if d < least else least
            for j in range(a.shape[0]):
                ax, ay = a[j, 0], a[j, 1]
                vx, vy = b[j, 0] - ax, b[j, 1] - ay
                vv = vx * vx + vy * vy
                vv = vv if vv > 1e-12 else 1e-12
                u = ((sx - ax) * vx + (sy - ay) * vy) / vv
                u = min(max(u, 0.0), 1.0)
                near_start = math.hypot(ax + u * vx - sx, ay + u * vy - sy)
                u = ((ex - ax) * vx + (ey - ay) * vy) / vv
                u = min(max(u, 0.0), 1.0)
                near_end = math.hypot(ax + u * vx - ex, ay + u * vy - ey)
                u = ((ax - sx) * rx + (ay - sy) * ry) / rr
                u = min(max(u, 0.0), 1.0)
                tip_a = math.hypot(sx + u * rx - ax, sy + u * ry - ay)
                bx, by = b[j, 0], b[j, 1]
                u = ((bx - sx) * rx + (by - sy) * ry) / rr
                u = min(max(u, 0.0), 1.0)
                tip_b = math.hypot(sx + u * rx - bx, sy + u * ry - by)
                d = min(min(near_start, near_end), min(tip_a, tip_b))
                cross = rx * vy - ry * vx
                if cross != 0.0:
                    qx, qy = ax - sx, ay - sy
                    t = (qx * vy - qy * vx) / cross
                    w = (qx * ry - qy * rx) / cross
                    if 0.0 < t < 1.0 and 0.0 < w < 1.0:
                        d = -d
                d = d - long_reach[i, j]
                least = d if d < least else least
            out[p, i] = least


class _Build:
    """The loop compiled on a thread of its own, once a process has measured enough pairs."""

    def __init__(self) -> None:
        self.pairs = 0
        self.thread: threading.Thread | None = None
        self.gaps: Gaps | None = None

    def count(self, pairs: int) -> None:
        self.pairs += pairs
        if self.thread is None and self.pairs >= COMPILE_AFTER:
            # A daemon: a process that ends first does not wait for a loop it no longer needs.
            self.thread = threading.Thread(
                target=self.run, name="ikgame gaps compiler", daemon=True
            )
            self.thread.start()

    def run(self) -> None:
        kernel = compiled("the obstacle gaps", _compile)
        if kernel is not None:
            self.gaps = _measure(kernel)


_build = _Build()


def compiled_gaps(pairs: int) -> Gaps | None:
    """The compiled gap measure, or None while it is not ready (or numba is missing, cannot
    compile, or is turned off). ``pairs`` is how many link and obstacle pairs the caller is
    about to measure, counted toward ``COMPILE_AFTER``."""
    if turned_off():
        return None
    gaps = _build.gaps
    if gaps is None:
        _build.count(pairs)
    return gaps


def _compile(numba: ModuleType) -> Callable[..., None]:
    # Compiled now, for C-ordered arrays only (the caller passes no others: an array of
    # another layout would have numba compile again, in the middle of a tick). Cached on disk:
    # the loop calls nothing of ikgame's, so a change to this module is the only change that
    # makes numba compile it again.
    grid, points = numba.float64[:, :, ::1], numba.float64[:, ::1]
    signature = numba.void(grid, grid, points, points, points, points, points, points)
    return numba.njit(signature, nogil=True, cache=True)(_gap_loop)


def _measure(kernel: Callable[..., None]) -> Gaps:
    """:data:`Gaps` by ``kernel``, for poses of any leading shape (the links' ends made
    C-ordered; the obstacles' arrays must be)."""

    def gaps(starts: np.ndarray, ends: np.ndarray, *obstacles: np.ndarray) -> np.ndarray:
        shape = starts.shape[:-1]
        flat = (-1, shape[-1], 2)
        starts = np.ascontiguousarray(starts).reshape(flat)
        ends = np.ascontiguousarray(ends).reshape(flat)
        out = np.empty(starts.shape[:2])
        kernel(starts, ends, *obstacles, out)
        return out.reshape(shape)

    return gaps
