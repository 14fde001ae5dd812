"""Solving tick after tick without getting trapped: restarts on a stall, and a per-chain cache.

The raw solvers are local: from a warm start they slide downhill, and joint limits make the
landscape full of places to stop short of a target that some pose within the limits reaches (a
base on its -30 deg stop when the answer needs +100 deg, a chain coiled into its limits, an elbow
that bends one way only). :class:`RobustSolver` wraps one of them for one chain and is called
once per tick:

1. **Cached answer.** While the last answer still puts the end effector within the tolerance of
   the target it is returned as it is, with zero iterations: a settled chain costs one forward
   kinematics, nothing when neither target nor skeleton changed. This is also the hysteresis
   that keeps a chain on one branch (elbow up or down) rather than flipping between two answers
   that both reach.
2. **Plain solve**, warm-started from whichever is nearer the target: the given (measured) pose,
   or the last answer (a moving target then stays on the branch the chain is following). When
   it arrives, or is still making headway, that is the answer: the common case costs what the
   raw solver costs.
3. **Recovery**, only when the plain solve stalled (``FAILURE``, or ``PROCESSING`` having gained
   less than ``STALL_PROGRESS`` of its start error) short of a target within reach. It restarts
   from other seeds, nearest first: the fallback solver from where the plain one stopped; each
   joint taken the other way round to aim at the target, inside its limits; the pose mirrored
   across the line from the base to the target, and with its bends reversed; the chain stretched
   toward the target; the middle of every joint's range; then ``RANDOM_SEEDS`` poses drawn within
   the limits by a generator seeded with ``RANDOM_SEED`` (so the same inputs give the same
   answer). Each seed runs the solver, then the fallback from where that stopped. The first seed
   that arrives wins; otherwise the lowest error is kept. At most ``budget`` iterations go into
   restarts per call; a search that runs out carries on at the next call with the same target,
   and one that has tried every seed is cached as ``FAILURE``, so an unreachable target costs
   nothing after that.

A target beyond the chain's reach gets the chain stretched straight toward it at once, when the
limits allow that pose (it is the closest any pose can come), with ``FAILURE``.

Angles are radians, lengths and positions pixels.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Final

import numpy as np

from ikgame.kinematics.ccd import wrap_angle
from ikgame.kinematics.jacobian import _chain_points, _check_solve_inputs, _wrap_free, solve_dls
from ikgame.kinematics.registry import get_solver
from ikgame.kinematics.skeleton import Skeleton
from ikgame.kinematics.solver import Solution, Solver, SolveStatus

__all__ = [
    "RobustSolver",
    "FALLBACK",
    "RESTART_BUDGET",
    "SEED_ITERATIONS",
    "RANDOM_SEEDS",
    "RANDOM_SEED",
    "STALL_PROGRESS",
]

RESTART_BUDGET: Final = 200
"""Default most iterations (of any solver) one call spends on restarts, beyond the plain solve.

On the 500 seeded random cases of docs/solvers.md a recovery that succeeds needs a median of
about 30 iterations; 200 lets most finish in the call that stalled while keeping a tick's worst
case near twenty plain solves."""

SEED_ITERATIONS: Final = 100
"""Most iterations one restart runs in one go, so a seed that crawls cannot eat the budget."""

RANDOM_SEEDS: Final = 8
"""Random poses (within the limits) tried after the deliberate seeds."""

RANDOM_SEED: Final = 20091
"""Seed of the generator that draws the random restarts, fresh for every search."""

STALL_PROGRESS: Final = 0.25
"""A solve still ``PROCESSING`` that gained less than this fraction of its start error stalled."""

BACK_OFF: Final = 0.15
"""The first restart moves every joint off its limits by this fraction of its range: the nearest
pose where the joints pressed into their limits can move both ways."""

ROUND_JOINTS: Final = 4
"""Joints, from the base out, that get a seed taking them the other way round their limits."""

FALLBACK: Final = {
    "ccd": "dls",
    "dls": "ccd",
    "fabrik": "dls",
    "jacobian_transpose": "dls",
}
"""The solver each solver's restarts fall back on: another method is trapped elsewhere."""

_TWO_PI: Final = 2.0 * math.pi


@dataclass(frozen=True, eq=False)
class _Answer:
    """A cached answer: angles (read-only), the target and skeleton it was solved for, its error."""

    angles: np.ndarray
    target: np.ndarray
    skeleton: Skeleton
    error: float
    status: SolveStatus


class RobustSolver:
    """One chain's solver with recovery from stalls and a cache; call :meth:`solve` every tick.

    Keep one per chain: it remembers the last answer and any search in progress. Change the
    skeleton (for example ``robust.skeleton = robust.skeleton.moved_to(base)`` when the base
    moves) or ``robust.solver_name`` at any time; :meth:`reset` forgets the cache (say, to
    re-solve a chain that is physically blocked from reaching its answer).

    >>> arm = Skeleton.chain([100, 80, 60], limits=[(-0.52, 2.09), (0.17, 2.97), (-2.97, -0.17)])
    >>> robust = RobustSolver(arm, "ccd")
    >>> sol = robust.solve(arm.lower, (-150.0, 20.0), max_iterations=10, tolerance=0.5)
    >>> sol.status.value, sol.error <= 0.5
    ('success', True)
    >>> robust.solve(sol.angles, (-150.0, 20.0), max_iterations=10, tolerance=0.5).iterations
    0
    """

    def __init__(
        self, skeleton: Skeleton, solver_name: str = "ccd", *, budget: int = RESTART_BUDGET
    ) -> None:
        if isinstance(budget, bool) or not isinstance(budget, int | np.integer) or budget < 0:
            raise ValueError(f"budget must be an integer >= 0 iterations, got {budget!r}")
        self.budget = int(budget)
        self._skeleton = skeleton
        self._name = ""
        self._solve: Solver = get_solver(solver_name)
        self._fallback: Solver = self._solve
        self.solver_name = solver_name

    @property
    def skeleton(self) -> Skeleton:
        """The chain being solved; set it when the base moves (the cache is checked against it)."""
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
        if not same_shape:
            self.reset()

    @property
    def solver_name(self) -> str:
        """The raw solver's name (``ccd``, ``dls``, ``fabrik``, ``jacobian_transpose``)."""
        return self._name

    @solver_name.setter
    def solver_name(self, name: str) -> None:
        self._solve = get_solver(name)
        self._fallback = get_solver(FALLBACK[name])
        self._name = name
        self.reset()

    def reset(self) -> None:
        """Forget the cached answer and any search in progress."""
        self._answer: _Answer | None = None
        self._search: _Search | None = None

    def solve(
        self,
        angles: np.ndarray,
        target: np.ndarray,
        *,
        max_iterations: int = 10,
        tolerance: float = 1.0,
    ) -> Solution:
        """Desired angles toward ``target`` (px) from the measured ``angles`` (radians).

        ``max_iterations`` bounds the plain solve; restarts add at most ``budget`` iterations.
        ``Solution.iterations`` counts both. The answer's angles are read-only.
        """
        skeleton = self._skeleton
        start, goal, tol = _check_solve_inputs(skeleton, angles, target, max_iterations, tolerance)
        answer = self._answer
        if answer is not None:
            error = self._error_of(answer, goal)
            if error <= tol or (answer.status is SolveStatus.FAILURE and error == answer.error):
                status = SolveStatus.SUCCESS if error <= tol else SolveStatus.FAILURE
                return Solution(answer.angles, status, 0, error)
        beyond = math.hypot(*(goal - skeleton.base)) - skeleton.reach
        if beyond >= 0.0:
            stretched = _stretched_toward(skeleton, goal)
            stretched_error = _error(skeleton, stretched, goal)
            # Only the straight chain aimed at the target comes this close; limits may forbid it.
            if stretched_error <= beyond + 1e-9 * skeleton.reach:
                status = SolveStatus.SUCCESS if stretched_error <= tol else SolveStatus.FAILURE
                return self._keep(Solution(stretched, status, 0, stretched_error), goal)
        start_error = _error(skeleton, start, goal)
        if answer is not None and error < start_error:
            start, start_error = answer.angles, error
        plain = self._solve(skeleton, start, goal, max_iterations=max_iterations, tolerance=tol)
        if plain.status is SolveStatus.SUCCESS:
            return self._keep(plain, goal)
        stalled = plain.status is SolveStatus.FAILURE or (
            start_error - plain.error < STALL_PROGRESS * start_error
        )
        search = self._search
        if search is not None and not search.aims_at(goal, tol):
            search = self._search = None
        if search is None and not stalled:
            return plain
        if search is None:
            search = self._search = _Search(
                skeleton, self._solve, self._fallback, plain.angles, goal, tol
            )
        used = search.run(skeleton, goal, tol, self.budget)
        best = plain
        if search.best is not None:
            found_error = _error(skeleton, search.best, goal)
            if found_error < plain.error:
                best = Solution(search.best, plain.status, 0, found_error)
        iterations = plain.iterations + used
        if best.error <= tol:
            return self._keep(
                Solution(best.angles, SolveStatus.SUCCESS, iterations, best.error), goal
            )
        if search.exhausted:
            return self._keep(
                Solution(best.angles, SolveStatus.FAILURE, iterations, best.error), goal
            )
        return Solution(best.angles, SolveStatus.PROCESSING, iterations, best.error)

    def _error_of(self, answer: _Answer, goal: np.ndarray) -> float:
        """The cached answer's error for ``goal`` on the current skeleton, px."""
        if answer.skeleton is self._skeleton and np.array_equal(answer.target, goal):
            return answer.error
        return _error(self._skeleton, answer.angles, goal)

    def _keep(self, solution: Solution, goal: np.ndarray) -> Solution:
        """Cache ``solution`` (an arrival, or the best there is) and return it read-only."""
        angles = _wrap_free(self._skeleton, np.asarray(solution.angles, dtype=float))
        angles.setflags(write=False)
        target = goal.copy()
        target.setflags(write=False)
        self._answer = _Answer(angles, target, self._skeleton, solution.error, solution.status)
        self._search = None
        return Solution(angles, solution.status, solution.iterations, solution.error)


class _Search:
    """Restarts for one target, resumable from call to call; remembers the best pose found."""

    def __init__(
        self,
        skeleton: Skeleton,
        solve: Solver,
        fallback: Solver,
        stalled: np.ndarray,
        target: np.ndarray,
        tolerance: float,
    ) -> None:
        self.target = target.copy()
        self.tolerance = tolerance
        self.best: np.ndarray | None = None
        self._best_error = math.inf
        # Each entry: a start pose and the solvers still to run from it, one after the other.
        self._queue: deque[tuple[np.ndarray, tuple[Solver, ...]]] = deque()
        self._seeds = _seeds(skeleton, solve, fallback, stalled, target)

    @property
    def exhausted(self) -> bool:
        """True once every seed has been tried."""
        return not self._queue and self._seeds is None

    def aims_at(self, goal: np.ndarray, tolerance: float) -> bool:
        """Whether this search serves ``goal``: the same target, to within the tolerance."""
        return tolerance == self.tolerance and math.hypot(*(goal - self.target)) <= tolerance

    def run(self, skeleton: Skeleton, goal: np.ndarray, tolerance: float, budget: int) -> int:
        """Try seeds until one arrives, none are left, or ``budget`` iterations are spent."""
        used = 0
        while used < budget and self._best_error > tolerance:
            entry = self._next()
            if entry is None:
                break
            angles, solvers = entry
            for index, solver in enumerate(solvers):
                allowed = min(SEED_ITERATIONS, budget - used)
                if allowed < 1:
                    self._queue.appendleft((angles, solvers[index:]))
                    return used
                sol = solver(skeleton, angles, goal, max_iterations=allowed, tolerance=tolerance)
                used += sol.iterations
                if sol.error < self._best_error:
                    self.best, self._best_error = sol.angles, sol.error
                if sol.status is SolveStatus.SUCCESS:
                    return used
                angles = sol.angles
        return used

    def _next(self) -> tuple[np.ndarray, tuple[Solver, ...]] | None:
        if self._queue:
            return self._queue.popleft()
        if self._seeds is not None:
            seed = next(self._seeds, None)
            if seed is not None:
                return seed
            self._seeds = None
        return None


def _seeds(
    skeleton: Skeleton, solve: Solver, fallback: Solver, stalled: np.ndarray, target: np.ndarray
) -> Iterator[tuple[np.ndarray, tuple[Solver, ...]]]:
    """Restart poses, each with the solvers to run from it, the nearest to ``stalled`` first.

    Near the stalled pose damped least squares goes first: its steps are the shortest that
    move the end effector, so it finds the answer nearest the pose rather than swinging the
    chain round (CCD turns the last joints first, whatever the distance).
    """
    if solve is not solve_dls:
        yield stalled, (solve_dls,)
    yield _backed_off(skeleton, stalled), (solve_dls,)
    both = (solve, fallback)
    points = _chain_points(skeleton, stalled)
    for j in range(min(ROUND_JOINTS, skeleton.count)):
        round_the_limit = _the_other_way_round(skeleton, stalled, points, j, target)
        if round_the_limit is not None:
            yield round_the_limit, both
    heading = math.atan2(*(target - skeleton.base)[::-1]) - skeleton.base_angle
    mirrored = -stalled
    mirrored[0] = 2.0 * heading - stalled[0]
    yield _aimed(skeleton, skeleton.clamp(mirrored), target), both
    bends_reversed = -stalled
    bends_reversed[0] = stalled[0]
    yield _aimed(skeleton, skeleton.clamp(bends_reversed), target), both
    yield _stretched_toward(skeleton, target), both
    yield _aimed(skeleton, _middle(skeleton), target), both
    rng = np.random.default_rng(RANDOM_SEED)
    low = np.maximum(skeleton.lower, -math.pi)
    high = np.minimum(skeleton.upper, math.pi)
    for _ in range(RANDOM_SEEDS):
        yield _aimed(skeleton, rng.uniform(low, high), target), both


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
    """Each joint in the middle of its range; a joint open on a side sits at 0 if it may."""
    middle = np.where(
        np.isfinite(skeleton.lower) & np.isfinite(skeleton.upper),
        0.5 * (skeleton.lower + skeleton.upper),
        0.0,
    )
    return skeleton.clamp(middle)


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


def _error(skeleton: Skeleton, angles: np.ndarray, target: np.ndarray) -> float:
    end = _chain_points(skeleton, angles)[-1]
    return math.hypot(float(end[0] - target[0]), float(end[1] - target[1]))
