"""The level script at run time: which target the chain aims at, and how each step scored.

A :class:`ScriptRunner` plays the level's steps in order. Each tick the simulation reads
``runner.target`` before stepping the world, then calls ``runner.observe(time, effector)``
with the new end-effector position; a step that finishes hands over to the next one at once.
Each step kind is a small class with ``target(time)``, ``observe(time, dt, effector)`` (True
when finished) and ``outcome()``; add a kind by adding a class and a line to ``_RUNS``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ikgame.level.model import ReachStep, Step, WaitStep

__all__ = ["StepOutcome", "ScriptRunner"]


@dataclass(frozen=True)
class StepOutcome:
    """How one script step went; times in s, errors in px (None where not measured).

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

    def as_dict(self) -> dict[str, object]:
        """Plain data for ``results.json``: floats rounded to 1e-4, unmeasured values None."""
        return {k: _plain(v) for k, v in asdict(self).items()}


def _plain(value: object) -> object:
    if isinstance(value, float):
        return round(value, 4) if math.isfinite(value) else None
    return value


class _ReachRun:
    """Aim at a fixed point; pass once the effector stays within tolerance for ``hold`` s."""

    kind = "reach"

    def __init__(self, index: int, step: ReachStep, start: float, previous: np.ndarray | None):
        self.index, self.step, self.start = index, step, start
        self.point = np.array(step.reach, dtype=float)
        self.entered: float | None = None
        self.error = math.nan
        self.done_as: StepOutcome | None = None

    def target(self, time: float) -> np.ndarray | None:
        return self.point

    def observe(self, time: float, dt: float, effector: np.ndarray) -> bool:
        self.error = float(np.hypot(*(effector - self.point)))
        if self.error <= self.step.tolerance:
            if self.entered is None:
                self.entered = time
            if time - self.entered >= self.step.hold - 1e-9:
                self._finish(time, reached=True)
                return True
        else:
            self.entered = None
        if time - self.start >= self.step.timeout - 1e-9:
            self._finish(time, reached=False)
            return True
        return False

    def _finish(self, time: float, *, reached: bool, note: str = "") -> None:
        self.done_as = StepOutcome(
            index=self.index,
            kind=self.kind,
            passed=reached,
            reached=reached,
            time_to_reach=(self.entered - self.start) if reached else None,
            final_error=self.error,
            started=self.start,
            ended=time,
            note=note if note else ("" if reached else "timed out"),
        )

    def outcome(self, time: float) -> StepOutcome:
        if self.done_as is None:
            self._finish(time, reached=False, note="level ended first")
        return self.done_as


class _WaitRun:
    """Keep the previous target for a while; always passes."""

    kind = "wait"

    def __init__(self, index: int, step: WaitStep, start: float, previous: np.ndarray | None):
        self.index, self.step, self.start, self.point = index, step, start, previous
        self.ended: float | None = None

    def target(self, time: float) -> np.ndarray | None:
        return self.point

    def observe(self, time: float, dt: float, effector: np.ndarray) -> bool:
        if time - self.start >= self.step.wait - 1e-9:
            self.ended = time
            return True
        return False

    def outcome(self, time: float) -> StepOutcome:
        ended = self.ended is not None
        return StepOutcome(
            self.index,
            self.kind,
            passed=ended,
            started=self.start,
            ended=self.ended if ended else time,
            note="" if ended else "level ended first",
        )


_RUNS = {ReachStep: _ReachRun, WaitStep: _WaitRun}


class ScriptRunner:
    """Plays a level's script steps in order and keeps their outcomes.

    >>> from ikgame.level.model import ReachStep
    >>> runner = ScriptRunner([ReachStep(reach=(0.0, 10.0), hold=0.0)])
    >>> runner.target.tolist()
    [0.0, 10.0]
    >>> runner.observe(0.1, 0.1, np.array([0.0, 9.0])); runner.done
    True
    """

    def __init__(self, steps: list[Step] | tuple[Step, ...]) -> None:
        self.steps = tuple(steps)
        self.outcomes: list[StepOutcome] = []
        self._run = None
        self._begin(0, 0.0, None)

    @property
    def step_index(self) -> int:
        """Index of the running step (== number of steps once the script is done)."""
        return len(self.outcomes)

    @property
    def done(self) -> bool:
        """True once every step has finished."""
        return self._run is None

    @property
    def target(self) -> np.ndarray | None:
        """The point the chain should aim at now, px (None before any target is set)."""
        return self._target

    def observe(self, time: float, dt: float, effector: np.ndarray) -> None:
        """Score the tick that just ended at ``time`` (s) with the effector at ``effector`` (px)."""
        if self._run is None:
            return
        if self._run.observe(time, dt, effector):
            self.outcomes.append(self._run.outcome(time))
            self._begin(len(self.outcomes), time, self._target)
        else:
            self._target = self._run.target(time)

    def finish(self, time: float) -> list[StepOutcome]:
        """End the script at ``time`` (s): unfinished steps fail. Returns every outcome."""
        while self._run is not None:
            self.outcomes.append(self._run.outcome(time))
            self._begin(len(self.outcomes), time, self._target)
        return self.outcomes

    def _begin(self, index: int, time: float, previous: np.ndarray | None) -> None:
        if index >= len(self.steps):
            self._run = None
            self._target = previous
            return
        step = self.steps[index]
        self._run = _RUNS[type(step)](index, step, time, previous)
        self._target = self._run.target(time)
