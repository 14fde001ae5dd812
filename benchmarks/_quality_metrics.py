"""Motion-quality measures on recorded trajectories, and reachability witnesses for stress levels.

Pure numpy, no pymunk: :mod:`benchmarks.quality` records a run tick by tick and hands the arrays
here, and the tests feed synthetic trajectories with known answers. Units: px, s, radians in,
degrees out where a name says ``deg``.

The second half answers "are these targets reachable?" for a chain or a tree of links: a pose
inside the joint limits that puts every targeted link end within tolerance, whose links keep clear
of the obstacles, and whose static gravity torque every motor can hold (:func:`find_witness`).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np

__all__ = [
    "ChainSpec",
    "ancestors",
    "approach_overshoot",
    "chain_points",
    "find_witness",
    "gravity_torques",
    "limit_excursion_deg",
    "link_segments",
    "obstacle_clearance",
    "rest_jitter",
    "span",
    "spin_joints",
    "stretched_toward",
]


def approach_overshoot(
    tips: np.ndarray, start: np.ndarray, target: np.ndarray, tolerance: float
) -> float | None:
    """Largest distance past ``target`` along the way the tip came in, as % of the approach.

    The approach distance runs from ``start`` (the tip when the step began) to ``target``; the
    tip came in along the line from where it was on the last tick before it first got within
    ``tolerance`` to the target. Past means beyond the target along that line, from that first
    tick on. A tip that sweeps in on a curve and settles has come in from the side, not along
    the line from where the step began: measured along that line, the last few px of a curve
    would read as going past. None when the tip never got there, or started within tolerance
    (no approach to overshoot).

    >>> tips = np.array([[0.0, 0.0], [90.0, 0.0], [104.0, 0.0], [100.0, 0.0]])
    >>> approach_overshoot(tips, np.zeros(2), np.array([100.0, 0.0]), 6.0)
    4.0
    >>> arc = np.array([[0.0, 0.0], [80.0, 40.0], [104.0, 8.0], [100.0, 0.0]])  # in from above
    >>> approach_overshoot(arc, np.zeros(2), np.array([100.0, 0.0]), 9.0)
    0.0
    """
    offset = target - start
    distance = float(np.hypot(*offset))
    if distance <= tolerance:
        return None
    inside = np.flatnonzero(np.hypot(*(tips - target).T) <= tolerance)
    if inside.size == 0:
        return None
    first = int(inside[0])
    came_from = tips[first - 1] if first > 0 else start
    way_in = target - came_from
    length = float(np.hypot(*way_in))
    direction = offset / distance if length == 0.0 else way_in / length
    past = (tips[first:] - target) @ direction
    return max(float(past.max()), 0.0) / distance * 100.0


def rest_jitter(tips: np.ndarray) -> float:
    """Spread of a tip at rest: the largest distance from its mean position, px.

    >>> rest_jitter(np.array([[0.0, 0.0], [2.0, 0.0], [1.0, 0.0]]))
    1.0
    """
    if len(tips) == 0:
        return 0.0
    return float(np.hypot(*(tips - tips.mean(axis=0)).T).max())


def limit_excursion_deg(angles: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> float:
    """Furthest any joint went past one of its limits over a run, degrees (0 if never).

    ``angles`` is (ticks, n) radians; ``lower`` and ``upper`` are (n,) radians, -inf / inf for
    a free side.

    >>> a = np.radians([[0.0, 10.0], [5.0, 33.0]])
    >>> round(limit_excursion_deg(a, np.radians([-10.0, -30.0]), np.radians([10.0, 30.0])), 6)
    3.0
    """
    if len(angles) == 0:
        return 0.0
    past = np.maximum(angles - upper, lower - angles)
    return max(math.degrees(float(past.max())), 0.0)


def spin_joints(angles: np.ndarray, limit_deg: float = 180.0) -> int:
    """How many joints turned through more than ``limit_deg`` within a window.

    ``angles`` is (ticks, n) continuous (unwrapped) radians, as a run measures them.

    >>> spin_joints(np.radians([[0.0, 0.0], [100.0, 10.0], [190.0, -5.0]]))
    1
    """
    if len(angles) == 0:
        return 0
    turned = np.degrees(angles.max(axis=0) - angles.min(axis=0))
    return int(np.count_nonzero(turned > limit_deg))


def stretched_toward(
    base: np.ndarray, tip: np.ndarray, target: np.ndarray, reach: float, tolerance: float
) -> bool:
    """True when the tip rests where a chain reaching for an out-of-reach target should.

    That is within ``tolerance`` of the nearest point of its reach: the point ``reach`` px from
    the base on the line to the target.

    >>> stretched_toward(np.zeros(2), np.array([0.0, 98.0]), np.array([0.0, 130.0]), 100.0, 6.0)
    True
    >>> stretched_toward(np.zeros(2), np.array([30.0, 90.0]), np.array([0.0, 130.0]), 100.0, 6.0)
    False
    """
    offset = target - base
    nearest = base + offset / float(np.hypot(*offset)) * reach
    return bool(np.hypot(*(tip - nearest)) <= tolerance)


@dataclasses.dataclass(frozen=True)
class ChainSpec:
    """A chain or tree of links for the kinematic checks: px, radians, mass units, px/s^2.

    Attributes:
        lengths, masses, widths, max_torque: (n,) per link.
        lower, upper: (n,) joint limits relative to the parent, radians (+-inf when free).
        base: (2,) base position; base_angle: mount direction, radians.
        gravity: (2,) px/s^2.
        segments: (k, 5) obstacle segments ``(ax, ay, bx, by, radius)``.
        circles: (c, 3) obstacle discs ``(x, y, radius)``.
        parents: (n,) int, each link's parent (listed before it), -1 for a root; None: a chain.
        offsets: (n, 2) where each root's joint sits in the base frame (x along ``base_angle``,
            y to its left), zero rows for the other links; None: every root on the base.
    """

    lengths: np.ndarray
    masses: np.ndarray
    widths: np.ndarray
    max_torque: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    base: np.ndarray
    base_angle: float
    gravity: np.ndarray
    segments: np.ndarray
    circles: np.ndarray
    parents: np.ndarray | None = None
    offsets: np.ndarray | None = None

    @property
    def reach(self) -> float:
        """Length of the chain stretched straight (of a tree: its longest path from a root),
        px."""
        if self.parents is None:
            return float(self.lengths.sum())
        return float((ancestors(self) @ self.lengths).max())


def ancestors(spec: ChainSpec) -> np.ndarray:
    """(n, n) bool: ``[i, j]`` when turning joint ``j`` moves the end of link ``i``.

    >>> tree = dataclasses.replace(_doc_spec(), parents=np.array([-1, -1]))
    >>> ancestors(tree).astype(int).tolist(), ancestors(_doc_spec()).astype(int).tolist()
    ([[1, 0], [0, 1]], [[1, 0], [1, 1]])
    """
    n = len(spec.lengths)
    if spec.parents is None:
        return np.tril(np.ones((n, n), dtype=bool))
    mask = np.eye(n, dtype=bool)
    for i, parent in enumerate(spec.parents):
        if parent >= 0:
            mask[i] |= mask[parent]
    return mask


def chain_points(spec: ChainSpec, angles: np.ndarray) -> np.ndarray:
    """(n + 1, 2) joint positions then the tip of a chain for local ``angles`` (radians), px.

    >>> spec = _doc_spec()
    >>> chain_points(spec, np.array([0.0, 0.0])).round(6).tolist()
    [[0.0, 0.0], [0.0, 100.0], [0.0, 200.0]]
    """
    world = spec.base_angle + np.cumsum(angles)
    steps = spec.lengths[:, None] * np.column_stack((np.cos(world), np.sin(world)))
    return np.vstack((spec.base, spec.base + np.cumsum(steps, axis=0)))


def link_segments(spec: ChainSpec, angles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(n, 2) starts and (n, 2) ends of the links of a chain or tree for local ``angles``, px.

    A root's angle is relative to ``base_angle``, any other link's to its parent's.

    >>> spec = dataclasses.replace(_doc_spec(), parents=np.array([-1, -1]),
    ...                            offsets=np.array([[0.0, 10.0], [20.0, -10.0]]))
    >>> starts, ends = link_segments(spec, np.array([0.0, -np.pi / 2]))
    >>> starts.round(6).tolist(), ends.round(6).tolist()
    ([[-10.0, 0.0], [10.0, 20.0]], [[-10.0, 100.0], [110.0, 20.0]])
    """
    if spec.parents is None:
        points = chain_points(spec, angles)
        return points[:-1], points[1:]
    n = len(spec.lengths)
    c, s = math.cos(spec.base_angle), math.sin(spec.base_angle)
    offsets = np.zeros((n, 2)) if spec.offsets is None else spec.offsets
    roots = spec.base + offsets @ np.array(((c, s), (-s, c)))
    starts, ends, world = np.empty((n, 2)), np.empty((n, 2)), np.empty(n)
    for i, parent in enumerate(spec.parents):
        if parent < 0:
            starts[i], world[i] = roots[i], spec.base_angle + angles[i]
        else:
            starts[i], world[i] = ends[parent], world[parent] + angles[i]
        ends[i] = starts[i] + spec.lengths[i] * np.array((math.cos(world[i]), math.sin(world[i])))
    return starts, ends


def gravity_torques(spec: ChainSpec, starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """(n,) static torque each joint's motor must hold against gravity in a pose, absolute.

    >>> spec = _doc_spec()
    >>> gravity_torques(spec, *link_segments(spec, np.array([-np.pi / 2, 0.0]))).tolist()
    [200000.0, 50000.0]
    """
    com = (starts + ends) / 2.0
    force = spec.masses[:, None] * spec.gravity
    moment = com[:, 0] * force[:, 1] - com[:, 1] * force[:, 0]
    # Torque about joint j of the links it carries (its subtree): sum_k (com_k - p_j) x f_k.
    if spec.parents is None:
        total_force = np.cumsum(force[::-1], axis=0)[::-1]
        outer = np.cumsum(moment[::-1])[::-1]
    else:
        carried = ancestors(spec).T
        total_force = carried @ force
        outer = carried @ moment
    return np.abs(outer - (starts[:, 0] * total_force[:, 1] - starts[:, 1] * total_force[:, 0]))


def _segment_distance(p0: np.ndarray, p1: np.ndarray, q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
    """Distance between segments p0-p1 (arrays of m) and the segment q0-q1, px."""

    def point_to_segment(x: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        ab = b - a
        denom = np.maximum(np.sum(ab * ab, axis=-1), 1e-12)
        u = np.clip(np.sum((x - a) * ab, axis=-1) / denom, 0.0, 1.0)
        return np.hypot(*(a + u[..., None] * ab - x).T)

    d = np.minimum.reduce(
        [
            point_to_segment(p0, q0, q1),
            point_to_segment(p1, q0, q1),
            point_to_segment(np.broadcast_to(q0, p0.shape), p0, p1),
            point_to_segment(np.broadcast_to(q1, p0.shape), p0, p1),
        ]
    )
    # Crossing segments are 0 apart; the endpoint distances above miss that case.
    r = p1 - p0
    s = q1 - q0
    cross = r[:, 0] * s[1] - r[:, 1] * s[0]
    qp = q0 - p0
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (qp[:, 0] * s[1] - qp[:, 1] * s[0]) / cross
        u = (qp[:, 0] * r[:, 1] - qp[:, 1] * r[:, 0]) / cross
    crossing = (cross != 0) & (t >= 0) & (t <= 1) & (u >= 0) & (u <= 1)
    return np.where(crossing, 0.0, d)


def obstacle_clearance(spec: ChainSpec, starts: np.ndarray, ends: np.ndarray) -> float:
    """Smallest gap between a link's surface and an obstacle's, px (inf with no obstacles).

    >>> spec = _doc_spec()
    >>> obstacle_clearance(spec, *link_segments(spec, np.zeros(2)))
    36.0
    """
    gap = math.inf
    radii = spec.widths / 2.0
    for ax, ay, bx, by, radius in spec.segments:
        d = _segment_distance(starts, ends, np.array([ax, ay]), np.array([bx, by]))
        gap = min(gap, float((d - radii - radius).min()))
    for cx, cy, radius in spec.circles:
        centre = np.array([cx, cy])
        d = _segment_distance(starts, ends, centre, centre)
        gap = min(gap, float((d - radii - radius).min()))
    return gap


def span(spec: ChainSpec, a: int, b: int) -> float:
    """The farthest apart the ends of links ``a`` and ``b`` can ever be, px.

    Both hang from the end of their last common ancestor (or from their roots' joints, when
    they share none), so they are at most the lengths from there apart; targets farther apart
    than that plus twice the tolerance cannot be met together in any pose.

    >>> fork = dataclasses.replace(_doc_spec(), lengths=np.array([100.0, 60.0, 50.0]),
    ...     parents=np.array([-1, 0, 0]), masses=np.ones(3), widths=np.ones(3))
    >>> span(fork, 1, 2), span(fork, 0, 2)
    (110.0, 50.0)
    """
    mask = ancestors(spec)
    shared = mask[a] & mask[b]
    own = (mask[a] & ~shared) @ spec.lengths + (mask[b] & ~shared) @ spec.lengths
    if shared.any():
        return float(own)
    starts, _ = link_segments(spec, np.zeros(len(spec.lengths)))
    roots = [int(np.flatnonzero(mask[i])[0]) for i in (a, b)]
    return float(own + np.hypot(*(starts[roots[0]] - starts[roots[1]])))


def find_witness(
    spec: ChainSpec,
    target: Sequence[float] | np.ndarray,
    tolerance: float,
    *,
    links: Sequence[int] | None = None,
    seed: int = 0,
    samples: int = 400,
    refine: int = 24,
) -> np.ndarray | None:
    """A pose (radians) proving ``target`` reachable, or None if the search found none.

    ``target`` is one point (x, y) for the end of the last link, or one point per link of
    ``links`` (a tree's effectors, all at once). A witness keeps every joint inside its limits,
    puts every targeted end within half of ``tolerance``, keeps each link clear of the obstacles,
    and asks no motor for more than its ``max_torque`` to hold it still against gravity. The
    search samples poses inside the limits (and the evenly bent poses), refines those and the
    ``refine`` closest by damped least squares on all the targets at once, clamped to the
    limits, and returns the first that passes: a found witness is a proof, a miss only a strong
    hint.

    >>> spec = _doc_spec()
    >>> pose = find_witness(spec, (120.0, 120.0), 6.0)
    >>> bool(np.hypot(*(chain_points(spec, pose)[-1] - (120.0, 120.0))) < 3.0)
    True
    >>> find_witness(spec, (0.0, 260.0), 6.0) is None
    True
    >>> fork = dataclasses.replace(_doc_spec(), parents=np.array([-1, -1]))
    >>> find_witness(fork, [(-80.0, 60.0), (90.0, 40.0)], 6.0, links=[0, 1]) is not None
    True
    """
    n = len(spec.lengths)
    ends_of = np.array([n - 1] if links is None else links, dtype=int)
    goals = np.asarray(target, dtype=float).reshape(len(ends_of), 2)
    rng = np.random.default_rng(seed)
    lo = np.where(np.isfinite(spec.lower), spec.lower, -math.pi)
    hi = np.where(np.isfinite(spec.upper), spec.upper, math.pi)
    # Even bends (the straight pose among them) seed long chains, which random poses coil up.
    bends = [np.clip(np.full(n, b), lo, hi) for b in np.radians((0.0, -2.0, 2.0, -10.0, 10.0))]
    random = rng.uniform(lo, hi, (samples, n))
    misses = np.array([_misses(spec, pose, ends_of, goals).sum() for pose in random])
    nearest = random[np.argsort(misses, kind="stable")[:refine]]
    for start in (*bends, (lo + hi) / 2.0, *nearest):
        pose = _refine(spec, start, ends_of, goals, lo, hi)
        starts, ends = link_segments(spec, pose)
        if (
            np.all(_misses(spec, pose, ends_of, goals) <= tolerance / 2.0)
            and np.all(gravity_torques(spec, starts, ends) <= spec.max_torque)
            and obstacle_clearance(spec, starts, ends) >= 0.0
        ):
            return pose
    return None


def _misses(spec: ChainSpec, pose: np.ndarray, links: np.ndarray, goals: np.ndarray) -> np.ndarray:
    """(k,) distance of each targeted link end from its goal in ``pose``, px."""
    return np.hypot(*(link_segments(spec, pose)[1][links] - goals).T)


def _refine(
    spec: ChainSpec,
    pose: np.ndarray,
    links: np.ndarray,
    goals: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
) -> np.ndarray:
    """Damped least squares toward every goal at once, clamped to the limits after each step."""
    pose = pose.copy()
    moves = ancestors(spec)[links]
    damping = 0.05 * spec.reach
    for _ in range(200):
        starts, ends = link_segments(spec, pose)
        error = goals - ends[links]
        if np.hypot(*error.T).max() < 1e-3:
            break
        # Rows 2j, 2j + 1: the end of links[j]; column i: z x (that end - joint i), if i moves it.
        lever = ends[links][:, None, :] - starts[None, :, :]
        jac = np.stack((-lever[..., 1] * moves, lever[..., 0] * moves), axis=1)
        jac = jac.reshape(2 * len(links), -1)
        step = jac.T @ np.linalg.solve(jac @ jac.T + damping**2 * np.eye(len(jac)), error.ravel())
        pose = np.clip(pose + step, lo, hi)
    return pose


def _doc_spec() -> ChainSpec:
    """Two 100 px links of 1 mass unit mounted straight up, free, a floor 40 px below."""
    return ChainSpec(
        lengths=np.array([100.0, 100.0]),
        masses=np.array([1.0, 1.0]),
        widths=np.array([8.0, 8.0]),
        max_torque=np.array([1e6, 1e6]),
        lower=np.full(2, -np.inf),
        upper=np.full(2, np.inf),
        base=np.zeros(2),
        base_angle=math.pi / 2,
        gravity=np.array([0.0, -1000.0]),
        segments=np.array([[-300.0, -40.0, 300.0, -40.0, 0.0]]),
        circles=np.zeros((0, 3)),
    )
