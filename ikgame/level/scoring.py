"""Scores: how well each step and goal went, and the level's score out of 100.

Per item (documented in docs/levels.md, section Scoring):

- reach: 0 when failed, else ``100 x (0.5 + 0.5 x clamp(1 - time_to_reach / timeout))``: half
  the marks for getting there, the other half for getting there fast.
- follow: 0 when failed, else ``100 x (0.5 + 0.5 x clamp(1 - mean_error / tolerance))``: half
  for staying within tolerance on average, the other half for how far within.
- goal: 100 when passed, else 0.
- wait and set steps are not scored (their ``score`` is None).

The level's score is the mean of its items' scores, rounded to 0.1; 0 when the run diverged;
100 or 0 (passed or not) for a level without a scored item. A goal is judged on the prop's
centre: inside its region when the run ends, and inside without a break for the last ``hold``
seconds.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np

from ikgame.level.model import Goal

__all__ = [
    "GoalOutcome",
    "GoalTracker",
    "reach_score",
    "follow_score",
    "level_score",
]

_EPS: Final = 1e-9
"""Slack on time comparisons (s): tick times are sums of floats."""


def _clamp01(value: float) -> float:
    return min(1.0, max(0.0, value))


def reach_score(time_to_reach: float | None, timeout: float) -> float:
    """Score of a reach step: 0 when not reached (``time_to_reach`` None), 50..100 when reached.

    >>> reach_score(1.0, 4.0), reach_score(None, 4.0)
    (87.5, 0.0)
    """
    if time_to_reach is None:
        return 0.0
    return 100.0 * (0.5 + 0.5 * _clamp01(1.0 - time_to_reach / timeout))


def follow_score(mean_error: float | None, tolerance: float) -> float:
    """Score of a passed follow step from its mean tracking error (px): 50..100.

    >>> follow_score(5.0, 20.0)
    87.5
    """
    if mean_error is None:
        return 0.0
    return 100.0 * (0.5 + 0.5 * _clamp01(1.0 - mean_error / tolerance))


def level_score(
    step_scores: Sequence[float | None],
    goal_scores: Sequence[float],
    *,
    passed: bool,
    diverged: bool,
) -> float:
    """The level's score, 0..100: the mean of the scored items (unscored steps are None).

    >>> level_score([100.0, None, 50.0], [0.0], passed=False, diverged=False)
    50.0
    """
    if diverged:
        return 0.0
    scores = [s for s in step_scores if s is not None] + list(goal_scores)
    if not scores:
        return 100.0 if passed else 0.0
    return round(sum(scores) / len(scores), 1)


@dataclass(frozen=True)
class GoalOutcome:
    """How one goal went: its prop's centre at the end (px) and how long it had been inside (s).

    >>> GoalOutcome(0, "goal 1", "ball", True, (1.0, 2.0), 0.5).as_dict()["final_position"]
    [1.0, 2.0]
    """

    index: int
    name: str
    prop: str
    passed: bool
    final_position: tuple[float, float]
    time_inside: float

    @property
    def score(self) -> float:
        """100 when passed, else 0."""
        return 100.0 if self.passed else 0.0

    def as_dict(self) -> dict[str, object]:
        """Plain data for ``results.json`` in a fixed key order, floats rounded to 1e-4."""
        return {
            "index": self.index,
            "name": self.name,
            "prop": self.prop,
            "passed": self.passed,
            "score": self.score,
            "final_position": [_round(v) for v in self.final_position],
            "time_inside": _round(self.time_inside),
        }


def _round(value: float) -> float | None:
    return round(value, 4) if math.isfinite(value) else None


class GoalTracker:
    """Watches each goal's prop every tick: when it last entered its region.

    ``prop_names`` lists the props in the order of the positions passed to :meth:`observe`.

    >>> from ikgame.level.model import Goal
    >>> tracker = GoalTracker([Goal(prop="ball", region=(0, 0, 10, 10))], ["ball"])
    >>> tracker.observe(0.5, np.array([[5.0, 5.0, 0.0]]))
    >>> tracker.finish(1.0, np.array([[5.0, 6.0, 0.0]]))[0].passed
    True
    """

    def __init__(self, goals: Sequence[Goal], prop_names: Sequence[str]) -> None:
        self.goals = tuple(goals)
        rows = {name: i for i, name in enumerate(prop_names)}
        self._rows = [rows[g.prop] for g in self.goals]
        self._entered: list[float | None] = [None] * len(self.goals)

    def observe(self, time: float, positions: np.ndarray) -> None:
        """Note which props are inside their goals at ``time`` (s); ``positions`` is (p, 3)."""
        for i, goal in enumerate(self.goals):
            x, y = positions[self._rows[i], :2]
            xmin, ymin, xmax, ymax = goal.region
            if xmin <= x <= xmax and ymin <= y <= ymax:
                if self._entered[i] is None:
                    self._entered[i] = time
            else:
                self._entered[i] = None

    def finish(self, time: float, positions: np.ndarray) -> tuple[GoalOutcome, ...]:
        """Judge every goal at the end of the run (``time`` s, final ``positions``)."""
        self.observe(time, positions)
        out = []
        for i, goal in enumerate(self.goals):
            entered = self._entered[i]
            inside = 0.0 if entered is None else time - entered
            x, y = positions[self._rows[i], :2]
            out.append(
                GoalOutcome(
                    index=i,
                    name=goal.name or f"goal {i + 1}",
                    prop=goal.prop,
                    passed=entered is not None and inside >= goal.hold - _EPS,
                    final_position=(float(x), float(y)),
                    time_inside=inside,
                )
            )
        return tuple(out)
