"""Keeping a skeleton clear of static obstacles: distances, clear answers, clear paths.

The raw solvers know only the targets. In a world with a shelf or a floor their answer can put a
link through an obstacle, and even a clear answer can be out of the skeleton's way when the
motors turn the joints toward it through the obstacle. :class:`Clearance` knows the obstacles, as
plain arrays, and the skeleton's links, each a capsule (a segment with a radius, half the link's
width). A chain aims its end effector at a point; a tree aims a
:class:`~ikgame.kinematics.targets.TargetSet` (a chain is the case of one effector):

- **gaps** (:meth:`Clearance.gaps`): each link's smallest distance to any obstacle's surface
  (negative when they overlap), and the same for a batch of poses at once.
- **a clear answer** (:meth:`Clearance.polish`): damped least squares on the targeted ends'
  errors (each row scaled by the square root of its target's weight) with one extra row per link
  closer than ``ACTIVE`` to an obstacle, asking that gap not to shrink, or to grow back to
  ``MARGIN`` (the rows of an inequality, active only near contact).
  :meth:`Clearance.clear_answer` polishes a set of seeds (the measured pose, the straight answer,
  the answer with its bends reversed, poses curled either way, ``RANDOM_SEEDS`` random poses
  within the limits, the nearest the target of ``RANDOM_POOL`` drawn, and where none of those
  arrives clear a chain zig-zagged along the line to its target both ways round) and keeps the
  clear one that arrives nearest the measured pose, preferring one the chain can turn to in a
  straight line, and before either one that keeps every joint ``STOP_ROOM`` off its stops.
- **a clear path** (:meth:`Clearance.route`): the motors turn every joint toward its goal
  together, so the chain moves close to the straight line in joint space. When that line sweeps
  through an obstacle (checked at poses no point of the chain moves more than ``PATH_STEP``
  between), a bidirectional random tree in joint space (RRT-connect, seeded, at most
  ``ROUTE_NODES`` nodes) finds a chain of clear straight pieces. A long chain's joint space is
  too wide for the trees: once they have done ``TREE_FIRST`` units of work, a chain is led by
  its end instead, drawn ``WALK_STEP`` px at a time along a way in the plane
  (:meth:`Clearance.tip_path`: its links back to the base, then the goal's out, pulled taut
  clear of the obstacles), each step polished clear from the last, so the links follow. If the
  end falls behind (a tree of links: once the trees have done that share), two new trees grow
  by sliding steps (at most ``SLIDE_NODES`` poses): a step that would bring a link within the
  margin and ``SLIDE_ROOM`` of an obstacle is turned along its surface, or along a joint's
  stop, instead of stopping there, so they follow a narrow passage between obstacles that
  straight steps seldom sample; the trees of straight steps go on only if they find none.
  Either way the pieces are shortened greedily, and the chain is steered through these via
  poses one after the other. A chain's two trees first grow along the poses its polish steps
  through drawing the end from each tree's root toward a point out in the open (the retreat;
  the sliding trees' polish slides along what it meets, and once they have drawn poses at
  random for ``TREE_FIRST`` units of work, they grow along walked retreats too: the end led
  back along the root's own links to the base and out). The trees draw poses as far as the
  goal, and a tree's piece whose links' gaps at its two ends outweigh how far the links can
  sweep between them is clear without sampling. A route that takes the
  targeted ends past the target and back is cut where they come nearest it (on its last
  piece, which ends on the target, where they pass it before swinging out). An
  :class:`Avoider` remembers the last route of several pieces it took up: a chain still at its
  end for which the trees find no way is routed back along it (the way out of a narrow passage
  is the way in).

:class:`Avoider` does this tick by tick for a controller: it takes the solver's answer and
returns the pose to command, keeping the clear answer and the route for the target until it
moves, so they are searched once, and spreading each search over ticks by a budget of counted
work (``SEARCH_RATE`` a simulated second) so that no tick carries a whole one; a chain at rest
or in the open costs two products of the links' levers a tick. A route is followed on its lines
(a straight way to the goal too), each pose commanded at most ``LEAD`` ahead of the joint that
has come least far. A target no clear pose reaches (under the floor) sends the chain to the
clear pose nearest it, where it rests held off the obstacle instead of pressing into it.
While the base moves it plans nothing (a plan would be stale by the next tick): it only holds
off an obstacle the links the solver's answers bring nearer it, polishing the pose it commanded
onto the target for where the base is now. An answer arrives when every targeted end is within
the tolerance of its target. Angles are radians, distances px.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable, Generator
from dataclasses import dataclass
from typing import Final, TypeVar

import numpy as np

from ikgame.kinematics._compiled_gaps import compiled_gaps
from ikgame.kinematics.recovery import HOLDS, SETTLED
from ikgame.kinematics.skeleton import Skeleton, tree_points
from ikgame.kinematics.solver import Solution, SolveStatus
from ikgame.kinematics.targets import TargetSet, columns

__all__ = [
    "ACTIVE",
    "MARGIN",
    "PATH_STEP",
    "ROUTE_NODES",
    "SLIDE_NODES",
    "SLIDE_STEP",
    "SLIDE_ROOM",
    "TREE_FIRST",
    "WALK_STEP",
    "WALK_ITERATIONS",
    "LEAD",
    "RANDOM_SEEDS",
    "RANDOM_POOL",
    "STOP_ROOM",
    "CHECK_UNITS",
    "ITERATION_UNITS",
    "POSE_UNITS",
    "POLISH_REACH",
    "JAMMED_WORK",
    "SEARCH_RATE",
    "Avoider",
    "Clearance",
    "Obstacles",
]

MARGIN: Final = 4.0
"""Gap a polished answer keeps between a link's surface and an obstacle's, px."""

ACTIVE: Final = 6.0
"""A link closer than this to an obstacle gets a clearance row in the polish, px."""

PATH_STEP: Final = 2.0
"""Most any point of the chain moves between two poses checked along a path, px: as paths keep
half of ``MARGIN`` clear at the poses checked, no link touches in between."""

ROUTE_NODES: Final = 2500
"""Most poses a route search adds to its two trees before it gives up: a narrow passage (the
last links reaching in under a round rock, in a band a few px wider than they are) took about
2,100 (1,500 found none), and a search that finds no way does that much more work before it
gives up."""

SLIDE_NODES: Final = 2500
"""Most poses the two trees of a sliding search (see :meth:`Clearance._connect`) hold before it
gives up."""

SLIDE_STEP: Final = 0.3
"""Largest joint change of one sliding step of a route tree, radians (as ``ROUTE_STEP``: away
from the obstacles a sliding step is a straight one)."""

SLIDE_ROOM: Final = 2.0
"""Gap beyond the margin a sliding step keeps each link near an obstacle, px: poses held just at
the margin leave the straight lines that shorten a route no room to cut a corner, and the
route in under the round rock of ``27_round_rock`` came in many short pieces, slower to follow
(its target reached 0.2 to 0.3 s later)."""

WALK_STEP: Final = 10.0
"""How far along its tip path a chain's end is drawn between two poses of a walked way, px."""

TREE_FIRST: Final = 20_000.0
"""Units of work the route trees do before a chain's way is walked by its end instead (the
trees go on if that finds none)."""

WALK_ITERATIONS: Final = 20
"""Polish iterations one step of a walked way takes at most."""

RANDOM_SEEDS: Final = 12
"""Random poses (within the limits) polished after the deliberate seeds of a clear answer."""

RANDOM_POOL: Final = 400
"""Random poses drawn for a clear answer's ``RANDOM_SEEDS``, which are the nearest of them."""

EARLIER_ANSWERS: Final = 4
"""Clear answers found for earlier targets that a clear answer's search keeps as its last seeds
(see :meth:`Clearance.seeds`)."""

RANDOM_SEED: Final = 7193
"""Seed of the generators of random seeds and route samples: the same inputs give the same
answers."""

STOP_ROOM: Final = 0.02
"""Share of a joint's range (within a turn) a clear answer keeps off each limit to count as off
its stops: an answer with a joint nearer a stop than that is taken only when no clear answer off
them is found (a fold pressed against a stop under a shelf leaves the chain no short way on)."""

POLISH_ITERATIONS: Final = 80
"""Iterations one seed of a clear answer is polished for."""

FREE_ITERATIONS: Final = 400
"""Most iterations of the obstacle-free polish that finds how near a target set's ends can come
(see :meth:`Clearance.clear_answer`)."""

HOLD_OFF_ITERATIONS: Final = 5
"""Most polish iterations a call of an :class:`Avoider` spends holding links off the obstacles
while the base carries the skeleton."""

CARRIED_STEP: Final = 2.0
"""Farthest the base and the joints may carry a link (px) before an :class:`Avoider` measures
the gaps of a carried skeleton again: a link coming near an obstacle is noticed at most this
late."""

STALE_ITERATIONS: Final = 12
"""A polish that has not improved on its best pose for this many iterations stops there."""

ROUTE_STEP: Final = 0.3
"""Largest joint change of one edge of a route tree, radians."""

AHEAD: Final = 100.0
"""A chain whose sweep to its via pose is at most this (px) may head for the next one. About
what ``LEAD`` turns an arm of a few hundred px through on its base joint: where the servo, held
that close to the pose it is sent to, begins to brake. At 40 px a chain following a way of
eight via poses had slowed to about 1 rad/s at each before it turned on."""

LEAD: Final = 0.3
"""Most a pose commanded on a route's piece leads the joint that has come least far along it,
radians (on the joint that turns most over the piece)."""

RELEASE_S: Final = 0.5
"""Time at rest on a clear goal after which the solver answers again even short of the target,
simulated s (120 calls at 240 ticks/s)."""

PINNED_S: Final = 0.1
"""Time a chain rests pressed into an obstacle, off its route, before a route on is planned
from there, simulated s (24 calls at 240 ticks/s; the simulation judges a chain blocked after
half a second without progress, so a count of calls would leave a chain at 30 ticks/s judged
blocked before it planned again)."""

JAMMED_WORK: Final = 150_000
"""Most units of work a search spends on a route to the clear pose nearest a target that no
clear pose reaches (see :class:`Avoider`) before it settles for one nearer the chain: the
routes to such poses on ``34_chain40_pressed_to_floor`` took 4,000 to 71,000 units where they
were found, and from CCD's chain resting at the first target's, none to the second's in the
500,000 of a whole step."""

SEARCH_RATE: Final = 288_000
"""Units of work an :class:`Avoider`'s search does in a simulated second at most: a simulation
gives it ``SEARCH_RATE / tick_rate`` units a call, so that a search takes the same simulated
time at any tick rate (and a game loop's frame the same CPU time). A chain holds still while
its search runs: at half this rate (600 units a tick at 240 ticks/s) the searches on the
quality suite's obstacle levels held their chains 0.3 to 2.6 s of their 4 to 6 s timeouts,
and eleven of its runs arrived too late. A unit is about 4.5 us of CPU time on the 2-core
development machine with numpy's gap measure, 2.2 to 2.4 us with the compiled one
(:mod:`~ikgame.kinematics._compiled_gaps`): a tick's 1,200 at 240 ticks/s, about 5.4 and 2.8
ms."""

ITERATION_UNITS: Final = 40
"""Units of search work one polish iteration counts for."""

CHECK_UNITS: Final = 15
"""Units of search work one step of a path check counts for, besides its poses: a pose counts
for ``POSE_UNITS`` per link and obstacle."""

POSE_UNITS: Final = 0.05
"""Units of search work a pose checked along a path counts for per link and obstacle."""

NEAREST_UNITS: Final = 0.002
"""Units of search work finding a route tree's nearest pose counts for per pose of the tree."""

PATH_CHUNK: Final = 100
"""Poses a path check measures in one step of a search."""

POLISH_REACH: Final = 0.1
"""Most a polish iteration aims a targeted end toward its target, as a share of the longest
lever (px/px): a far target pulls the pose there in short steps that stay near the seed, not in
one long damped step that flings a long chain into a coil."""

_MAX_STEP: Final = 0.2
_MAX_SAMPLES: Final = 400


_T = TypeVar("_T")
_Work = Generator[float, None, _T]
"""A search in steps: each yields the units of work it did, and the search returns its result."""


def _capped(work: _Work[_T], units: float) -> _Work[_T | None]:
    """``work``, given up (None) once it has done more than ``units`` of work."""
    spent = 0.0
    try:
        while spent <= units:
            step = next(work)
            spent += step
            yield step
    except StopIteration as done:
        return done.value
    work.close()
    return None


def _finish(work: _Work[_T]) -> _T:
    """Run a search to its end, all at once."""
    while True:
        try:
            next(work)
        except StopIteration as done:
            return done.value


@dataclass(frozen=True, eq=False)
class Obstacles:
    """Static obstacles as capsules: (k, 5) rows ``(ax, ay, bx, by, radius)``, px.

    A disc is a capsule whose two ends coincide. Build from a level's arrays with
    :meth:`from_arrays`.

    >>> obs = Obstacles.from_arrays(np.array([[0.0, 0.0, 10.0, 0.0, 1.0]]), np.array([[5, 5, 2]]))
    >>> obs.capsules.tolist()
    [[0.0, 0.0, 10.0, 0.0, 1.0], [5.0, 5.0, 5.0, 5.0, 2.0]]
    """

    capsules: np.ndarray

    def __post_init__(self) -> None:
        capsules = np.array(self.capsules, dtype=float).reshape(-1, 5)
        if not np.all(np.isfinite(capsules)) or np.any(capsules[:, 4] < 0):
            raise ValueError("obstacles must be finite, with radii >= 0 px")
        capsules.setflags(write=False)
        object.__setattr__(self, "capsules", capsules)

    @classmethod
    def from_arrays(cls, segments: np.ndarray, circles: np.ndarray) -> Obstacles:
        """Segments (k, 5) ``(ax, ay, bx, by, radius)`` and circles (m, 3) ``(x, y, radius)``."""
        seg = np.asarray(segments, dtype=float)
        disc = np.asarray(circles, dtype=float)
        if seg.size and (seg.ndim != 2 or seg.shape[1] != 5):
            raise ValueError(f"segments must have shape (k, 5), got {seg.shape}")
        if disc.size and (disc.ndim != 2 or disc.shape[1] != 3):
            raise ValueError(f"circles must have shape (m, 3), got {disc.shape}")
        disc = disc.reshape(-1, 3)
        as_capsules = np.column_stack((disc[:, :2], disc[:, :2], disc[:, 2]))
        return cls(np.vstack((seg.reshape(-1, 5), as_capsules)))

    def __len__(self) -> int:
        return int(self.capsules.shape[0])


class Clearance:
    """Distances from a skeleton's links (capsules of ``radii``, px) to static ``obstacles``.

    Set :attr:`skeleton` when the base moves.

    >>> arm = Skeleton.chain([100.0, 100.0], base_angle=math.pi / 2)
    >>> shelf = Obstacles.from_arrays(np.array([[-50.0, 150.0, 50.0, 150.0, 0.0]]), np.empty((0, 3)))
    >>> room = Clearance(arm, np.full(2, 5.0), shelf)
    >>> room.gaps(np.zeros(2)).tolist()  # the upper link runs through the shelf
    [45.0, -55.0]
    >>> room.is_clear(room.polish(np.zeros(2), np.array([120.0, 60.0])).angles)
    True

    A tree aims a :class:`~ikgame.kinematics.targets.TargetSet`; its links start at their
    parents' ends (here two arms on a torso, both up through the shelf, sent out sideways):

    >>> arms = Skeleton.tree([100.0, 80.0, 80.0], [-1, 0, 0], base_angle=math.pi / 2)
    >>> room = Clearance(arms, np.full(3, 5.0), shelf)
    >>> room.gaps(np.zeros(3)).tolist()
    [45.0, -35.0, -35.0]
    >>> aim = TargetSet([1, 2], [(-80.0, 100.0), (80.0, 100.0)])
    >>> sol = room.polish(np.zeros(3), aim)
    >>> sol.status.name, room.is_clear(sol.angles), bool(room.misses(sol.angles, aim).max() <= 0.5)
    ('SUCCESS', True, True)
    """

    def __init__(
        self, skeleton: Skeleton, radii: np.ndarray, obstacles: Obstacles, *, margin: float = MARGIN
    ) -> None:
        radii = np.asarray(radii, dtype=float)
        if radii.shape != (skeleton.count,) or not np.all(np.isfinite(radii)) or np.any(radii < 0):
            raise ValueError(f"radii must be ({skeleton.count},) finite px >= 0")
        if not (math.isfinite(margin) and margin >= 0):
            raise ValueError(f"margin must be a finite number of px >= 0, got {margin!r}")
        self.skeleton = skeleton
        self.radii = radii
        self.obstacles = obstacles
        self.margin = float(margin)
        # The clear answers found off the stops for earlier targets, the latest first.
        self._earlier: deque[np.ndarray] = deque(maxlen=EARLIER_ANSWERS)
        self.strain: Callable[[np.ndarray], float] | None = None
        """What holding a pose still takes of the motors, as
        :attr:`~ikgame.kinematics.recovery.RobustSolver.strain`, if known: a clear answer
        they cannot hold (past ``HOLDS``) is taken only when no clear one they hold is found
        (see :meth:`clear_answer`)."""
        caps = obstacles.capsules
        self._a = caps[:, :2]
        self._b = caps[:, 2:4]
        self._r = caps[:, 4]
        self._reach = radii[:, None] + self._r  # (n, k) the gap at which link and obstacle touch
        self._ends = np.stack((self._a, self._b))[:, None, :]  # (2, 1, k, 2) obstacles' ends
        # Gaps are measured apart for round obstacles (circles: both ends one point) and long
        # ones (segments), which need their ends and crossings measured too.
        round_ = np.all(self._a == self._b, axis=-1)
        self._centers = self._a[round_]
        # C-ordered, as the compiled gap measure takes them (numpy's masks leave them not).
        self._round_reach = np.ascontiguousarray(self._reach[:, round_])
        self._long_ends = np.ascontiguousarray(self._ends[:, :, ~round_])
        self._long_reach = np.ascontiguousarray(self._reach[:, ~round_])
        # How far a point of link i can be from joint j when j moves it (0 when it does not):
        # the step bound of path checks link by link; over every link, the longest way down
        # from joint j through its subtree.
        lengths = skeleton.lengths
        anc = skeleton.ancestors
        depth = anc @ lengths  # each link's end, along its path from the base
        self._link_lever = np.where(anc, depth[:, None] - depth[None, :] + lengths[None, :], 0.0)
        self._lever = self._link_lever.max(axis=0)
        self._pose_units = POSE_UNITS * skeleton.count * len(obstacles)

    # -- distances ---------------------------------------------------------------------------

    def points(self, poses: np.ndarray) -> np.ndarray:
        """Link points for (..., n) poses, px: a chain's (..., n + 1, 2) joints then the end
        effector; a tree's (..., 2n, 2) link starts then link ends (as
        :func:`~ikgame.kinematics.skeleton.forward_kinematics` orders them)."""
        sk = self.skeleton
        if not sk.is_chain:
            return self._tree_points(poses)
        world = np.cumsum(poses, axis=-1) + sk.base_angle
        joints = np.empty((*poses.shape[:-1], sk.count + 1, 2))
        joints[..., 0, :] = sk.base
        np.multiply(sk.lengths, np.cos(world), out=joints[..., 1:, 0])
        np.multiply(sk.lengths, np.sin(world), out=joints[..., 1:, 1])
        return np.cumsum(joints, axis=-2, out=joints)

    def _tree_points(self, poses: np.ndarray) -> np.ndarray:
        """(..., 2n, 2) link starts then link ends of a tree for (..., n) poses, px."""
        sk = self.skeleton
        if poses.ndim == 1:
            starts, ends, _ = tree_points(sk, poses, sk.root_points())
            return np.concatenate((starts, ends))
        path = sk.ancestors.astype(float)
        root_points = sk.root_points()
        world = poses @ path.T + sk.base_angle
        steps = sk.lengths[:, None] * np.stack((np.cos(world), np.sin(world)), axis=-1)
        ends = np.einsum("ij,...jd->...id", path, steps) + root_points
        roots = (sk.parents < 0)[:, None]
        starts = np.where(roots, root_points, ends[..., sk.parents, :])
        return np.concatenate((starts, ends), axis=-2)

    def _links(self, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Each link's start and end (..., n, 2) from :meth:`points`."""
        if self.skeleton.is_chain:
            return pts[..., :-1, :], pts[..., 1:, :]
        n = self.skeleton.count
        return pts[..., :n, :], pts[..., n:, :]

    def _pairs(self, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Signed gaps (..., n, k), the point on each link nearest the obstacle (..., n, k, 2)
        and the unit direction that widens the gap when that point moves along it."""
        starts, ends = self._links(pts)
        p0 = starts[..., None, :]
        p1 = ends[..., None, :]
        q0, q1 = self._a, self._b
        # Candidates: each link end against the obstacle, each obstacle end against the link
        # (both ends in one call: the calls, not the arithmetic, are the cost here); the
        # nearest pair is the first of the least distance.
        if self.skeleton.is_chain:
            # A chain's links share their joints: each joint's nearest points once.
            joints = _nearest_on(pts[..., :, None, :], q0, q1)  # (..., n + 1, k, 2)
            from_start, from_end = joints[..., :-1, :, :], joints[..., 1:, :, :]
        else:
            from_start, from_end = _nearest_on(p0, q0, q1), _nearest_on(p1, q0, q1)
        on_links = _nearest_on(
            self._ends, starts[..., None, :, None, :], ends[..., None, :, None, :]
        )  # (..., 2, n, k, 2)
        point, off = p0, p0 - from_start
        d = np.hypot(off[..., 0], off[..., 1])
        for on_link, on_obstacle in (
            (p1, from_end),
            (on_links[..., 0, :, :, :], q0),
            (on_links[..., 1, :, :, :], q1),
        ):
            offset = on_link - on_obstacle
            dist = np.hypot(offset[..., 0], offset[..., 1])
            nearer = dist < d
            d = np.where(nearer, dist, d)
            point = np.where(nearer[..., None], on_link, point)
            off = np.where(nearer[..., None], offset, off)
        unit = off / np.maximum(d, 1e-9)[..., None]
        crossing = _crossing(starts, ends, q0, q1)
        # A link through a thin obstacle: the way out is back the shortest way it came in.
        sign = np.where(crossing, -1.0, 1.0)
        return sign * d - self._reach, point, sign[..., None] * unit

    def _gaps(self, pts: np.ndarray, links: np.ndarray | None = None) -> np.ndarray:
        """Each link's smallest signed gap (..., n) to any obstacle, px; with ``links``
        (indices), those links' only (..., len(links)), the same numbers. Measured by the
        compiled loop once a process has built it (:mod:`~ikgame.kinematics._compiled_gaps`),
        the same numbers again."""
        starts, ends = self._links(pts)
        round_reach, long_reach = self._round_reach, self._long_reach
        if links is not None:
            starts, ends = starts[..., links, :], ends[..., links, :]
            round_reach, long_reach = round_reach[links], long_reach[links]
        compiled = compiled_gaps(starts[..., 0].size * len(self.obstacles))
        if compiled is not None:
            q0, q1 = self._long_ends[0, 0], self._long_ends[1, 0]
            return compiled(starts, ends, self._centers, round_reach, q0, q1, long_reach)
        shared = self.skeleton.is_chain and links is None
        least: list[np.ndarray] = []
        if len(self._centers):
            # A round obstacle is a point with a radius: no ends of its own to measure from,
            # and no link crosses it.
            centers = self._centers
            if shared:
                # A chain's links share their joints: each joint's distance is computed once.
                off = pts[..., :, None, :] - centers
                joints = np.hypot(off[..., 0], off[..., 1])  # (..., n + 1, k)
                near_start, near_end = joints[..., :-1, :], joints[..., 1:, :]
            else:
                off = starts[..., :, None, :] - centers
                near_start = np.hypot(off[..., 0], off[..., 1])  # (..., n, k)
                off = ends[..., :, None, :] - centers
                near_end = np.hypot(off[..., 0], off[..., 1])
            along = _distance_to(centers, starts[..., :, None, :], ends[..., :, None, :])
            d = np.minimum(np.minimum(near_start, near_end), along)
            least.append((d - round_reach).min(axis=-1))
        if self._long_reach.shape[-1]:
            q0, q1 = self._long_ends[0, 0], self._long_ends[1, 0]
            if shared:
                joints = _distance_to(pts[..., :, None, :], q0, q1)  # (..., n + 1, k)
                near_start, near_end = joints[..., :-1, :], joints[..., 1:, :]
            else:
                near_start = _distance_to(starts[..., :, None, :], q0, q1)  # (..., n, k)
                near_end = _distance_to(ends[..., :, None, :], q0, q1)
            p0 = starts[..., None, :, None, :]
            p1 = ends[..., None, :, None, :]
            tips = _distance_to(self._long_ends, p0, p1).min(axis=-3)  # (..., n, k)
            d = np.minimum(np.minimum(near_start, near_end), tips)
            crossing = _crossing(starts, ends, q0, q1)
            least.append((np.where(crossing, -d, d) - long_reach).min(axis=-1))
        return least[0] if len(least) == 1 else np.minimum(least[0], least[1])

    def gaps(self, angles: np.ndarray) -> np.ndarray:
        """(n,) each link's smallest gap to any obstacle, px (inf with none; < 0 overlapping)."""
        if not len(self.obstacles):
            return np.full(self.skeleton.count, math.inf)
        return self._gaps(self.points(np.asarray(angles, dtype=float)))

    def smallest_gaps(self, poses: np.ndarray) -> np.ndarray:
        """(b,) the smallest gap of each of (b, n) poses over every link and obstacle, px."""
        if not len(self.obstacles):
            return np.full(len(poses), math.inf)
        return self._gaps(self.points(poses)).min(axis=-1)

    def swept(self, a: np.ndarray, b: np.ndarray) -> float:
        """Farthest any point of the skeleton can move on the straight line from pose ``a`` to
        ``b``, px: a bound, so a pose ``swept`` px clear at ``a`` stays clear all the way."""
        return float(np.abs(b - a) @ self._lever)

    def swept_links(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """(n,) farthest any point of each link can move on the straight line from pose ``a``
        to ``b``, px: :meth:`swept` link by link, so a link near an obstacle whose own joints
        barely turn is seen to stay clear however far the rest moves."""
        return self._link_lever @ np.abs(b - a)

    def is_clear(self, angles: np.ndarray, floor: float = 0.0) -> bool:
        """True when no link comes closer than ``floor`` px to an obstacle."""
        return bool(self.gaps(angles).min() >= floor)

    # -- answers -----------------------------------------------------------------------------

    def _aim(self, target: np.ndarray | TargetSet) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The targeted links, their points (k, 2) px and the square roots of their weights: a
        chain's point target is its last link's end with weight 1."""
        if isinstance(target, TargetSet):
            target.check(self.skeleton)
            return target.links, target.points, np.sqrt(target.weights)
        point = np.asarray(target, dtype=float)
        return np.array([self.skeleton.count - 1]), point[None, :], np.ones(1)

    def misses(self, angles: np.ndarray, target: np.ndarray | TargetSet) -> np.ndarray:
        """(k,) each targeted end's distance from its target at ``angles``, px (one for a
        chain's point)."""
        links, points, _ = self._aim(target)
        _, ends = self._links(self.points(np.asarray(angles, dtype=float)))
        off = points - ends[links]
        return np.hypot(off[:, 0], off[:, 1])

    def polish(
        self,
        angles: np.ndarray,
        target: np.ndarray | TargetSet,
        *,
        iterations: int = POLISH_ITERATIONS,
        tolerance: float = 0.5,
        avoid: bool = True,
    ) -> Solution:
        """Damped least squares toward ``target`` (a point for a chain's end effector, or a
        :class:`~ikgame.kinematics.targets.TargetSet`) that keeps every link ``margin`` px clear.

        Returns the best pose seen: clear first, then nearest the targets (the weighted root
        mean square of the targeted ends' distances, the one distance for a chain; it stops
        after ``STALE_ITERATIONS`` without a better one). ``SUCCESS`` when it is clear and every
        targeted end is within ``tolerance`` px, else ``PROCESSING``; the solution's error is
        that mean distance. With ``avoid`` False the obstacles play no part (plain damped least
        squares).
        """
        return _finish(self._polishing(angles, target, iterations, tolerance, avoid))

    def _polishing(
        self,
        angles: np.ndarray,
        target: np.ndarray | TargetSet,
        iterations: int,
        tolerance: float,
        avoid: bool,
        trail: list[np.ndarray] | None = None,
        *,
        slide: bool = False,
    ) -> _Work[Solution]:
        """:meth:`polish`, an iteration (``ITERATION_UNITS`` of work) a step; with ``trail``,
        each clear pose it steps through is appended to it; with ``slide``, a step that brings
        a link near an obstacle is a sliding step (:meth:`_sliding`, ``ITERATION_UNITS`` more)
        of the one the polish asks for, so the poses keep the margin."""
        sk = self.skeleton
        pose = sk.clamp(np.asarray(angles, dtype=float).copy())
        links, points, scale = self._aim(target)
        moves = sk.ancestors  # moves[i, j]: joint j moves link i
        n = sk.count
        weights = scale**2
        best, best_key, stale = pose, (math.inf, math.inf), 0
        best_misses = np.full(len(links), math.inf)
        damping = (0.02 * float(self._lever.max())) ** 2
        reach = POLISH_REACH * float(self._lever.max())
        for _ in range(iterations):
            pts = self.points(pose)
            starts, ends = self._links(pts)
            reached = ends[links]
            off = points - reached
            if avoid and len(self.obstacles):
                gap, point, unit = self._pairs(pts)
            else:
                gap = np.full((n, 0), math.inf)
            # Counted here, before the iteration can end the polish, so every iteration counts.
            yield ITERATION_UNITS
            misses = np.hypot(off[:, 0], off[:, 1])
            if len(links) == 1:
                dist = float(misses[0])
            else:
                dist = math.sqrt(float(weights @ misses**2 / weights.sum()))
            key = (max(0.0, -float(gap.min(initial=math.inf))), dist)
            if trail is not None and key[0] == 0.0:
                trail.append(pose.copy())
            if key < best_key:
                best, best_key, best_misses, stale = pose.copy(), key, misses, 0
            else:
                stale += 1
                if stale > STALE_ITERATIONS:
                    break
            arrived = bool(np.all(misses <= tolerance))
            if key[0] == 0.0 and arrived and gap.min(initial=math.inf) >= self.margin:
                break
            aims = columns(reached, starts, moves[links]) * scale[:, None, None]
            rows = [aims.reshape(-1, n)]
            pull = off * np.minimum(1.0, reach / np.maximum(misses, 1e-12))[:, None]
            wanted = [(pull * scale[:, None]).reshape(-1)]
            near, obstacles = np.nonzero(gap < self.margin + ACTIVE)
            if near.size:
                p = point[near, obstacles]
                u = unit[near, obstacles]
                lever = p[:, None, :] - starts[None, :, :]
                moved = -lever[..., 1] * u[:, None, 0] + lever[..., 0] * u[:, None, 1]
                rows.append(np.where(moves[near], moved, 0.0))
                wanted.append(np.maximum(self.margin - gap[near, obstacles], 0.0))
            jac = np.vstack(rows)
            err = np.concatenate(wanted)
            step = jac.T @ np.linalg.solve(jac @ jac.T + damping * np.eye(len(err)), err)
            largest = float(np.abs(step).max())
            if largest > _MAX_STEP:
                step *= _MAX_STEP / largest
            if slide and near.size:
                pose = yield from self._sliding(pose, step)
            else:
                pose = sk.clamp(pose + step)
        status = SolveStatus.SUCCESS
        if best_key[0] > 0.0 or np.any(best_misses > tolerance):
            status = SolveStatus.PROCESSING
        return Solution(best, status, iterations, best_key[1])

    def seeds(
        self, measured: np.ndarray, answer: np.ndarray, target: np.ndarray | TargetSet
    ) -> list[np.ndarray]:
        """Starts for :meth:`clear_answer`: the measured pose, the answer, the answer with its
        bends reversed (every joint but the roots), the links curled evenly either way, then
        ``RANDOM_SEEDS`` random poses within the limits (seeded): of ``RANDOM_POOL`` drawn, the
        clear ones whose targeted ends come nearest their targets (weighted), then the others
        by the same measure; then a chain zig-zagged along the line to its target (see
        :meth:`_zigzags`); last, the clear answers off the stops found for the last
        ``EARLIER_ANSWERS`` targets, the latest first. :meth:`clear_answer` polishes the
        zig-zags only where no seed before them arrives clear, and the earlier answers only
        where no seed at all does.

        A target over a shelf's far side, for a chain folded under it, can lie where none of
        the target's own seeds polishes to a clear pose (`70_above_below_left_thin_shelf`, CCD,
        (-230, 150) after (-140, 52): from the chain's pose the end stalled 101 px short, from
        the solver's answer 11.5 px short with a link in the shelf, from the other seeds 49 to
        110 px short, and the zig-zags reached it only through the shelf; the chain, taken to
        be jammed, rested 101 px off, `blocked`). The clear answer found for a target on the
        same side earlier, (-130, 155), polishes onto it over the shelf."""
        return [seed for phase in self._phases(measured, answer, target) for seed in phase.seeds()]

    def _phases(
        self, measured: np.ndarray, answer: np.ndarray, target: np.ndarray | TargetSet
    ) -> tuple[_SeedPhase, ...]:
        """The groups of :meth:`seeds`, in the order :meth:`clear_answer` polishes them."""
        answer = np.asarray(answer, float)
        # Drawing and measuring the pool of random seeds, counted as that many poses checked:
        # paid only by a search the deliberate seeds did not settle.
        drawing = POSE_UNITS * RANDOM_POOL * self.skeleton.count * len(self.obstacles)
        return (
            _SeedPhase(lambda: self._deliberate_seeds(measured, answer)),
            _SeedPhase(lambda: self._random_seeds(target), units=drawing),
            # The zig-zags only where no other seed arrives clear: under a shelf, where others
            # arrive but none by a clear straight line, a zig-zag that did sent five links into
            # a fold they could not leave for the next target.
            _SeedPhase(lambda: self._zigzags(target), last_resort=True),
            # An earlier target's answer that does not arrive is no start to take the end onto
            # the target from: the target's own seeds' nearest are.
            _SeedPhase(lambda: list(self._earlier), last_resort=True, own=False),
        )

    def _zigzags(self, target: np.ndarray | TargetSet) -> list[np.ndarray]:
        """A chain folded in a zig-zag, each link turned the same angle off the line from the
        base to a point ``target`` one way and the next the other, so that the chain spans
        that line just as far as the target: both ways round (none for a tree, a target set
        or a target at or beyond the chain's reach).

        A chain in a low corridor reaches a target near its base only folded back and forth
        along it: from the answer, the curls and the random poses the polish found no clear
        pose that reached (ten 34 px links in a corridor 58 px high, `71_low_corridor`, rested
        108 px short of (160, 0), `blocked`); from a zig-zag it needs only to flatten it.

        >>> arm = Skeleton.chain([30.0] * 4)
        >>> nothing = Obstacles.from_arrays(np.empty((0, 5)), np.empty((0, 3)))
        >>> room = Clearance(arm, np.full(4, 3.0), nothing)
        >>> [np.degrees(pose).round(0).tolist() for pose in room._zigzags(np.array([60.0, 0.0]))]
        [[-60.0, 120.0, -120.0, 120.0], [60.0, -120.0, 120.0, -120.0]]
        """
        sk = self.skeleton
        if not sk.is_chain or isinstance(target, TargetSet) or sk.count < 2:
            return []
        point = np.asarray(target, dtype=float) - sk.base
        distance, reach = float(np.hypot(*point)), float(sk.reach)
        if distance >= reach:
            return []
        off = math.acos(distance / reach)
        aim = math.atan2(point[1], point[0]) - sk.base_angle
        seeds = []
        for side in (1.0, -1.0):
            pose = np.array([2.0 * off * side * (-1.0) ** (k + 1) for k in range(sk.count)])
            pose[0] = aim - off * side
            seeds.append(sk.clamp(pose))
        return seeds

    def _deliberate_seeds(self, measured: np.ndarray, answer: np.ndarray) -> list[np.ndarray]:
        """The seeds of :meth:`seeds` before the random ones."""
        sk = self.skeleton
        n = sk.count
        reversed_bends = np.where(sk.parents < 0, answer, -answer)
        curl = math.pi / max(n, 2)
        starts = [measured, answer, reversed_bends, np.full(n, curl), np.full(n, -curl)]
        return [sk.clamp(np.asarray(s, dtype=float)) for s in starts]

    def _random_seeds(self, target: np.ndarray | TargetSet) -> list[np.ndarray]:
        """The random seeds of :meth:`seeds`."""
        sk = self.skeleton
        rng = np.random.default_rng(RANDOM_SEED)
        low = np.maximum(sk.lower, -math.pi)
        high = np.minimum(sk.upper, math.pi)
        pool = rng.uniform(low, high, (RANDOM_POOL, sk.count))
        links, points, scale = self._aim(target)
        _, ends = self._links(self.points(pool))
        off = points - ends[:, links]
        misses = (scale**2 * (off**2).sum(axis=-1)).sum(axis=-1)
        clear = self.smallest_gaps(pool) >= 0.0
        # A pose drawn at random a long way off lands the polish in a fold it cannot leave (a
        # link hooked round an obstacle's end); one already near reaching the target rarely does.
        return list(sk.clamp(pool[np.lexsort((misses, ~clear))[:RANDOM_SEEDS]]))

    def off_stops(self, angles: np.ndarray) -> bool:
        """Whether every limited joint of ``angles`` keeps ``STOP_ROOM`` of its range (within a
        turn) off both its limits.

        >>> arm = Skeleton.chain([100.0, 100.0], limits=[None, (-1.0, 1.0)])
        >>> post = Obstacles.from_arrays(np.empty((0, 5)), np.array([[0.0, 250.0, 10.0]]))
        >>> room = Clearance(arm, np.full(2, 5.0), post)
        >>> room.off_stops(np.array([3.1, -0.85])), room.off_stops(np.array([0.0, -0.97]))
        (True, False)
        """
        sk = self.skeleton
        low = np.maximum(sk.lower, -math.pi)
        high = np.minimum(sk.upper, math.pi)
        room = STOP_ROOM * (high - low)
        inside = (angles >= low + room) & (angles <= high - room)
        return bool(np.all(inside | ~sk.limited))

    def clear_answer(
        self,
        measured: np.ndarray,
        answer: np.ndarray,
        target: np.ndarray | TargetSet,
        tolerance: float,
    ) -> np.ndarray | None:
        """A clear pose with every targeted end within ``tolerance`` of its target, or None if
        no seed found one.

        Among the seeds' polished poses, the first the skeleton can turn to in a straight clear
        line wins; otherwise the clear one nearest ``measured`` in joint space. With
        :attr:`strain` known, poses the motors cannot hold (past ``HOLDS``) count only when no
        seed arrives at one they hold: under a ceiling, six weakening links hanging were sent
        to a clear pose asking 1.09 of a motor where the solver's own asked 0.95, sagged off it
        and ended `blocked` 62 px from the target. Poses with a joint
        on its stop (within ``STOP_ROOM``, see :meth:`off_stops`) count only when no seed
        arrives off the stops: a fold pressed against a stop under a shelf, a straight turn
        away, left five links a 3 s route from a target a little deeper in. When no seed of a
        chain arrives, the clear one that came nearest is taken onto the target with the
        obstacles ignored and polished off them again (a polish close by an obstacle can stall
        a px short, the pull on the end balanced by the push off it).

        The points of a target set can lie out of joint reach (pulled apart, or one a little
        past an arm's reach) with the obstacles nowhere near: when no seed arrives, the clear
        pose nearest the targets (weighted, polished on for ``FREE_ITERATIONS``) is the answer
        if the obstacles are not what keeps it from them, that is if plain least squares from
        it (as long, obstacles ignored) brings no end more than ``tolerance`` nearer its
        target.
        """
        found = _finish(self._answering(measured, answer, target, tolerance))
        return None if found is None or found[2] else found[0]

    def _answering(
        self,
        measured: np.ndarray,
        answer: np.ndarray,
        target: np.ndarray | TargetSet,
        tolerance: float,
    ) -> _Work[tuple[np.ndarray, bool, bool] | None]:
        """:meth:`clear_answer` in steps of work (see :class:`Avoider`), with whether the
        straight line to it from ``measured`` was checked clear and whether the obstacles keep
        it from the targets (jammed).

        Where :meth:`clear_answer` finds none because the obstacles are in the way (the targets
        reached with them ignored, but no clear pose polished onto them: a target under the
        floor), the clear pose the polish brought nearest the targets is returned, jammed: the
        nearest a chain can come without pressing into an obstacle. None when no pose polished
        is clear, or a chain's target is out of reach even with the obstacles ignored."""
        measured = np.asarray(measured, float)
        found: list[np.ndarray] = []
        short: list[Solution] = []
        # The first answer on a stop the chain can turn to in a straight clear line: taken only
        # if no answer off the stops is found.
        pressed: np.ndarray | None = None
        # Answers the motors cannot hold: taken only if none they hold is found.
        strained: list[np.ndarray] = []
        strain = self.strain
        for phase in self._phases(measured, answer, target):
            if phase.last_resort and (found or pressed is not None or strained):
                break
            if phase.units:
                yield phase.units
            for start in phase.seeds():
                sol = yield from self._polishing(start, target, POLISH_ITERATIONS, tolerance, True)
                if sol.status is not SolveStatus.SUCCESS:
                    if phase.own and self.is_clear(sol.angles):
                        short.append(sol)
                    continue
                if strain is not None and strain(sol.angles) > HOLDS:
                    strained.append(sol.angles)
                    continue
                free = self.off_stops(sol.angles)
                if (free or pressed is None) and (yield from self._checking(measured, sol.angles)):
                    if free:
                        self._earlier.appendleft(sol.angles.copy())
                        return sol.angles, True, False
                    pressed = sol.angles
                    continue
                found.append(sol.angles)
        roomy = [pose for pose in found if self.off_stops(pose)]
        if roomy:
            nearest = min(roomy, key=lambda pose: float(np.abs(pose - measured).sum()))
            self._earlier.appendleft(nearest.copy())
            return nearest, False, False
        if pressed is not None:
            return pressed, True, False
        found = found or strained
        if not found and short and not isinstance(target, TargetSet):
            # Close by an obstacle the polish can stall a px short, the pull on the end balanced
            # by the push off the obstacle. From the nearest such pose the end is taken onto the
            # target with the obstacles ignored, and the polish then only has to push off them.
            start = min(short, key=lambda sol: sol.error)
            free = yield from self._polishing(
                start.angles, target, POLISH_ITERATIONS, tolerance, False
            )
            if free.status is not SolveStatus.SUCCESS:
                return None
            sol = yield from self._polishing(
                free.angles, target, POLISH_ITERATIONS, tolerance, True
            )
            if sol.status is SolveStatus.SUCCESS:
                return sol.angles, (yield from self._checking(measured, sol.angles)), False
            if self.is_clear(sol.angles) and sol.error < start.error:
                start = sol
            return start.angles, False, True
        if not found and short:
            start = min(short, key=lambda sol: sol.error).angles
            # Both polished to the end, so that they differ only where an obstacle is in the way.
            nearest = (yield from self._polishing(start, target, FREE_ITERATIONS, 0.5, True)).angles
            free = yield from self._polishing(nearest, target, FREE_ITERATIONS, tolerance, False)
            gained = self.misses(nearest, target) - self.misses(free.angles, target)
            return nearest, False, bool(np.any(gained > tolerance))
        if not found:
            return None
        return min(found, key=lambda pose: float(np.abs(pose - measured).sum())), False, False

    # -- paths -------------------------------------------------------------------------------

    def _samples(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Poses along the straight line from ``a`` to ``b`` (both ends included), spaced so
        that no point of the chain moves more than ``PATH_STEP`` px between two."""
        swept = self.swept(a, b)
        count = min(_MAX_SAMPLES, max(2, math.ceil(swept / PATH_STEP) + 1))
        fractions = np.linspace(0.0, 1.0, count)[:, None]
        return a + fractions * (b - a)

    def path_clear(self, a: np.ndarray, b: np.ndarray) -> bool:
        """Whether the straight joint-space line from ``a`` to ``b`` keeps every link half the
        margin clear (the motors do not follow the line exactly, and a link rubbing along an
        obstacle drags). A start already closer than that may only get farther."""
        a, b = np.asarray(a, float), np.asarray(b, float)
        if len(self.obstacles) and self._line_bound(a, b, self.margin / 2.0)[1].all():
            return True
        return _finish(self._checking(a, b))

    def _line_bound(
        self, a: np.ndarray, b: np.ndarray, floor: float
    ) -> tuple[float, np.ndarray, np.ndarray]:
        """For the straight line from ``a`` to ``b``: the least gap (px) it may come to
        (:func:`_least_gap` of ``floor`` and the start's), which links it keeps at least that
        clear for certain ((n,) bool), and the gap (px) each link keeps all along it by the
        bound, from its gaps at the two ends alone. A link's gap, while above zero, shrinks no
        faster than its points move (see :meth:`_stepping`), so a link whose bound is above
        zero and at least the least gap is as clear as sampling the line would find it."""
        ends = self._link_gaps(np.stack((a, b)))
        bar = _least_gap(floor, float(ends[0].min()))
        kept = (ends[0] + ends[1] - self.swept_links(a, b)) / 2.0
        return bar, (kept >= bar) & (kept > 0.0), kept

    def _checking(self, a: np.ndarray, b: np.ndarray, keep: float | None = None) -> _Work[bool]:
        """:meth:`path_clear`, ``PATH_CHUNK`` poses a step, from both ends of the line inward,
        stopping at the first chunk that comes too close; with ``keep``, the gap (px) to keep
        instead of half the margin.

        A line is as often blocked near its far end as near its start: of the 202 lines that
        shortening a way in under a shelf found blocked, about half were blocked within 50 of
        their 400 poses of one end and half of the other."""
        if not len(self.obstacles):
            return True
        poses = self._samples(np.asarray(a, float), np.asarray(b, float))
        bar = 0.0
        firsts = range(0, len(poses), PATH_CHUNK)
        for k in range(len(firsts)):
            first = firsts[k // 2] if k % 2 == 0 else firsts[-1 - k // 2]
            gaps = self.smallest_gaps(poses[first : first + PATH_CHUNK])
            yield CHECK_UNITS + len(gaps) * self._pose_units
            if first == 0:
                bar = _least_gap(self.margin / 2.0 if keep is None else keep, float(gaps[0]))
                gaps = gaps[1:]
            if not np.all(gaps >= bar):
                return False
        return True

    def route(self, start: np.ndarray, goal: np.ndarray) -> list[np.ndarray] | None:
        """Via poses from ``start`` to the clear ``goal``, each reached from the one before in a
        clear straight line; None when the search found none. The goal comes last, or for a
        chain led there by its end (see :meth:`tip_path`) another clear pose that puts the end
        where the goal does.

        >>> arm = Skeleton.chain([100.0, 100.0], base_angle=math.pi / 2)
        >>> post = Obstacles.from_arrays(np.empty((0, 5)), np.array([[0.0, 185.0, 20.0]]))
        >>> room = Clearance(arm, np.full(2, 5.0), post)
        >>> start, goal = np.array([0.8, 0.8]), np.array([-0.8, -0.8])
        >>> room.path_clear(start, goal)
        False
        >>> way = room.route(start, goal)
        >>> all(room.path_clear(a, b) for a, b in zip([start, *way], way))
        True
        """
        return _finish(self._routing(start, goal))

    def _routing(
        self,
        start: np.ndarray,
        goal: np.ndarray,
        back: list[np.ndarray] | None = None,
        *,
        slide: bool = True,
    ) -> _Work[list[np.ndarray] | None]:
        """:meth:`route` in steps of work (see :class:`Avoider`); with ``back``, poses each
        reached from the one before in a clear straight line (an earlier route walked back),
        the way along them is tried when the trees find none in their share (see
        :meth:`_retracing`); without ``slide``, no sliding trees search and the way back is
        tried only when the trees find none at all (see :meth:`_searching`)."""
        start = np.asarray(start, float)
        goal = np.asarray(goal, float)
        if (yield from self._checking(start, goal)):
            return [goal]
        found, keep = yield from self._searching(start, goal, back, slide=slide)
        if found is None and back:
            found = yield from self._retracing(start, goal, back)
        if found is None:
            return None
        # Greedy shortcuts: from each pose, the farthest one reachable in a clear straight line.
        way: list[np.ndarray] = []
        here, index = start, 0
        while index < len(found):
            far = len(found) - 1
            while far > index and not (yield from self._checking(here, found[far], keep)):
                far -= 1
            here, index = found[far], far + 1
            way.append(here)
        return way

    def _searching(
        self,
        start: np.ndarray,
        goal: np.ndarray,
        back: list[np.ndarray] | None = None,
        *,
        slide: bool = True,
    ) -> _Work[tuple[list[np.ndarray] | None, float]]:
        """The poses from ``start`` (excluded) to ``goal`` the trees find (:meth:`_connect`), or
        for a chain the walked way (:meth:`_walking`), and the least gap (px) the lines that
        shorten them keep: half the margin for the trees', the margin for a walked way (its own
        poses keep that; cut at half of it, its long swings grazed a shelf's end, and twenty
        links the motors carried a little off the line caught there).

        The trees search first: where they find a way at all in a few joint dimensions they find
        it in a few thousand units of work. A chain's way is walked once they have done
        ``TREE_FIRST`` units (or given up sooner); thirty links round a rock got no way from
        2,500 nodes (7.5 million units). Where the walk finds none (for a tree of links, at
        that point), with ``slide`` the sliding trees search next (:meth:`_connect` with
        ``slide``; first, with ``back``, the way back along an earlier route, see
        :meth:`_retracing`), and the trees of straight steps go on only if they find none: from
        the other bend, the way in under the rock of ``27_round_rock`` (the middle joint on its
        stop) took them 10,000 units, and 2,500 straight tries found none. Started later, once
        the straight trees gave up, they found it too late for the chain to follow it in the
        target's time."""
        tree = self._connect(start, goal)
        spent, walk = 0.0, self.skeleton.is_chain
        while True:
            try:
                units = next(tree)
            except StopIteration as done:
                found = done.value
                break
            yield units
            spent += units
            if (walk or slide) and spent >= TREE_FIRST:
                if walk:
                    walk = False
                    walked = yield from self._walking(start, goal)
                    if walked is not None:
                        tree.close()
                        return walked, self.margin
                if slide:
                    slide = False
                    slid = yield from self._sliding_way(start, goal, back)
                    if slid is not None:
                        tree.close()
                        return slid, self.margin / 2.0
        if found is None and walk:
            walked = yield from self._walking(start, goal)
            if walked is not None:
                return walked, self.margin
        if found is None and slide:
            found = yield from self._sliding_way(start, goal, back)
        return found, self.margin / 2.0

    def _sliding_way(
        self, start: np.ndarray, goal: np.ndarray, back: list[np.ndarray] | None
    ) -> _Work[list[np.ndarray] | None]:
        """The way back along ``back`` (:meth:`_retracing`), if there is one, else the way the
        sliding trees find (:meth:`_connect` with ``slide``), or None."""
        if back:
            way = yield from self._retracing(start, goal, back)
            if way is not None:
                return way
        return (yield from self._connect(start, goal, slide=True))

    def _retracing(
        self, start: np.ndarray, goal: np.ndarray, back: list[np.ndarray]
    ) -> _Work[list[np.ndarray] | None]:
        """The poses from ``start`` along ``back`` as far as the first from which ``goal`` is
        reached in a clear straight line, then the goal; None when ``start`` is more than
        ``AHEAD`` px of sweep from the first (the chain has left that route's end: a way back
        along it would be a detour), when the line from ``start`` to the first, or from each to
        the next, is not clear, or when none leads to the goal.

        A chain that came in through a narrow passage (the last links threaded under a rock, in a
        band a few px wider than they are) rests at the end of the route that led it in, and
        the way out is that route walked back: random trees in joint space seldom find it again
        (on ``27_round_rock`` none did in a search of 107,000 units of work). It is tried only
        once they have done their share (``TREE_FIRST``, and a chain's walk found none) or found
        none: where they find a way soon it is the shorter one (back along the route the chain
        came by, it reached the next target of ``07_target_on_base`` 0.09 s later), and a way
        out the sliding trees find on 27 took the chain 0.5 s longer than the way back."""
        if self.swept(start, back[0]) > AHEAD:
            return None
        here, via = start, []
        for pose in back:
            if not (yield from self._checking(here, pose)):
                return None
            here = pose
            via.append(pose)
            if (yield from self._checking(here, goal)):
                return [*via, goal]
        return None

    def _trimming(
        self,
        start: np.ndarray,
        way: list[np.ndarray],
        target: np.ndarray | TargetSet,
        tolerance: float,
    ) -> _Work[list[np.ndarray]]:
        """A route ``way`` from ``start`` cut where the targeted ends come nearest ``target``
        on its pieces before the last, when that is nearer than they are at the last via pose:
        the via poses before the cut, the cut, then a clear answer polished from the cut
        (within ``tolerance``) when the line to it is clear, else the goal when the line to it
        is; when neither is, or no piece before the last comes nearer, the route as
        :meth:`_passing` leaves it.

        The search knows poses, not where they put the ends: a via pose can lie past the
        target, and a chain following the route takes its end past the target and back (10%
        of the approach on two stress levels). The answer polished from where the end passes
        nearest is a short turn away; the goal can be a long one."""
        if len(way) < 2:
            return way
        poses = [start, *way[:-1]]
        pieces = [self._samples(a, b) for a, b in zip(poses, poses[1:], strict=False)]
        samples = np.concatenate(pieces)
        yield CHECK_UNITS + len(samples) * self._pose_units
        links, points, scale = self._aim(target)
        _, ends = self._links(self.points(samples))
        misses = (scale**2 * ((points - ends[:, links]) ** 2).sum(axis=-1)).sum(axis=-1)
        nearest = int(np.argmin(misses))
        if misses[nearest] >= misses[-1]:
            return (yield from self._passing(way, target, tolerance))
        cut = samples[nearest]
        # The via poses the chain passes before the cut.
        passed = way[: int(np.searchsorted(np.cumsum([len(p) for p in pieces]), nearest, "right"))]
        near = yield from self._polishing(cut, target, POLISH_ITERATIONS, tolerance, True)
        if near.status is SolveStatus.SUCCESS and (yield from self._checking(cut, near.angles)):
            return [*passed, cut, near.angles]
        # Checked from the goal, as the route's tree from the goal checks its pieces: a goal
        # polished to within the margin (a target just above the floor) may be approached as
        # near as it is.
        if (yield from self._checking(way[-1], cut)):
            return [*passed, cut, way[-1]]
        return (yield from self._passing(way, target, tolerance))

    def _passing(
        self, way: list[np.ndarray], target: np.ndarray | TargetSet, tolerance: float
    ) -> _Work[list[np.ndarray]]:
        """A route ``way`` (at least two poses) whose last piece takes the targeted ends past
        the target and then out more than twice as far from it as they passed (and farther
        than ``tolerance``) before they come back to it at the goal, cut where they passed
        nearest and ended by a clear answer polished from there (within ``tolerance``) when
        the line to it is clear; the route as it was otherwise.

        The goal is on the target, so the cut of :meth:`_trimming` (a piece before the last
        nearer the target than its end) never finds such a pass. On
        `35_twenty_links_under_shelf` the last piece in under the shelf took the end within
        2.7 px of the target 60% of the way along, then 43 px past it and back."""
        samples = self._samples(way[-2], way[-1])
        yield CHECK_UNITS + len(samples) * self._pose_units
        links, points, scale = self._aim(target)
        _, ends = self._links(self.points(samples))
        apart = np.sqrt((scale**2 * ((points - ends[:, links]) ** 2).sum(axis=-1)).sum(axis=-1))
        # The farthest the ends swing out from the nearest they passed before.
        passed = np.minimum.accumulate(apart)
        out = int(np.argmax(apart - passed))
        nearest = int(np.argmin(apart[: out + 1]))
        if nearest == 0 or not apart[out] > max(2.0 * passed[out], tolerance):
            return way
        cut = samples[nearest]
        near = yield from self._polishing(cut, target, POLISH_ITERATIONS, tolerance, True)
        if near.status is SolveStatus.SUCCESS and (yield from self._checking(cut, near.angles)):
            return [*way[:-1], cut, near.angles]
        return way

    def tip_path(self, start: np.ndarray, goal: np.ndarray) -> np.ndarray:
        """(m, 2) a way in the plane for a chain's end from where pose ``start`` puts it to
        where pose ``goal`` does, px: ``start``'s links from the end back to the base, then
        ``goal``'s out to its end, pulled taut by straight pieces that keep the last link's
        radius, the margin and ``ACTIVE`` px from every obstacle.

        The links follow where the end leads, so the way keeps to the side of each obstacle on
        which the goal's links pass it (a way over a rock the chain is too short to go round
        and down would be shorter for the end alone).

        Ten 20 px links standing straight up, a floor and a rock; the goal reaches in under
        the rock's far side, and so does the way (the points after the first):

        >>> arm = Skeleton.chain([20.0] * 10, base_angle=math.pi / 2)
        >>> floor = np.array([[-300.0, -10.0, 300.0, -10.0, 0.0]])
        >>> room = Clearance(arm, np.full(10, 2.0), Obstacles.from_arrays(floor, [[100, 60, 30]]))
        >>> up = np.zeros(10)
        >>> under = room.clear_answer(up, up, np.array([150.0, 10.0]), 0.5)
        >>> np.round(room.tip_path(up, under)[:, 1]).tolist()
        [200.0, 36.0, 29.0, 21.0, 28.0, 37.0, 30.0, 10.0]
        """
        if not self.skeleton.is_chain:
            raise ValueError("a tip path is for a chain")
        return _finish(self._tip_path(np.asarray(start, float), np.asarray(goal, float)))

    def _tip_path(self, start: np.ndarray, goal: np.ndarray) -> _Work[np.ndarray]:
        """:meth:`tip_path`, a point of the way a step (``CHECK_UNITS`` each)."""
        return (
            yield from self._taut(np.concatenate((self.points(start)[::-1], self.points(goal)[1:])))
        )

    def _taut(self, line: np.ndarray) -> _Work[np.ndarray]:
        """(m, 2) the (k, 2) points of ``line`` (px) pulled taut: from each point kept, the
        farthest along the line reached by a straight piece that keeps the last link's radius,
        the margin and ``ACTIVE`` px from every obstacle (``CHECK_UNITS`` a piece)."""
        keep = float(self.radii[-1]) + self.margin + ACTIVE
        way, here = [line[0]], 0
        while here < len(line) - 1:
            ahead = line[here + 1 :]
            clear = self._segment_gaps(line[here], ahead) >= keep
            yield CHECK_UNITS
            # The line's own pieces are links of clear poses: kept even when nearer than that.
            far = int(np.nonzero(clear)[0].max(initial=0))
            here += far + 1
            way.append(line[here])
        return np.array(way)

    def _segment_gaps(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """(m,) the smallest gap (px) of each segment from point ``a`` to the (m, 2) points
        ``b`` to any obstacle's surface."""
        q0, q1 = self._a, self._b
        a = np.broadcast_to(a, b.shape)
        d = np.minimum(_distance_to(a[:, None], q0, q1), _distance_to(b[:, None], q0, q1))
        ends = _distance_to(np.stack((q0, q1))[:, None], a[:, None], b[:, None]).min(axis=0)
        d = np.minimum(d, ends)
        return (np.where(_crossing(a, b, q0, q1), -d, d) - self._r).min(axis=-1, initial=math.inf)

    def _walking(self, start: np.ndarray, goal: np.ndarray) -> _Work[list[np.ndarray] | None]:
        """A chain's way from ``start`` to ``goal`` led by its end: the poses (``start``
        excluded) the polish steps the end through along :meth:`tip_path`, ``WALK_STEP`` px at a
        time from the last, each reached from the one before in a clear straight line, then the
        goal, or if that line is not clear the last pose polished onto the goal's end; None when
        the end falls behind by more than a step or a step is not clear.

        A long chain's joint space is too wide for random trees (thirty links round a rock: no
        way in 2,500 nodes, 7.5 million units of work); drawn by its end along a way in the open,
        the links follow it, each clear of what they pass."""
        way = yield from self._tip_path(start, goal)
        pose, poses = start, []
        for aim in _marks(way, WALK_STEP):
            sol = yield from self._polishing(pose, aim, WALK_ITERATIONS, 1.0, True)
            behind = float(self.misses(sol.angles, aim)[0])
            if behind > WALK_STEP or not self.is_clear(sol.angles):
                return None
            if not (yield from self._checking(pose, sol.angles)):
                return None
            pose = sol.angles
            poses.append(pose)
        if (yield from self._checking(pose, goal)):
            return [*poses, goal]
        end = self.points(goal)[-1]
        sol = yield from self._polishing(pose, end, POLISH_ITERATIONS, 0.5, True)
        if sol.status is not SolveStatus.SUCCESS:
            return None
        return [*poses, sol.angles] if (yield from self._checking(pose, sol.angles)) else None

    def _connect(
        self, start: np.ndarray, goal: np.ndarray, *, slide: bool = False
    ) -> _Work[list[np.ndarray] | None]:
        """RRT-connect in joint space: the poses from ``start`` (excluded) to ``goal``; with
        ``slide``, its trees grow by sliding steps (see :meth:`_extend`), ``SLIDE_NODES`` poses
        at most.

        A chain's two trees first grow along the ways its polish draws the end from each root
        toward the retreat point (:meth:`_retreating`, sliding with ``slide``), and the goal's
        tree reaches for the end of the start's before any pose is drawn at random. Poses are
        drawn within :meth:`_sampled_box`. A chain's sliding trees, once their random poses
        have done ``TREE_FIRST`` units of work, grow along the walked retreats too (see
        :meth:`_retreating`), and the goal's reaches for the start's new end: where the trees
        find a way at all they find it soon (under ``27_round_rock``'s rock in 10,000 units),
        and walked first the retreats made that way 0.4 s later; five links folded the other
        way deep under a shelf took the random trees 210,000 units, their walked retreats
        17,000."""
        sk = self.skeleton
        rng = np.random.default_rng(RANDOM_SEED)
        low, high = self._sampled_box(start, goal)
        ends = self._link_gaps(np.stack((start, goal)))
        yield CHECK_UNITS + 2 * self._pose_units
        trees = [_Tree(start, ends[0]), _Tree(goal, ends[1])]
        walk = slide and sk.is_chain
        if sk.is_chain:
            found = yield from self._retreats(trees, slide=slide)
            if found is not None:
                return found
        growing = self._growing(trees, rng, low, high, slide=slide)
        spent = 0.0
        while True:
            try:
                units = next(growing)
            except StopIteration as done:
                return done.value
            yield units
            spent += units
            if walk and spent >= TREE_FIRST:
                walk = False
                found = yield from self._retreats(trees, walk=True)
                if found is not None:
                    growing.close()
                    return found

    def _retreats(
        self, trees: list[_Tree], *, slide: bool = False, walk: bool = False
    ) -> _Work[list[np.ndarray] | None]:
        """Grow a chain's two route trees (from the start and from the goal, in that order)
        along their retreats (:meth:`_retreating`) and the goal's toward the end of the
        start's: the poses of the way that joins them (the start excluded), or None."""
        from_start, from_goal = trees
        out = yield from self._retreating(from_start, slide=slide, walk=walk)
        yield from self._retreating(from_goal, slide=slide, walk=walk)
        reached, arrived = yield from self._extend(from_goal, from_start.poses[out], reach=True)
        if not arrived:
            return None
        return (from_start.lineage(out) + from_goal.lineage(reached)[::-1])[1:]

    def _growing(
        self,
        trees: list[_Tree],
        rng: np.random.Generator,
        low: np.ndarray,
        high: np.ndarray,
        *,
        slide: bool,
    ) -> _Work[list[np.ndarray] | None]:
        """The random part of :meth:`_connect`: each of the two ``trees`` (from the start and
        from the goal) in turn grows toward a pose drawn between ``low`` and ``high`` and the
        other toward what it added, until they meet (the poses of the way, the start excluded)
        or the search gives up (None)."""
        from_start, from_goal = trees
        order = [from_start, from_goal]
        tries = 0
        while (from_start.size + from_goal.size < SLIDE_NODES) if slide else tries < ROUTE_NODES:
            tries += 1
            grow, other = order
            sample = rng.uniform(low, high)
            new, _ = yield from self._extend(grow, sample, reach=True, slide=slide)
            if new is not None:
                reached, arrived = yield from self._extend(
                    other, grow.poses[new], reach=True, slide=slide
                )
                if arrived:
                    a = grow.lineage(new)
                    b = other.lineage(reached)
                    path = a + b[::-1] if grow is from_start else b + a[::-1]
                    return path[1:]
            order.reverse()
        return None

    def _sampled_box(self, start: np.ndarray, goal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The lowest and highest angle of each joint the route trees from ``start`` to
        ``goal`` draw poses between, radians: within the limits, a half turn either side of the
        start (a free joint's every angle, once), and as far as the goal. A goal bent the other
        way from a joint on its stop lies more than a half turn off (from +150 deg to -78 deg,
        under a shelf): without it the trees never drew a pose on the goal's side of that joint,
        and found no way to it in 430,000 units of work.

        >>> arm = Skeleton.chain([100.0, 100.0], limits=[None, (-2.6, 2.6)])
        >>> room = Clearance(arm, np.full(2, 5.0), Obstacles.from_arrays(np.empty((0, 5)), []))
        >>> low, high = room._sampled_box(np.array([0.0, 2.6]), np.array([0.0, -1.4]))
        >>> np.round(low, 2).tolist(), np.round(high, 2).tolist()
        ([-3.14, -1.4], [3.14, 2.6])
        """
        sk = self.skeleton
        low = np.maximum(sk.lower, np.minimum(start - math.pi, goal))
        high = np.minimum(sk.upper, np.maximum(start + math.pi, goal))
        return low, high

    def _retreating(self, tree: _Tree, *, slide: bool = False, walk: bool = False) -> _Work[int]:
        """Grow a chain's ``tree`` from its root along the poses its polish steps through
        drawing the end toward the retreat point (half the chain's reach out along the base's
        mount, where a chain stands folded clear of what is around its base), as far as each
        is reached from the last in a clear straight line: the index of the last node added
        (the root's when none).

        A chain threaded under a shelf comes out along its own clearance rows, a way random
        poses almost never fall on. With ``slide`` (the sliding trees' retreats), each polish
        step that brings a link near an obstacle is a sliding step (:meth:`_sliding`) of it:
        the polish's clearance rows only weigh against the pull on the end, and drawn up and
        out from under a shelf the end pressed into the shelf's underside to within the 2 px a
        line keeps, so the trail's lines were not clear and the tree stopped under the shelf
        (five 80 px links, the end at (140, 70)); sliding along the underside, the trail leads
        out into the open in ten poses.

        With ``walk`` (sliding too), the end is drawn ``WALK_STEP`` px at a time along a way in
        the plane back along the root's own links to the base and from there out to the
        retreat point (pulled taut, as :meth:`tip_path`), until it falls behind by more than a
        step. Drawn straight at the retreat point, five links deep under a shelf, folded so
        that the third joint bends the links back under it, stopped with the end at (136, 84),
        still under the shelf, and that joint on its stop; led back the way its links lie, the
        chain draws out from under the shelf like a snake and reaches the retreat point."""
        sk = self.skeleton
        mount = np.array([math.cos(sk.base_angle), math.sin(sk.base_angle)])
        point = np.asarray(sk.base, dtype=float) + 0.5 * sk.reach * mount
        if walk:
            line = np.concatenate((self.points(tree.poses[0])[::-1], point[None]))
            aims = _marks((yield from self._taut(line)), WALK_STEP)
            iterations, tolerance = WALK_ITERATIONS, 1.0
        else:
            aims, iterations, tolerance = point[None], POLISH_ITERATIONS, 0.5
        last = 0
        for aim in aims:
            trail: list[np.ndarray] = []
            sol = yield from self._polishing(
                tree.poses[last], aim, iterations, tolerance, True, trail, slide=slide or walk
            )
            for pose in trail[1:]:
                new, arrived = yield from self._extend(tree, pose, reach=True)
                if arrived:
                    last = new
            if walk and sol.error > WALK_STEP:
                # The end fell behind: the links are caught (a fold on its stop under a rock).
                break
        return last

    def _extend(
        self, tree: _Tree, toward: np.ndarray, *, reach: bool = False, slide: bool = False
    ) -> _Work[tuple[int | None, bool]]:
        """Grow ``tree`` from its nearest node toward a pose, ``ROUTE_STEP`` at a time (once,
        or with ``reach`` until it gets there or is blocked): the index of the last node added
        (None if none) and whether it is the pose itself. With ``slide``, ``SLIDE_STEP`` at a
        time, each step turned along the obstacles it would bring a link within the margin of
        (:meth:`_sliding`), for as long as it brings the tree a tenth of a step nearer."""
        near = tree.nearest(toward)
        yield tree.size * NEAREST_UNITS
        added = None
        while True:
            here = tree.poses[near]
            gap = toward - here
            largest = float(np.abs(gap).max())
            if slide:
                nxt = yield from self._sliding(here, gap)
                arrived = bool(np.array_equal(nxt, toward))
                if not arrived and math.dist(nxt, toward) > math.dist(here, toward) - (
                    SLIDE_STEP / 10.0
                ):
                    return added, False
            else:
                arrived = largest <= ROUTE_STEP
                nxt = toward if arrived else here + gap * (ROUTE_STEP / largest)
            gaps = yield from self._stepping(here, tree.gaps[near], nxt)
            if gaps is None:
                return added, False
            near = added = tree.add(nxt, gaps, near)
            if arrived or not reach:
                return added, arrived

    def _sliding(self, here: np.ndarray, toward: np.ndarray) -> _Work[np.ndarray]:
        """The pose one sliding step from ``here`` along the joint change ``toward`` (cut to
        ``SLIDE_STEP``; ``here + toward`` itself when it is that short and turned by no gap),
        within the limits (``ITERATION_UNITS`` of work).

        The step nearest the one asked for that keeps, to first order, every link near an
        obstacle (within ``ACTIVE`` of the margin) the margin and ``SLIDE_ROOM`` clear of it:
        each such gap a row of how fast joint motion widens it, and the rows the step would
        take below that held to it (damped least squares), those it would bring there next
        too. So a tree slides along an obstacle's surface, and along a stop (where the limits
        cut the step), instead of stopping there: a narrow passage between obstacles is a way
        along their surfaces."""
        sk = self.skeleton
        short = float(np.abs(toward).max()) <= SLIDE_STEP
        wanted = toward if short else toward * (SLIDE_STEP / float(np.abs(toward).max()))
        pts = self.points(here)
        starts, _ = self._links(pts)
        gap, point, unit = self._pairs(pts)
        yield ITERATION_UNITS
        near, obstacles = np.nonzero(gap < self.margin + ACTIVE)
        step = wanted
        if near.size:
            lever = point[near, obstacles][:, None, :] - starts[None, :, :]
            u = unit[near, obstacles]
            moved = -lever[..., 1] * u[:, None, 0] + lever[..., 0] * u[:, None, 1]
            rows = np.where(sk.ancestors[near], moved, 0.0)
            least = self.margin + SLIDE_ROOM - gap[near, obstacles]
            held = np.zeros(len(rows), dtype=bool)
            damping = (0.02 * float(self._lever.max())) ** 2
            for _ in range(len(rows)):
                below = (rows @ step < least) & ~held
                if not below.any():
                    break
                held |= below
                jac = rows[held]
                lack = least[held] - jac @ wanted
                step = wanted + jac.T @ np.linalg.solve(
                    jac @ jac.T + damping * np.eye(len(jac)), lack
                )
            largest = float(np.abs(step).max())
            if largest > SLIDE_STEP:
                step = step * (SLIDE_STEP / largest)
        # Unturned, a short step lands on the pose itself (the tree arrives there).
        return sk.clamp(here + (toward if short and step is wanted else step))

    def _link_gaps(self, poses: np.ndarray) -> np.ndarray:
        """(b, n) each link's smallest gap to any obstacle at each of (b, n) poses, px."""
        return self._gaps(self.points(poses))

    def _stepping(
        self, here: np.ndarray, gaps: np.ndarray, to: np.ndarray
    ) -> _Work[np.ndarray | None]:
        """Whether the straight line from ``here`` (its links' gaps ``gaps``) to ``to`` is clear
        by :meth:`path_clear`'s measure: the links' gaps at ``to``, or None.

        A link whose gaps at the two ends add up to more than it can sweep between them, and
        twice the least gap allowed, cannot come that near in between (its gap shrinks at most
        as fast as its points move): a piece in the open costs one pose. The line is sampled
        only as finely as the other links move."""
        ahead = self._link_gaps(to[None])[0]
        yield CHECK_UNITS + self._pose_units
        bar = _least_gap(self.margin / 2.0, float(gaps.min()))
        if ahead.min() < bar:
            return None
        sweeps = self.swept_links(here, to)
        # Only a gap kept above zero bounds the way: a link overlapping an obstacle at the
        # start (a negative bar) could pass through it in between.
        open_ = (gaps + ahead - sweeps >= 2.0 * bar) & (bar > 0.0)
        if np.all(open_):
            return ahead
        swept = float(sweeps[~open_].max())
        count = min(_MAX_SAMPLES, max(2, math.ceil(swept / PATH_STEP) + 1))
        poses = here + np.linspace(0.0, 1.0, count)[1:-1, None] * (to - here)
        # The open links cannot come below the bar: only the others are measured.
        links = None if not open_.any() else np.flatnonzero(~open_)
        for first in range(0, len(poses), PATH_CHUNK):
            chunk = self._gaps(self.points(poses[first : first + PATH_CHUNK]), links).min(axis=-1)
            yield CHECK_UNITS + len(chunk) * self._pose_units
            if not np.all(chunk >= bar):
                return None
        return ahead


@dataclass(frozen=True)
class _SeedPhase:
    """A group of a clear answer's seeds (see :meth:`Clearance.seeds`): ``seeds()`` draws them,
    at the cost of ``units`` of work; a ``last_resort`` is polished only where no seed before it
    arrived clear; a clear pose an ``own`` seed stalls in (the target's own, not an earlier
    target's answer) may be the start the end is taken onto the target from."""

    seeds: Callable[[], list[np.ndarray]]
    units: float = 0.0
    last_resort: bool = False
    own: bool = True


class _Tree:
    """A route search's tree in joint space: its poses (rows; the root first), each link's gap
    (px) at each, and each pose's parent (-1 for the root)."""

    def __init__(self, root: np.ndarray, gaps: np.ndarray) -> None:
        self.poses = np.empty((64, len(root)))
        self.gaps = np.empty((64, len(gaps)))
        self.parents: list[int] = []
        self.size = 0
        self.add(root, gaps, -1)

    def add(self, pose: np.ndarray, gaps: np.ndarray, parent: int) -> int:
        """Add a pose reached from ``parent`` in a clear straight line: its index."""
        if self.size == len(self.poses):
            self.poses = np.concatenate((self.poses, np.empty_like(self.poses)))
            self.gaps = np.concatenate((self.gaps, np.empty_like(self.gaps)))
        self.poses[self.size] = pose
        self.gaps[self.size] = gaps
        self.parents.append(parent)
        self.size += 1
        return self.size - 1

    def nearest(self, pose: np.ndarray) -> int:
        """The index of the pose nearest ``pose`` (the largest joint difference)."""
        return int(np.argmin(np.abs(self.poses[: self.size] - pose).max(axis=1)))

    def lineage(self, index: int) -> list[np.ndarray]:
        """The poses from the root to ``index``."""
        path = []
        while index >= 0:
            path.append(self.poses[index].copy())
            index = self.parents[index]
        return path[::-1]


class Avoider:
    """Turns a solver's answer into a pose to command that keeps the chain clear, tick by tick.

    Call :meth:`steer` with the measured pose, the solver's solution and the target every tick. It
    returns the solution unchanged when its pose is clear and the chain can turn to it in a clear
    straight line (measured again only when the joints could have used up the gap, so a chain at
    rest costs two products of the links' levers); otherwise a clear answer for the target
    (:meth:`Clearance.clear_answer`) and, when the straight way to it is blocked, the next via pose
    of a route (:meth:`Clearance.route`), with status ``PROCESSING``. The clear answer and the route
    are kept until the target moves, so they are searched once (a chain resting short of the target
    for ``RELEASE_S`` is handed back to the solver). When the obstacles keep every clear
    pose from the target (it lies under the floor), the chain is sent instead to the clear pose
    nearest it, by a route if one is found within ``JAMMED_WORK``, else to the pose the polish
    draws it to from where it is, and kept there (:attr:`jammed`): it rests held off the
    obstacle, where the solver's answer would press it in. When no clear pose or no route is
    found at all, the solver's own solution is returned for that target: the chain behaves as
    without obstacles (and a jammed one is reported blocked). With ``replan``, a chain the
    motors carried off the planned line, whose straight way on to its via pose is blocked from
    where it is, gets a new route from there; without it, only one that rests there with a link
    pressed into an obstacle (see ``PINNED_S``). While the base moves (its
    :attr:`clearance`'s skeleton is another one each call) nothing is planned, and the solver's
    answers are handed on until they bring a link within ``ACTIVE`` px of the margin of an
    obstacle nearer it: from then on, until no link is that near, the pose commanded the call
    before is polished onto the target for where the base is now (``HOLD_OFF_ITERATIONS``
    iterations at most), so the links near it come no nearer as the base carries them by.

    A call is a tick of ``tick_rate`` ticks a simulated second. The search is spread over calls:
    each does at most ``budget`` units of its work (by default ``SEARCH_RATE``'s share of a tick;
    ``ITERATION_UNITS`` per polish iteration, ``CHECK_UNITS`` per step of a path check and
    ``POSE_UNITS`` per pose checked, link and obstacle; a count, not a clock, so runs repeat
    exactly) and then stops until the next call, in the same order as all at once, so it finds
    what one call would have found, some calls later. While it runs (see :attr:`planning`), with
    status ``PROCESSING``, the chain heads for the solver's answer if that is still on its way
    (``PROCESSING``) and it and the straight way to it are clear; else it goes on along the plan
    it has for an earlier target, if any; else it holds the pose it was last sent to, which it
    was heading for along a way checked clear (else the pose it was in when the search began,
    where the route will start). A search goes on when the target moves meanwhile (a target that
    moves every tick would otherwise never get one): its plan is followed while one for the new
    target is searched for, and the chain is routed again from where it is when the first piece
    of a finished plan is not clear from there. It is dropped when the solver's answer needs
    none.

    >>> arm = Skeleton.chain([100.0, 100.0], base_angle=math.pi / 2)
    >>> shelf = Obstacles.from_arrays(np.array([[-50.0, 150.0, 50.0, 150.0, 0.0]]), np.empty((0, 3)))
    >>> guide = Avoider(Clearance(arm, np.full(2, 5.0), shelf), budget=ITERATION_UNITS)
    >>> through = Solution(np.zeros(2), SolveStatus.SUCCESS, 1, 0.0)  # straight up, through it
    >>> at = np.array([-1.0, 0.0])
    >>> steered = guide.steer(at, through, np.array([0.0, 200.0]), 160.0)
    >>> guide.planning, steered.status.name, steered.angles.tolist()  # holds while it searches
    (True, 'PROCESSING', [-1.0, 0.0])
    >>> while guide.planning:
    ...     steered = guide.steer(at, through, np.array([0.0, 200.0]), 160.0)
    >>> guide.clearance.is_clear(steered.angles)
    True
    """

    def __init__(
        self,
        clearance: Clearance,
        *,
        replan: bool = False,
        tick_rate: float = 240.0,
        budget: float | None = None,
    ) -> None:
        if not (math.isfinite(tick_rate) and tick_rate > 0):
            raise ValueError(
                f"tick_rate must be a positive number of calls a second, got {tick_rate!r}"
            )
        budget = SEARCH_RATE / tick_rate if budget is None else budget
        if not budget > 0:
            raise ValueError(f"budget must be a positive number of work units, got {budget!r}")
        # numpy loads its random module on first use (several ms): load it with the avoider,
        # not in the tick of its first search.
        import numpy.random  # noqa: F401

        self.clearance = clearance
        self.replan = replan
        """Whether to route again from where the chain is when the way on is blocked."""
        self.budget = budget
        """Units of search work one call does at most before its last step (``math.inf``: the
        whole search in one call)."""
        # RELEASE_S and PINNED_S in calls.
        self._release_after = max(1, round(RELEASE_S * tick_rate))
        self._pinned_after = max(1, round(PINNED_S * tick_rate))
        self._skeleton = clearance.skeleton
        self._held_off: np.ndarray | None = None
        self._carried: tuple[Skeleton, np.ndarray, np.ndarray, bool] | None = None
        self.reset()

    def reset(self) -> None:
        """Forget the clear answer, the route, any search and the pose last commanded (say,
        after the chain was found blocked)."""
        self._forget()
        self._commanded: np.ndarray | None = None
        self._traveled: list[np.ndarray] = []
        self._unchecked = False
        self._ahead: _Ahead | None = None
        # The key of the target last steered for, and whether that call did search work.
        self._steered: tuple[float, ...] | None = None
        self._worked = False

    def _forget(self) -> None:
        """Forget the clear answer, the route and any search."""
        self._target: tuple[float, ...] | None = None
        self._goal: np.ndarray | None = None
        self._way: list[np.ndarray] = []
        self._origin: np.ndarray | None = None
        # Whether the plan was taken up on the last call, from a search the solver's answer
        # could have dropped (see _steer).
        self._set_out = False
        self._given_up: tuple[float, ...] | None = None
        self._tolerance: float | np.ndarray = 0.0
        self._jammed = False
        self._resting = 0
        self._rest_misses = np.zeros(0)
        # Where the chain came to rest with a link pressed into an obstacle, and for how many
        # calls it has stayed there (see _pinned).
        self._pin: np.ndarray | None = None
        self._pinned_calls = 0
        # The last pose _pinned measured clear, and its links' gaps.
        self._clear_at: tuple[np.ndarray, np.ndarray] | None = None
        self._line: tuple[np.ndarray, np.ndarray, float] | None = None
        self._checked: tuple[np.ndarray, np.ndarray] | None = None
        self._search: _Search | None = None

    @property
    def planning(self) -> bool:
        """True while a search is spread over calls (the chain waits, see the class)."""
        return self._search is not None

    @property
    def jammed(self) -> bool:
        """True while the chain is sent to the clear pose nearest a target the obstacles keep
        every clear pose from (under the floor, say): it comes to rest there, held off them,
        instead of pressing into them, and is as stuck as one pressing. Not while a search for
        a target since runs."""
        return self._jammed and self._goal is not None and self._search is None

    @property
    def idle(self) -> bool:
        """True when the solver's answer is commanded as it is: no search, and no plan being
        followed (each call then only checks the answer and the way to it)."""
        return self._search is None and self._goal is None

    def steer(
        self,
        measured: np.ndarray,
        solution: Solution,
        target: np.ndarray | TargetSet,
        tolerance: float,
    ) -> Solution:
        """The solution to command this tick (see the class): ``target`` is a chain's point or
        a tree's :class:`~ikgame.kinematics.targets.TargetSet` (kept until any of its points
        moves)."""
        self._unchecked = False
        steered = self._steer(self._turned(measured), solution, target, tolerance)
        # The solver's answer handed on unchecked is no pose to wait at.
        self._commanded = None if self._unchecked else steered.angles
        return steered

    def _turned(self, measured: np.ndarray) -> np.ndarray:
        """The ``measured`` pose, its free joints read as the turns nearest the pose commanded
        last while a plan is followed: they are measured within [-pi, pi], but a planned line
        can run on past a half turn (round an obstacle the long way), and the chain would be
        taken for back at the line's start."""
        last = self._commanded
        if not self._way or last is None:
            return measured
        free = ~self.clearance.skeleton.limited
        turned = last + np.remainder(measured - last + math.pi, 2.0 * math.pi) - math.pi
        return np.where(free, turned, measured)

    def _steer(
        self,
        measured: np.ndarray,
        solution: Solution,
        target: np.ndarray | TargetSet,
        tolerance: float,
    ) -> Solution:
        """:meth:`steer`, but for noting the pose commanded."""
        room = self.clearance
        if room.skeleton is not self._skeleton:
            # The base moved: a plan made for it is stale, and one made now would be stale by the
            # next tick, so the solver answers until the base stands still again, held off the
            # obstacles.
            self._skeleton = room.skeleton
            self.reset()
            self._unchecked = True
            return self._hold_off(solution, target, tolerance)
        self._held_off = self._carried = None
        key = _key(target)
        self._steered = key
        if key == self._given_up:
            self._unchecked = True
            return solution
        if self._search is None and key != self._target:
            self._take_ahead(key, measured)
        search = self._search
        if search is None and self._goal is not None and key == self._target:
            set_out, self._set_out = self._set_out, False
            if set_out and not self._needs(measured, solution)[0]:
                # The solver's answer arrived, clear and clear to turn to, on the call after
                # the search ended: its plan is dropped as the search would have been one
                # call slower. (Taken up, the ways round held weak arms under heavy gravity
                # to the pace of their slowest joint: 69's reached its second target only as
                # the step timed out, and 80's stalled on its way, blocked 286 px off.)
                self._drop()
                return solution
            if not self._arrived(measured, target):
                if not (self.replan or self._pinned(measured)) or self._clear_way(
                    measured, self._way[0]
                ):
                    return self._follow(measured, solution)
                # The motors left the planned line (joints at their speed or torque limits at
                # different times) and the way on from here is blocked: plan again from here.
                work = self._rerouting(measured, self._goal, self._tolerance, jammed=self._jammed)
                search = self._begin(key, measured, work, reroute=True)
                return self._advance(search, measured, solution)
            self._forget()
        if search is None or not (search.reroute and search.key == key):
            needed, goal = self._needs(measured, solution)
            if not needed:
                self._drop()
                return solution
            if search is None:
                work = self._planning(measured, solution.angles, target, tolerance, goal)
                search = self._begin(key, measured, work, reroute=False)
        return self._advance(search, measured, solution)

    def _hold_off(
        self, solution: Solution, target: np.ndarray | TargetSet, tolerance: float
    ) -> Solution:
        """While the base carries the skeleton: the solver's answer, until the answers bring a
        link within ``ACTIVE`` px of the margin of an obstacle nearer it; from then on, until no
        link is that near, the pose held off the obstacles on the last call (the answer, on the
        first) polished onto the target for where the base is now, so that the links near an
        obstacle come no nearer (and back out to the margin) as the base carries them by. A
        solver at rest on the target answers with the pose it measures, which leaves the links
        to the motors' feed-forward: it holds the target, blind to the obstacles."""
        gaps, closing = self._carried_gaps(solution.angles)
        if gaps.min() >= self.clearance.margin + ACTIVE or (self._held_off is None and not closing):
            self._held_off = None
            return solution
        start = solution.angles if self._held_off is None else self._held_off
        polished = self.clearance.polish(
            start, target, iterations=HOLD_OFF_ITERATIONS, tolerance=tolerance
        )
        self._held_off = polished.angles
        # An unreachable target stays a failure, held off the obstacles or not.
        status = solution.status if solution.status is SolveStatus.FAILURE else polished.status
        return Solution(polished.angles, status, solution.iterations, polished.error)

    def _carried_gaps(self, pose: np.ndarray) -> tuple[np.ndarray, bool]:
        """Each link's gap (px) at the carried skeleton's ``pose``, and whether a link within
        ``ACTIVE`` px of the margin has come nearer since the gaps were measured before (a first
        link the base slides along a floor stays as near, and does not count).

        The gaps are measured again only when the base and the joints could have carried a link
        into that reach since the last measure, and then more than ``CARRIED_STEP`` px; until
        then the last measure stands."""
        room = self.clearance
        skeleton = room.skeleton
        reach = room.margin + ACTIVE
        carried = self._carried
        if carried is not None:
            was, since, gaps, closing = carried
            shift = math.dist(skeleton.base, was.base)
            shift += abs(skeleton.base_angle - was.base_angle) * skeleton.reach
            moved = shift + room.swept_links(since, pose)
            if np.all((gaps - moved >= reach) | (moved <= CARRIED_STEP)):
                return gaps, closing
        fresh = room.gaps(pose)
        closing = carried is not None and bool(np.any((fresh < reach) & (fresh < carried[2])))
        self._carried = (skeleton, pose.copy(), fresh, closing)
        return fresh, closing

    def _begin(
        self,
        key: tuple[float, ...],
        measured: np.ndarray,
        work: _Work[_Plan | None],
        *,
        reroute: bool,
    ) -> _Search:
        """Start a search from ``measured`` for the target of ``key`` (with ``reroute``, a new
        route for the current plan): the chain waits at the pose last commanded, which it was
        heading for along a way checked clear, if there is one (not the solver's answer handed
        on unchecked), else where it is (for a new route always: the way on from here is what
        was blocked)."""
        start = np.array(measured, dtype=float)
        last = self._commanded
        hold = start if reroute or last is None else last
        self._search = _Search(key, work, start, hold, reroute)
        return self._search

    def _planning(
        self,
        start: np.ndarray,
        answer: np.ndarray,
        target: np.ndarray | TargetSet,
        tolerance: float,
        goal: np.ndarray | None,
    ) -> _Work[_Plan | None]:
        """The search for a target: a route to ``goal``, else (or when it is None) to a clear
        answer, else, when the obstacles keep every clear pose from the target, to the clear pose
        nearest it (a jammed plan). A ``goal`` with a joint on its stop comes after a clear
        answer off the stops (see :meth:`Clearance.clear_answer`), before any on them."""
        room = self.clearance
        start = np.array(start, dtype=float)
        if goal is not None and room.off_stops(goal):
            plan = yield from self._rerouting(start, goal, tolerance, target)
            if plan is not None:
                return plan
            # The solver's clear answer can lie where no clear way leads (a fold the joint
            # limits shut in behind an obstacle); an answer polished from the seeds may not.
            goal = None
        # The solver's clear answer on a stop: a way to it is searched for only when no clear
        # answer off the stops is found, or no way to one.
        pressed = goal
        found = yield from room._answering(start, answer, target, tolerance)
        if pressed is not None and (found is None or not room.off_stops(found[0])):
            plan = yield from self._rerouting(start, pressed, tolerance, target)
            if plan is not None:
                return plan
            pressed = None
        if found is None:
            return None
        goal, straight, jammed = found
        arrival = self._arrival(goal, target, tolerance)
        if straight:
            # The straight way to it was just checked clear: the route is that line.
            return goal, [goal], arrival, jammed
        if jammed:
            return (yield from self._jamming(start, goal, target, tolerance))
        plan = yield from self._rerouting(start, goal, arrival, target)
        if plan is None and pressed is not None:
            plan = yield from self._rerouting(start, pressed, tolerance, target)
        return plan

    def _jamming(
        self,
        start: np.ndarray,
        nearest: np.ndarray,
        target: np.ndarray | TargetSet,
        tolerance: float,
    ) -> _Work[_Plan]:
        """A jammed plan: a route to the clear pose ``nearest`` the target, if one is found
        within ``JAMMED_WORK``; else the clear pose the polish draws ``start`` to toward the
        target, when the straight way to it is clear; else ``start``: a chain that cannot reach
        the target comes to rest near it, not pressing into what keeps it off (a search for a
        way that does not exist would run on for millions of units)."""
        room = self.clearance
        # Where the ends come nearest a target they never reach is no cut to make.
        plan = yield from _capped(
            self._rerouting(start, nearest, tolerance, jammed=True), JAMMED_WORK
        )
        if plan is None:
            near = yield from room._polishing(start, target, POLISH_ITERATIONS, tolerance, True)
            clear = room.is_clear(near.angles)
            goal = (
                near.angles if clear and (yield from room._checking(start, near.angles)) else start
            )
            plan = goal, [goal], tolerance, True
        return plan[0], plan[1], self._arrival(plan[0], target, tolerance), True

    def _arrival(
        self, goal: np.ndarray, target: np.ndarray | TargetSet, tolerance: float
    ) -> np.ndarray:
        """The tolerance (px, per target) to arrive at ``goal`` within: ends it leaves short of
        their targets (out of reach, or kept off by obstacles) arrive within ``tolerance`` of
        where it leaves them."""
        misses = self.clearance.misses(goal, target)
        return np.where(misses > tolerance, misses + tolerance, tolerance)

    def _rerouting(
        self,
        start: np.ndarray,
        goal: np.ndarray,
        tolerance: float | np.ndarray,
        target: np.ndarray | TargetSet | None = None,
        *,
        jammed: bool = False,
    ) -> _Work[_Plan | None]:
        """The search for a route from ``start`` to ``goal``: the plan (``jammed`` when the goal
        is only the clear pose nearest the target), or None. With the ``target``, a route that
        takes the targeted ends past it and back is cut where they come nearest (see
        :meth:`Clearance._trimming`)."""
        start = np.array(start, dtype=float)
        room = self.clearance
        # A jammed goal is only where the chain comes to rest short of a target it cannot
        # reach, and its search is cut short (``JAMMED_WORK``): the sliding trees found ways
        # to it where the straight ones found others, and on ``34_chain40_pressed_to_floor``
        # DLS's chain, resting elsewhere, took 0.64 s longer to the next target.
        way = yield from room._routing(start, goal, self._traveled[::-1], slide=not jammed)
        if way is None:
            return None
        if target is not None:
            way = yield from room._trimming(start, way, target, float(np.min(tolerance)))
        return way[-1], way, tolerance, jammed

    def foresee(
        self,
        measured: np.ndarray,
        target: np.ndarray | TargetSet,
        tolerance: float,
        solve: Callable[[np.ndarray, np.ndarray | TargetSet], Solution],
    ) -> None:
        """Plan ahead for ``target``, the one that will follow the target steered for now, for
        a chain at rest in the ``measured`` pose: on a call after one that did no search work,
        do up to ``budget`` units of the search :meth:`steer` would begin for ``target`` from
        there, with ``solve(pose, target)``, the solver's answer from there. That is asked again,
        with the same pose array, on each call while the answer is on its way, as the chain's
        own solver is asked while the chain waits for a search; the search's work is done once
        the answer has arrived and still needs it (not clear, or not clear to turn to), so no
        work goes into a search :meth:`steer` would drop. When ``target`` comes, a chain still
        within ``SETTLED`` of that pose on every joint takes up that search as its own, done or
        part done (unless the answer its solver gives then needs none: see :meth:`steer`), so a
        level's next way is searched while its chain holds a target. (Planned from the pose the
        chain is sent to instead, before it rests there, the solver's answer from it can be
        another than from where the chain comes to rest: a long chain sags under gravity, and
        FABRIK's thirty links of ``48_chain30_gravity`` took 1.5 s instead of 0.6 to the goal it
        gave.)

        >>> arm = Skeleton.chain([100.0, 100.0], base_angle=math.pi / 2)
        >>> shelf = Obstacles.from_arrays(np.array([[-50.0, 150.0, 50.0, 150.0, 0.0]]), np.empty((0, 3)))
        >>> guide = Avoider(Clearance(arm, np.full(2, 5.0), shelf))
        >>> at = np.array([-1.0, 0.0])
        >>> held = guide.steer(at, Solution(at, SolveStatus.SUCCESS, 1, 0.0), np.zeros(2), 1.0)
        >>> through = Solution(np.zeros(2), SolveStatus.SUCCESS, 1, 0.0)  # straight up, through it
        >>> for tick in range(60):
        ...     guide.foresee(at, np.array([0.0, 200.0]), 1.0, lambda pose, target: through)
        >>> steered = guide.steer(at, through, np.array([0.0, 200.0]), 1.0)
        >>> guide.planning, guide.clearance.is_clear(steered.angles)  # its way was ready
        (False, True)
        """
        worked, self._worked = self._worked, False
        key = _key(target)
        if worked or self._search is not None or key == self._steered:
            return
        start = self._turned(measured)
        ahead = self._ahead
        if ahead is None or ahead.search.key != key or not _within(start, ahead.search.start):
            answer = solve(start, target)
            needed, goal = self._needs(start, answer)
            work = self._planning(start, answer.angles, target, tolerance, goal)
            ahead = self._ahead = _Ahead(_Search(key, work, start, start, False), answer)
            ahead.needless = not needed
        elif not ahead.needless and ahead.answer.status is SolveStatus.PROCESSING:
            # The chain waits while its search runs, and its solver answers from where it
            # waits, tick after tick, until the answer arrives (and may need no search).
            ahead.answer = solve(ahead.search.start, target)
            ahead.needless = not self._needs(ahead.search.start, ahead.answer)[0]
        if not ahead.needless and ahead.answer.status is not SolveStatus.PROCESSING:
            self._run(ahead.search)

    def _needs(self, measured: np.ndarray, solution: Solution) -> tuple[bool, np.ndarray | None]:
        """Whether the solver's ``solution`` from ``measured`` needs a search, and the goal to
        route to: none when every link is far enough from every obstacle, or the answer arrived
        clear and clear to turn to; an answer that arrived clear is the goal, and one still on
        its way (PROCESSING) is no goal (a clear one that arrives is searched for instead)."""
        if self._far_enough(measured, solution.angles):
            return False, None
        if solution.status is SolveStatus.PROCESSING or not self.clearance.is_clear(
            solution.angles
        ):
            return True, None
        if self._clear_way(measured, solution.angles):
            return False, None
        return True, solution.angles

    def _take_ahead(self, key: tuple[float, ...], measured: np.ndarray) -> None:
        """Take up the search :meth:`foresee` planned for the target of ``key``, if the chain
        rests within ``SETTLED`` of the pose it started from and the solver's answer there
        needed it."""
        ahead = self._ahead
        if ahead is None or ahead.search.key != key:
            return
        self._ahead = None
        search = ahead.search
        if ahead.needless or not _within(measured, search.start):
            return
        last = self._commanded
        search.hold = measured.copy() if last is None else last
        self._search = search

    def _run(self, search: _Search) -> bool:
        """Do up to ``budget`` units of ``search``'s work; True once it is done."""
        spent = 0.0
        try:
            while not search.done and spent < self.budget:
                spent += next(search.work)
        except StopIteration as finished:
            search.done, search.plan = True, finished.value
        return search.done

    def _advance(self, search: _Search, measured: np.ndarray, solution: Solution) -> Solution:
        """Do this call's share of the search; once it is done, take up its plan."""
        self._worked = True
        if not self._run(search):
            return self._wait(search, measured, solution)
        plan = search.plan
        self._search = None
        if plan is None:
            # Searched once for this target: the solver's own answer it is, until it moves.
            self._drop()
            self._given_up = search.key
            self._unchecked = True
            return solution
        self._target, (self._goal, self._way, self._tolerance, self._jammed) = search.key, plan
        # A route round an obstacle is remembered from where it started: the next target's way
        # can be the same way back.
        self._traveled = [search.start, *self._way] if len(self._way) > 1 else []
        # Every plan is followed piece by piece on its checked lines, a straight way to the goal
        # too: sent to a far goal in one go, the joints with far to turn lag the others, and the
        # ends can come onto the target with a joint still far off, and swing on past it.
        self._origin = measured.copy()
        # A search that routes the plan again drops for no answer of the solver's (see _steer).
        self._set_out = not search.reroute
        moved = not np.array_equal(measured, search.start)
        if moved and not self._clear_way(measured, self._way[0]):
            # The chain went on (along an earlier plan, or drifting while it held) and the
            # first piece is not clear from where it is now: route again from here.
            work = self._rerouting(measured, self._goal, self._tolerance, jammed=self._jammed)
            return self._wait(
                self._begin(search.key, measured, work, reroute=True), measured, solution
            )
        return self._follow(measured, solution)

    def _wait(self, search: _Search, measured: np.ndarray, solution: Solution) -> Solution:
        """What to command while ``search`` runs: the solver's answer still on its way, when it
        and the straight way to it are clear (a pose on the way to the target, if no goal); else
        on along an earlier target's plan; else hold (see :meth:`_begin`)."""
        pose = search.hold
        if not search.reroute:
            answer = solution.angles
            on_its_way = solution.status is SolveStatus.PROCESSING
            if on_its_way and self.clearance.is_clear(answer) and self._clear_way(measured, answer):
                pose = answer
            elif self._way:
                pose = self._follow(measured, solution).angles
        return Solution(pose, SolveStatus.PROCESSING, solution.iterations, solution.error)

    def _drop(self) -> None:
        """Forget the plan and any search: the solver's answer is commanded as it is."""
        self._target, self._goal, self._way, self._search = None, None, [], None
        self._jammed = False
        self._origin = None
        self._set_out = False

    def _arrived(self, measured: np.ndarray, target: np.ndarray | TargetSet) -> bool:
        """Whether the solver may answer again: the chain has rested on the clear goal (within
        ``SETTLED`` of it on every joint, no targeted end coming more than the goal's tolerance
        nearer its target or farther from it) for ``RELEASE_S`` with a targeted end still
        farther than the tolerance from its target (sagging short, say), where re-solving
        from the measured pose brings it the last pixels. A long chain within ``SETTLED`` on
        every joint can still be far from its goal, still closing in, and is not at rest.

        A jammed chain (:attr:`jammed`) keeps its goal until the target moves: no clear pose
        reaches the target, and the solver's answer would press it into the obstacle.

        A chain resting on the goal with its end effector on the target keeps the goal until
        the target moves: the solver's own answer (CCD's from a pose a few px short, or one it
        followed before) can be another pose, and swinging over to it overshoots.
        """
        if self._jammed or not _within(measured, self._goal):
            self._resting = 0
            return False
        misses = self.clearance.misses(measured, target)
        if self._resting == 0 or np.any(np.abs(misses - self._rest_misses) > self._tolerance):
            self._resting, self._rest_misses = 0, misses
        self._resting += 1
        if self._resting < self._release_after:
            return False
        return bool(np.any(misses > self._tolerance))

    def _pinned(self, measured: np.ndarray) -> bool:
        """Whether the chain has rested (within ``SETTLED`` on every joint) for ``PINNED_S``
        with a link pressed into an obstacle: the motors carried it off the planned line
        into one, and it stays there. A link that brushes an obstacle on its way along the
        line (a long chain low over the floor) moves on, and keeps its route.

        Asked on every tick a chain follows a route, so the gaps are measured only when the
        last clear pose measured no longer proves them: a link's gap shrinks no faster than
        its points move (:meth:`Clearance.swept_links`)."""
        room = self.clearance
        if self._clear_at is not None:
            pose, gaps = self._clear_at
            if float((gaps - room.swept_links(pose, measured)).min()) > 1e-6:
                self._pin = None
                return False
        gaps = room.gaps(measured)
        if gaps.min() >= 0.0:
            self._clear_at = (measured.copy(), gaps)
            self._pin = None
            return False
        self._clear_at = None
        if self._pin is None or not _within(measured, self._pin):
            self._pin, self._pinned_calls = measured.copy(), 0
        self._pinned_calls += 1
        return self._pinned_calls >= self._pinned_after

    def _clear_way(self, measured: np.ndarray, pose: np.ndarray) -> bool:
        """Whether the straight line from ``measured`` to ``pose`` is clear.

        A chain moving along a line checked before is on it still, give or take: every pose of
        the new line is within ``slack`` px (the larger of how far the chain is off the old line
        and how far the new end is from the old one) of a pose of the old line's rest, so the
        old line's smallest gap less that slack bounds the new one's, and the line is sampled
        afresh only when that bound runs out. Nor is a link sampled along the line that its
        gaps at the two ends prove clear (:meth:`Clearance._line_bound`): the answer is the
        same, and over the conductor's run a quarter as many links are measured (this check
        is outside the search's budget, on any tick the chain heads straight near obstacles).
        """
        room = self.clearance
        floor = room.margin / 2.0
        line = self._line
        if line is not None:
            start, end, gap = line
            d = end - start
            span = float(d @ d)
            s = 0.0 if span == 0.0 else min(max(float((measured - start) @ d) / span, 0.0), 1.0)
            slack = max(room.swept(start + s * d, measured), room.swept(end, pose))
            if gap - slack >= floor:
                return True
        bar, proven, kept = room._line_bound(measured, pose, floor)
        least = float(kept[proven].min()) if proven.any() else math.inf
        if not proven.all():
            gaps = room._gaps(room.points(room._samples(measured, pose)), np.flatnonzero(~proven))
            sampled = gaps.min(axis=-1)
            if not np.all(sampled[1:] >= bar):
                self._line = None
                return False
            least = min(least, float(sampled.min()))
        self._line = (measured.copy(), pose.copy(), least)
        return True

    def _far_enough(self, measured: np.ndarray, pose: np.ndarray) -> bool:
        """Whether every link is so far from every obstacle that neither ``pose`` nor the way
        to it can bring it into one (link by link: a torso standing on the floor while its arms
        swing above is far enough). The gaps are measured afresh only when the motion since the
        last measure could have used one up, so a chain at rest or in the open costs two products
        of the links' levers with the joints' changes."""
        room = self.clearance
        ahead = room.swept_links(measured, pose)
        checked = self._checked
        if checked is not None:
            since, gaps = checked
            if np.all(gaps - room.swept_links(since, measured) - ahead >= 0.0):
                return True
        gaps = room.gaps(measured)
        self._checked = (measured.copy(), gaps)
        return bool(np.all(gaps - ahead >= 0.0))

    def _follow(self, measured: np.ndarray, solution: Solution) -> Solution:
        """The pose to head for: the next via pose once the chain, near the current one (within
        ``AHEAD`` px of sweep), can turn to it in a clear straight line, or once it rests on the
        current one (within ``SETTLED``: each piece is clear from its start, and the chain is
        there); a pose on the next piece instead of the current via pose where the corner there
        can be cut on the move (see :meth:`_corner`). Not the via pose itself, but the pose on
        the piece's line at most ``LEAD`` radians ahead of the joint that has come the least
        far along it (see :meth:`_lead`)."""
        room = self.clearance
        way = self._way
        while len(way) > 1:
            near = room.swept(measured, way[0]) <= AHEAD
            if near and room.path_clear(measured, way[1]):
                del way[0]
                self._origin = measured.copy()
            elif _within(measured, way[0]):
                self._origin = way.pop(0)
            else:
                cut = self._corner(measured, way[0], way[1])
                if cut is way[1]:
                    del way[0]
                elif cut is not None:
                    way[0] = cut
                if cut is not None:
                    self._origin = measured.copy()
                break
        status = SolveStatus.PROCESSING if len(way) > 1 else solution.status
        pose = self._lead(measured, self._origin, way[0])
        return Solution(pose, status, solution.iterations, solution.error)

    def _corner(
        self, measured: np.ndarray, via: np.ndarray, onward: np.ndarray
    ) -> np.ndarray | None:
        """The lead on the next piece (from the ``via`` pose toward ``onward``, see
        :meth:`_lead`) to head for instead of the via pose, or None: once the lead on this
        piece has come to the via pose, where the lines from the chain at ``measured`` to where
        it could run on to along this piece while it stops (``LEAD`` past the via pose, as far
        as the servo's braking from a lead away carries it), from there to that lead, and
        straight to it are all clear (:meth:`Clearance.path_clear`). The lead takes the via
        pose's place in the way, the chain's pose the origin's, so every line the chain is
        sent along was checked clear from where it was; heading for it, the corner it cuts
        can be cut again, further on.

        Where the line on from the chain to the next via pose is blocked until the chain is
        nearly on the one before (a corner round an obstacle), the chain braked to rest at
        every via pose: on `66_round_rocks_low_gaps` (CCD, from beyond the right rock to low
        in front of the left one) a way of seven pieces took 3.9 s to follow, about 0.3 s of
        it at each corner slowing down and speeding up again, and the arm arrived 4.4 s into
        a 5 s step that asks a 1 s hold; cutting corners, 3.4 s. Checked only along the
        straight line to the lead on the next piece, the chain cut them too soon: on
        `39_five_links_under_shelf_left` (DLS) its momentum, its fastest joint at 3.6 rad/s,
        carried it into the shelf's underside, and the step ended `blocked`.
        """
        origin = self._origin
        if self._lead(measured, origin, via) is not via:
            return None
        span = via - origin
        largest = float(np.abs(span).max())
        past = via + (LEAD / largest) * span if largest > 0.0 else via
        ahead = self._lead(measured, via, onward)
        room = self.clearance
        if (
            room.path_clear(measured, past)
            and room.path_clear(past, ahead)
            and room.path_clear(measured, ahead)
        ):
            return ahead
        return None

    @staticmethod
    def _lead(measured: np.ndarray, origin: np.ndarray, via: np.ndarray) -> np.ndarray:
        """The pose on the line from ``origin`` to ``via`` at most ``LEAD`` radians (on the
        joint that turns most) ahead of how far along it the laggard of the joints has come.

        The motors do not keep to a line: the outer joints, turning less mass, speed up sooner
        than the inner ones, and a chain sent straight to a far via pose leads with its last
        links, which can press them into the obstacle the line kept clear of. Held to a pose
        just ahead of the slowest joint, the others wait for it, and the chain keeps near the
        line it was checked along."""
        span = via - origin
        largest = float(np.abs(span).max())
        if largest <= LEAD:
            return via
        turning = np.abs(span) > 0.1 * largest
        along = float(np.min((measured - origin)[turning] / span[turning]))
        ahead = max(along, 0.0) + LEAD / largest
        return via if ahead >= 1.0 else origin + ahead * span


_Plan = tuple[np.ndarray, list[np.ndarray], float | np.ndarray, bool]
"""A found plan: the clear goal, the via poses to it (the goal last), the tolerance to arrive
within and whether it is jammed (the goal only the clear pose nearest a target the obstacles
keep every clear pose from)."""


@dataclass(eq=False)
class _Ahead:
    """A search begun ahead for the next target (see :meth:`Avoider.foresee`), the solver's
    latest answer from the pose it starts from, and whether that answer needs no search (which
    :meth:`Avoider._steer` would then drop)."""

    search: _Search
    answer: Solution
    needless: bool = False


@dataclass(eq=False)
class _Search:
    """A search spread over an :class:`Avoider`'s calls: the target it is for (its key), its
    work, the pose it starts from, the pose to hold meanwhile and whether it routes the current
    plan again; once its work is done, the plan it found (or None)."""

    key: tuple[float, ...]
    work: _Work[_Plan | None]
    start: np.ndarray
    hold: np.ndarray
    reroute: bool
    done: bool = False
    plan: _Plan | None = None


def _within(pose: np.ndarray, other: np.ndarray) -> bool:
    """Whether ``pose`` is within ``SETTLED`` of ``other`` on every joint."""
    return bool(np.abs(pose - other).max() <= SETTLED)


def _key(target: np.ndarray | TargetSet) -> tuple[float, ...]:
    """What identifies a target: a point's coordinates, or a target set's links then points."""
    if isinstance(target, TargetSet):
        return (*map(float, target.links), *map(float, target.points.ravel()))
    return (float(target[0]), float(target[1]))


def _marks(way: np.ndarray, step: float) -> np.ndarray:
    """(k, 2) points along the (m, 2) ``way`` (px), ``step`` px apart at most and evenly spread,
    its first point excluded and its last included.

    >>> _marks(np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 5.0]]), 6.0).tolist()
    [[5.0, 0.0], [10.0, 0.0], [10.0, 5.0]]
    """
    along = np.concatenate(([0.0], np.cumsum(np.hypot(*np.diff(way, axis=0).T))))
    count = max(1, math.ceil(along[-1] / step))
    marks = np.linspace(0.0, along[-1], count + 1)[1:]
    return np.column_stack([np.interp(marks, along, way[:, k]) for k in range(2)])


def _least_gap(floor: float, start: float) -> float:
    """The smallest gap (px) a path starting ``start`` px clear may come to: ``floor``, or no
    closer than its start already is when that is closer still."""
    return min(floor, start - 1e-9)


def _distance_to(x: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance from each x to the nearest point of each segment a-b (broadcast), px."""
    offset = _nearest_on(x, a, b) - x
    return np.hypot(offset[..., 0], offset[..., 1])


def _nearest_on(x: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The point of each segment a-b nearest each x (broadcast), px."""
    # Written out by coordinate: on arrays of a few dozen points numpy's per-call cost is the
    # whole cost, and np.sum and np.clip cost several times a plain product or bound.
    ab = b - a
    ax = x - a
    abx, aby = ab[..., 0], ab[..., 1]
    u = (ax[..., 0] * abx + ax[..., 1] * aby) / np.maximum(abx * abx + aby * aby, 1e-12)
    return a + np.minimum(np.maximum(u, 0.0), 1.0)[..., None] * ab


def _crossing(p0: np.ndarray, p1: np.ndarray, q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
    """(..., n, k) whether link segments p0-p1 (..., n, 2) cross obstacle segments q0-q1 (k, 2)."""
    r = (p1 - p0)[..., :, None, :]
    s = (q1 - q0)[None, :, :]
    qp = q0[None, :, :] - p0[..., :, None, :]
    cross = r[..., 0] * s[..., 1] - r[..., 1] * s[..., 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (qp[..., 0] * s[..., 1] - qp[..., 1] * s[..., 0]) / cross
        u = (qp[..., 0] * r[..., 1] - qp[..., 1] * r[..., 0]) / cross
    return (cross != 0) & (t > 0) & (t < 1) & (u > 0) & (u < 1)
