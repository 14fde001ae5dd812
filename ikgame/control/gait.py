"""A gait for a legged body: where each foot should be, tick by tick.

A foot stands still in the world (it is *planted*) until the body has carried the foot's rest
spot (where the foot sits under a body at rest, fixed in the body's frame) too far from it. Then
the foot's group of legs lifts, swings over the ground in an arc and lands a little ahead of the
rest spot, on the terrain below. The groups take turns, so the others hold the body up while one
swings. Nothing here knows about pymunk or the level: the body's pose comes in every tick, the
feet's targets go out, and the terrain is the level's static obstacles as plain arrays.

Positions are world px (y up), angles radians, times s.
"""

from __future__ import annotations

import bisect
import itertools
import math
import numbers
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["FootState", "Footing", "Gait", "GaitParams", "Terrain", "default_groups"]

PATH_SAMPLES: Final = 64
"""Points along a step's path checked against the terrain when the step is planned."""

SINK_DEPTH: Final = 10.0
"""How deep below the ground (px) :class:`Footing` can see a foot sink."""

_FEW_RAYS: Final = 16
"""Up to this many rays, :meth:`Terrain.heights` casts them one by one in Python floats (as many
as a tick casts, one per foot), where numpy's per-call overhead costs more than the arithmetic."""

STILL: Final = 1e-6
"""A rest spot moving slower than this sideways (px/s) is standing still."""


def _finite(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    return float(value)


def _number(name: str, value: object, *, positive: bool) -> float:
    number = _finite(name, value)
    if number < 0 or (positive and number == 0):
        raise ValueError(f"{name} must be {'> 0' if positive else '>= 0'}, got {value!r}")
    return number


def _point(name: str, value: ArrayLike) -> np.ndarray:
    point = np.asarray(value, dtype=float)
    if point.shape != (2,) or not (math.isfinite(point[0]) and math.isfinite(point[1])):
        raise ValueError(f"{name} must be a finite point (x, y) in px, got {value!r}")
    return point


def _rows(name: str, value: ArrayLike | None, columns: int, layout: str) -> np.ndarray:
    rows = np.asarray([] if value is None else value, dtype=float)
    if rows.size == 0:
        return np.zeros((0, columns))
    if rows.ndim != 2 or rows.shape[1] != columns or not np.all(np.isfinite(rows)):
        raise ValueError(f"{name} must be a finite ({layout}) array with one row each")
    if np.any(rows[:, -1] < 0):
        raise ValueError(f"{name}: every radius must be >= 0")
    return rows


@dataclass(frozen=True)
class GaitParams:
    """How a creature walks.

    >>> GaitParams(stride=60.0, step_height=20.0, step_time=0.25, threshold=30.0).step_time
    0.25

    Attributes:
        stride: a foot lands ``stride / 2`` ahead of its rest spot, in the direction the rest
            spot moves, px (>= 0).
        step_height: how high a step lifts the foot above the straight line from where it
            lifts to where it lands (more where the ground between is higher), px (>= 0).
        step_time: how long a step takes, s (> 0).
        threshold: how far behind a planted foot the body may carry its rest spot (sideways,
            px, > 0) before the foot steps.
    """

    stride: float
    step_height: float
    step_time: float
    threshold: float

    def __post_init__(self) -> None:
        _number("stride", self.stride, positive=False)
        _number("step_height", self.step_height, positive=False)
        _number("step_time", self.step_time, positive=True)
        _number("threshold", self.threshold, positive=True)


class Terrain:
    """The static ground feet stand on: segment obstacles (capsules: a segment thickened by its
    radius) and circle obstacles, as the ``Scene`` holds them.

    >>> ground = Terrain(segments=[[-100.0, 0.0, 100.0, 0.0, 5.0]], circles=[[50.0, 0.0, 20.0]])
    >>> ground.ground_below(0.0, 100.0), ground.ground_below(50.0, 100.0)
    (5.0, 20.0)
    >>> ground.ground_below(200.0, 100.0) is None
    True

    Args:
        segments: (k, 5) rows ``(ax, ay, bx, by, radius)``, px.
        circles: (m, 3) rows ``(x, y, radius)``, px.
    """

    def __init__(self, segments: ArrayLike | None = None, circles: ArrayLike | None = None) -> None:
        segs = _rows("segments", segments, 5, "ax, ay, bx, by, radius")
        circs = _rows("circles", circles, 3, "x, y, radius")
        a, b, radius = segs[:, 0:2], segs[:, 2:4], segs[:, 4:5]
        along = b - a
        length = np.hypot(along[:, 0], along[:, 1])[:, None]
        # A capsule is the rectangle its segment sweeps along the normal plus a disc at each
        # end; a ray meets the union where it meets the highest of the parts.
        normal = np.where(length > 0, np.stack([-along[:, 1], along[:, 0]], 1), [[0.0, 1.0]])
        offset = normal / np.where(length > 0, length, 1.0) * radius
        corners = np.stack([a + offset, b + offset, b - offset, a - offset], axis=1)
        ends = np.roll(corners, -1, axis=1)
        self._edge_start = corners
        self._edge_delta = ends - corners
        self._edge_vertical = self._edge_delta[..., 0] == 0
        self._edge_dx = np.where(self._edge_vertical, 1.0, self._edge_delta[..., 0])
        self._edge_low = np.minimum(corners[..., 1], ends[..., 1])
        self._edge_high = np.maximum(corners[..., 1], ends[..., 1])
        self._discs = np.concatenate([np.hstack([a, radius]), np.hstack([b, radius]), circs])
        # The same as Python floats, for the few rays a tick casts (see _height), each part
        # with the x range outside which no ray can meet it.
        disc_rows = [
            (*_x_range(cx - r, cx + r), cx, cy, r * r) for cx, cy, r in self._discs.tolist()
        ]
        edge_rows = [
            (*_x_range(min(xs), max(xs)), list(zip(xs, *rows, strict=True)))
            for xs, *rows in zip(
                self._edge_start[..., 0].tolist(),
                self._edge_start[..., 1].tolist(),
                self._edge_dx.tolist(),
                self._edge_delta[..., 1].tolist(),
                self._edge_vertical.tolist(),
                self._edge_low.tolist(),
                self._edge_high.tolist(),
                strict=True,
            )
        ]
        # The x axis cut at every part's range ends, with the parts whose range meets each
        # cut (in their order here): a ray looks at its own cut's parts only.
        self._cuts = sorted({end for row in disc_rows + edge_rows for end in row[:2]})
        bounds = [-math.inf, *self._cuts, math.inf]
        self._parts = [
            (
                [row for row in disc_rows if row[0] <= right and row[1] >= left],
                [row for row in edge_rows if row[0] <= right and row[1] >= left],
            )
            for left, right in itertools.pairwise(bounds)
        ]

    def heights(self, xs: ArrayLike, y_from: ArrayLike) -> np.ndarray:
        """:meth:`ground_below` for many rays at once (``xs`` and ``y_from`` broadcast
        together), px; nan where a ray meets nothing.

        >>> Terrain(circles=[[0.0, 0.0, 10.0]]).heights([0.0, 6.0, 20.0], 50.0)
        array([10.,  8., nan])
        """
        x, top = np.asarray(xs, dtype=float), np.asarray(y_from, dtype=float)
        if x.shape != top.shape:
            x, top = np.broadcast_arrays(x, top)
        if x.size <= _FEW_RAYS:
            found = [
                self._height(*ray)
                for ray in zip(x.ravel().tolist(), top.ravel().tolist(), strict=True)
            ]
            return np.array(found, dtype=float).reshape(x.shape)
        x, top = x[..., None], top[..., None]
        cx, cy, r = self._discs.T
        half = r * r - (x - cx) ** 2
        chord = np.sqrt(np.maximum(half, 0.0))
        meets = (half >= 0) & (cy - chord <= top)
        disc_hit = np.max(
            np.where(meets, np.minimum(cy + chord, top), -np.inf), axis=-1, initial=-np.inf
        )
        across = x[..., None] - self._edge_start[..., 0]
        t = across / self._edge_dx
        ys = self._edge_start[..., 1] + t * self._edge_delta[..., 1]
        # A vertical edge meets the ray along its whole length, or not at all.
        along = self._edge_vertical & (across == 0)
        on_edge = (~self._edge_vertical & (t >= 0) & (t <= 1)) | along
        high = np.max(np.where(on_edge, np.where(along, self._edge_high, ys), -np.inf), axis=-1)
        low = np.min(np.where(on_edge, np.where(along, self._edge_low, ys), np.inf), axis=-1)
        rect_hit = np.max(
            np.where(low <= top, np.minimum(high, top), -np.inf), axis=-1, initial=-np.inf
        )
        hit = np.maximum(disc_hit, rect_hit)
        return np.where(np.isfinite(hit), hit, np.nan)

    def _height(self, x: float, top: float) -> float:
        """One ray of :meth:`heights`, in Python floats: the same operations on each disc and
        edge, in the same order, so the same results to the bit."""
        discs, segments = self._parts[bisect.bisect_right(self._cuts, x)]
        disc_hit = -math.inf
        for lo, hi, cx, cy, rr in discs:
            if not lo <= x <= hi:
                continue
            off = x - cx
            half = rr - off * off
            chord = math.sqrt(max(half, 0.0))
            if half >= 0 and cy - chord <= top:
                disc_hit = max(disc_hit, min(cy + chord, top))
        rect_hit = -math.inf
        for lo, hi, edges in segments:
            if not lo <= x <= hi:
                continue
            high, low = -math.inf, math.inf
            for sx, sy, dx, dy, vertical, edge_low, edge_high in edges:
                across = x - sx
                if vertical:
                    if across == 0:
                        high, low = max(high, edge_high), min(low, edge_low)
                    continue
                t = across / dx
                if 0 <= t <= 1:
                    ys = sy + t * dy
                    high, low = max(high, ys), min(low, ys)
            if low <= top:
                rect_hit = max(rect_hit, min(high, top))
        hit = max(disc_hit, rect_hit)
        return hit if math.isfinite(hit) else math.nan

    def ground_below(self, x: float, y_from: float) -> float | None:
        """Where a ray cast straight down from ``(x, y_from)`` first meets an obstacle: its
        height, px, or None when nothing lies below. A ray that starts inside an obstacle meets
        it at once (``y_from``).

        >>> ground = Terrain(circles=[[0.0, 0.0, 10.0]])
        >>> ground.ground_below(6.0, 50.0), ground.ground_below(6.0, 5.0), ground.ground_below(6.0, -20.0)
        (8.0, 5.0, None)
        """
        hit = float(self.heights(x, y_from))
        return None if math.isnan(hit) else hit


def _x_range(lo: float, hi: float) -> tuple[float, float]:
    """``[lo, hi]`` widened by far more than rounding: a ray outside it cannot meet a part
    spanning ``lo`` to ``hi``, however its arithmetic rounds."""
    slack = 1e-6 * (abs(lo) + abs(hi) + 1.0)
    return lo - slack, hi + slack


def default_groups(legs: Sequence[str]) -> tuple[tuple[str, ...], ...]:
    """Two groups that alternate, for legs listed in left/right pairs from front to back (left
    front, right front, left second, ...): each group takes every other leg down each side, so
    four legs step in diagonal pairs and six in tripods. One leg makes one group.

    >>> default_groups(["fl", "fr", "hl", "hr"])
    (('fl', 'hr'), ('fr', 'hl'))
    >>> default_groups(["l1", "r1", "l2", "r2", "l3", "r3"])
    (('l1', 'r2', 'l3'), ('r1', 'l2', 'r3'))
    """
    names = tuple(legs)
    if not names:
        raise ValueError("a gait needs at least one leg")
    if len(set(names)) != len(names):
        raise ValueError(f"leg names must be unique, got {list(names)}")
    if len(names) == 1:
        return (names,)
    # Leg i is on side i % 2 of pair i // 2; a group alternates both down the body and across.
    return tuple(
        tuple(leg for i, leg in enumerate(names) if (i // 2 + i % 2) % 2 == g) for g in (0, 1)
    )


@dataclass(frozen=True, eq=False)
class FootState:
    """One foot's phase, as of the last update.

    >>> FootState(planted=True, point=np.array([30.0, 0.0]), progress=0.0).planted
    True

    Attributes:
        planted: whether the foot stands still in the world (False: it is stepping).
        point: where it stands, or where the step under way lands, world px.
        progress: how far through its step the foot is, 0..1 (0 when planted).
    """

    planted: bool
    point: np.ndarray
    progress: float


@dataclass(frozen=True, eq=False)
class _Step:
    group: int
    start: float
    lift: np.ndarray
    land: np.ndarray
    height: np.ndarray


def _ease(s: np.ndarray | float) -> np.ndarray | float:
    return s * s * (3.0 - 2.0 * s)


def _rotate(points: np.ndarray, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return points @ np.array([[c, s], [-s, c]])


class Gait:
    """Feet targets for a body walking over a terrain.

    A planted foot keeps its exact world point. Once the body has carried a foot's rest spot
    more than ``threshold`` px sideways past it (in the direction the rest spot moves; when the
    rest spot stands still, more than ``max(threshold, stride / 2)`` either way), the foot's
    group lifts, if no other group is stepping: groups take turns in order, the first one due
    from the turn on. Each foot of the group follows an arc over ``step_time``: eased sideways,
    a half sine in height ``step_height`` above the straight line (raised where the terrain
    between is higher), and lands exactly on the ground below the spot ``stride / 2`` ahead of
    where its rest spot will be (the body's linear and angular velocity, estimated from
    successive updates, carried forward over the step). Where no ground lies below (or it lies
    more than ``reach`` below the rest spot), the foot lands at its rest spot's height. Rays are
    cast from the body's height: ground above the body is a wall, and a step that would cross
    one lands short of it.

    >>> ground = Terrain(segments=[[-1000.0, 0.0, 1000.0, 0.0, 0.0]])
    >>> params = GaitParams(stride=40.0, step_height=15.0, step_time=0.2, threshold=25.0)
    >>> rest = {"front": (30.0, -60.0), "back": (-30.0, -60.0)}
    >>> gait = Gait(params, rest, ground, position=(0.0, 60.0))
    >>> gait.update(0.01, 0.01, (1.0, 60.0), 0.0)["front"]  # dropped to the ground, planted
    array([30.,  0.])
    >>> for tick in range(2, 37):  # 100 px/s to the right
    ...     targets = gait.update(tick / 100, 0.01, (float(tick), 60.0), 0.0)
    >>> gait.swinging, targets["front"], gait.feet["front"].point  # half way through a step
    (0, array([63., 15.]), array([96.,  0.]))
    >>> targets["back"]  # planted while the front steps
    array([-30.,   0.])

    Args:
        params: stride, step height, step time and threshold.
        rest: each leg's rest spot in the body frame (x along the body's angle, y to its left),
            px, in leg order.
        terrain: the ground.
        position: the body's position when the gait starts, px.
        angle: the body's angle then, radians.
        groups: legs that step together; default :func:`default_groups` of the legs.
        feet: where each foot stands at the start, px; default: on the ground below its rest
            spot.
        reach: ground deeper than this below a rest spot is out of the leg's reach, px; default:
            any depth.
    """

    def __init__(
        self,
        params: GaitParams,
        rest: Mapping[str, ArrayLike],
        terrain: Terrain,
        *,
        position: ArrayLike,
        angle: float = 0.0,
        groups: Sequence[Sequence[str]] | None = None,
        feet: Mapping[str, ArrayLike] | None = None,
        reach: float | None = None,
    ) -> None:
        legs = tuple(rest)
        chosen = default_groups(legs)  # checks there are legs, too
        if groups is not None:
            chosen = tuple(tuple(group) for group in groups)
        grouped = [leg for group in chosen for leg in group]
        if any(not group for group in chosen) or sorted(grouped) != sorted(legs):
            raise ValueError(
                f"groups must share the legs {list(legs)} out, each leg in exactly one "
                f"non-empty group, got {[list(g) for g in chosen]}"
            )
        self._params = params
        self._legs = legs
        self._groups = chosen
        self._members = tuple(np.array([legs.index(leg) for leg in g]) for g in chosen)
        self._rest = np.array([_point(f"rest spot of {leg!r}", rest[leg]) for leg in legs])
        self._terrain = terrain
        self._reach = None if reach is None else _number("reach", reach, positive=True)
        self._position = _point("position", position)
        self._angle = _finite("angle", angle)
        self._velocity = np.zeros(2)
        self._spin = 0.0
        spots = self._rest_world(self._position, self._angle)
        if feet is None:
            self._planted = self._ground(spots[:, 0], spots, self._position[1])
        else:
            if set(feet) != set(legs):
                raise ValueError(f"feet must give a point for each leg {list(legs)}")
            self._planted = np.array([_point(f"foot {leg!r}", feet[leg]) for leg in legs])
        self._step: _Step | None = None
        self._progress = 0.0
        self._turn = 0

    @property
    def params(self) -> GaitParams:
        """Stride, step height, step time and threshold."""
        return self._params

    @property
    def legs(self) -> tuple[str, ...]:
        """The legs, in order."""
        return self._legs

    @property
    def groups(self) -> tuple[tuple[str, ...], ...]:
        """The groups of legs that step together, in turn order."""
        return self._groups

    @property
    def swinging(self) -> int | None:
        """The index of the group stepping now, or None when every foot is planted."""
        return None if self._step is None else self._step.group

    @property
    def feet(self) -> dict[str, FootState]:
        """Every foot's phase as of the last update."""
        states = {
            leg: FootState(True, self._planted[i].copy(), 0.0) for i, leg in enumerate(self._legs)
        }
        if self._step is not None:
            for k, i in enumerate(self._members[self._step.group]):
                states[self._legs[i]] = FootState(False, self._step.land[k].copy(), self._progress)
        return states

    def update(
        self, time: float, dt: float, position: ArrayLike, angle: float
    ) -> dict[str, np.ndarray]:
        """Advance to ``time`` (s), ``dt`` s after the previous update (or the start), with the
        body at ``position`` (px) and ``angle`` (radians); returns every foot's target, world
        px. A step that has run its ``step_time`` lands first, then a group that is due lifts
        (the group that has just landed stands until the next update at least)."""
        if not (math.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a positive number of seconds, got {dt!r}")
        position = _point("position", position)
        angle = _finite("angle", angle)
        self._velocity = (position - self._position) / dt
        turn = angle - self._angle
        self._spin = math.remainder(turn, math.tau) / dt
        self._position, self._angle = position, angle
        step = self._step
        landed = None
        if step is not None and time - step.start >= self._params.step_time:
            self._planted[self._members[step.group]] = step.land
            self._step, landed = None, step.group
        if self._step is None:
            self._lift_if_due(time, landed)
        targets = self._planted.copy()
        self._progress = 0.0
        if self._step is not None:
            self._progress = min(max((time - self._step.start) / self._params.step_time, 0.0), 1.0)
            targets[self._members[self._step.group]] = self._arc(self._step, self._progress)
        return {leg: targets[i] for i, leg in enumerate(self._legs)}

    def _rest_world(self, position: np.ndarray, angle: float) -> np.ndarray:
        return position + _rotate(self._rest, angle)

    def _ground(self, xs: np.ndarray, spots: np.ndarray, body_y: float) -> np.ndarray:
        """Feet on the ground below ``xs`` (rays from the body's height or the rest spot's,
        whichever is higher), or at the rest spot's height where no ground is in reach."""
        heights = self._terrain.heights(xs, np.maximum(body_y, spots[:, 1]))
        if self._reach is not None:
            heights[heights < spots[:, 1] - self._reach] = np.nan
        return np.stack([xs, np.where(np.isnan(heights), spots[:, 1], heights)], axis=1)

    def _lift_if_due(self, time: float, landed: int | None) -> None:
        """Lift the first group due from the turn on; not one that has only now landed, which
        stands for a tick at least."""
        params = self._params
        spots = self._rest_world(self._position, self._angle)
        # Python floats, elementwise as numpy would be: a handful of legs, every tick.
        body_y = float(self._position[1])
        velocity_x, spin = float(self._velocity[0]), self._spin
        either_way = max(params.threshold, params.stride / 2)
        direction: list[float] = []
        due: list[bool] = []
        for x, y, foot_x in zip(
            spots[:, 0].tolist(), spots[:, 1].tolist(), self._planted[:, 0].tolist(), strict=True
        ):
            sideways = velocity_x - spin * (y - body_y)
            heading = math.copysign(1.0, sideways) if abs(sideways) > STILL else 0.0
            gap = x - foot_x
            direction.append(heading)
            due.append(heading * gap > params.threshold if heading != 0 else abs(gap) > either_way)
        for k in range(len(self._groups)):
            group = (self._turn + k) % len(self._groups)
            if group != landed and any(due[i] for i in self._members[group].tolist()):
                self._turn = (group + 1) % len(self._groups)
                self._step = self._plan(group, time, np.array(direction))
                return

    def _plan(self, group: int, time: float, direction: np.ndarray) -> _Step:
        params = self._params
        members = self._members[group]
        ahead = params.step_time
        body = self._position + self._velocity * ahead
        spots = self._rest_world(body, self._angle + self._spin * ahead)[members]
        lift = self._planted[members]
        goal = spots[:, 0] + direction[members] * params.stride / 2
        ray_from = np.maximum(body[1], spots[:, 1])[:, None]
        # Ground as high as the ray's start is a wall: the foot lands at the last clear spot
        # before it, or (a wall at its heel) where it stands.
        path = lift[:, :1] + (goal - lift[:, 0])[:, None] * np.linspace(0.0, 1.0, PATH_SAMPLES)
        walled = self._terrain.heights(path, ray_from) >= ray_from
        first = np.argmax(walled, axis=1)
        short = walled.any(axis=1)
        land_x = np.where(short, path[np.arange(len(members)), np.maximum(first - 1, 0)], goal)
        land = self._ground(land_x, spots, body[1])
        land[short & (first == 0)] = lift[short & (first == 0)]
        # Lift the arc where the terrain between stands above the straight line, by as much as
        # keeps the foot a full half sine of step_height over it at every point checked.
        s = np.linspace(0.0, 1.0, PATH_SAMPLES + 2)[1:-1]
        line = lift[:, None, :] + (land - lift)[:, None, :] * _ease(s)[:, None]
        heights = self._terrain.heights(line[..., 0], ray_from)
        need = np.where(np.isnan(heights), 0.0, (heights - line[..., 1]) / np.sin(np.pi * s))
        height = params.step_height + np.maximum(need.max(axis=1), 0.0)
        return _Step(group, time, lift.copy(), land, height)

    def _arc(self, step: _Step, s: float) -> np.ndarray:
        if s >= 1.0:
            return step.land
        points = step.lift + (step.land - step.lift) * _ease(s)
        points[:, 1] += step.height * math.sin(math.pi * s)
        return points


class Footing:
    """How well the planted feet held, measured tick by tick: for each leg the steps it took,
    how far from its spot it came down (px), the farthest it slid once down (px) and the deepest
    it sank below the ground (px).

    A planted foot is *down* from the first tick it is within ``settle`` px of the spot the gait
    planted it on (a foot that lands late comes down a little after the gait's landing time; one
    that never gets there is down from the start). ``landing`` is its largest distance from the
    spot on the gait's landing tick, ``slip`` its largest distance from where it came down while
    it stays planted, and ``sink`` how far its tip's centre went below the ``ground`` it stands
    on (the terrain grown by the foot's radius; up to :data:`SINK_DEPTH`).

    >>> ground = Terrain(segments=[[-100.0, 0.0, 100.0, 0.0, 0.0]])
    >>> footing = Footing(("a",), ground, settle=1.0)
    >>> planted = {"a": FootState(True, np.zeros(2), 0.0)}
    >>> for y in (3.0, 0.5, -0.5):
    ...     footing.observe(planted, {"a": np.array([0.0, y])})
    >>> footing.as_dict()
    {'a': {'steps': 1, 'landing': 3.0, 'slip': 1.0, 'sink': 0.5}}
    """

    def __init__(self, legs: Sequence[str], ground: Terrain, *, settle: float) -> None:
        self._legs = tuple(legs)
        self._ground = ground
        self._settle = _number("settle", settle, positive=True)
        self._planted = dict.fromkeys(self._legs, False)
        self._down: dict[str, tuple[float, float] | None] = dict.fromkeys(self._legs)
        self._steps = dict.fromkeys(self._legs, 0)
        self._landing = dict.fromkeys(self._legs, 0.0)
        self._slip = dict.fromkeys(self._legs, 0.0)
        self._sink = dict.fromkeys(self._legs, 0.0)

    def observe(self, feet: Mapping[str, FootState], positions: Mapping[str, np.ndarray]) -> None:
        """One tick: each foot's phase from the gait and where the foot really is (px)."""
        at = np.array([positions[leg] for leg in self._legs], dtype=float)
        # Rays from a little above each foot: from higher up, the top of a wall the foot stands
        # beside would read as ground it sank into.
        grounds = self._ground.heights(at[:, 0], at[:, 1] + SINK_DEPTH).tolist()
        for leg, (x, y), ground in zip(self._legs, at.tolist(), grounds, strict=True):
            if not math.isnan(ground):
                self._sink[leg] = max(self._sink[leg], ground - y)
            foot = feet[leg]
            if not foot.planted:
                self._planted[leg], self._down[leg] = False, None
                continue
            foot_x, foot_y = foot.point.tolist()
            off = float(np.hypot(x - foot_x, y - foot_y))
            if not self._planted[leg]:
                self._planted[leg] = True
                self._steps[leg] += 1
                self._landing[leg] = max(self._landing[leg], off)
            down = self._down[leg]
            if down is None:
                if off <= self._settle:
                    self._down[leg] = (x, y)
                continue
            self._slip[leg] = max(self._slip[leg], float(np.hypot(x - down[0], y - down[1])))

    def as_dict(self) -> dict[str, dict[str, float | int]]:
        """Per leg: ``steps`` (plantings begun) and ``landing``, ``slip`` and ``sink`` (px, 6
        decimals)."""
        return {
            leg: {
                "steps": self._steps[leg],
                "landing": round(self._landing[leg], 6),
                "slip": round(self._slip[leg], 6),
                "sink": round(max(self._sink[leg], 0.0), 6),
            }
            for leg in self._legs
        }
