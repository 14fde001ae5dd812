"""Per-tick joint control: IK solver -> desired angles -> motor rates.

Each tick the solver is warm-started from the measured pose and returns desired local angles
within the joint limits. Each motor is then asked for a relative angular velocity proportional to
its angle error (``gain``, 1/s), clamped by the joint's speed limit (rad/s). The motor's torque
limit is its ``max_force`` in the world, so a weak joint simply falls behind.

Because the gain is in 1/s and the motor holds a velocity, the pose approaches the desired one
with time constant ``1 / gain`` seconds whatever the tick rate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ikgame.kinematics import Skeleton, Solution, SolveStatus, get_solver, wrap_angle

__all__ = ["Command", "Controller", "joint_error"]


def joint_error(desired: np.ndarray, measured: np.ndarray, limited: np.ndarray) -> np.ndarray:
    """Signed angle error per joint, radians.

    A free joint takes the short way round (wrapped to [-pi, pi]). A limited joint is measured
    in its limits' frame and is never wrapped, so it never tries the long way through a limit.

    >>> joint_error(np.array([3.0, 3.0]), np.array([-3.0, -3.0]), np.array([False, True]))
    array([-0.28318531,  6.        ])
    """
    error = np.asarray(desired, dtype=float) - measured
    free = ~limited
    error[free] = [wrap_angle(e) for e in error[free]]
    return error


@dataclass(frozen=True, eq=False)
class Command:
    """One tick's decision: the solution and the motor rates it turned into.

    Attributes:
        solution: the solver's desired angles, status, iterations and kinematic error.
        rates: (n,) commanded relative angular velocity per joint (child - parent), rad/s.
    """

    solution: Solution
    rates: np.ndarray


class Controller:
    """Turns a target into motor rates; ``command(measured, target)`` once per tick.

    >>> ctl = Controller(Skeleton.chain([100.0]), "ccd", max_speed=np.array([1.0]))
    >>> ctl.command(np.zeros(1), np.array([0.0, 100.0])).rates.tolist()
    [1.0]
    """

    def __init__(
        self,
        skeleton: Skeleton,
        solver: str,
        *,
        max_speed: np.ndarray,
        gain: float = 12.0,
        iterations: int = 10,
        arrival: float = 0.5,
    ) -> None:
        if not (math.isfinite(gain) and gain > 0):
            raise ValueError(f"gain must be a positive number (1/s), got {gain!r}")
        self.skeleton = skeleton
        self.solver_name = solver
        self.solve = get_solver(solver)
        self.max_speed = np.asarray(max_speed, dtype=float)
        self.gain = float(gain)
        self.iterations = int(iterations)
        self.arrival = float(arrival)
        self._limited = skeleton.limited
        self._held: np.ndarray | None = None

    def set_solver(self, name: str) -> None:
        """Switch solver from the next tick on (``ccd``, ``jacobian_transpose``, ``dls``, ``fabrik``)."""
        self.solve = get_solver(name)
        self.solver_name = name

    def command(self, measured: np.ndarray, target: np.ndarray | None) -> Command:
        """Motor rates toward ``target`` (px) from the ``measured`` local angles (radians).

        With no target the chain holds the last pose it was asked for (or its current one).
        """
        if target is None:
            if self._held is None:
                self._held = self.skeleton.clamp(measured.copy())
            solution = Solution(self._held, SolveStatus.SUCCESS, 0, 0.0)
        else:
            start = np.where(self._limited, measured, [wrap_angle(a) for a in measured])
            solution = self.solve(
                self.skeleton,
                start,
                target,
                max_iterations=self.iterations,
                tolerance=self.arrival,
            )
            self._held = solution.angles
        error = joint_error(solution.angles, measured, self._limited)
        rates = np.clip(self.gain * error, -self.max_speed, self.max_speed)
        return Command(solution, rates)
