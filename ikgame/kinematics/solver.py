"""The interface every IK solver shares: a status, a solution, and the registry by name.

A solver is a free function ``solve(skeleton, angles, target, *, max_iterations, tolerance)``
that starts from ``angles`` (radians, warm start) and returns a :class:`Solution` whose angles
respect the skeleton's joint limits. A multi-target solver takes a
:class:`~ikgame.kinematics.targets.TargetSet` in place of the one target point.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import TYPE_CHECKING, Protocol

import numpy as np

from ikgame.kinematics.skeleton import Skeleton

if TYPE_CHECKING:
    from ikgame.kinematics.targets import TargetSet

__all__ = ["SolveStatus", "Solution", "Solver", "TargetSolver"]


class SolveStatus(Enum):
    """Where a solve ended, in the CCD article's three states.

    >>> SolveStatus.SUCCESS.value
    'success'
    """

    SUCCESS = "success"
    """The end effector is within the tolerance of the target."""
    PROCESSING = "processing"
    """Still moving toward the target when the iteration budget ran out."""
    FAILURE = "failure"
    """The solver can get no closer (for example, the target is out of reach)."""


@dataclass(frozen=True, eq=False)
class Solution:
    """Desired local joint angles and how the solve went.

    >>> Solution(np.zeros(2), SolveStatus.SUCCESS, 1, 0.0).status.value
    'success'

    Attributes:
        angles: (n,) desired local joint angles, radians, within the joint limits.
        status: where the solve ended.
        iterations: iterations used.
        error: distance from the end effector to the target at ``angles``, px; for several
            targets, the largest distance over the targeted effectors.
        errors: (k,) distance from each targeted effector to its target, px, in the order of
            the :class:`~ikgame.kinematics.targets.TargetSet`; None from the chain solvers.
    """

    angles: np.ndarray
    status: SolveStatus
    iterations: int
    error: float
    errors: np.ndarray | None = None


class Solver(Protocol):
    """The signature of every solver function (``solve_ccd``, ``solve_dls`` ...)."""

    def __call__(
        self,
        skeleton: Skeleton,
        angles: np.ndarray,
        target: np.ndarray,
        *,
        max_iterations: int = ...,
        tolerance: float = ...,
    ) -> Solution: ...


class TargetSolver(Protocol):
    """The signature of every multi-target solver (``solve_ccd_targets`` ...): a
    :class:`~ikgame.kinematics.targets.TargetSet` instead of one point."""

    def __call__(
        self,
        skeleton: Skeleton,
        angles: np.ndarray,
        targets: TargetSet,
        *,
        max_iterations: int = ...,
        tolerance: float = ...,
    ) -> Solution: ...
