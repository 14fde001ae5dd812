"""Skeletons as arrays, and forward kinematics.

A skeleton is a set of rigid links joined by revolute joints. Link ``i`` starts at joint ``i``
and extends ``lengths[i]`` pixels along its own x axis; its joint angle is measured relative to
its parent link (or, for a root link, relative to the base direction ``base_angle``). A child
joint sits at the end of its parent link, so a joint's offset in its parent's frame is
``(lengths[parent], 0)``. The end of a link without children is an end effector.

Angles are radians, lengths and positions pixels, world y points up.
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

__all__ = ["Skeleton", "forward_kinematics", "check_point", "check_angles"]


def check_point(point: object, name: str = "target") -> np.ndarray:
    """Return ``point`` as a finite float array of shape (2,), or raise ``ValueError``.

    >>> check_point((1, 2))
    array([1., 2.])
    """
    try:
        arr = np.asarray(point, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be a pair of numbers (x, y), got {point!r}") from exc
    if arr.shape != (2,):
        raise ValueError(f"{name} must have shape (2,), got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite, got {arr.tolist()}")
    return arr


def check_angles(angles: object, count: int) -> np.ndarray:
    """Return ``angles`` as a finite float array of shape (count,), or raise ``ValueError``.

    >>> check_angles([0, 0.5], 2)
    array([0. , 0.5])
    """
    try:
        arr = np.asarray(angles, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"angles must be numbers, got {angles!r}") from exc
    if arr.shape != (count,):
        raise ValueError(f"angles must have shape ({count},), got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"angles must be finite, got {arr.tolist()}")
    return arr


@dataclass(frozen=True, eq=False)
class Skeleton:
    """Links and joints as arrays; build chains with :meth:`Skeleton.chain`.

    >>> Skeleton.chain([100, 50]).count
    2

    Attributes:
        lengths: (n,) link lengths, px.
        parents: (n,) parent link index, -1 for a link attached to the base.
        lower, upper: (n,) joint limits relative to the parent, radians; -inf / inf when free.
        base: (2,) world position of the base, px.
        base_angle: direction of the base frame, radians (0 is +x, pi/2 is straight up).
    """

    lengths: np.ndarray
    parents: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    base: np.ndarray
    base_angle: float = 0.0

    def __post_init__(self) -> None:
        # Copies, so a caller's array (or a view of it) cannot change a validated skeleton.
        lengths = np.array(self.lengths, dtype=float)
        n = lengths.shape[0] if lengths.ndim == 1 else 0
        if lengths.ndim != 1 or n == 0:
            raise ValueError(f"lengths must be a non-empty 1-D array, got shape {lengths.shape}")
        if not np.all(np.isfinite(lengths)) or np.any(lengths <= 0):
            raise ValueError(f"lengths must be finite and positive, got {lengths.tolist()}")
        parents = np.array(self.parents, dtype=np.int64)
        if parents.shape != (n,):
            raise ValueError(f"parents must have shape ({n},), got shape {parents.shape}")
        if np.any(parents >= np.arange(n)) or np.any(parents < -1):
            raise ValueError("each parent index must be -1 or smaller than the link's own index")
        lower = np.broadcast_to(np.asarray(self.lower, dtype=float), (n,)).copy()
        upper = np.broadcast_to(np.asarray(self.upper, dtype=float), (n,)).copy()
        if np.any(np.isnan(lower)) or np.any(np.isnan(upper)) or np.any(lower > upper):
            raise ValueError("joint limits must satisfy lower <= upper (radians)")
        base = check_point(self.base, "base").copy()
        if not np.isfinite(self.base_angle):
            raise ValueError("base_angle must be finite")
        for name, value in (
            ("lengths", lengths),
            ("parents", parents),
            ("lower", lower),
            ("upper", upper),
            ("base", base),
        ):
            value.setflags(write=False)
            object.__setattr__(self, name, value)
        object.__setattr__(self, "base_angle", float(self.base_angle))

    @classmethod
    def chain(
        cls,
        lengths: Sequence[float] | np.ndarray,
        *,
        base: Sequence[float] = (0.0, 0.0),
        base_angle: float = 0.0,
        limits: Sequence[tuple[float, float] | None] | None = None,
    ) -> Skeleton:
        """A serial chain: link ``i`` hangs off link ``i - 1``; limits in radians or None.

        >>> Skeleton.chain([1, 1], limits=[None, (-1.0, 1.0)]).upper.tolist()
        [inf, 1.0]
        """
        n = len(lengths)
        limits = [None] * n if limits is None else list(limits)
        if len(limits) != n:
            raise ValueError(f"limits must have one entry per link ({n}), got {len(limits)}")
        lower = [-np.inf if lim is None else lim[0] for lim in limits]
        upper = [np.inf if lim is None else lim[1] for lim in limits]
        return cls(
            lengths=np.asarray(lengths, dtype=float),
            parents=np.arange(n) - 1,
            lower=np.asarray(lower, dtype=float),
            upper=np.asarray(upper, dtype=float),
            base=np.asarray(base, dtype=float),
            base_angle=base_angle,
        )

    @property
    def count(self) -> int:
        """Number of links (and joints)."""
        return int(self.lengths.shape[0])

    @cached_property
    def is_chain(self) -> bool:
        """True when link ``i``'s parent is ``i - 1`` for every link."""
        return bool(np.array_equal(self.parents, np.arange(self.count) - 1))

    @cached_property
    def limited(self) -> np.ndarray:
        """(n,) bool: which joints have a finite limit on either side."""
        return np.isfinite(self.lower) | np.isfinite(self.upper)

    @property
    def reach(self) -> float:
        """Longest distance from the base to any end effector, px (all links straight)."""
        depth = np.zeros(self.count)
        for i, p in enumerate(self.parents):
            depth[i] = self.lengths[i] + (depth[p] if p >= 0 else 0.0)
        return float(depth.max())

    def moved_to(self, base: Sequence[float] | np.ndarray) -> Skeleton:
        """The same skeleton with its base at ``base`` (px).

        Cheap enough to call every tick while a base moves: only the new point is checked,
        the already validated arrays are shared.

        >>> Skeleton.chain([1.0]).moved_to((3, 4)).base.tolist()
        [3.0, 4.0]
        """
        point = check_point(base, "base").copy()
        point.setflags(write=False)
        moved = copy.copy(self)
        object.__setattr__(moved, "base", point)
        return moved

    def clamp(self, angles: np.ndarray) -> np.ndarray:
        """Angles clipped to the joint limits, radians.

        >>> Skeleton.chain([1], limits=[(-0.5, 0.5)]).clamp(np.array([2.0])).tolist()
        [0.5]
        """
        return np.clip(angles, self.lower, self.upper)


def forward_kinematics(skeleton: Skeleton, angles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World positions of the joints and world angles of the links (px, radians).

    Returns ``(points, world_angles)``. For a chain, ``points`` has shape (n + 1, 2): joint 0 ..
    joint n-1, then the end effector. For a tree it has shape (2n, 2): the n link starts, then
    the n link ends. ``world_angles`` has shape (n,).

    >>> pts, world = forward_kinematics(Skeleton.chain([10, 10]), np.array([np.pi / 2, 0.0]))
    >>> np.round(pts, 6).tolist()
    [[0.0, 0.0], [0.0, 10.0], [0.0, 20.0]]
    """
    angles = check_angles(angles, skeleton.count)
    if skeleton.is_chain:
        world = skeleton.base_angle + np.cumsum(angles)
        steps = skeleton.lengths[:, None] * np.column_stack((np.cos(world), np.sin(world)))
        points = np.vstack((skeleton.base, skeleton.base + np.cumsum(steps, axis=0)))
        return points, world
    n = skeleton.count
    world = np.empty(n)
    starts = np.empty((n, 2))
    ends = np.empty((n, 2))
    for i, p in enumerate(skeleton.parents):
        if p < 0:
            world[i] = skeleton.base_angle + angles[i]
            starts[i] = skeleton.base
        else:
            world[i] = world[p] + angles[i]
            starts[i] = ends[p]
        ends[i] = starts[i] + skeleton.lengths[i] * np.array((np.cos(world[i]), np.sin(world[i])))
    return np.vstack((starts, ends)), world
