"""Several targets at once: which link ends should reach which points, and how much each counts.

A :class:`TargetSet` names links by index; the end of ``links[j]`` should reach ``points[j]``.
The multi-target solvers minimise the weighted sum of squared distances

    F = 1/2 * sum_j weights[j] * |points[j] - end(links[j])|^2

whose gradient is the sum of each target's own gradient. When the targets cannot all be reached
(two effectors sharing joints, pulled apart), a solve settles at the weighted least-squares
compromise; the weights say which effector wins how much. Joints that move no targeted link are
left as they are: an effector without a target holds its pose.

Angles are radians, positions pixels.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ikgame.kinematics.skeleton import Skeleton, check_angles, tree_points

__all__ = ["TargetSet", "stacked_jacobian"]


@dataclass(frozen=True, eq=False)
class TargetSet:
    """One target point per chosen link end, with a weight each.

    >>> targets = TargetSet([1, 3], [(10, 0), (0, 10)], weights=[1.0, 2.0])
    >>> len(targets), targets.weights.tolist()
    (2, [1.0, 2.0])

    Attributes:
        links: (k,) distinct link indices whose ends are targeted (usually end effectors).
        points: (k, 2) where each of those ends should be, px.
        weights: (k,) > 0, each target's weight in the least-squares sum (None: all 1).
    """

    links: np.ndarray
    points: np.ndarray
    weights: np.ndarray | None = None

    def __post_init__(self) -> None:
        links = _checked_links(self.links)
        k = links.shape[0]
        try:
            points = np.array(self.points, dtype=float)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"targets must be link indices and (x, y) points: {exc}") from exc
        if points.shape != (k, 2):
            raise ValueError(f"points must have shape ({k}, 2), got shape {points.shape}")
        if not np.isfinite(points).all():
            raise ValueError(f"points must be finite, got {points.tolist()}")
        weights = np.ones(k) if self.weights is None else np.array(self.weights, dtype=float)
        if weights.shape != (k,):
            raise ValueError(f"weights must have shape ({k},), got shape {weights.shape}")
        listed = weights.tolist()
        if not all(math.isfinite(w) and w > 0 for w in listed):
            raise ValueError(f"weights must be finite and > 0, got {listed}")
        for name, value in (("links", links), ("points", points), ("weights", weights)):
            value.setflags(write=False)
            object.__setattr__(self, name, value)

    def __len__(self) -> int:
        return int(self.links.shape[0])

    def check(self, skeleton: Skeleton) -> None:
        """``ValueError`` unless every targeted link is one of ``skeleton``'s.

        >>> TargetSet([2], [(0, 0)]).check(Skeleton.chain([1, 1]))
        Traceback (most recent call last):
        ...
        ValueError: target links must be < 2 (the skeleton's links), got [2]
        """
        _check_bound(self.links, skeleton.count)


def stacked_jacobian(
    skeleton: Skeleton, angles: np.ndarray, links: Sequence[int] | np.ndarray
) -> np.ndarray:
    """The (2k, n) Jacobian of the ends of ``links``, stacked: px per radian.

    Rows ``2j`` and ``2j + 1`` are ``d(x, y of the end of links[j]) / d(angles)``: column ``i``
    is the perpendicular of ``end - joint_i`` where joint ``i`` moves that end, else zero. Map
    target velocities (stacked the same way) to joint rates with a damped pseudo-inverse,
    ``J^T (J J^T + lambda^2 I)^-1 v``.

    >>> tree = Skeleton.tree([10, 10, 10], [-1, 0, 0])
    >>> stacked_jacobian(tree, np.zeros(3), [1, 2])[[1, 3]].tolist()
    [[20.0, 10.0, 0.0], [20.0, 0.0, 10.0]]
    """
    angles = check_angles(angles, skeleton.count)
    # The links are checked as a target set's are.
    chosen = _checked_links(links)
    _check_bound(chosen, skeleton.count)
    starts, ends, _ = tree_points(skeleton, angles, skeleton.root_points())
    mask = skeleton.ancestors[chosen]
    return columns(ends[chosen], starts, mask).reshape(-1, skeleton.count)


def _checked_links(value: object) -> np.ndarray:
    """``value`` as a new (k,) int64 array of distinct link indices >= 0, or ``ValueError``."""
    try:
        links = np.array(value)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"targets must be link indices and (x, y) points: {exc}") from exc
    if links.ndim != 1 or links.shape[0] == 0:
        raise ValueError(f"links must be a non-empty 1-D array, got shape {links.shape}")
    if links.dtype.kind not in "iu":
        raise ValueError(f"links must be integer link indices, got {links.tolist()}")
    links = links.astype(np.int64, copy=False)
    listed = links.tolist()
    if min(listed) < 0 or len(set(listed)) != len(listed):
        raise ValueError(f"links must be distinct indices >= 0, got {listed}")
    return links


def _check_bound(links: np.ndarray, count: int) -> None:
    """``ValueError`` unless every one of ``links`` is below ``count``."""
    if int(links.max()) >= count:
        raise ValueError(
            f"target links must be < {count} (the skeleton's links), got {links.tolist()}"
        )


def columns(effectors: np.ndarray, starts: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """(k, 2, n) Jacobian of each effector (k, 2) about the joints ``starts`` (n, 2), with the
    columns of joints that do not move it (``mask`` (k, n) False) zero."""
    arms = effectors[:, None, :] - starts[None, :, :]
    out = np.empty((effectors.shape[0], 2, starts.shape[0]))
    np.multiply(-arms[:, :, 1], mask, out=out[:, 0])
    np.multiply(arms[:, :, 0], mask, out=out[:, 1])
    return out
