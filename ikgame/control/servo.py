"""The joint servo: angle errors -> a velocity each motor can reach and stop from -> torques.

A plain proportional servo (rate = gain x error, clipped by the speed limit) only slows down
within ``max_speed / gain`` of the goal, which is too late for a heavy, stretched arm, and once a
motor is at its torque limit it keeps asking for more, so a saturated arm swings like a pendulum.
This servo instead:

1. commands, per joint, ``min(max_speed, gain |e|, sqrt(2 a |e|))`` toward the goal, where ``a``
   is the deceleration the joint's spare torque (its limit less what gravity takes) gives the
   inertia beyond it: a velocity it can still brake from in time;
2. never asks a joint for a velocity change it cannot make in one tick (``a x dt``), and a
   joint that is saturated yet carried away from its goal asks only to stop until the target
   moves (anti-windup): it comes to rest where its torque runs out instead of swinging there;
3. turns the wanted velocity change into feed-forward torques and pivot forces with the chain's
   dynamics (:func:`~ikgame.control.dynamics.plan_drive`), within the torque limits, so that the
   physics engine's motors only correct what the model missed. Without that, the constraint
   solver would have to find the torques of a long chain by itself in a few iterations, and it
   does not: a 30-link chain never settles.

Units: radians, rad/s, px, s, torques mass px^2/s^2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final

import numpy as np

from ikgame.control.dynamics import ChainInertia, inverse_dynamics, plan_drive

__all__ = ["Servo", "ServoCommand"]

BRAKE_SHARE: Final = 0.5
"""Share of a joint's spare torque the velocity profile plans to brake with: the rest is margin
for the other joints moving at the same time, which the one-joint inertia does not see."""


@dataclass(frozen=True, eq=False)
class ServoCommand:
    """What the servo asks of the world for one tick.

    Attributes:
        rates: (n,) relative angular velocity each motor should hold by the end of the tick
            (child - parent), rad/s.
        torques: (n,) feed-forward joint torques, within the limits.
        forces: (n, 2) feed-forward pivot forces (parent on child, world frame).
        budgets: (n,) torque each motor may still add to correct errors, >= 0.
        saturated: (n,) bool, joints whose feed-forward torque is at its limit.
    """

    rates: np.ndarray
    torques: np.ndarray
    forces: np.ndarray
    budgets: np.ndarray
    saturated: np.ndarray


class Servo:
    """Drives a chain's joints toward desired angles within torque and speed limits.

    >>> servo = Servo(ChainInertia(np.array([10.0]), np.array([2.0]), np.array([50.0 / 3.0])),
    ...               max_torque=np.array([1.0e6]), max_speed=np.array([2.0]), gain=12.0)
    >>> command = servo.command(np.array([1.0]), np.zeros(1), np.zeros(1), (0.0, 0.0), 1 / 240)
    >>> command.rates.round(6).tolist(), command.saturated.tolist()
    ([2.0], [False])
    """

    def __init__(
        self,
        inertia: ChainInertia,
        *,
        max_torque: np.ndarray,
        max_speed: np.ndarray,
        gain: float,
    ) -> None:
        self.inertia = inertia
        self.max_torque = np.asarray(max_torque, dtype=float)
        self.max_speed = np.asarray(max_speed, dtype=float)
        self.gain = float(gain)
        count = len(self.max_torque)
        self._stalled = np.zeros(count, dtype=bool)
        self._saturated = np.zeros(count, dtype=bool)
        self._velocities = np.zeros(count)

    def retry(self) -> None:
        """Let joints that stalled at their torque limit push for their goals again: the target
        moved, or the world changed (gravity), so the goal may be within reach now."""
        self._stalled[:] = False

    def command(
        self,
        error: np.ndarray,
        world_angles: np.ndarray,
        velocities: np.ndarray,
        gravity: tuple[float, float] | np.ndarray,
        dt: float,
        goal_rates: np.ndarray | None = None,
    ) -> ServoCommand:
        """One tick's command from each joint's angle ``error`` (radians) and the measured pose.

        ``world_angles`` are per link (radians), ``velocities`` per joint (child - parent,
        rad/s), ``gravity`` px/s^2 and ``dt`` the tick, s. ``goal_rates`` (rad/s) is how fast
        the desired angles themselves move, when they follow a moving target: the servo moves
        with them and closes the error on top, instead of lagging behind.
        """
        omega = np.cumsum(velocities)
        still = np.zeros_like(omega)
        hold = inverse_dynamics(self.inertia, world_angles, still, still, gravity)
        spare = np.maximum(self.max_torque - np.abs(hold.torques), 0.0)
        reach = spare / hold.inertia
        brake = BRAKE_SHARE * reach
        # Anti-windup: a joint pushing at its limit yet carried away from its goal cannot get
        # there; it asks only to stop, until :meth:`retry`, so it comes to rest where its
        # torque runs out instead of swinging about that point like a pendulum. Carried away
        # means moving from the goal faster than a tick ago: an overshoot that the motor is
        # braking slows down instead, and is no stall.
        self._stalled |= (
            self._saturated
            & (velocities * error < 0.0)
            & (np.abs(velocities) > np.abs(self._velocities))
        )
        self._velocities = velocities
        size = np.where(self._stalled, 0.0, np.abs(error))
        speed = np.minimum(
            np.minimum(self.max_speed, self.gain * size), np.sqrt(2.0 * brake * size)
        )
        target = np.sign(error) * speed
        if goal_rates is not None:
            target = target + goal_rates
        target = np.clip(target, -self.max_speed, self.max_speed)
        # Joints of a long chain moving at once whip its far end round: the torques that merely
        # keep those velocities grow with their square. Slow every joint by one factor until
        # they fit in the share of spare torque that braking leaves.
        spin = inverse_dynamics(self.inertia, world_angles, np.cumsum(target), still, (0.0, 0.0))
        need = np.abs(spin.torques)
        room = (1.0 - BRAKE_SHARE) * spare
        over = need > room
        if np.any(over):
            target = target * math.sqrt(float(np.min(room[over] / need[over])))
        # Approach that velocity no faster than each joint's spare torque allows: a servo that
        # asked for the whole change in one tick would saturate every motor after any knock.
        wanted = np.clip(target, velocities - reach * dt, velocities + reach * dt)
        wanted_acceleration = (wanted - velocities) / dt
        drive = plan_drive(
            self.inertia, world_angles, omega, wanted_acceleration, gravity, self.max_torque
        )
        if not drive.consistent:
            # Moving faster than the motors can hold (after a knock, say): feeding forward the
            # swing's own loads, clipped, would fight the pivots and fling a long chain apart.
            # Gravity and the wanted acceleration alone, and pymunk's pivots find the rest.
            drive = plan_drive(
                self.inertia, world_angles, still, wanted_acceleration, gravity, self.max_torque
            )
        self._saturated = drive.saturated
        return ServoCommand(
            rates=velocities + drive.accelerations * dt,
            torques=drive.loads.torques,
            forces=drive.loads.forces,
            budgets=np.maximum(self.max_torque - np.abs(drive.loads.torques), 0.0),
            saturated=drive.saturated,
        )
