"""The level script at run time: where each effector aims, and how each step scored.

A :class:`ScriptRunner` plays the level's steps in order. Each tick the simulation reads
``runner.targets`` (``runner.target`` for a chain) before stepping the world, then calls
``runner.observe(time, dt, effectors)`` with the new effector positions (a chain may pass its
tip's alone); a step that finishes hands over to the next one at once. Targets are sticky: an
effector keeps its last target until a later step sets it again, and one never targeted has
none (it holds its pose).

Each step kind is a small class with ``effectors`` (the names it moves), ``targets(time)``,
``observe(time, dt, positions)`` (True when finished) and ``outcome(time)``; add a kind by adding
a class and a line to ``_RUNS``.

Two kinds never reach a run class: a ``sequence`` is expanded into reach steps when the runner
is built (:func:`expand_script`), and a ``set`` step finishes the moment it begins, leaving its
changes in :attr:`ScriptRunner.pending` for the simulation to apply to the world and controller.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np

from ikgame.level.model import (
    CHAIN_EFFECTOR,
    FollowCircle,
    FollowLine,
    FollowLissajous,
    FollowPolyline,
    ReachStep,
    SequenceStep,
    SetChanges,
    SetStep,
    Step,
    WaitStep,
    follow_duration,
)
from ikgame.level.scoring import follow_score, reach_score

__all__ = ["StepOutcome", "ScriptRunner", "expand_script", "follow_path", "EASINGS"]

_EPS: Final = 1e-9
"""Slack on time comparisons (s): tick times are sums of floats."""

EASINGS: Final[dict[str, Callable[[float], float]]] = {
    "linear": lambda u: u,
    "in": lambda u: u * u,
    "out": lambda u: 1.0 - (1.0 - u) * (1.0 - u),
    "in-out": lambda u: u * u * (3.0 - 2.0 * u),
}
"""How a follow step's path parameter runs, as a map of [0, 1] onto itself."""

_OUTCOME_KEYS: Final = (
    "index",
    "source",
    "kind",
    "passed",
    "score",
    "reached",
    "time_to_reach",
    "final_error",
    "mean_error",
    "max_error",
    "started",
    "ended",
    "note",
)


@dataclass(frozen=True)
class StepOutcome:
    """How one script step went; times in s, errors in px (None where not measured).

    ``index`` counts the steps as they run (each point of a ``sequence`` is a step of its own);
    ``source`` is the step's index in the file's ``script`` list. ``score`` is 0..100 for the
    steps that are scored (reach, follow) and None for wait and set. In a tree (a script whose
    effectors are named), ``effectors`` names those the step moved and ``final_errors`` gives
    each one's final error in that order; ``final_error`` is then the largest of them. A
    chain's outcomes leave both empty.

    >>> StepOutcome(0, "reach", True, True, 1.25, 2.0).as_dict()["time_to_reach"]
    1.25
    """

    index: int
    kind: str
    passed: bool
    reached: bool | None = None
    time_to_reach: float | None = None
    final_error: float | None = None
    mean_error: float | None = None
    max_error: float | None = None
    started: float = 0.0
    ended: float | None = None
    note: str = ""
    score: float | None = None
    source: int | None = None
    effectors: tuple[str, ...] = ()
    final_errors: tuple[float, ...] = ()

    def as_dict(self) -> dict[str, object]:
        """Plain data for ``results.json``, in a fixed key order: floats rounded to 1e-4,
        unmeasured values None; ``effectors`` and ``final_errors`` last, in a tree only.

        >>> StepOutcome(0, "reach", True, effectors=("a", "b"),
        ...     final_errors=(1.0, 2.5)).as_dict()["final_errors"]
        [1.0, 2.5]
        """
        out = {key: _plain(getattr(self, key)) for key in _OUTCOME_KEYS}
        if self.effectors:
            out["effectors"] = list(self.effectors)
            out["final_errors"] = [_plain(e) for e in self.final_errors]
        return out


def _plain(value: object) -> object:
    if isinstance(value, float):
        return round(value, 4) if math.isfinite(value) else None
    return value


def expand_script(steps: list[Step] | tuple[Step, ...]) -> tuple[tuple[int, Step], ...]:
    """The steps as they run, each with its index in the file: sequences become reach steps.

    >>> [(i, type(s).__name__) for i, s in expand_script(
    ...     [WaitStep(wait=1.0), SequenceStep(sequence=[(0, 1), (1, 0)])])]
    [(0, 'WaitStep'), (1, 'ReachStep'), (1, 'ReachStep')]
    """
    out: list[tuple[int, Step]] = []
    for source, step in enumerate(steps):
        if isinstance(step, SequenceStep):
            out.extend((source, reach) for reach in step.reach_steps())
        else:
            out.append((source, step))
    return tuple(out)


PathFn = Callable[[float], tuple[float, float]]


def follow_path(step: FollowLine | FollowCircle | FollowLissajous | FollowPolyline) -> PathFn:
    """The target's position (px) ``s`` seconds along a follow step's path, before easing.

    >>> from ikgame.level.model import FollowCircle
    >>> path = follow_path(FollowCircle(follow="circle", center=(0, 0), radius=10, period=4,
    ...     duration=4))
    >>> [round(v, 6) for v in path(1.0)]
    [0.0, 10.0]
    """
    if isinstance(step, FollowLine):
        (x0, y0), (x1, y1), duration = step.from_, step.to, step.duration

        def line(s: float) -> tuple[float, float]:
            u = s / duration
            return (x0 + (x1 - x0) * u, y0 + (y1 - y0) * u)

        return line
    if isinstance(step, FollowCircle):
        (cx, cy), radius = step.center, step.radius
        start = math.radians(step.start)
        turn = (1.0 if step.direction == "ccw" else -1.0) * 2.0 * math.pi / step.period

        def circle(s: float) -> tuple[float, float]:
            angle = start + turn * s
            return (cx + radius * math.cos(angle), cy + radius * math.sin(angle))

        return circle
    if isinstance(step, FollowLissajous):
        (cx, cy), (ax, ay) = step.center, step.amplitude
        wx, wy = (2.0 * math.pi * f for f in step.frequency)
        phase = math.radians(step.phase)

        def lissajous(s: float) -> tuple[float, float]:
            return (cx + ax * math.sin(wx * s + phase), cy + ay * math.sin(wy * s))

        return lissajous
    points = [(float(x), float(y)) for x, y in step.points]
    along = [0.0]
    for a, b in zip(points, points[1:], strict=False):
        along.append(along[-1] + math.dist(a, b))
    speed = step.speed

    def polyline(s: float) -> tuple[float, float]:
        distance = min(max(speed * s, 0.0), along[-1])
        i = min(bisect.bisect_right(along, distance), len(points) - 1)
        piece = along[i] - along[i - 1]
        u = (distance - along[i - 1]) / piece if piece > 0 else 1.0
        (x0, y0), (x1, y1) = points[i - 1], points[i]
        return (x0 + (x1 - x0) * u, y0 + (y1 - y0) * u)

    return polyline


class _Run:
    """What every step kind shares: where it sits in the script, when it began, and which
    effectors it moves (``named``: report them in the outcome, as a tree's script does)."""

    kind = ""

    def __init__(self, index: int, source: int, start: float, named: bool) -> None:
        self.index, self.source, self.start, self.named = index, source, start, named
        self.effectors: tuple[str, ...] = ()
        self.errors: dict[str, float] = {}

    def targets(self, time: float) -> dict[str, np.ndarray]:
        return {}

    def _outcome(self, passed: bool, ended: float, **measures: object) -> StepOutcome:
        if self.named and self.effectors:
            measures["effectors"] = self.effectors
            measures["final_errors"] = tuple(self.errors.get(n, math.nan) for n in self.effectors)
        return StepOutcome(
            index=self.index,
            kind=self.kind,
            passed=passed,
            started=self.start,
            ended=ended,
            source=self.source,
            **measures,
        )


class _ReachRun(_Run):
    """Aim each of the step's effectors at its point; pass once they are all within tolerance
    together for ``hold`` s. The step's error is the largest of theirs."""

    kind = "reach"

    def __init__(
        self,
        index: int,
        source: int,
        step: ReachStep,
        start: float,
        default: str | None,
        named: bool,
    ) -> None:
        super().__init__(index, source, start, named)
        self.step = step
        self.points = {
            name: np.array(point, dtype=float) for name, point in step.targets(default).items()
        }
        self.effectors = tuple(self.points)
        self.entered: float | None = None
        self.error = math.nan
        self.done_as: StepOutcome | None = None

    def targets(self, time: float) -> dict[str, np.ndarray]:
        return self.points

    def observe(self, time: float, dt: float, positions: Mapping[str, np.ndarray]) -> bool:
        self.errors = {
            name: _distance(positions[name], point) for name, point in self.points.items()
        }
        self.error = max(self.errors.values())
        if self.error <= self.step.tolerance:
            if self.entered is None:
                self.entered = time
            if time - self.entered >= self.step.hold - _EPS:
                self._finish(time, reached=True)
                return True
        else:
            self.entered = None
        if time - self.start >= self.step.timeout - _EPS:
            self._finish(time, reached=False)
            return True
        return False

    def _finish(self, time: float, *, reached: bool, note: str = "") -> None:
        time_to_reach = (self.entered - self.start) if reached else None
        self.done_as = self._outcome(
            reached,
            time,
            reached=reached,
            time_to_reach=time_to_reach,
            final_error=self.error,
            note=note if note else ("" if reached else "timed out"),
            score=reach_score(time_to_reach, self.step.timeout),
        )

    def outcome(self, time: float) -> StepOutcome:
        if self.done_as is None:
            self._finish(time, reached=False, note="level ended first")
        return self.done_as


class _FollowRun(_Run):
    """Aim the effector at the path's start for ``lead_in`` s, then at a target moving along the
    path; the tracking error is measured every tick of the motion and passes when its mean stays
    within tolerance."""

    kind = "follow"

    def __init__(
        self, index: int, source: int, step, start: float, default: str | None, named: bool
    ) -> None:
        super().__init__(index, source, start, named)
        self.step = step
        self.name = _effector(step.effector, default)
        self.effectors = (self.name,)
        self.path = follow_path(step)
        self.ease = EASINGS[step.easing]
        self.duration = follow_duration(step)
        self.moving_from = start + step.lead_in
        self.point = np.array(self.path(0.0))
        self.total = 0.0
        self.samples = 0
        self.worst = 0.0
        self.error = math.nan
        self.ended: float | None = None

    def targets(self, time: float) -> dict[str, np.ndarray]:
        return {self.name: self.point}

    def observe(self, time: float, dt: float, positions: Mapping[str, np.ndarray]) -> bool:
        t = time - self.moving_from
        if t > _EPS:
            u = min(t / self.duration, 1.0)
            self.point = np.array(self.path(self.duration * self.ease(u)))
            self.error = _distance(positions[self.name], self.point)
            self.errors = {self.name: self.error}
            self.total += self.error
            self.samples += 1
            self.worst = max(self.worst, self.error)
            if t >= self.duration - _EPS:
                self.ended = time
                return True
        return False

    def outcome(self, time: float) -> StepOutcome:
        mean = self.total / self.samples if self.samples else None
        if self.ended is None:
            passed, note = False, "level ended first"
        elif mean is not None and mean <= self.step.tolerance:
            passed, note = True, ""
        else:
            passed, note = False, "mean tracking error above tolerance"
        return self._outcome(
            passed,
            time if self.ended is None else self.ended,
            final_error=self.error,
            mean_error=mean,
            max_error=self.worst if self.samples else None,
            note=note,
            score=follow_score(mean, self.step.tolerance) if passed else 0.0,
        )


class _WaitRun(_Run):
    """Keep every target for a while; passes unless the level ends first."""

    kind = "wait"

    def __init__(
        self,
        index: int,
        source: int,
        step: WaitStep,
        start: float,
        default: str | None,
        named: bool,
    ) -> None:
        super().__init__(index, source, start, named)
        self.step = step
        self.ended: float | None = None

    def observe(self, time: float, dt: float, positions: Mapping[str, np.ndarray]) -> bool:
        if time - self.start >= self.step.wait - _EPS:
            self.ended = time
            return True
        return False

    def outcome(self, time: float) -> StepOutcome:
        ended = self.ended is not None
        return self._outcome(
            ended, self.ended if ended else time, note="" if ended else "level ended first"
        )


def _distance(point: np.ndarray, other: np.ndarray) -> float:
    """How far apart two (2,) points are, px: numpy's hypot of their differences, taken over
    floats (numpy's calls on two numbers cost more than the sums)."""
    (x, y), (u, v) = np.asarray(point, dtype=float).tolist(), np.asarray(other).tolist()
    return float(np.hypot(x - u, y - v))


def _effector(name: str | None, default: str | None) -> str:
    """The effector a step moves: the one it names, else the script's only one."""
    if name is not None:
        return name
    if default is None:
        raise ValueError(
            "a step that names no effector moves the only one, and this script has several; "
            'name it: effector = "name"'
        )
    return default


_RUNS = {
    ReachStep: _ReachRun,
    FollowLine: _FollowRun,
    FollowCircle: _FollowRun,
    FollowLissajous: _FollowRun,
    FollowPolyline: _FollowRun,
    WaitStep: _WaitRun,
}


class ScriptRunner:
    """Plays a level's script steps in order and keeps their outcomes.

    ``effectors`` names the effectors the script moves (``Level.script_effectors``; a chain's
    one, ``"tip"``, by default). A step that names none moves the only one; in a tree of several
    every step names its effectors (the level model checks it).

    >>> from ikgame.level.model import ReachStep
    >>> runner = ScriptRunner([ReachStep(reach=(0.0, 10.0), hold=0.0)])
    >>> runner.target.tolist()
    [0.0, 10.0]
    >>> runner.observe(0.1, 0.1, np.array([0.0, 9.0])); runner.done
    True
    >>> tree = ScriptRunner([ReachStep(reach={"left": (0, 5), "right": (9, 5)})],
    ...     effectors=("left", "right"))
    >>> {name: point.tolist() for name, point in tree.targets.items()}
    {'left': [0.0, 5.0], 'right': [9.0, 5.0]}
    """

    def __init__(
        self, steps: list[Step] | tuple[Step, ...], effectors: Sequence[str] = (CHAIN_EFFECTOR,)
    ) -> None:
        self.steps = expand_script(steps)
        self.effectors = tuple(effectors)
        self.outcomes: list[StepOutcome] = []
        # Changes of set steps that began, oldest first, until take_changes().
        self.pending: list[SetChanges] = []
        self._default = self.effectors[0] if len(self.effectors) == 1 else None
        # A chain's outcomes keep the shape results.json has always had.
        self._named = self.effectors != (CHAIN_EFFECTOR,)
        self._targets: dict[str, np.ndarray] = {}
        self._run = None
        self._upcoming: dict[str, np.ndarray] | None = None
        self._begin(0, 0.0)

    @property
    def default_effector(self) -> str | None:
        """The effector a step that names none moves: the only one, or None when the script
        moves several."""
        return self._default

    @property
    def step_index(self) -> int:
        """Index of the running step (== number of steps once the script is done)."""
        return len(self.outcomes)

    @property
    def done(self) -> bool:
        """True once every step has finished."""
        return self._run is None

    @property
    def targets(self) -> dict[str, np.ndarray]:
        """Every effector's current target, px, by name: those a step has aimed so far (each
        keeps its last target until a step sets it again), in the order first aimed."""
        return dict(self._targets)

    @property
    def target(self) -> np.ndarray | None:
        """The point the only effector aims at now, px (None before any target is set, and in a
        script of several effectors: read :attr:`targets`)."""
        return None if self._default is None else self._targets.get(self._default)

    @property
    def upcoming(self) -> dict[str, np.ndarray] | None:
        """Every effector's target once the next step begins, px, by name, when it is known
        before then: the running step holds its targets still (a reach or a wait) and the next
        is a reach step, with no set step between (one can change the solver or the gains);
        else None. A controller plans the way there while the chain holds its target.

        >>> runner = ScriptRunner([ReachStep(reach=(0, 10)), ReachStep(reach=(5, 5))])
        >>> runner.upcoming["tip"].tolist()
        [5.0, 5.0]
        """
        return self._upcoming

    def take_changes(self) -> list[SetChanges]:
        """The changes of the ``set`` steps that began since the last call, oldest first.

        >>> from ikgame.level.model import SetStep
        >>> ScriptRunner([SetStep(set={"gain": 20.0})]).take_changes()[0].gain
        20.0
        """
        changes, self.pending = self.pending, []
        return changes

    def observe(
        self, time: float, dt: float, effectors: Mapping[str, np.ndarray] | np.ndarray
    ) -> None:
        """Score the tick that just ended at ``time`` (s) with the effectors at ``effectors``
        (px, by name; a chain may pass its tip's position alone)."""
        if self._run is None:
            return
        # An array (a chain's tip, every tick) is told apart first: asking the Mapping ABC
        # costs more.
        if isinstance(effectors, np.ndarray) or not isinstance(effectors, Mapping):
            if self._default is None:
                raise ValueError(
                    f"this script moves several effectors ({', '.join(self.effectors)}); "
                    "observe them by name"
                )
            effectors = {self._default: effectors}
        finished = self._run.observe(time, dt, effectors)
        self._targets.update(self._run.targets(time))
        if finished:
            self.outcomes.append(self._run.outcome(time))
            self._begin(len(self.outcomes), time)

    def finish(self, time: float) -> list[StepOutcome]:
        """End the script at ``time`` (s): unfinished steps fail. Returns every outcome."""
        while self._run is not None:
            self.outcomes.append(self._run.outcome(time))
            self._begin(len(self.outcomes), time, ended=True)
        return self.outcomes

    def _begin(self, index: int, time: float, *, ended: bool = False) -> None:
        while index < len(self.steps) and isinstance(self.steps[index][1], SetStep):
            source, step = self.steps[index]
            if not ended:
                self.pending.append(step.set)
            note = "level ended first" if ended else ", ".join(sorted(step.set.model_fields_set))
            self.outcomes.append(
                StepOutcome(
                    index, "set", not ended, started=time, ended=time, note=note, source=source
                )
            )
            index += 1
        self._upcoming = None
        if index >= len(self.steps):
            self._run = None
            return
        source, step = self.steps[index]
        self._run = _RUNS[type(step)](index, source, step, time, self._default, self._named)
        self._targets.update(self._run.targets(time))
        if isinstance(self._run, _ReachRun | _WaitRun) and index + 1 < len(self.steps):
            after = self.steps[index + 1][1]
            if isinstance(after, ReachStep):
                points = after.targets(self._default).items()
                self._upcoming = self._targets | {
                    name: np.array(point, dtype=float) for name, point in points
                }
