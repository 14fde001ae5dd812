"""Solving tick after tick without getting trapped: restarts on a stall, and a per-chain cache.

The raw solvers are local: from a warm start they slide downhill, and joint limits make the
landscape full of places to stop short of a target that some pose within the limits reaches (a
base on its -30 deg stop when the answer needs +100 deg, a chain coiled into its limits, an elbow
that bends one way only). :class:`RobustSolver` wraps one of them for one chain and is called
once per tick:

1. **Cached answer.** An answer that a restart from a far seed found is returned as it is,
   with zero iterations, while it still puts the end effector within the tolerance of the target
   and until the chain has arrived on it (every joint within ``SETTLED``): a chain on its way to
   an answer found the long way round keeps heading there instead of falling back into the trap
   or flipping to another branch half way (hysteresis). The best pose for a target no pose
   reaches is returned, for nothing, for as long as that target stays.
2. **Plain solve** from the measured pose, as the raw solver is called without this class: its
   answer is the nearest to where the chain is. When it arrives, or is still making headway,
   that is the answer: the common case costs the raw solver's iterations. But while the chain
   comes in to the last answer, which still reaches (and the motors can hold), a fresh answer
   more than ``JUMPED`` times as far from the chain, or a plain solve stuck short of the target,
   gives way to the last answer: a solver whose answer is not continuous in its start (FABRIK
   against tight limits) would otherwise hand the chain a goal of another shape every tick.
   A target that moves on every call (one the chain follows) gets the plain answer that
   arrives slid off the joints' stops along the poses that keep the end where it is, while a
   limited joint is within ``OFF_STOPS`` of one: a follower pressed against its stops has no
   room left to follow with, and one coiled into them is trapped.
3. **Recovery**, only when the plain solve stalled short of a target within reach: ``FAILURE``;
   ``PROCESSING`` having gained less than ``STALL_PROGRESS`` of its start error; or
   ``STALL_CALLS`` calls on one target without arriving. It restarts from other seeds, the
   nearest to the chain first. Damped least squares goes first, from the stalled pose and from
   that pose moved ``BACK_OFF`` off the limits (and before them from the measured pose, when the
   stalled one has wandered ``WANDERED`` from it: a stalled CCD answer can coil far from the
   chain): its steps are the shortest that move the end effector, so it finds the answer
   nearest the pose. Once the target has held still for
   ``STILL_CALLS`` calls (a moving target would be elsewhere by the time the chain had swung
   round), far seeds follow, each run by the solver and then by its ``FALLBACK`` from the seed
   too: each of the first ``ROUND_JOINTS`` joints turned to aim at the target the other way
   round its limits; the pose mirrored across the line from the base to the target, and with its
   bends reversed; the chain stretched toward the target; the middle of every joint's range;
   ``RANDOM_SEEDS`` poses drawn within the limits by a generator seeded with ``RANDOM_SEED`` (the
   same inputs give the same answers). The first seed that arrives wins; otherwise the lowest
   error is kept. A call spends at most ``budget`` iterations on restarts; a search that runs out
   carries on at the next call with the same target, and one that has tried every seed is cached
   as ``FAILURE``, so an unreachable target costs nothing after that. When the target moves on
   before a search arrives, no new search starts for ``RETRY_CALLS`` calls.

A target beyond the chain's reach gets the chain stretched straight toward it at once, when the
limits allow that pose (it is the closest any pose can come), with ``FAILURE``.

With :attr:`RobustSolver.strain` set (what holding a pose still takes of the motors, which only
the caller knows: this package knows no dynamics), a plain answer, arrived or still on its way,
that takes more than ``STRAINED`` of some motor's limit starts, once the target has held still
for ``STILL_CALLS`` calls, the same restarts (with
``HOLD_SEEDS`` random poses, then the answer slid along the poses that keep the end on the
target toward one the motors hold), in which only an arrival within ``HOLDS`` counts. The first
one the chain can get to through poses the motors hold (every pose checked on the straight line
in joint space from the chain's, :func:`holds_along`) and that leaves them room to brake (within
``SPENT``) is followed like a far seed's answer; the first that leaves them less room, or that
they hold only at rest, is served while the search goes on, and followed once every seed has
been tried. Until one is found the chain waits where the search began; once every seed has
failed, the target asks more than the motors have, and the answer is the pose nearest it that
they hold (:func:`held_nearest`), a ``FAILURE`` cached as a target out of reach is.

:meth:`RobustSolver.solve_targets` is the same for a tree and a
:class:`~ikgame.kinematics.targets.TargetSet`, with the multi-target solvers: the cache, the
stall test (on the largest distance), the near restarts by damped least squares, then the middle
of every joint's range and the random poses as far seeds; restarts are ranked by the weighted
objective, so targets that cannot all be reached keep the best weighted compromise found. A
chain with one target at its tip goes to :meth:`RobustSolver.solve`.

Angles are radians, lengths and positions pixels.
"""

from __future__ import annotations

import copy
import math
from collections import deque
from collections.abc import Callable, Generator, Iterator, Mapping
from dataclasses import dataclass, replace
from types import MappingProxyType
from typing import Final, TypeVar

import numpy as np

from ikgame.kinematics._floats import FloatChain, float_angles, float_point
from ikgame.kinematics.ccd import wrap_angle
from ikgame.kinematics.jacobian import _chain_points, _check_settings, jacobian, solve_dls
from ikgame.kinematics.multi_jacobian import solve_dls_targets
from ikgame.kinematics.registry import get_solver, get_target_solver
from ikgame.kinematics.skeleton import Skeleton, tree_points
from ikgame.kinematics.solver import Solution, Solver, SolveStatus, TargetSolver
from ikgame.kinematics.targets import TargetSet

__all__ = [
    "RobustSolver",
    "FALLBACK",
    "RESTART_BUDGET",
    "SEED_ITERATIONS",
    "RANDOM_SEEDS",
    "RANDOM_SEED",
    "WANDERED",
    "STALL_PROGRESS",
    "RETRY_CALLS",
    "STALL_CALLS",
    "SETTLED",
    "JUMPED",
    "STILL_CALLS",
    "STRAINED",
    "HOLDS",
    "HOLD_SEEDS",
    "WAY_STEPS",
    "RELIEF_STEPS",
    "RELIEF_TURN",
    "OFF_STOPS",
    "OFF_STOPS_STEPS",
    "OFF_STOPS_TURN",
    "holds_along",
    "held_nearest",
    "HELD_STEPS",
    "NEAREST_STRAINS",
]

RESTART_BUDGET: Final = 100
"""Default most iterations (of any solver) one call spends on restarts, beyond the plain solve:
ten plain solves at the default 10 iterations a tick. A search that needs more goes on at the
next call with the same target."""

SEED_ITERATIONS: Final = 50
"""Most iterations one restart runs in one go, so a seed that crawls cannot eat the budget."""

STALL_CALLS: Final = 20
"""Calls on one target still ``PROCESSING`` after which the solve counts as stalled anyway.

CCD on a long chain can creep toward a target for hundreds of iterations, gaining a little on
every call; 20 calls is 83 ms at 240 ticks/s."""

RETRY_CALLS: Final = 10
"""Calls without a new search after the target moved away from one that had not arrived.

A target that moves every tick makes every search start afresh; a solver that lags behind it
(say CCD on a long chain) would otherwise pay the whole budget on every tick."""

RANDOM_SEEDS: Final = 8
"""Random poses (within the limits) tried after the deliberate seeds."""

STRAINED: Final = 1.0
"""Share of a motor's torque limit past which the motors cannot hold an answer still (see
:attr:`RobustSolver.strain`): :meth:`RobustSolver.solve` then looks for another."""

HOLDS: Final = 0.95
"""Share of each motor's torque limit an answer found instead may take to hold still: the rest
is left to move and to brake with. Below ``STRAINED``, so that the chain, settling near such an
answer, does not set off another search. A plain answer past it where the target found the
chain is searched past too, but stands where nothing with the margin arrives."""

HOLD_SEEDS: Final = 32
"""Random poses tried for an answer the motors can hold, when the plain one arrives in a pose
they cannot: such poses are a narrow share of those that arrive (a tenth, on an arm of four
links whose motors weaken toward the tip)."""

WAY_STEPS: Final = (0.125, 0.25, 0.375, 0.5, 0.625, 0.75, 0.875)
"""Where on the straight line in joint space from a chain's pose to another (as a share of the
way) :func:`holds_along` checks what holding still takes of the motors."""

RELIEF_STEPS: Final = 40
"""Most steps of the slide from an answer the motors cannot hold toward one they can, the end
kept on the target (see ``_relieved``)."""

RELIEF_TURN: Final = 0.05
"""Radians: the most one joint turns in one step of that slide."""

OFF_STOPS: Final = 0.15
"""Radians: an answer for a moving target with a limited joint this near one of its stops is
slid off them (see ``_off_stops``)."""

OFF_STOPS_STEPS: Final = 4
"""Most steps of that slide in one call."""

OFF_STOPS_TURN: Final = 0.03
"""Radians: the most one joint turns in one step of that slide."""

HELD_STEPS: Final = 100
"""Most steps toward a target the motors cannot hold the end at, from a pose they hold (see
:func:`held_nearest`)."""

SPENT: Final = 0.9
"""Share of some motor's torque limit that holding the chain where a target found it takes,
past which a solve looks for an answer whose way the motors hold (see
:meth:`RobustSolver.solve`). A search for an answer the motors hold prefers one within it too:
such a rest leaves them room to brake on the way in and to set off from."""

NEAREST_STRAINS: Final = 100
"""How many times one call of :meth:`RobustSolver.solve` asks the strain of poses on the way
to :func:`held_nearest`'s at most, but for the step that passes it (a step asks it for its
slope and up to a dozen times more), the plain answer serving meanwhile. On a chain whose
base cannot hold it reaching out, the costliest such call took 3.8 ms on ten links and 8.6 ms
on thirty with the servo's slope (14 and 12 ms with the slope by differences). Taken at once,
the steps toward a torque-bound target cost 140 ms for ten links and 360 ms for thirty (by
differences)."""

SLOPE_STRAINS: Final = 4
"""How many strains asked a slope in closed form (:attr:`RobustSolver.strain_slope`) counts
as: about what it costs. A servo's slope took 28-31 us on 3 to 30 links, where its strain took
5.5-10 us, and 50-135 us on 200 to 1000 links, where the strain took 31-80 us."""

JUMPED: Final = 2.0
"""A fresh answer more than this many times as far from the chain (its largest joint turn) as
the last answer, which the chain is coming in to and which still reaches, has jumped to another
shape: the last answer is kept (see ``RobustSolver._kept``). From poses on the way in, a
continuous solver's fresh answers lie about as far from the chain as the last one (1.0 to 1.1
times as far, CCD's on `15_zero_g_light`); FABRIK's against limits of +-7 deg jumped to four
times as far."""

RANDOM_SEED: Final = 20091
"""Seed of the generator that draws the random restarts, fresh for every search."""

SETTLED: Final = 0.01
"""A chain within this of a followed answer on every joint (radians, about 0.6 deg) has arrived:
from then on the plain solve answers again."""

STILL_CALLS: Final = 2
"""Calls with one and the same target before restarts may go far from the stalled pose."""

WANDERED: Final = math.pi
"""Joint turns (radians, summed over the joints) beyond which a stalled answer has wandered from
the chain's pose, and the restarts begin at the chain's pose instead."""

STALL_PROGRESS: Final = 0.01
"""A solve still ``PROCESSING`` that gained less than this fraction of its start error stalled."""

BACK_OFF: Final = 0.15
"""The first restart moves every joint off its limits by this fraction of its range: the nearest
pose where the joints pressed into their limits can move both ways."""

ROUND_JOINTS: Final = 4
"""Joints, from the base out, that get a seed taking them the other way round their limits."""

FALLBACK: Final[Mapping[str, str]] = MappingProxyType(
    {"ccd": "dls", "dls": "ccd", "fabrik": "dls", "jacobian_transpose": "dls"}
)
"""The solver each solver's restarts fall back on: another method is trapped elsewhere."""

_TWO_PI: Final = 2.0 * math.pi


_Out = TypeVar("_Out")

_Goal = tuple[float, float] | tuple[tuple[int, ...], tuple[float, ...], tuple[float, ...]]
"""A target as the cache compares it: a point (px), or a target set's links, points (flattened,
px) and weights."""


@dataclass(frozen=True, eq=False)
class _Answer:
    """A cached answer: its angles (read-only, and as floats), the goal and skeleton frame it was
    solved for, its error (px) and status."""

    angles: np.ndarray
    listed: list[float]
    target: _Goal
    frame: object
    """The ``RobustSolver._frame`` it was solved in: a new one whenever the skeleton changes."""
    error: float
    status: SolveStatus
    followed: bool
    """Found by a far restart: followed while it reaches, wherever the chain is on its way."""
    errors: np.ndarray | None = None


class RobustSolver:
    """One chain's solver with recovery from stalls and a cache; call :meth:`solve` every tick.

    Keep one per chain: it remembers the last answer and any search in progress. Change the
    skeleton (for example ``robust.skeleton = robust.skeleton.moved_to(base)`` when the base
    moves) or ``robust.solver_name`` at any time; :meth:`reset` forgets the cache (say, to
    re-solve a chain that is physically blocked from reaching its answer).

    >>> arm = Skeleton.chain([100, 80, 60], limits=[(-0.52, 2.09), (0.17, 2.97), (-2.97, -0.17)])
    >>> robust = RobustSolver(arm, "ccd")
    >>> pose = arm.lower  # the base on its stop; the target is the long way round
    >>> for tick in range(3):
    ...     sol = robust.solve(pose, (-150.0, 20.0), max_iterations=10, tolerance=0.5)
    ...     pose = sol.angles
    >>> sol.status.value, sol.error <= 0.5
    ('success', True)
    >>> robust.solve(pose, (-150.0, 20.0), max_iterations=10, tolerance=0.5).iterations
    0
    """

    def __init__(
        self, skeleton: Skeleton, solver_name: str = "ccd", *, budget: int = RESTART_BUDGET
    ) -> None:
        if isinstance(budget, bool) or not isinstance(budget, int | np.integer) or budget < 0:
            raise ValueError(f"budget must be an integer >= 0 iterations, got {budget!r}")
        self.budget = int(budget)
        self._skeleton = skeleton
        self._chain = _float_chain(skeleton)
        self._free: list[bool] = (~skeleton.limited).tolist()
        self._frame = object()
        self._carried = False  # the base moved since the last solve
        self.leaning = False
        """True when the last :meth:`solve_targets` answer was the plain solve leaning toward
        targets beyond their branches' reach while the base carries the skeleton: an answer
        that changes only as the base moves, which a caller may keep for a frame."""
        self._reach = skeleton.reach
        self._name = ""
        self._solve: Solver = get_solver(solver_name)
        self._fallback: Solver = self._solve
        self._solve_targets: TargetSolver = get_target_solver(solver_name)
        self._fallback_targets: TargetSolver = self._solve_targets
        self.strain: Callable[[np.ndarray], float] | None = None
        """The largest share of a motor's torque limit that holding a chain's pose (local
        angles, radians) still takes, if known: an answer past ``STRAINED`` sends
        :meth:`solve` looking for one within ``HOLDS``."""
        self.strain_slope: Callable[[np.ndarray], np.ndarray] | None = None
        """The gradient of :attr:`strain` at a pose (per joint, per radian), if known in closed
        form: without it, the slides down the strain take it by differences, which ask the
        strain once per joint (on a thousand links, 88 ms a step)."""
        self.most_strain = math.inf
        """The most :attr:`strain` can be at any pose, if a bound is known: where it is
        within ``STRAINED``, no way to an answer needs checking for poses the motors cannot
        hold."""
        self.solver_name = solver_name

    @property
    def skeleton(self) -> Skeleton:
        """The chain or tree being solved; set it when the base moves (the cache is checked
        against it)."""
        return self._skeleton

    @skeleton.setter
    def skeleton(self, skeleton: Skeleton) -> None:
        old = self._skeleton
        same_shape = skeleton.lengths is old.lengths or (
            np.array_equal(skeleton.lengths, old.lengths)
            and np.array_equal(skeleton.parents, old.parents)
            and np.array_equal(skeleton.lower, old.lower)
            and np.array_equal(skeleton.upper, old.upper)
        )
        self._skeleton = skeleton
        unmoved = skeleton.base_angle == old.base_angle and np.array_equal(skeleton.base, old.base)
        same_shape = same_shape and (
            skeleton.root_offsets is old.root_offsets
            or np.array_equal(skeleton.root_offsets, old.root_offsets)
        )
        if same_shape and unmoved:
            return
        self._frame = object()
        self._carried = same_shape
        if same_shape and self._chain is not None:
            # Only the base moved: the float copies of lengths and limits still hold.
            chain = copy.copy(self._chain)
            chain.base_x, chain.base_y = (float(v) for v in skeleton.base)
            chain.base_angle = skeleton.base_angle
            self._chain = chain
        elif not same_shape:
            self._chain = _float_chain(skeleton)
            self._free = (~skeleton.limited).tolist()
            self._reach = skeleton.reach
            self.reset()

    @property
    def solver_name(self) -> str:
        """The raw solver's name (``ccd``, ``dls``, ``fabrik``, ``jacobian_transpose``)."""
        return self._name

    @solver_name.setter
    def solver_name(self, name: str) -> None:
        self._solve = get_solver(name)
        self._fallback = get_solver(FALLBACK[name])
        self._solve_targets = get_target_solver(name)
        self._fallback_targets = get_target_solver(FALLBACK[name])
        self._name = name
        self.reset()

    def reset(self) -> None:
        """Forget the cached answer and any search in progress."""
        self._answer: _Answer | None = None
        self._search: _Search | None = None
        self._quiet = 0
        self._pending: _Goal | None = None
        self._waiting = 0
        self._moves = 0  # calls in a row with a goal other than the call before's
        # The measured pose at the first call for the goal, where the chain set off from, and
        # (once asked) whether holding it there spent the motors and whether the plain answer
        # the goal found asked more than the margin they rest with (see _held_answer).
        self._set_off: list[float] = []
        self._spent: bool | None = None
        self._edge: bool | None = None
        self._unheld: _Goal | None = None
        # The target whose search for an answer with a way the motors hold found none.
        self._way_searched: _Goal | None = None
        # The cached plain answer and how far the chain was from it at the last call.
        self._approach: tuple[_Answer, float] | None = None

    def solve(
        self,
        angles: np.ndarray,
        target: np.ndarray,
        *,
        max_iterations: int = 10,
        tolerance: float = 1.0,
    ) -> Solution:
        """Desired angles toward ``target`` (px), warm-started from the measured ``angles``.

        ``max_iterations`` bounds the plain solve; restarts add at most ``budget`` iterations;
        ``Solution.iterations`` counts both. Answers that are cached come back read-only. Needs
        a chain with joint 0 on the base; see :meth:`solve_targets` for anything else.
        """
        tol = _check_settings(max_iterations, tolerance)
        if self._chain is None:
            raise ValueError("solve needs a chain with joint 0 on the base; use solve_targets")
        measured = float_angles(angles, self._skeleton.count)
        goal = float_point(target)
        chain = self._chain
        cached = self._cached(
            measured, goal, tol, lambda listed: (math.sqrt(chain.error_sqr(listed, *goal)), None)
        )
        if cached is not None:
            return cached
        self._count_calls(goal, measured)
        stretched = self._stretched(goal, tol)
        if stretched is not None:
            return self._keep(stretched, goal, followed=False)
        start = np.array(measured)
        plain = self._solve(
            self._skeleton, start, goal, max_iterations=max_iterations, tolerance=tol
        )
        skeleton = self._skeleton
        if self._moves > 1 and plain.status is SolveStatus.SUCCESS:
            plain = _off_stops(skeleton, plain, np.array(goal), tol)
        before = (
            0.0
            if plain.status is SolveStatus.SUCCESS
            else math.sqrt(chain.error_sqr(skeleton.clamp(start).tolist(), *goal))
        )
        kept = self._kept(measured, plain, goal, tol, _stuck(plain, before))
        if kept is not None:
            return kept
        target = np.array(goal)
        strain = self.strain
        if (
            plain.status is not SolveStatus.FAILURE
            and strain is not None
            and self._waiting >= STILL_CALLS
        ):
            held = self._held_answer(
                plain, goal, target, tol, start, strain, _sloped(strain, self.strain_slope)
            )
            if held is not None:
                return held
        if plain.status is SolveStatus.SUCCESS:
            # Arriving from where an unfinished search left the chain is that search's answer.
            search = self._search
            followed = (
                search is not None and search.aims_at(np.array(goal), tol) and search.best_far
            )
            return self._approached(measured, self._keep(plain, goal, followed))
        recovered = self._recover(
            plain,
            goal,
            target,
            tol,
            before,
            lambda angles: (_error(skeleton, angles, target), None),
            lambda stalled: (
                _near_seeds(skeleton, self._solve, skeleton.clamp(start), stalled),
                _far_seeds(skeleton, self._solve, self._fallback, stalled, target),
            ),
        )
        return self._approached(measured, recovered)

    def solve_targets(
        self,
        angles: np.ndarray,
        targets: TargetSet,
        *,
        max_iterations: int = 10,
        tolerance: float = 1.0,
    ) -> Solution:
        """Desired angles toward every target of ``targets``, warm-started from the measured
        ``angles`` (radians): :meth:`solve` for a tree, with the multi-target solver.

        ``Solution.error`` is the largest distance (px), ``Solution.errors`` each target's. A
        chain with joint 0 on the base and one target at its tip gets :meth:`solve`'s answer.

        >>> legs = Skeleton.tree([60, 50, 60, 50], [-1, 0, -1, 2],
        ...                      limits=[(-2.6, -0.5), (-2.0, 0.0)] * 2,
        ...                      root_offsets=[(-40, 0), (0, 0), (40, 0), (0, 0)])
        >>> robust = RobustSolver(legs, "fabrik")
        >>> feet = TargetSet(legs.effectors, [(-30.0, -100.0), (40.0, -100.0)])
        >>> sol = robust.solve_targets(legs.clamp(np.zeros(4)), feet, tolerance=0.5)
        >>> sol.status.value, bool(sol.errors.max() <= 0.5)
        ('success', True)
        >>> robust.solve_targets(sol.angles, feet, tolerance=0.5).iterations
        0
        """
        if not isinstance(targets, TargetSet):
            raise ValueError(f"targets must be a TargetSet, got {type(targets).__name__}")
        self.leaning = False
        skeleton = self._skeleton
        targets.check(skeleton)
        if (
            self._chain is not None
            and len(targets) == 1
            and int(targets.links[0]) == skeleton.count - 1
        ):
            sol = self.solve(
                angles, targets.points[0], max_iterations=max_iterations, tolerance=tolerance
            )
            return Solution(
                sol.angles, sol.status, sol.iterations, sol.error, np.array([sol.error])
            )
        tol = _check_settings(max_iterations, tolerance)
        measured = float_angles(angles, skeleton.count)
        goal = _goal_key(targets)

        def measure(angles: np.ndarray | list[float]) -> tuple[float, np.ndarray]:
            errors = _target_errors(skeleton, np.asarray(angles), targets)
            return float(errors.max()), errors

        cached = self._cached(measured, goal, tol, measure)
        if cached is not None:
            return cached
        self._count_calls(goal, measured)
        start = np.array(measured)
        plain = self._solve_targets(
            skeleton, start, targets, max_iterations=max_iterations, tolerance=tol
        )
        before = 0.0 if plain.status is SolveStatus.SUCCESS else measure(skeleton.clamp(start))[0]
        kept = self._kept(measured, plain, goal, tol, _stuck(plain, before))
        if kept is not None:
            return kept
        if plain.status is SolveStatus.SUCCESS:
            search = self._search
            followed = search is not None and search.aims_at(targets, tol) and search.best_far
            return self._approached(measured, self._keep(plain, goal, followed))
        carried, self._carried = self._carried, False
        if carried and _out_of_reach(skeleton, targets, tol):
            # While the base carries the skeleton toward targets still beyond their branches'
            # reach, no restart brings them closer, and a search would start afresh in every new
            # frame: the plain solve, leaning toward them, is the answer for now.
            self.leaning = True
            return plain
        recovered = self._recover(
            plain,
            goal,
            targets,
            tol,
            before,
            measure,
            lambda stalled: (
                _near_seeds(
                    skeleton, self._solve_targets, skeleton.clamp(start), stalled, solve_dls_targets
                ),
                _far_tree_seeds(skeleton, self._solve_targets, self._fallback_targets),
            ),
        )
        return self._approached(measured, recovered)

    def _count_calls(self, goal: _Goal, measured: list[float]) -> None:
        """Count the calls in a row with one and the same goal, and those in a row with a
        new one each; note the ``measured`` pose (radians) a new goal finds the chain in."""
        if goal == self._pending:
            self._waiting += 1
            self._moves = 0
        else:
            self._pending, self._waiting = goal, 0
            self._moves += 1
            self._set_off, self._spent, self._edge = measured, None, None

    def _cached(
        self,
        measured: list[float],
        goal: _Goal,
        tol: float,
        measure: Callable[[list[float]], tuple[float, np.ndarray | None]],
    ) -> Solution | None:
        """The cached answer if it still serves, else None; ``measure(angles)`` gives a pose's
        error and per-target errors for the goal, px.

        An answer a restart from a far seed found is followed while it reaches the goal and the
        chain is on its way there: solving from the measured pose half way could fall back into
        the trap, or take the other branch. Once the chain is within ``SETTLED`` of it on every
        joint, the plain solve takes over again, from the measured pose: re-solving from where
        the motors actually hold the chain (sagging under gravity, say) is what brings the end
        effector the last pixels. The best pose for a goal no pose reaches is returned for as
        long as the goal stays the same.
        """
        answer = self._answer
        if answer is None:
            return None
        same = answer.frame is self._frame and answer.target == goal
        if same and answer.status is SolveStatus.FAILURE:
            return Solution(answer.angles, SolveStatus.FAILURE, 0, answer.error, answer.errors)
        if not answer.followed:
            return None
        if _within(self._free, measured, answer.listed):
            self._answer = replace(answer, followed=False)
            return None
        error, errors = (answer.error, answer.errors) if same else measure(answer.listed)
        if error > tol:
            return None
        return Solution(answer.angles, SolveStatus.SUCCESS, 0, error, errors)

    def _kept(
        self, measured: list[float], plain: Solution, goal: _Goal, tol: float, stuck: bool
    ) -> Solution | None:
        """The last answer instead of the new ``plain`` one while the chain comes in to it, or
        None: when the last answer still reaches the same goal in the same frame, the motors can
        hold it (when :attr:`strain` is known), the chain has come nearer it since the last call
        (its largest joint turn to it shrank) without having arrived (within ``SETTLED``), and
        ``plain`` is ``stuck`` (it would start a search from far seeds) or lies more than
        ``JUMPED`` times as far from the chain.

        Solved afresh from a pose in motion, a solver whose answer is not continuous in its
        start (FABRIK's passes against tight limits: starts 0.15 deg apart, answers 12 deg
        apart; CCD's elbow flipped over by a fresh solve as the tip swept by) hands the servo a
        goal of another shape tick after tick, and the chain, braking for one and thrown toward
        the next, swings past the target; a search from far seeds after a stuck solve does the
        same. A continuous solver's fresh answer, from a pose on the way in, is about as near
        as the last one and is taken: it steers the end's course (the last answer kept whenever
        it was the nearer, the eight light links of `15_zero_g_light` took 0.83 s to reach
        their targets with CCD instead of 0.71). Once the chain has arrived or no longer comes
        nearer (at rest, sagging off it), the fresh answer takes over, solved from where the
        motors hold the chain.
        """
        answer = self._answer
        if (
            answer is None
            or answer.frame is not self._frame
            or answer.target != goal
            or answer.status is not SolveStatus.SUCCESS
            or answer.error > tol
        ):
            return None
        last = self._approach
        gap = _gap(self._free, measured, answer.listed)
        self._approach = (answer, gap)
        if last is None or last[0] is not answer or not SETTLED < gap < last[1]:
            return None
        if not stuck and JUMPED * gap >= _gap(self._free, measured, plain.angles.tolist()):
            return None
        strain = self.strain
        if strain is not None and strain(answer.angles) > STRAINED:
            return None
        self._search = None
        return Solution(
            answer.angles, SolveStatus.SUCCESS, plain.iterations, answer.error, answer.errors
        )

    def _approached(self, measured: list[float], solution: Solution) -> Solution:
        """``solution``, just cached, noted with how far the chain is from it (see
        :meth:`_kept`): a plain answer or one a restart found. Unnoted, a restart's answer that
        the chain came in to gave way to the first plain answer that arrived: on
        `33_zero_g_thirty_five_links` (CCD, third target) one with a joint 210 deg from the
        chain's, 34 px from the target, and the chain turned it round, 0.77 s to the target
        instead of 0.43."""
        answer = self._answer
        self._approach = (
            None if answer is None else (answer, _gap(self._free, measured, answer.listed))
        )
        return solution

    def _stretched(self, goal: tuple[float, float], tol: float) -> Solution | None:
        """The chain stretched toward a goal at or beyond its reach, when the limits allow it."""
        chain = self._chain
        beyond = math.hypot(goal[0] - chain.base_x, goal[1] - chain.base_y) - self._reach
        if beyond < 0.0:
            return None
        stretched = _stretched_toward(self._skeleton, np.array(goal))
        error = math.sqrt(chain.error_sqr(stretched.tolist(), *goal))
        # Only the straight chain aimed at the target comes this close; limits may forbid it.
        if error > beyond + 1e-9 * self._reach:
            return None
        status = SolveStatus.SUCCESS if error <= tol else SolveStatus.FAILURE
        return Solution(stretched, status, 0, error)

    def _recover(
        self,
        plain: Solution,
        goal: _Goal,
        target: np.ndarray | TargetSet,
        tol: float,
        before: float,
        measure: Callable[[np.ndarray], tuple[float, np.ndarray | None]],
        seeds: Callable[[np.ndarray], tuple[_Seeds, _Seeds]],
    ) -> Solution:
        """After a plain solve that fell short: search when it stalled, keep the best.

        ``before`` is the error at the start (px); ``measure(angles)`` a pose's error and
        per-target errors; ``seeds(stalled)`` the near and far restarts from a stalled pose.
        """
        skeleton = self._skeleton
        stalled = _stuck(plain, before) or self._waiting >= STALL_CALLS
        search = self._search
        if search is not None and search.accept is not None:
            # A search for a pose the motors can hold counts only such arrivals; a stall takes
            # any arrival.
            search = self._search = None
        if search is not None and not search.aims_at(target, tol):
            # The target moved on before the search arrived: wait before the next one.
            search = self._search = None
            self._quiet = RETRY_CALLS
        if search is None and (not stalled or self._quiet > 0):
            self._quiet = max(self._quiet - 1, 0)
            return plain
        if search is None:
            search = self._search = _Search(*seeds(plain.angles), target, tol)
        # Far restarts only for a target that holds still: while it moves, an answer that
        # swings the chain round would be stale before the chain got there.
        search.far = self._waiting >= STILL_CALLS
        used = search.run(skeleton, target, tol, self.budget)
        best = plain
        if search.best is not None:
            found = Solution(search.best, plain.status, 0, *measure(search.best))
            if search.score(found) < search.score(plain):
                best = found
        iterations = plain.iterations + used
        if best.error <= tol or search.exhausted:
            status = SolveStatus.SUCCESS if best.error <= tol else SolveStatus.FAILURE
            if status is SolveStatus.FAILURE:
                # No pose reaches the goal from here; while the base carries the skeleton the
                # cached failure serves no longer, and searching again every tick would cost the
                # whole budget each time.
                self._quiet = RETRY_CALLS
            answer = Solution(best.angles, status, iterations, best.error, best.errors)
            return self._keep(answer, goal, best is not plain and search.best_far)
        return Solution(best.angles, SolveStatus.PROCESSING, iterations, best.error, best.errors)

    def _held_answer(
        self,
        plain: Solution,
        goal: tuple[float, float],
        target: np.ndarray,
        tol: float,
        start: np.ndarray,
        strain: Callable[[np.ndarray], float],
        slope: _Slope,
    ) -> Solution | None:
        """The answer instead of ``plain`` (arrived, or on its way) for a target that holds
        still, where the motors cannot hold it or the way to it from a spent rest (see
        :meth:`_held` and :meth:`_held_way`); None where ``plain`` stands."""
        skeleton = self._skeleton

        def seeds() -> tuple[_Seeds, _Seeds]:
            # The stall's restarts, then random poses and the slide (see _far_held_seeds).
            return (
                _near_seeds(skeleton, self._solve, skeleton.clamp(start), plain.angles),
                _far_held_seeds(
                    skeleton, self._solve, self._fallback, plain.angles, target, strain, slope
                ),
            )

        def holds(angles: np.ndarray) -> bool:
            return strain(angles) <= HOLDS

        def roomy(angles: np.ndarray) -> bool:
            return strain(angles) <= SPENT

        def way(most: float) -> Callable[[np.ndarray], bool]:
            return lambda angles: holds_along(
                strain, start, _short_way(skeleton, angles - start), most
            )

        asks = strain(plain.angles)
        if self._edge is None:
            # Asked once a goal: the plain answer's strain, crossing HOLDS from call to call
            # as the chain moves, would start and drop the search by turns.
            self._edge = asks > HOLDS
        strained = asks > STRAINED

        def way_unsafe() -> bool:
            return self.most_strain > STRAINED and not way(STRAINED)(plain.angles)

        # Asked only where it decides something (its poses' strains, on every call).
        unsafe = None
        if goal != self._unheld and not strained and self._edge:
            # An answer at the edge whose way asks more than the motors have waits below.
            unsafe = way_unsafe()
        if goal != self._unheld and (strained or (self._edge and not unsafe)):
            # Still on its way too: a solver that takes many calls to arrive (CCD) would
            # otherwise bring the end to the target in a pose the motors cannot hold, and the
            # switch to one they can would carry it away again. Only for a target that holds
            # still: one that moves would start a search, and pay its budget, on every call.
            # So too where the target found the answer at the edge of what they hold, past
            # the margin they rest with (HOLDS): `61_heavy_gravity_weak_motors`' base, asked
            # 0.98 of its torque by DLS's answer for the fourth target, let the arm sag off it.
            search, iterations = self._searched(
                plain, target, tol, seeds(), holds, way(STRAINED), roomy
            )
            if not strained:
                # Until one with room to brake arrives, the first with the margin, and where
                # none has the margin, the plain answer: the motors hold it all the same.
                found = self._found(search, goal, target, iterations, search.tight)
                if found is not None:
                    return found
                if not search.exhausted:
                    return replace(plain, iterations=iterations)
                self._unheld, self._search = goal, None
                return None
            return self._held(
                plain,
                goal,
                target,
                tol,
                search,
                iterations,
                skeleton.clamp(start),
                lambda: _held_nearest_steps(
                    skeleton, (skeleton.clamp(start), plain.angles), target, strain, slope
                ),
            )
        if goal == self._way_searched:
            return None
        if self._spent is None:
            self._spent = strain(np.array(self._set_off)) > SPENT
        if unsafe is None:
            unsafe = way_unsafe()
        if unsafe or (self._spent and not way(HOLDS)(plain.angles)):
            # An answer the motors hold at rest but not on the way to it with the margin they
            # rest with (HOLDS): from the pose where a torque-bound target left
            # `46_heavy_weak_second_branch` (its base at 0.95 of its limit), CCD's and FABRIK's
            # answer swung the elbow out (0.93 at rest, up to 1.03 on the way), and the elbow,
            # its braking taking torque the base did not have, passed its goal by 30 deg. An
            # answer whose way the motors hold so is searched for; with none (an arm lifted
            # from a stretched rest, where no straight way holds), the plain answer it is,
            # unless it leaves them less than the margin at rest (see _held_way). From any
            # rest, so is one whose way asks more than the motors have (``unsafe``): the
            # upright arm of `80_heavy_weak_three_swing_over`, leaning toward CCD's answer
            # (0.97 at rest, 1.19 on the way), fell past the target onto the floor. Spent
            # where the target found the chain, not where it passes on its way: 80's FABRIK
            # arm, 16 px from its third target and closing, passed a pose asking 0.90, and the
            # answer found from there, the elbow bent the other way, whipped it through the
            # target and down onto the floor (91.6% past).
            search, iterations = self._searched(
                plain, target, tol, seeds(), holds, way(HOLDS), roomy
            )
            if search.origin is None:
                search.origin = skeleton.clamp(start)
            wait = search.origin if unsafe else None
            return self._held_way(plain, goal, target, search, iterations, wait)
        return None

    def _held(
        self,
        plain: Solution,
        goal: tuple[float, float],
        target: np.ndarray,
        tol: float,
        search: _Search,
        iterations: int,
        start: np.ndarray,
        nearest: Callable[[], Generator[int, None, np.ndarray | None]],
    ) -> Solution:
        """After a plain solve that arrives in a pose the motors cannot hold, the ``search``:
        restarts from the seeds of a stall, in which only arrivals they can hold count. The first
        the chain can get to through poses they hold, with room to brake on the way in
        (within :data:`SPENT`), wins and is followed. The first with less room, else the
        first they hold only at rest, is served while the search goes on, and followed once
        it has tried every seed. With none, the chain waits where the search began (``start``
        at its first call: that pose is the answer, ``processing``) rather than set off toward
        a pose the motors cannot hold: on `57_heavy_weak_four`'s torque-bound second target
        CCD's and JT's arms, leaning toward the plain answer while the search ran, sank onto
        the floor, where no pose near them held and they could not get up for the next two
        targets; waiting, they come to rest in the held pose nearest the target and reach the
        next two.

        The room is what stops the chain on its answer: on `81_heavy_weak_five_swing_over`
        DLS's first arrival for the first target asked 0.93 of some motor at rest; the elbow,
        holding 0.90 to 0.95 of its torque as it lowered the arm, had 5% of it to brake with,
        passed its goal at 51 deg/s and stopped 11 deg beyond it, and the last link, its motor
        at its limit, fell onto its stop (`blocked` 48 px off). A later seed's answer asks 0.83,
        and the arm reaches all six targets.

        An answer found so can lie far from the chain in joint space, and the way there matters
        as much as the answer: on `40_seven_weak_links_hanging` FABRIK's first arrival for the
        third target asked 0.93 of some motor, but the straight line to it up to 1.69, and the
        joints, coming in each at its own pace, passed poses asking 1.35 (the last joint turned
        218 deg, its reaction carrying the sixth back until it stalled); the arm rested
        `blocked` 82 px off. Where no arrival has such a way (an arm lifted out straight), the
        first is served at once all the same: the chain sets off toward it while the search
        goes on.

        Once every seed has failed, the target asks more than the motors have (or lies where
        no seed found a pose they hold): the pose nearest it that they hold (``nearest()``
        steps toward it, about ``NEAREST_STRAINS`` strains asked a call, the plain answer
        serving meanwhile) is the
        answer, a ``FAILURE`` cached like a target out of reach; where no pose near the chain
        or the plain answer is one they hold, the plain answer stays. Pushing on for the plain
        answer, the weak joints stalled one by one where their torque ran out, and the arm
        sagged, lifted and sagged again as the joints beyond them came in: the five weak links
        of `29_five_weak_links` moved their end 3 to 4 px in the last half second of the
        torque-bound target's hold."""
        meanwhile = search.fallback if search.tight is None else search.tight
        found = self._found(search, goal, target, iterations, meanwhile)
        if found is not None:
            return found
        if not search.exhausted:
            if search.origin is None:
                search.origin = start
            return self._arrival(search.origin, target, iterations, SolveStatus.PROCESSING)
        if search.nearest is None:
            search.nearest = nearest()
        try:
            spent = 0
            while spent < NEAREST_STRAINS:
                spent += next(search.nearest)
        except StopIteration as done:
            self._unheld = goal
            self._search = None
            if done.value is not None:
                angles = done.value
                error = _error(self._skeleton, angles, target)
                status = SolveStatus.SUCCESS if error <= tol else SolveStatus.FAILURE
                answer = Solution(angles, status, iterations, error)
                return self._keep(answer, goal, followed=False)
        return replace(plain, iterations=iterations)

    def _searched(
        self,
        plain: Solution,
        target: np.ndarray,
        tol: float,
        seeds: tuple[_Seeds, _Seeds],
        holds: Callable[[np.ndarray], bool],
        way: Callable[[np.ndarray], bool],
        roomy: Callable[[np.ndarray], bool],
    ) -> tuple[_Search, int]:
        """The search for arrivals the motors hold (``holds``), through poses they hold
        (``way``), taken on by this call's budget; and the iterations of ``plain`` and of it."""
        search = self._search
        if search is None or search.accept is None or not search.aims_at(target, tol):
            search = self._search = _Search(*seeds, target, tol, holds, way, roomy)
        search.far = True
        used = search.run(self._skeleton, target, tol, self.budget)
        return search, plain.iterations + used

    def _held_way(
        self,
        plain: Solution,
        goal: tuple[float, float],
        target: np.ndarray,
        search: _Search,
        iterations: int,
        wait: np.ndarray | None,
    ) -> Solution | None:
        """After a plain solve whose answer the motors hold (or one on its way) but not the
        way to it, the ``search`` for an arrival they hold through poses they hold, with room
        to brake (within :data:`SPENT`): it replaces the plain answer. The first such arrival
        with less room serves while the search goes on and is followed once it has tried
        every seed; without one the plain answer serves meanwhile, unless its way
        asks more than the motors have somewhere: then the pose to ``wait`` in does (where the
        search began, and the ways it finds start), ``processing``; once it has tried
        every seed, None (the plain answer is taken as any other), but where the motors do not
        hold the plain answer with the margin they rest with (:data:`HOLDS`) and the search
        found an arrival they do (whose way they do not hold either), that arrival.

        No straight way holds for an arm lifted from a stretched rest, whichever answer it
        lifts to; one that leaves the motors no margin at rest also leaves them none to move
        with. The five weak links of `29_five_weak_links`, lifting for (140, 84) FABRIK's
        answer that asked 0.994 of a motor, pushed at their limits for 1.4 s (the second
        joint sagging 35 deg back from its goal) until the answer, solved afresh, drifted past
        1.0 and the search for one they hold began. What it found at once (asking 0.84) is
        the arrival this search had found on the fifth call; served then, the arm reaches
        the target 0.7 s sooner.
        """
        found = self._found(search, goal, target, iterations, search.tight)
        if found is not None:
            return found
        if not search.exhausted:
            if wait is not None:
                # The chain stays where the search began rather than set off on a way the
                # motors cannot hold.
                return self._arrival(wait, target, iterations, SolveStatus.PROCESSING)
            return replace(plain, iterations=iterations)
        self._way_searched = goal
        self._search = None
        strain = self.strain
        if search.fallback is None or strain is None or strain(plain.angles) <= HOLDS:
            return None
        answer = self._arrival(search.fallback, target, iterations)
        return self._keep(answer, goal, followed=True)

    def _found(
        self,
        search: _Search,
        goal: _Goal,
        target: np.ndarray,
        iterations: int,
        meanwhile: np.ndarray | None,
    ) -> Solution | None:
        """The ``search``'s arrival, kept; else ``meanwhile`` (an arrival it does not end on),
        served while it goes on and kept once it has tried every seed; None without either."""
        found = search.best if search.arrived else None
        if found is None and search.exhausted:
            found = meanwhile
        if found is not None:
            return self._keep(self._arrival(found, target, iterations), goal, followed=True)
        if meanwhile is not None:
            # Not kept: the search goes on at the next call.
            return self._arrival(meanwhile, target, iterations)
        return None

    def _arrival(
        self,
        angles: np.ndarray,
        target: np.ndarray,
        iterations: int,
        status: SolveStatus = SolveStatus.SUCCESS,
    ) -> Solution:
        """The pose ``angles`` (radians) as an answer for ``target`` (px): a search's arrival,
        or with ``processing`` the pose the chain waits in."""
        return Solution(angles, status, iterations, _error(self._skeleton, angles, target))

    def _keep(self, solution: Solution, goal: _Goal, followed: bool) -> Solution:
        """Cache ``solution`` (an arrival, or the best there is) and return it read-only."""
        # Every solver returns a new array, so it can be frozen and shared rather than copied.
        angles = solution.angles
        angles.setflags(write=False)
        self._answer = _Answer(
            angles,
            angles.tolist(),
            goal,
            self._frame,
            solution.error,
            solution.status,
            followed,
            solution.errors,
        )
        self._search = None
        return solution


_Start = np.ndarray | Generator[int, None, np.ndarray]
"""A restart's start pose, or steps that work it out (yielding how many times each asked the
strain, which a search counts as iterations) and return it."""

_Seeds = Iterator[tuple[_Start, tuple[Solver | TargetSolver, ...]]]
"""Start poses, each with the solvers to run from it one after the other."""


class _Search:
    """Restarts for one target (a point, or a target set), resumable from call to call;
    remembers the best pose found: the lowest error for a point, the lowest weighted objective
    for a target set.

    The near seeds are always tried; the far ones only while ``far`` is set.
    """

    def __init__(
        self,
        near: _Seeds,
        far: _Seeds,
        target: np.ndarray | TargetSet,
        tolerance: float,
        accept: Callable[[np.ndarray], bool] | None = None,
        prefer: Callable[[np.ndarray], bool] | None = None,
        roomy: Callable[[np.ndarray], bool] | None = None,
    ) -> None:
        self.target = target.copy() if isinstance(target, np.ndarray) else target
        self.tolerance = tolerance
        self.accept = accept
        """Whether an arrival counts (the motors can hold it, say); None: every one does."""
        self.prefer = prefer
        """Whether an arrival that counts ends the search (the chain gets there through poses
        the motors hold, say); None: every one does."""
        self.roomy = roomy
        """Whether a preferred arrival leaves the motors room to brake (see ``SPENT``); None:
        every one does."""
        self.fallback: np.ndarray | None = None
        """The first arrival that counts but does not end the search, if any."""
        self.tight: np.ndarray | None = None
        """The first preferred arrival without that room, if any."""
        self.origin: np.ndarray | None = None
        """The pose (radians) the chain was in when the search began, where its ways start."""
        self.nearest: Generator[int, None, np.ndarray | None] | None = None
        """Once every seed has failed, the steps toward the pose nearest the target that
        counts (see :func:`held_nearest`), under way."""
        self.far = False
        self.best: np.ndarray | None = None
        self.best_far = False
        self._best_error = math.inf
        self._best_score = math.inf
        # Each entry: a start pose, the solvers still to run from it one after the other, and
        # whether it is a far seed.
        self._queue: deque[tuple[_Start, tuple[Solver | TargetSolver, ...], bool]] = deque()
        self._near: _Seeds | None = near
        self._far: _Seeds | None = far

    @property
    def exhausted(self) -> bool:
        """True once every seed, far ones included, has been tried."""
        return not self._queue and self._near is None and self._far is None

    @property
    def arrived(self) -> bool:
        """True once a restart has arrived (in a pose that counts)."""
        return self._best_error <= self.tolerance

    def aims_at(self, goal: np.ndarray | TargetSet, tolerance: float) -> bool:
        """Whether this search serves ``goal``: the same target, to within the tolerance."""
        if tolerance != self.tolerance:
            return False
        target = self.target
        if isinstance(target, np.ndarray):
            return math.hypot(*(goal - target)) <= tolerance
        return (
            isinstance(goal, TargetSet)
            and np.array_equal(goal.links, target.links)
            and np.array_equal(goal.weights, target.weights)
            and bool(np.all(np.hypot(*(goal.points - target.points).T) <= tolerance))
        )

    def score(self, sol: Solution) -> float:
        """How good an answer is, lower better: the error for a point, the weighted objective
        (doubled) for a target set."""
        if sol.errors is None or not isinstance(self.target, TargetSet):
            return sol.error
        return float(self.target.weights @ sol.errors**2)

    def run(
        self, skeleton: Skeleton, goal: np.ndarray | TargetSet, tolerance: float, budget: int
    ) -> int:
        """Try seeds until one arrives, none are left, or ``budget`` iterations are spent."""
        used = 0
        while used < budget and self._best_error > tolerance:
            entry = self._next()
            if entry is None:
                break
            angles, solvers, far = entry
            if not isinstance(angles, np.ndarray):
                # A start still being worked out: a step of it, then the rest later.
                try:
                    used += next(angles)
                except StopIteration as done:
                    angles = done.value
                else:
                    self._queue.appendleft((angles, solvers, far))
                    continue
            for index, solver in enumerate(solvers):
                allowed = min(SEED_ITERATIONS, budget - used)
                if allowed < 1:
                    self._queue.appendleft((angles, solvers[index:], far))
                    return used
                sol = solver(skeleton, angles, goal, max_iterations=allowed, tolerance=tolerance)
                used += sol.iterations
                if (
                    sol.status is SolveStatus.SUCCESS
                    and self.accept is not None
                    and not self.accept(sol.angles)
                ):
                    break  # it arrives, but not in a pose that counts: the next seed
                if (
                    sol.status is SolveStatus.SUCCESS
                    and self.prefer is not None
                    and not self.prefer(sol.angles)
                ):
                    if self.fallback is None or (
                        self.roomy is not None
                        and not self.roomy(self.fallback)
                        and self.roomy(sol.angles)
                    ):
                        self.fallback = sol.angles
                    break  # it counts, but a better one may follow: the next seed
                if (
                    sol.status is SolveStatus.SUCCESS
                    and self.roomy is not None
                    and not self.roomy(sol.angles)
                ):
                    if self.tight is None:
                        self.tight = sol.angles
                    break  # it leaves the motors little to brake with: one with room may follow
                score = self.score(sol)
                if score < self._best_score or sol.status is SolveStatus.SUCCESS:
                    self.best, self.best_far = sol.angles, far
                    self._best_error, self._best_score = sol.error, score
                if sol.status is SolveStatus.SUCCESS:
                    return used
                angles = sol.angles
        return used

    def _next(self) -> tuple[_Start, tuple[Solver | TargetSolver, ...], bool] | None:
        if self._queue:
            return self._queue.popleft()
        if self._near is not None:
            seed = next(self._near, None)
            if seed is not None:
                return (*seed, False)
            self._near = None
        if self._far is not None and self.far:
            seed = next(self._far, None)
            if seed is not None:
                return (*seed, True)
            self._far = None
        return None


def _out_of_reach(skeleton: Skeleton, targets: TargetSet, tol: float) -> bool:
    """True when some target lies farther from its branch's root joint than the branch is long
    (plus ``tol``, px)."""
    roots = skeleton.root_points()[targets.links]
    lengths = skeleton.ancestors[targets.links] @ skeleton.lengths
    return bool(np.any(np.hypot(*(targets.points - roots).T) > lengths + tol))


def _near_seeds(
    skeleton: Skeleton,
    solve: Solver | TargetSolver,
    here: np.ndarray,
    stalled: np.ndarray,
    dls: Solver | TargetSolver = solve_dls,
) -> _Seeds:
    """Restarts next to the stalled pose, by damped least squares (``dls``, the chain's or the
    multi-target one): its steps are the shortest that move the end effector, so it finds the
    answer nearest the pose. From the chain's pose ``here`` first when the stalled one has
    wandered more than ``WANDERED`` from it (CCD turns the last joints first, whatever the
    distance, and can coil a long chain the long way round)."""
    if solve is not dls:
        if float(np.abs(stalled - here).sum()) > WANDERED:
            yield here, (dls,)
        yield stalled, (dls,)
    yield _backed_off(skeleton, stalled), (dls,)


def holds_along(
    strain: Callable[[np.ndarray], float],
    start: np.ndarray,
    way: np.ndarray,
    most: float = STRAINED,
) -> bool:
    """Whether the motors can hold every pose checked (at ``WAY_STEPS``) on the straight line
    in joint space from ``start`` to ``start + way`` (radians): ``strain`` (what holding a pose
    still takes of them, as :attr:`RobustSolver.strain`) within ``most`` at each. Neither end
    is checked.

    A chain whose joints come in together keeps to that line; one whose joints come in each at
    its own pace passes near it.

    >>> strain = lambda angles: float(np.abs(angles).max())  # a stand-in
    >>> holds_along(strain, np.zeros(2), np.array([0.5, 1.1]))
    True
    >>> holds_along(strain, np.zeros(2), np.array([0.5, 2.0]))
    False
    """
    return all(strain(start + step * way) <= most for step in WAY_STEPS)


def _short_way(skeleton: Skeleton, turns: np.ndarray) -> np.ndarray:
    """``turns`` (radians, per joint) with each free joint's the short way round, within
    [-pi, pi], as the servo turns it; a limited joint's as it is, as it never goes round.

    >>> arm = Skeleton.chain([100, 80], limits=[None, (-3.0, 3.0)])
    >>> _short_way(arm, np.array([-5.9, -5.9])).round(2).tolist()
    [0.38, -5.9]
    """
    return np.where(skeleton.limited, turns, (turns + math.pi) % _TWO_PI - math.pi)


def _far_held_seeds(
    skeleton: Skeleton,
    solve: Solver,
    fallback: Solver,
    strained: np.ndarray,
    target: np.ndarray,
    strain: Callable[[np.ndarray], float],
    slope: _Slope,
) -> _Seeds:
    """The far restarts of a search for a pose the motors can hold (``HOLD_SEEDS`` random),
    then the ``strained`` answer slid toward one they can hold (``_relieved``). The slide comes
    last: it finds a pose near the answer, but the way there may pass poses the motors cannot
    hold (a weak base lifting the stretched arm), where a far pose, folded, can be reached."""
    yield from _far_seeds(skeleton, solve, fallback, strained, target, HOLD_SEEDS, chained=True)
    yield _relieved(skeleton, strained, strain, slope), (solve_dls,)


def _relieved(
    skeleton: Skeleton, angles: np.ndarray, strain: Callable[[np.ndarray], float], slope: _Slope
) -> Generator[int, None, np.ndarray]:
    """``angles`` slid along the poses that keep the end where it is (the null space of the
    end's Jacobian) down the ``strain`` of holding them, until it is within ``HOLDS`` or stops
    falling: the arm's own answer, rearranged so the motors can hold it. The slide leaves the
    end a little off; the restart from it brings the end back.

    A chain has many poses for one end point and random restarts seldom land on one its weak
    motors can hold (those bend the strong joints near the base and keep the links beyond the
    weak ones near the vertical); the slide goes there from the answer at hand. A step at a
    time, each yielding how many times it asked the ``strain``: on thirty links the whole
    slide took 20 ms, more than a frame, in the one call of the search that came to it."""
    counted, counted_slope, asked = _counting(strain, slope)
    start = skeleton.clamp(np.array(angles, dtype=float))
    pose, _ = yield from _asking(_slid_down(skeleton, start, counted, counted_slope, True), asked)
    return pose


def _keeping_end(skeleton: Skeleton, pose: np.ndarray, turns: np.ndarray) -> np.ndarray:
    """``turns`` (radians, per joint) less their part that moves the end: their projection on
    the poses that keep the end where it is at ``pose`` (the null space of its Jacobian)."""
    jac = jacobian(skeleton, pose)
    return turns - np.linalg.pinv(jac) @ (jac @ turns)


def _off_stops(skeleton: Skeleton, plain: Solution, target: np.ndarray, tol: float) -> Solution:
    """The arrived ``plain`` answer for a moving ``target`` (px), slid off the joints' stops
    along the poses that keep the end where it is, when a limited joint is within
    ``OFF_STOPS`` of one: down the sum of each limited joint's squared offset from the middle of
    its range (as a share of half the range), ``OFF_STOPS_TURN`` at most per joint and step, for
    ``OFF_STOPS_STEPS`` steps. The slid pose is the answer if its end is still within ``tol``
    (px) of the target; otherwise ``plain`` stands.

    A solver follows a moving target from where the chain is, and nothing in its step keeps the
    joints off their stops: CCD turns each joint as far as the end asks, and curls a chain into
    them. On `58_moving_base_line`, the base sliding under a target that came near it, CCD
    curled the last two of five joints onto their -150 deg stops; the end followed, until the
    line led where no pose near that coil reaches, and from the coil no restart got out (CCD,
    and damped least squares from the coil and from it backed off the stops, each ended 27 px
    short). Slid off the stops as it follows, the chain keeps the room to follow with.

    >>> arm = Skeleton.chain([100.0, 100.0, 100.0], limits=[(-2.5, 2.5)] * 3)
    >>> coiled = np.array([0.3, 2.45, -1.0])  # the elbow 0.05 rad from its stop
    >>> end = _chain_points(arm, coiled)[-1]
    >>> slid = _off_stops(arm, Solution(coiled, SolveStatus.SUCCESS, 3, 0.0), end, 0.5)
    >>> slid.angles.round(3).tolist(), bool(slid.error <= 0.5)  # the elbow turns back a little
    ([0.24, 2.437, -0.88], True)
    """
    limited = skeleton.limited
    lower, upper = skeleton.lower, skeleton.upper
    pose = plain.angles
    if not np.any(limited & ((pose - lower < OFF_STOPS) | (upper - pose < OFF_STOPS))):
        return plain
    middle = np.where(limited, (lower + upper) / 2.0, 0.0)
    spread = np.where(limited, ((upper - lower) / 2.0) ** 2, 1.0)
    for _ in range(OFF_STOPS_STEPS):
        away = _keeping_end(skeleton, pose, np.where(limited, (middle - pose) / spread, 0.0))
        largest = float(np.abs(away).max())
        if largest < 1e-12:
            break
        pose = skeleton.clamp(pose + away * min(1.0, OFF_STOPS_TURN / largest))
    error = _error(skeleton, pose, target)
    if error > tol:
        return plain
    return Solution(pose, plain.status, plain.iterations, error)


def _run_out(steps: Generator[object, None, _Out]) -> _Out:
    """The return value of a generator of steps (see :func:`_held_nearest_steps`), run out."""
    while True:
        try:
            next(steps)
        except StopIteration as done:
            return done.value


def _slid_down(
    skeleton: Skeleton,
    pose: np.ndarray,
    strain: Callable[[np.ndarray], float],
    slope: _Slope,
    keep_end: bool,
) -> Generator[None, None, tuple[np.ndarray, float]]:
    """``pose`` (radians, within the limits) slid down the ``strain`` of holding it, its
    steepest way (along the poses that keep the end where it is, the null space of the end's
    Jacobian, if ``keep_end``), ``RELIEF_TURN`` at most per joint and step, until it is within
    ``HOLDS`` or stops falling, a step at a time: the pose and its strain."""
    now = strain(pose)
    for _ in range(RELIEF_STEPS):
        if now <= HOLDS:
            break
        down = -slope(pose, now)
        if keep_end:
            down = _keeping_end(skeleton, pose, down)
        largest = float(np.abs(down).max())
        if largest < 1e-12:
            break
        step = down * (RELIEF_TURN / largest)
        for _ in range(6):
            trial = skeleton.clamp(pose + step)
            after = strain(trial)
            if after < now:
                pose, now = trial, after
                break
            step = step / 2.0
        else:
            break
        yield None
    return pose, now


def held_nearest(
    skeleton: Skeleton,
    starts: tuple[np.ndarray, ...],
    target: np.ndarray,
    strain: Callable[[np.ndarray], float],
    slope: Callable[[np.ndarray], np.ndarray] | None = None,
) -> np.ndarray | None:
    """The pose nearest ``target`` (px) that the motors hold (``strain`` within ``HOLDS``), as
    far as steps from each of ``starts`` (radians) find it: the answer for a target the motors
    cannot hold the end at, as the chain stretched toward it is for one out of reach. None
    when no start slides down to a pose they hold. ``slope`` is the strain's gradient (as
    :attr:`RobustSolver.strain_slope`); None takes it by differences.

    From each start the pose first slides down the ``strain`` (its steepest way, any joint)
    until the motors hold it; then damped least-squares steps bring the end toward the target,
    each shortened until it keeps within ``HOLDS``. On the edge, the steepest way down the
    error less its part that raises the strain slides along it. The end nearest the target
    wins.

    >>> arm = Skeleton.chain([100, 100])
    >>> strain = lambda angles: abs(float(angles[0])) / 0.5  # the base holds up to 0.475 rad
    >>> pose = held_nearest(arm, (np.zeros(2),), np.array([0.0, 200.0]), strain)
    >>> bool(strain(pose) <= HOLDS), round(float(pose[0]), 2)
    (True, 0.47)
    """
    return _run_out(_held_nearest_steps(skeleton, starts, target, strain, _sloped(strain, slope)))


def _held_nearest_steps(
    skeleton: Skeleton,
    starts: tuple[np.ndarray, ...],
    target: np.ndarray,
    strain: Callable[[np.ndarray], float],
    slope: _Slope,
) -> Generator[int, None, np.ndarray | None]:
    """:func:`held_nearest` a step at a time, so that a caller can spread the work over
    calls: each step yields how many times it asked the ``strain``, and the pose is the
    generator's return value."""
    counted, counted_slope, asked = _counting(strain, slope)
    best, best_error = None, math.inf
    for start in starts:
        pose = skeleton.clamp(np.array(start, dtype=float))
        held, now = yield from _asking(
            _slid_down(skeleton, pose, counted, counted_slope, False), asked
        )
        if now > HOLDS:
            continue
        held = yield from _asking(
            _held_toward(skeleton, held, target, counted, counted_slope), asked
        )
        error = _error(skeleton, held, target)
        if error < best_error:
            best, best_error = held, error
    return best


def _counting(
    strain: Callable[[np.ndarray], float], slope: _Slope
) -> tuple[Callable[[np.ndarray], float], _Slope, list[int]]:
    """``strain`` and its ``slope``, and a one-item list that counts how many times the strain
    is asked: a slope by differences asks it through the counted strain, one in closed form
    counts as ``SLOPE_STRAINS``."""
    asked = [0]

    def counted(angles: np.ndarray) -> float:
        asked[0] += 1
        return strain(angles)

    if isinstance(slope, _Differences):
        return counted, _Differences(counted), asked

    def counted_slope(angles: np.ndarray, now: float) -> np.ndarray:
        asked[0] += SLOPE_STRAINS
        return slope(angles, now)

    return counted, counted_slope, asked


def _asking(steps: Generator[None, None, _Out], asked: list[int]) -> Generator[int, None, _Out]:
    """``steps`` that yield, after each, how many times the strain was asked since the last
    (``asked[0]`` counts them all), and return what ``steps`` return."""
    before = asked[0]
    while True:
        try:
            next(steps)
        except StopIteration as done:
            return done.value
        yield asked[0] - before
        before = asked[0]


_Slope = Callable[[np.ndarray, float], np.ndarray]
"""The gradient of a strain at a pose (radians), given the strain there."""


class _Differences:
    """The gradient of ``strain`` by forward differences: one strain asked per joint."""

    def __init__(self, strain: Callable[[np.ndarray], float]) -> None:
        self.strain = strain

    def __call__(self, pose: np.ndarray, now: float) -> np.ndarray:
        nudges = 1e-4 * np.eye(len(pose))
        return np.array([self.strain(pose + nudge) - now for nudge in nudges]) / 1e-4


def _sloped(
    strain: Callable[[np.ndarray], float], slope: Callable[[np.ndarray], np.ndarray] | None
) -> _Slope:
    """The gradient of ``strain``: ``slope`` where given, else by differences."""
    if slope is None:
        return _Differences(strain)
    return lambda pose, now: slope(pose)


def _held_toward(
    skeleton: Skeleton,
    pose: np.ndarray,
    target: np.ndarray,
    strain: Callable[[np.ndarray], float],
    slope: _Slope,
) -> Generator[None, None, np.ndarray]:
    """Damped least-squares steps from ``pose`` (held within ``HOLDS``) toward ``target``
    (px), each kept within ``HOLDS``, until the end comes no nearer, a step at a time: the
    pose they end at."""
    damping = (0.1 * skeleton.reach) ** 2
    error = _error(skeleton, pose, target)
    now = strain(pose)
    for _ in range(HELD_STEPS):
        end = _chain_points(skeleton, pose)[-1]
        jac = jacobian(skeleton, pose)
        toward = jac.T @ np.linalg.solve(jac @ jac.T + damping * np.eye(2), target - end)
        largest = float(np.abs(toward).max())
        if largest < 1e-9:
            break
        step = toward * min(1.0, RELIEF_TURN / largest)
        moved = _shortened(skeleton, pose, step, target, error, strain)
        if moved is None:
            # On the edge of what the motors hold: slide along it, the steepest way down the
            # error (the Jacobian transpose's) less its part that raises the strain. That
            # part taken from the least-squares step can leave a step that turns away from
            # the target.
            rising = slope(pose, now)
            down = jac.T @ (target - end)
            rise = float(down @ rising)
            if rise > 0.0:
                down = down - rise / float(rising @ rising) * rising
            largest = float(np.abs(down).max())
            if largest < 1e-12:
                break
            moved = _shortened(
                skeleton, pose, down * (RELIEF_TURN / largest), target, error, strain
            )
            if moved is None:
                break
        pose, error, now = moved
        yield None
    return pose


def _shortened(
    skeleton: Skeleton,
    pose: np.ndarray,
    step: np.ndarray,
    target: np.ndarray,
    error: float,
    strain: Callable[[np.ndarray], float],
) -> tuple[np.ndarray, float, float] | None:
    """``pose`` moved by ``step`` (radians), halved up to five times, to the first pose that
    brings the end nearer ``target`` than ``error`` (px) and that the motors hold (``strain``
    within ``HOLDS``): that pose, its error and its strain; None if none does."""
    for _ in range(6):
        trial = skeleton.clamp(pose + step)
        after = _error(skeleton, trial, target)
        if after < error and (held := strain(trial)) <= HOLDS:
            return trial, after, held
        step = step / 2.0
    return None


def _far_tree_seeds(skeleton: Skeleton, solve: TargetSolver, fallback: TargetSolver) -> _Seeds:
    """A tree's restarts elsewhere in the joints' ranges: the middle of every range, then the
    random poses, each run by the solver and by its fallback (see :func:`_both`)."""
    yield from _both(_middle(skeleton), solve, fallback)
    for pose in _random_poses(skeleton):
        yield from _both(pose, solve, fallback)


def _both(
    pose: np.ndarray,
    solve: Solver | TargetSolver,
    fallback: Solver | TargetSolver,
    chained: bool = False,
) -> _Seeds:
    """A far restart from ``pose``: ``solve`` from it, then ``fallback`` from it too, or with
    ``chained``, from where ``solve`` stopped.

    From where the solver stopped, the fallback only polishes the trap the solver fell into:
    from every seed, CCD coiled sixteen light links' far joints onto their -165 deg stops
    28.8 px short of (-320, 30), at 96% of their reach, damped least squares run on from there
    could not leave the coil, and the search ended ``FAILURE``, a reachable target reported out
    of reach (`82_zero_g_sixteen_light_links`). From the seed it arrives. The search for an
    answer the motors hold chains them (see :func:`_far_held_seeds`): there the fallback from
    the seed cost two weak hanging arms their passing runs (`36_six_weak_links_hanging` with
    FABRIK came to rest with 2.1 px of jitter, `40_seven_weak_links_hanging` with CCD missed a
    target)."""
    if chained:
        yield pose, (solve, fallback)
    else:
        yield pose, (solve,)
        yield pose, (fallback,)


def _random_poses(skeleton: Skeleton, count: int = RANDOM_SEEDS) -> Iterator[np.ndarray]:
    """``count`` poses within the limits (within [-pi, pi]), from a fresh generator."""
    rng = np.random.default_rng(RANDOM_SEED)
    low = np.maximum(skeleton.lower, -math.pi)
    high = np.minimum(skeleton.upper, math.pi)
    for _ in range(count):
        yield rng.uniform(low, high)


def _far_seeds(
    skeleton: Skeleton,
    solve: Solver,
    fallback: Solver,
    stalled: np.ndarray,
    target: np.ndarray,
    drawn: int = RANDOM_SEEDS,
    chained: bool = False,
) -> _Seeds:
    """Restarts elsewhere in the joints' ranges (:func:`_far_poses`), each run by the solver
    and by its fallback (see :func:`_both`, which ``chained`` goes to)."""
    for pose in _far_poses(skeleton, stalled, target, drawn):
        yield from _both(pose, solve, fallback, chained)


def _far_poses(
    skeleton: Skeleton, stalled: np.ndarray, target: np.ndarray, drawn: int
) -> Iterator[np.ndarray]:
    """The far restarts, in order: round each of the first ``ROUND_JOINTS`` joints' limits,
    mirrored, bends reversed, stretched toward the target, the middle of every range, then
    ``drawn`` random poses; each (but the stretched one) aimed at the target."""
    points = _chain_points(skeleton, stalled)
    for j in range(min(ROUND_JOINTS, skeleton.count)):
        round_the_limit = _the_other_way_round(skeleton, stalled, points, j, target)
        if round_the_limit is not None:
            yield round_the_limit
    heading = math.atan2(*(target - skeleton.base)[::-1]) - skeleton.base_angle
    mirrored = -stalled
    mirrored[0] = 2.0 * heading - stalled[0]
    yield _aimed(skeleton, skeleton.clamp(mirrored), target)
    bends_reversed = -stalled
    bends_reversed[0] = stalled[0]
    yield _aimed(skeleton, skeleton.clamp(bends_reversed), target)
    yield _stretched_toward(skeleton, target)
    yield _aimed(skeleton, _middle(skeleton), target)
    for pose in _random_poses(skeleton, drawn):
        yield _aimed(skeleton, pose, target)


def _the_other_way_round(
    skeleton: Skeleton, angles: np.ndarray, points: np.ndarray, j: int, target: np.ndarray
) -> np.ndarray | None:
    """``angles`` with joint ``j`` turned to aim the end at the target the way its limits allow.

    None when the short way is allowed anyway (the solver would have taken it) or the joint is
    free. When neither way reaches the aim, the joint goes to its other limit, as far round as
    it can.
    """
    low, high = skeleton.lower[j], skeleton.upper[j]
    if not skeleton.limited[j]:
        return None
    arm = points[-1] - points[j]
    to_target = target - points[j]
    turn = math.atan2(arm[0] * to_target[1] - arm[1] * to_target[0], arm @ to_target)
    wanted = angles[j] + turn
    if low <= wanted <= high:
        return None
    seed = angles.copy()
    for other in (wanted - _TWO_PI, wanted + _TWO_PI):
        if low <= other <= high:
            seed[j] = other
            return seed
    seed[j] = low if wanted > high else high
    return seed if math.isfinite(seed[j]) else None


def _backed_off(skeleton: Skeleton, angles: np.ndarray) -> np.ndarray:
    """``angles`` with every joint moved ``BACK_OFF`` of its range away from its limits."""
    low = np.maximum(skeleton.lower, -math.pi)
    high = np.minimum(skeleton.upper, math.pi)
    margin = BACK_OFF * (high - low)
    return np.clip(angles, low + margin, high - margin)


def _middle(skeleton: Skeleton) -> np.ndarray:
    """Each joint in the middle of its range within [-pi, pi] (a free joint at 0), radians."""
    return 0.5 * (np.maximum(skeleton.lower, -math.pi) + np.minimum(skeleton.upper, math.pi))


def _stretched_toward(skeleton: Skeleton, target: np.ndarray) -> np.ndarray:
    """The chain as straight as its limits allow, its base joint aimed at the target, radians."""
    return _aimed(skeleton, skeleton.clamp(np.zeros(skeleton.count)), target)


def _aimed(skeleton: Skeleton, angles: np.ndarray, target: np.ndarray) -> np.ndarray:
    """``angles`` with the base joint turned so the base-to-end line points at the target.

    The turn goes whichever way round the base joint's limits allow; ``angles`` (within the
    limits) are returned as they are when neither way does.
    """
    end = _chain_points(skeleton, angles)[-1] - skeleton.base
    to_target = target - skeleton.base
    turn = math.atan2(end[0] * to_target[1] - end[1] * to_target[0], end @ to_target)
    wanted = wrap_angle(angles[0] + turn)
    low, high = skeleton.lower[0], skeleton.upper[0]
    choices = [c for c in (wanted, wanted - _TWO_PI, wanted + _TWO_PI) if low <= c <= high]
    if not choices:
        # Clamping the aim would pile every seed onto one limit; keep the seed's own variety.
        return angles
    aimed = angles.copy()
    aimed[0] = min(choices, key=lambda c: abs(c - angles[0]))
    return aimed


def _stuck(plain: Solution, before: float) -> bool:
    """Whether a plain solve that started ``before`` px from its goal stuck short of it: it
    failed, or gained less than ``STALL_PROGRESS`` of that."""
    return plain.status is SolveStatus.FAILURE or (
        plain.status is SolveStatus.PROCESSING and before - plain.error < STALL_PROGRESS * before
    )


def _gap(free_joints: list[bool], measured: list[float], answer: list[float]) -> float:
    """The largest turn (radians) any joint of ``measured`` has to make to ``answer`` (a free
    joint the short way round)."""
    return max(
        abs(wrap_angle(a - m)) if free else abs(a - m)
        for m, a, free in zip(measured, answer, free_joints, strict=True)
    )


def _within(free_joints: list[bool], measured: list[float], answer: list[float]) -> bool:
    """Whether every joint of ``measured`` is within ``SETTLED`` of ``answer`` (a free joint the
    short way round)."""
    for m, a, free in zip(measured, answer, free_joints, strict=True):
        gap = abs(m - a)
        if gap > SETTLED and not (free and abs(wrap_angle(m - a)) <= SETTLED):
            return False
    return True


def _error(skeleton: Skeleton, angles: np.ndarray, target: np.ndarray) -> float:
    end = _chain_points(skeleton, angles)[-1]
    return math.hypot(float(end[0] - target[0]), float(end[1] - target[1]))


def _float_chain(skeleton: Skeleton) -> FloatChain | None:
    """The chain as floats for :meth:`RobustSolver.solve`, or None for a tree or a chain whose
    joint 0 sits off the base (only :meth:`RobustSolver.solve_targets` takes those)."""
    return FloatChain(skeleton) if skeleton.is_chain and not skeleton.has_root_offsets else None


def _goal_key(targets: TargetSet) -> _Goal:
    """A target set as the cache compares it."""
    return (
        tuple(targets.links.tolist()),
        tuple(targets.points.ravel().tolist()),
        tuple(targets.weights.tolist()),
    )


def _target_errors(skeleton: Skeleton, angles: np.ndarray, targets: TargetSet) -> np.ndarray:
    """(k,) distance from each targeted end to its target, px."""
    ends = tree_points(skeleton, angles, skeleton.root_points())[1][targets.links]
    return np.hypot(*(ends - targets.points).T)
