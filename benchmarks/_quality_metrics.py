"""Motion-quality measures on recorded trajectories, and reachability witnesses for stress levels.

Pure numpy, no pymunk: :mod:`benchmarks.quality` records a run tick by tick and hands the arrays
here, and the tests feed synthetic trajectories with known answers. Units: px, s, radians in,
degrees out where a name says ``deg``.

The second half answers "is this target reachable?" for a chain: a pose inside the joint limits
whose tip is within tolerance, whose links keep clear of the obstacles, and whose static gravity
torque every motor can hold (:func:`find_witness`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = [
    "ChainSpec",
    "approach_overshoot",
    "chain_points",
    "find_witness",
    "gravity_torques",
    "limit_excursion_deg",
    "obstacle_clearance",
    "rest_jitter",
    "spin_joints",
    "stretched_toward",
]


def approach_overshoot(
    tips: np.ndarray, start: np.ndarray, target: np.ndarray, tolerance: float
) -> float | None:
    """Largest distance past ``target`` along the approach, as % of the approach distance.

    The approach runs from ``start`` (the tip when the step began) to ``target``. Only the
    ticks from the first one within ``tolerance`` of the target on count; None when the tip
    never got there, or started within tolerance (no approach to overshoot).

    >>> tips = np.array([[0.0, 0.0], [90.0, 0.0], [104.0, 0.0], [100.0, 0.0]])
    >>> approach_overshoot(tips, np.zeros(2), np.array([100.0, 0.0]), 6.0)
    4.0
    """
    offset = target - start
    distance = float(np.hypot(*offset))
    if distance <= tolerance:
        return None
    inside = np.flatnonzero(np.hypot(*(tips - target).T) <= tolerance)
    if inside.size == 0:
        return None
    direction = offset / distance
    past = (tips[inside[0] :] - target) @ direction
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


@dataclass(frozen=True)
class ChainSpec:
    """A serial chain for the kinematic checks: px, radians, mass units, px/s^2.

    Attributes:
        lengths, masses, widths, max_torque: (n,) per link.
        lower, upper: (n,) joint limits relative to the parent, radians (+-inf when free).
        base: (2,) base position; base_angle: mount direction, radians.
        gravity: (2,) px/s^2.
        segments: (k, 5) obstacle segments ``(ax, ay, bx, by, radius)``.
        circles: (c, 3) obstacle discs ``(x, y, radius)``.
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

    @property
    def reach(self) -> float:
        """Length of the chain stretched straight, px."""
        return float(self.lengths.sum())


def chain_points(spec: ChainSpec, angles: np.ndarray) -> np.ndarray:
    """(n + 1, 2) joint positions then the tip for local ``angles`` (radians), px.

    >>> spec = _doc_spec()
    >>> chain_points(spec, np.array([0.0, 0.0])).round(6).tolist()
    [[0.0, 0.0], [0.0, 100.0], [0.0, 200.0]]
    """
    world = spec.base_angle + np.cumsum(angles)
    steps = spec.lengths[:, None] * np.column_stack((np.cos(world), np.sin(world)))
    return np.vstack((spec.base, spec.base + np.cumsum(steps, axis=0)))


def gravity_torques(spec: ChainSpec, points: np.ndarray) -> np.ndarray:
    """(n,) static torque each joint's motor must hold against gravity in a pose, absolute.

    >>> spec = _doc_spec()
    >>> gravity_torques(spec, chain_points(spec, np.array([-np.pi / 2, 0.0]))).tolist()
    [200000.0, 50000.0]
    """
    com = (points[:-1] + points[1:]) / 2.0
    force = spec.masses[:, None] * spec.gravity
    # Torque about joint j of the links from j on: sum_k (com_k - p_j) x f_k.
    moment = com[:, 0] * force[:, 1] - com[:, 1] * force[:, 0]
    total_force = np.cumsum(force[::-1], axis=0)[::-1]
    outer = np.cumsum(moment[::-1])[::-1]
    joints = points[:-1]
    return np.abs(outer - (joints[:, 0] * total_force[:, 1] - joints[:, 1] * total_force[:, 0]))


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


def obstacle_clearance(spec: ChainSpec, points: np.ndarray) -> float:
    """Smallest gap between a link's surface and an obstacle's, px (inf with no obstacles).

    >>> spec = _doc_spec()
    >>> obstacle_clearance(spec, chain_points(spec, np.zeros(2)))
    36.0
    """
    gap = math.inf
    radii = spec.widths / 2.0
    for ax, ay, bx, by, radius in spec.segments:
        d = _segment_distance(points[:-1], points[1:], np.array([ax, ay]), np.array([bx, by]))
        gap = min(gap, float((d - radii - radius).min()))
    for cx, cy, radius in spec.circles:
        centre = np.array([cx, cy])
        d = _segment_distance(points[:-1], points[1:], centre, centre)
        gap = min(gap, float((d - radii - radius).min()))
    return gap


def find_witness(
    spec: ChainSpec,
    target: Sequence[float],
    tolerance: float,
    *,
    seed: int = 0,
    samples: int = 400,
    refine: int = 24,
) -> np.ndarray | None:
    """A pose (radians) proving ``target`` reachable, or None if the search found none.

    A witness keeps every joint inside its limits, puts the tip within half of ``tolerance``,
    keeps each link clear of the obstacles, and asks no motor for more than its ``max_torque``
    to hold it still against gravity. The search samples poses inside the limits (and the
    evenly bent poses), refines those and the ``refine`` closest by damped least squares clamped to the
    limits, and returns the first that passes: a found witness is a proof, a miss only a
    strong hint.

    >>> spec = _doc_spec()
    >>> pose = find_witness(spec, (120.0, 120.0), 6.0)
    >>> bool(np.hypot(*(chain_points(spec, pose)[-1] - (120.0, 120.0))) < 3.0)
    True
    >>> find_witness(spec, (0.0, 260.0), 6.0) is None
    True
    """
    goal = np.asarray(target, dtype=float)
    rng = np.random.default_rng(seed)
    lo = np.where(np.isfinite(spec.lower), spec.lower, -math.pi)
    hi = np.where(np.isfinite(spec.upper), spec.upper, math.pi)
    n = len(spec.lengths)
    # Even bends (the straight pose among them) seed long chains, which random poses coil up.
    bends = [np.clip(np.full(n, b), lo, hi) for b in np.radians((0.0, -2.0, 2.0, -10.0, 10.0))]
    random = rng.uniform(lo, hi, (samples, n))
    tips = np.array([chain_points(spec, pose)[-1] for pose in random])
    nearest = random[np.argsort(np.hypot(*(tips - goal).T), kind="stable")[:refine]]
    for start in (*bends, (lo + hi) / 2.0, *nearest):
        pose = _refine(spec, start, goal, lo, hi)
        points = chain_points(spec, pose)
        if (
            np.hypot(*(points[-1] - goal)) <= tolerance / 2.0
            and np.all(gravity_torques(spec, points) <= spec.max_torque)
            and obstacle_clearance(spec, points) >= 0.0
        ):
            return pose
    return None


def _refine(
    spec: ChainSpec, pose: np.ndarray, goal: np.ndarray, lo: np.ndarray, hi: np.ndarray
) -> np.ndarray:
    """Damped least squares toward ``goal``, clamped to the limits after every step."""
    pose = pose.copy()
    for _ in range(200):
        points = chain_points(spec, pose)
        error = goal - points[-1]
        if np.hypot(*error) < 1e-3:
            break
        # Column j of the Jacobian: z x (tip - joint j).
        lever = points[-1] - points[:-1]
        jac = np.vstack((-lever[:, 1], lever[:, 0]))
        damping = 0.05 * spec.reach
        step = jac.T @ np.linalg.solve(jac @ jac.T + damping**2 * np.eye(2), error)
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
