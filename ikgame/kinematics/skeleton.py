"""Skeletons as arrays, and forward kinematics.

A skeleton is a set of rigid links joined by revolute joints. Link ``i`` starts at joint ``i``
and extends ``lengths[i]`` pixels along its own x axis; its joint angle is measured relative to
its parent link (or, for a root link, relative to the base direction ``base_angle``). A child
joint sits at the end of its parent link, so a joint's offset in its parent's frame is
``(lengths[parent], 0)``. The end of a link without children is an end effector.

A skeleton whose parents form several branches is a tree (build it with
:meth:`Skeleton.tree`). A root link's joint sits at ``base`` plus its row of ``root_offsets``,
given in the base frame (x along ``base_angle``, y to its left), so the hips of a body can sit at
different points of it; a chain's offsets are zero unless given.

Angles are radians, lengths and positions pixels, world y points up.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

__all__ = ["Skeleton", "forward_kinematics", "tree_points", "check_point", "check_angles"]


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
    if not np.isfinite(arr).all():
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
    if not np.isfinite(arr).all():
        raise ValueError(f"angles must be finite, got {arr.tolist()}")
    return arr


def _limit_bounds(
    limits: Sequence[tuple[float, float] | None] | None, n: int
) -> tuple[np.ndarray, np.ndarray]:
    """(lower, upper) radians from one ``(lower, upper)`` or None (free) per link."""
    limits = [None] * n if limits is None else list(limits)
    if len(limits) != n:
        raise ValueError(f"limits must have one entry per link ({n}), got {len(limits)}")
    lower = [-np.inf if lim is None else lim[0] for lim in limits]
    upper = [np.inf if lim is None else lim[1] for lim in limits]
    return np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)


def _check_root_offsets(offsets: object, parents: np.ndarray) -> np.ndarray:
    """``root_offsets`` as a new (n, 2) float array (zeros for None), or ``ValueError``."""
    n = parents.shape[0]
    if offsets is None:
        return np.zeros((n, 2))
    try:
        arr = np.array(offsets, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"root_offsets must be (x, y) rows of numbers, got {offsets!r}") from exc
    if arr.shape != (n, 2):
        raise ValueError(f"root_offsets must have shape ({n}, 2), got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError("root_offsets must be finite")
    if np.any(arr[parents >= 0]):
        raise ValueError("root_offsets must be zero for links with a parent (only roots sit off)")
    return arr


@dataclass(frozen=True, eq=False)
class Skeleton:
    """Links and joints as arrays; build chains with :meth:`Skeleton.chain`, trees with
    :meth:`Skeleton.tree`.

    >>> Skeleton.chain([100, 50]).count
    2

    Attributes:
        lengths: (n,) link lengths, px.
        parents: (n,) parent link index, -1 for a link attached to the base.
        lower, upper: (n,) joint limits relative to the parent, radians; -inf / inf when free.
        base: (2,) world position of the base, px.
        base_angle: direction of the base frame, radians (0 is +x, pi/2 is straight up).
        root_offsets: (n, 2) where each root link's joint sits in the base frame, px (x along
            ``base_angle``, y to its left); zero rows for links with a parent. ``None`` (the
            default) means all zeros: every root joint on the base.
    """

    lengths: np.ndarray
    parents: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    base: np.ndarray
    base_angle: float = 0.0
    root_offsets: np.ndarray | None = None

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
        offsets = _check_root_offsets(self.root_offsets, parents)
        for name, value in (
            ("lengths", lengths),
            ("parents", parents),
            ("lower", lower),
            ("upper", upper),
            ("base", base),
            ("root_offsets", offsets),
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
        lower, upper = _limit_bounds(limits, n)
        return cls(
            lengths=np.asarray(lengths, dtype=float),
            parents=np.arange(n) - 1,
            lower=lower,
            upper=upper,
            base=np.asarray(base, dtype=float),
            base_angle=base_angle,
        )

    @classmethod
    def tree(
        cls,
        lengths: Sequence[float] | np.ndarray,
        parents: Sequence[int] | np.ndarray,
        *,
        base: Sequence[float] = (0.0, 0.0),
        base_angle: float = 0.0,
        limits: Sequence[tuple[float, float] | None] | None = None,
        root_offsets: Sequence[Sequence[float]] | np.ndarray | None = None,
    ) -> Skeleton:
        """A tree: link ``i`` hangs off link ``parents[i]`` (-1: the base); limits in radians or
        None; ``root_offsets`` (n, 2) px in the base frame, zero rows for non-roots.

        >>> hips = Skeleton.tree([50, 40, 50, 40], [-1, 0, -1, 2],
        ...                      root_offsets=[(-30, 0), (0, 0), (30, 0), (0, 0)])
        >>> hips.effectors.tolist(), hips.children
        ([1, 3], ((1,), (), (3,), ()))
        """
        n = len(lengths)
        lower, upper = _limit_bounds(limits, n)
        return cls(
            lengths=np.asarray(lengths, dtype=float),
            parents=np.asarray(parents),
            lower=lower,
            upper=upper,
            base=np.asarray(base, dtype=float),
            base_angle=base_angle,
            root_offsets=root_offsets,  # type: ignore[arg-type]  # checked and converted there
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
    def has_root_offsets(self) -> bool:
        """True when some root joint sits off the base (a nonzero row of ``root_offsets``)."""
        return bool(np.any(self.root_offsets))

    @cached_property
    def children(self) -> tuple[tuple[int, ...], ...]:
        """Each link's child links, in index order.

        >>> Skeleton.tree([1, 1, 1], [-1, 0, 0]).children
        ((1, 2), (), ())
        """
        kids: list[list[int]] = [[] for _ in range(self.count)]
        for i, p in enumerate(self.parents.tolist()):
            if p >= 0:
                kids[p].append(i)
        return tuple(tuple(k) for k in kids)

    @cached_property
    def effectors(self) -> np.ndarray:
        """(k,) int, read-only: the links without children (their ends are the end effectors),
        in index order.

        >>> Skeleton.tree([1, 1, 1], [-1, 0, 0]).effectors.tolist()
        [1, 2]
        """
        leaves = np.array([i for i, kids in enumerate(self.children) if not kids], dtype=np.int64)
        leaves.setflags(write=False)
        return leaves

    @cached_property
    def ancestors(self) -> np.ndarray:
        """(n, n) bool, read-only: ``ancestors[i, j]`` when turning joint ``j`` moves the end of
        link ``i`` (``j`` is ``i`` or one of its ancestors). Row ``i`` is the path from the base
        to link ``i``; column ``j`` is the subtree of link ``j``.

        >>> Skeleton.tree([1, 1, 1], [-1, 0, 0]).ancestors.astype(int).tolist()
        [[1, 0, 0], [1, 1, 0], [1, 0, 1]]
        """
        n = self.count
        mask = np.eye(n, dtype=bool)
        for i, p in enumerate(self.parents.tolist()):
            if p >= 0:
                mask[i] |= mask[p]
        mask.setflags(write=False)
        return mask

    @cached_property
    def _paths(self) -> np.ndarray:
        """``ancestors`` as 0.0 / 1.0 floats: the matrix products of :func:`tree_points` cast
        it so on every call otherwise (the same products, so the same sums)."""
        paths = self.ancestors.astype(float)
        paths.setflags(write=False)
        return paths

    @cached_property
    def _is_root(self) -> np.ndarray:
        """(n, 1) bool: which links hang from the base, as a column."""
        column = (self.parents < 0)[:, None]
        column.setflags(write=False)
        return column

    @cached_property
    def roots(self) -> np.ndarray:
        """(n,) int, read-only: the root link each link hangs from (a root is its own).

        >>> Skeleton.tree([1, 1, 1], [-1, 0, -1]).roots.tolist()
        [0, 0, 2]
        """
        roots = np.argmax(self.ancestors, axis=1)
        roots.setflags(write=False)
        return roots

    def root_points(self) -> np.ndarray:
        """(n, 2) world position of the joint of the root each link hangs from, px; read-only.

        >>> Skeleton.tree([1, 1], [-1, -1], base=(5, 0), base_angle=np.pi / 2,
        ...               root_offsets=[(0, 0), (2, 0)]).root_points().round(6).tolist()
        [[5.0, 0.0], [5.0, 2.0]]
        """
        return self._root_points

    @cached_property
    def _root_points(self) -> np.ndarray:
        """:meth:`root_points`, worked out once per base (:meth:`moved_to` drops it)."""
        if not self.has_root_offsets:
            points = np.full((self.count, 2), self.base)
        else:
            c, s = np.cos(self.base_angle), np.sin(self.base_angle)
            offsets = self.root_offsets[self.roots]
            points = self.base + offsets @ np.array(((c, s), (-s, c)))
        points.setflags(write=False)
        return points

    @cached_property
    def _memo(self) -> dict[object, object]:
        """Work that depends only on the links and limits (a solver's set-up for a target set,
        say), done once per skeleton: :meth:`moved_to` copies share it as they share those
        arrays. Kept within the kinematics package."""
        return {}

    @cached_property
    def limited(self) -> np.ndarray:
        """(n,) bool: which joints have a finite limit on either side."""
        return np.isfinite(self.lower) | np.isfinite(self.upper)

    @cached_property
    def all_limited(self) -> bool:
        """True when every joint has a finite limit on either side (none wraps round).

        >>> Skeleton.chain([1, 1], limits=[None, (-1.0, 1.0)]).all_limited
        False
        """
        return bool(self.limited.all())

    @cached_property
    def reach(self) -> float:
        """Longest distance from the base to any end effector, px (all links straight, each
        root's offset included)."""
        depth = np.zeros(self.count)
        for i, p in enumerate(self.parents):
            depth[i] = self.lengths[i] + (depth[p] if p >= 0 else 0.0)
        if self.has_root_offsets:
            depth += np.hypot(*self.root_offsets[self.roots].T)
        return float(depth.max())

    def moved_to(self, base: Sequence[float] | np.ndarray, angle: float | None = None) -> Skeleton:
        """The same skeleton with its base at ``base`` (px), turned to ``angle`` (radians) if
        given.

        Cheap enough to call every tick while a base moves: only the new point is checked,
        the already validated arrays are shared.

        >>> Skeleton.chain([1.0]).moved_to((3, 4)).base.tolist()
        [3.0, 4.0]
        """
        point = check_point(base, "base").copy()
        point.setflags(write=False)
        moved = copy.copy(self)
        # The copy shares every cached value but the one that depends on the base.
        moved.__dict__.pop("_root_points", None)
        object.__setattr__(moved, "base", point)
        if angle is not None:
            if not math.isfinite(angle):
                raise ValueError(f"angle must be finite, got {angle!r}")
            object.__setattr__(moved, "base_angle", float(angle))
        return moved

    def world_angles(self, angles: np.ndarray) -> np.ndarray:
        """(n,) world angle of each link for local joint ``angles``, radians: each joint's angle
        summed with its ancestors' and the base's.

        >>> Skeleton.tree([1, 1, 1], [-1, 0, 0]).world_angles(np.array([0.5, 0.25, -0.5])).tolist()
        [0.5, 0.75, 0.0]
        """
        # np.add.accumulate is np.cumsum without its dispatch, which costs more on ten links.
        path = np.add.accumulate(angles) if self.is_chain else self._paths @ angles
        return path + self.base_angle

    def clamp(self, angles: np.ndarray | Sequence[float]) -> np.ndarray:
        """Angles (an array or a list) clipped to the joint limits, radians.

        >>> Skeleton.chain([1], limits=[(-0.5, 0.5)]).clamp(np.array([2.0])).tolist()
        [0.5]
        >>> Skeleton.chain([1, 1], limits=[(-0.5, 0.5)] * 2).clamp([-2.0, 0.25]).tolist()
        [-0.5, 0.25]
        """
        # The array's own clip, the same as np.clip without its dispatch, which costs more than
        # the clip on a few links (solvers and the controller clamp every tick).
        return np.asarray(angles, dtype=float).clip(self.lower, self.upper)


def forward_kinematics(skeleton: Skeleton, angles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World positions of the joints and world angles of the links (px, radians).

    Returns ``(points, world_angles)``. For a chain, ``points`` has shape (n + 1, 2): joint 0 ..
    joint n-1, then the end effector. For a tree it has shape (2n, 2): the n link starts, then
    the n link ends. ``world_angles`` has shape (n,). Root joints sit at their ``root_offsets``.

    >>> pts, world = forward_kinematics(Skeleton.chain([10, 10]), np.array([np.pi / 2, 0.0]))
    >>> np.round(pts, 6).tolist()
    [[0.0, 0.0], [0.0, 10.0], [0.0, 20.0]]
    """
    angles = check_angles(angles, skeleton.count)
    if skeleton.is_chain:
        world = skeleton.base_angle + np.cumsum(angles)
        steps = skeleton.lengths[:, None] * np.column_stack((np.cos(world), np.sin(world)))
        origin = skeleton.root_points()[0] if skeleton.has_root_offsets else skeleton.base
        points = np.vstack((origin, origin + np.cumsum(steps, axis=0)))
        return points, world
    starts, ends, world = tree_points(skeleton, angles, skeleton.root_points())
    return np.vstack((starts, ends)), world


def tree_points(
    skeleton: Skeleton, angles: np.ndarray, root_points: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Forward kinematics of any skeleton without input checks: (n, 2) link starts, (n, 2)
    link ends (px) and (n,) world angles (radians).

    Sums along each link's path (``Skeleton.ancestors``) as matrix products, which beats a loop
    over the links for any tree a level holds. ``root_points`` is ``skeleton.root_points()``,
    passed in so that a solver computes it once per solve.

    >>> tree = Skeleton.tree([1, 1, 1], [-1, 0, 0])
    >>> tree_points(tree, np.array([0, 0.5 * np.pi, 0]), tree.root_points())[1].round(6).tolist()
    [[1.0, 0.0], [1.0, 1.0], [2.0, 0.0]]
    """
    path = skeleton._paths
    world = path @ angles
    world += skeleton.base_angle
    steps = np.empty((skeleton.count, 2))
    np.multiply(skeleton.lengths, np.cos(world), out=steps[:, 0])
    np.multiply(skeleton.lengths, np.sin(world), out=steps[:, 1])
    ends = path @ steps
    ends += root_points
    starts = np.where(skeleton._is_root, root_points, ends[skeleton.parents])
    return starts, ends, world
