"""The joint servo: angle errors -> a velocity each motor can reach and stop from -> torques.

A plain proportional servo (rate = gain x error, clipped by the speed limit) only slows down
within ``max_speed / gain`` of the goal, which is too late for a heavy, stretched arm, and once a
motor is at its torque limit it keeps asking for more, so a saturated arm swings like a pendulum.
This servo instead:

1. commands, per joint, ``min(max_speed, gain |e|, sqrt(2 a |e|))`` toward the goal, where ``a``
   is the deceleration the joint's spare torque (its limit less what gravity takes) gives the
   inertia beyond it: a velocity it can still brake from in time;
2. never asks a joint for a velocity change it cannot make in one tick (``a x dt``), and a
   joint at its torque limit toward its goal yet carried away from it (faster and faster, or
   at any speed past a creep when gravity overloads it), with its static load taking at least
   half its torque that way, asks only to stop until the target moves or its goal comes to lie
   the other way (anti-windup): it comes to rest where its torque runs out instead of swinging
   there;
3. turns the wanted velocity change into feed-forward torques and pivot forces with the chain's
   dynamics (:func:`~ikgame.control.dynamics.plan_drive`), within the torque limits, so that the
   physics engine's motors only correct what the model missed. Without that, the constraint
   solver would have to find the torques of a long chain by itself in a few iterations, and it
   does not: a 30-link chain never settles. A joint that stalled, or that gravity overloads,
   gives way at its limit where the motion needs more of it, rather than set the one factor
   every other joint's acceleration is scaled by (:func:`~ikgame.control.dynamics.give_way`);
   the joints nearer the base whose accelerations ease the joint that sets that factor keep
   them whole (:func:`~ikgame.control.dynamics.ease`). The motors beyond a joint that the
   far links' braking carries on past its goal get no torque to correct their rates with
   (:func:`_overrun`): correcting, they pushed it on further.

Units: radians, rad/s, px, s, torques mass px^2/s^2.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Final

import numpy as np

from ikgame.control._floats import FloatInertia, Loads, fit_floats
from ikgame.control.dynamics import ChainInertia, JointLoads, Pose, fit_drive

__all__ = ["Servo", "ServoCommand"]

STALL_TIME: Final = 0.1
"""How long a joint must be carried away from its goal, s, to count as stalled: a knock or the
last of a previous move's momentum is not a stall."""

STALL_SPEED: Final = 0.02
"""A joint carried away slower than this (rad/s) is creeping, not stalled."""

STALL_LOAD: Final = 0.5
"""Share of a joint's torque limit its static load (gravity at the pose it is in) must take
toward its goal for the joint to stall: one carried off while its load leaves it more is carried
by the chain's own motion, which passes, not held off by a load it cannot beat."""

BRAKE_FLOOR: Final = 0.1
"""Share of a joint's torque limit its braking plans on at least, even where its load leaves
it less at the pose it is in now."""

FLOAT_LINKS: Final = 30
"""Chains (and trees) up to this many links are driven over Python floats, longer ones over
numpy arrays: the same numbers either way, whichever is faster."""

PACE_STEPS: Final = (0.25, 0.5, 0.75, 1.0)
"""Where on their way (as a share of it) the joints a servo bringing them in together could
wait for one are checked for the load they would put on it, running on ahead (see
:func:`_paced`)."""

SECTION_LINKS: Final = 30
"""Chains (and trees) longer than this, when a joint runs out of torque, keep the wanted
accelerations of the joints up to it and scale only those beyond it; shorter ones scale every
joint's by one factor, which keeps the motion's direction, but for those nearer the base that
ease the joint that runs out (see :func:`fit_drive`). One factor set by the base of 200 links
leaves every joint a few percent of its wanted acceleration, tick after tick, and the chain
swings under gravity as if unpowered."""

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
    """

    rates: np.ndarray
    torques: np.ndarray
    forces: np.ndarray
    budgets: np.ndarray


class Servo:
    """Drives a chain's joints toward desired angles within torque and speed limits.

    >>> servo = Servo(ChainInertia(np.array([10.0]), np.array([2.0]), np.array([50.0 / 3.0])),
    ...               max_torque=np.array([1.0e6]), max_speed=np.array([2.0]), gain=12.0)
    >>> command = servo.command(np.array([1.0]), np.zeros(1), np.zeros(1), (0.0, 0.0), 1 / 240)
    >>> command.rates.round(6).tolist(), command.budgets.round(1).tolist()
    ([2.0], [968000.0])
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
        # Per joint, as lists: the float path (most chains) reads and writes them every tick;
        # the array path keeps arrays between its ticks instead.
        # Per joint, the sign of its angle error when it stalled (0 while it has not): a stall
        # holds for as long as its goal stays on that side.
        self._stalled: list[float] | np.ndarray = [0.0] * count
        # At its torque limit toward its goal on the last tick. A joint at its limit the other
        # way is being swung away from its goal by its own motor (its share of the whole
        # chain's motion), not held off by a load it cannot beat.
        self._straining: list[bool] | np.ndarray = [False] * count
        # Straining on the last tick or the one before: a joint that cannot hold its load can
        # alternate between its limit and just under it as the motor and the feed-forward take
        # turns, and is pushing all the same.
        self._pushing: list[bool] | np.ndarray = [False] * count
        self._velocities: list[float] | np.ndarray = [0.0] * count
        self._carried: list[float] | np.ndarray = [0.0] * count
        self._floats = FloatInertia(inertia) if inertia.count <= FLOAT_LINKS else None
        if self._floats is not None:
            self._quiet = _Quiet(self._floats, self.max_torque.tolist())
        self._sections = inertia.count > SECTION_LINKS
        self._limits = self.max_torque.tolist()
        self._speeds = self.max_speed.tolist()
        self._floors = [BRAKE_FLOOR * lim for lim in self._limits]

    @property
    def stalled(self) -> np.ndarray:
        """(n,) bool: joints that gave up pushing for their goal at their torque limit (see
        :meth:`retry`)."""
        return np.array(self._stalled) != 0.0

    @property
    def any_stalled(self) -> bool:
        """True when some joint has stalled: ``stalled.any()``, without building the array."""
        stalled = self._stalled
        return any(stalled) if isinstance(stalled, list) else bool(stalled.any())

    def strain(self, world_angles: np.ndarray, gravity: tuple[float, float]) -> float:
        """The largest share of a joint's torque limit that holding the chain still at
        ``world_angles`` (per link, radians) takes under ``gravity`` (px/s^2): past 1, the
        motors cannot hold the pose.

        >>> one = ChainInertia(np.array([10.0]), np.array([2.0]), np.array([50.0 / 3.0]))
        >>> servo = Servo(one, max_torque=np.array([1.8e4]), max_speed=np.ones(1), gain=12.0)
        >>> servo.strain(np.zeros(1), (0.0, -900.0))
        0.5
        """
        if self._floats is not None:
            held = self._floats.pose(world_angles).loads(gravity=gravity)[0]
            return max([abs(h) / lim for h, lim in zip(held, self._limits, strict=True)])
        held = Pose(self.inertia, world_angles).loads(gravity=gravity).torques
        return float(np.max(np.abs(held) / self.max_torque))

    def braking(
        self, world_angles: np.ndarray, velocities: np.ndarray, gravity: tuple[float, float]
    ) -> np.ndarray:
        """(n,) what each joint may slow its turning by, rad/s^2, as :meth:`command` plans its
        stop: the share :data:`BRAKE_SHARE` of the torque left on the side that opposes its
        ``velocities`` (rad/s) once it holds its load under ``gravity`` (px/s^2) at
        ``world_angles``, never less than that share of :data:`BRAKE_FLOOR` of its limit, over
        the inertia beyond it.

        >>> one = ChainInertia(np.array([10.0]), np.array([2.0]), np.array([50.0 / 3.0]))
        >>> servo = Servo(one, max_torque=np.array([1.8e4]), max_speed=np.ones(1), gain=12.0)
        >>> servo.braking(np.zeros(1), np.ones(1), (0.0, 0.0)).round(1).tolist()
        [135.0]
        """
        if self._floats is not None:
            pose = self._floats.pose(world_angles)
            pull = (float(gravity[0]), float(gravity[1]))
            hold, inertia = np.array(pose.loads(gravity=pull)[0]), np.array(pose.inertia())
        else:
            pose = Pose(self.inertia, world_angles)
            hold, inertia = pose.loads(gravity=gravity).torques, pose.inertia()
        return _capacities(self.max_torque, hold, inertia, velocities > 0.0)[3]

    def most_strain(self, gravity: tuple[float, float]) -> float:
        """A bound on :meth:`strain` over every pose, from one pass over the links: each
        joint's load taken as if the chain beyond it lay out level with each link's weight at
        its far end. A chain whose motors that leaves within their limits holds any pose.

        >>> one = ChainInertia(np.array([10.0]), np.array([2.0]), np.array([50.0 / 3.0]))
        >>> servo = Servo(one, max_torque=np.array([1.8e4]), max_speed=np.ones(1), gain=12.0)
        >>> servo.most_strain((0.0, -900.0))
        1.0
        """
        pull = math.hypot(*gravity)
        if pull == 0.0:
            return 0.0
        inertia = self.inertia
        # Sizes past what floats hold bound nothing: infinity.
        with np.errstate(over="ignore"):
            lever = inertia.beyond(np.asarray(inertia.lengths, dtype=float) * inertia.mass_beyond)
            return pull * float(np.max(lever / self.max_torque))

    def strain_slope(self, world_angles: np.ndarray, gravity: tuple[float, float]) -> np.ndarray:
        """(n,) how :meth:`strain` at ``world_angles`` changes as each joint turns, everything
        beyond it turning with it, per radian: the slope of the joint that strains most. One
        pass over the links, where differences would ask the strain once per joint.

        >>> one = ChainInertia(np.array([10.0]), np.array([2.0]), np.array([50.0 / 3.0]))
        >>> servo = Servo(one, max_torque=np.array([1.8e4]), max_speed=np.ones(1), gain=12.0)
        >>> servo.strain_slope(np.full(1, np.pi / 4), (0.0, -900.0)).round(4).tolist()
        [-0.3536]
        """
        pose = Pose(self.inertia, world_angles)
        held = pose.loads(gravity=gravity).torques
        worst = int(np.argmax(np.abs(held) / self.max_torque))
        side = math.copysign(1.0, held[worst]) / self.max_torque[worst]
        return side * pose.held_slope(worst, gravity)

    def _room(
        self, torques: np.ndarray, hold: np.ndarray, share: float, there: np.ndarray | None = None
    ) -> np.ndarray:
        """The ``share`` of each joint's torque left, beyond its ``hold`` load, on the side of
        ``torques``; at least the floor, as for braking. Given the load ``there`` (at the goal),
        no more than all the torque left beyond it either (see :func:`_fit_floats`)."""
        side = np.sign(torques)
        floor = BRAKE_FLOOR * self.max_torque
        room = share * np.maximum(self.max_torque - side * hold, floor)
        if there is None:
            return room
        return np.minimum(room, np.maximum(self.max_torque - side * there, floor))

    def retry(self) -> None:
        """Let joints that stalled at their torque limit push for their goals again: the target
        moved, or the world changed (gravity), so the goal may be within reach now."""
        self._stalled = [0.0] * len(self._stalled)

    def _remember(self, saturated: list[bool], torques: list[float], errors: list[float]) -> None:
        """Keep this tick's joints at their torque limit toward their goal (the sign of their
        angle ``errors``, radians), and which were pushing (see ``_pushing``)."""
        if not any(saturated):
            # Most ticks: none is at its limit, and those pushing are those straining before.
            self._pushing, self._straining = self._straining, [False] * len(saturated)
            return
        toward = [
            at_limit and torque * error > 0.0
            for at_limit, torque, error in zip(saturated, torques, errors, strict=True)
        ]
        self._pushing = [now or last for now, last in zip(toward, self._straining, strict=True)]
        self._straining = toward

    def command(
        self,
        error: np.ndarray,
        world_angles: np.ndarray,
        velocities: np.ndarray,
        gravity: tuple[float, float] | np.ndarray,
        dt: float,
        goal_rates: np.ndarray | None = None,
        *,
        steered: bool = False,
        together: bool = False,
    ) -> ServoCommand:
        """One tick's command from each joint's angle ``error`` (radians) and the measured pose.

        ``world_angles`` are per link (radians), ``velocities`` per joint (child - parent,
        rad/s), ``gravity`` px/s^2 and ``dt`` the tick, s. ``goal_rates`` (rad/s) is how fast
        the desired angles themselves move, when they follow a moving target: the servo moves
        with them and closes the error on top, instead of lagging behind. ``steered`` says the
        goal is a pose on a way planned round obstacles: the motion keeps its direction when a
        joint runs out of torque (one factor for all, none kept whole by
        :func:`~ikgame.control.dynamics.ease`), since only the lines of the way were checked
        clear. Eased off its line, twenty links following their way out from under a shelf
        caught on it. ``together`` closes every joint's error in the same time, the longest any
        joint needs at its own speed (see :func:`_together`): the chain keeps to the straight
        line in joint space to its goal, the joints waiting for one that cannot keep up where
        running on without it would load it past its torque (see :func:`_paced`).
        """
        if self._floats is not None:
            return self._command_floats(
                self._floats,
                error,
                world_angles,
                velocities,
                gravity,
                dt,
                goal_rates,
                steered,
                together,
            )
        along = self.inertia.along
        pose = Pose(self.inertia, world_angles)
        hold = pose.loads(gravity=gravity)
        inertia = pose.inertia()
        up, down, floor, brake = _capacities(self.max_torque, hold.torques, inertia, error > 0.0)
        # A joint gravity overloads has no capacity toward its goal at this pose by that count,
        # yet the others' motion can lend it some (their reaction on it): it asks for as much
        # as its limit and the load could give either way, and gives way at its limit where
        # the motion needs more (see fit_drive).
        overloaded = ~(np.abs(hold.torques) <= self.max_torque)
        wide = (self.max_torque + np.abs(hold.torques)) / inertia
        up, down = np.where(overloaded, wide, up), np.where(overloaded, wide, down)
        # Anti-windup: a joint pushing at its limit yet carried away from its goal cannot get
        # there; it asks only to stop, until :meth:`retry`, so it comes to rest where its
        # torque runs out instead of swinging about that point like a pendulum. Carried away
        # means moving from the goal faster and faster for a while: an overshoot that the motor
        # is braking slows down instead, and is no stall. Nor is a joint whose static load
        # leaves it over half its torque toward the goal stalled: the chain's own motion (a
        # long chain's swing) carries it off, and that passes.
        # A joint its static load overloads is carried off at any speed past the creep: braking
        # at its limit, it sags at a steady speed or even slows, and gets nowhere all the same.
        load = np.sign(error) * hold.torques
        speed_now = np.abs(velocities)
        faster = speed_now > np.maximum(np.abs(np.asarray(self._velocities)), STALL_SPEED)
        sagging = (load > self.max_torque) & (speed_now > STALL_SPEED)
        carried = np.asarray(self._pushing) & (velocities * error < 0.0) & (faster | sagging)
        carried_for = np.where(carried, np.asarray(self._carried) + dt, 0.0)
        loaded = load >= STALL_LOAD * self.max_torque
        side = np.sign(error)
        was = np.asarray(self._stalled)
        sides = np.where(
            (was != 0.0) & (was == side) | ((carried_for >= STALL_TIME) & loaded), side, 0.0
        )
        stalled = sides != 0.0
        self._carried, self._stalled = carried_for, sides
        self._velocities = np.array(velocities, dtype=float)
        size = np.where(stalled, 0.0, np.abs(error))
        speed = np.minimum(
            np.minimum(self.max_speed, self.gain * size), np.sqrt(2.0 * brake * size)
        )
        closing = np.sign(error) * speed
        if together:
            errors, closings, reach = error.tolist(), closing.tolist(), None
            if gravity[0] or gravity[1]:
                # Without gravity no pose loads a joint, and none is waited for (see _paced).
                now = velocities.tolist()
                reach = _paced(
                    errors,
                    closings,
                    now,
                    _reach(errors, now, up.tolist(), down.tolist(), floor.tolist(), dt),
                    hold.torques.tolist(),
                    self._limits,
                    lambda turns: (
                        Pose(self.inertia, world_angles + along(np.array(turns)))
                        .loads(gravity=gravity)
                        .torques.tolist()
                    ),
                )
            closing = np.array(_together(errors, closings, reach))
        # Each joint's profile brakes it alone; stopping them all at once also loads the joints
        # nearer the base with the others' deceleration. Stop together, by the time the first
        # of them must have stopped (at a constant deceleration), within the braking share:
        # those torques grow with the square of the velocities, so one factor fits them. The
        # stop ends at the goal: within all the room the load there leaves, too.
        moving = np.abs(closing) > 1e-9
        if np.any(moving):
            stop_in = float(np.min(2.0 * np.abs(error[moving]) / np.abs(closing[moving])))
            halt = pose.loads(alpha=along(-closing / stop_in)).torques
            there = Pose(self.inertia, world_angles + along(error)).loads(gravity=gravity).torques
            room = self._room(halt, hold.torques, BRAKE_SHARE, there)
            closing = closing * _fit(np.abs(halt), room)
        target = closing if goal_rates is None else closing + goal_rates
        target = np.clip(target, -self.max_speed, self.max_speed)
        # Joints of a long chain moving at once whip its far end round: the torques that merely
        # keep those velocities grow with their square. Slow every joint by one factor until
        # they fit in the share of spare torque that braking leaves.
        spin = pose.loads(omega=along(target)).torques
        target = target * _fit(np.abs(spin), self._room(spin, hold.torques, 1.0 - BRAKE_SHARE))
        # Approach that velocity no faster than each joint's spare torque allows: a servo that
        # asked for the whole change in one tick would saturate every motor after any knock.
        slowest, fastest = velocities - down * dt, velocities + up * dt
        wanted = np.clip(target, slowest, fastest)
        # Joints asking for all the braking they have: a velocity this tick cannot bring them to.
        hard = np.where(velocities > 0.0, target < slowest, (velocities < 0.0) & (target > fastest))
        wanted_acceleration = (wanted - velocities) / dt
        push = pose.loads(alpha=along(wanted_acceleration))
        joints = np.arange(len(error))

        def near(k: int) -> JointLoads:
            return pose.loads(alpha=along(np.where(joints <= k, wanted_acceleration, 0.0)))

        head = near if self._sections else None

        def alone(k: int) -> JointLoads:
            return pose.loads(alpha=along((joints == k).astype(float)))

        # The joints that give way at their torque limit (see the float path's weak_joints).
        weak = (stalled | ~(np.abs(hold.torques) <= self.max_torque), alone)

        def turning(accelerations: np.ndarray) -> JointLoads:
            return pose.loads(alpha=along(accelerations))

        easing = None if steered else turning
        drive = fit_drive(
            hold + pose.loads(omega=along(velocities)),
            push,
            wanted_acceleration,
            self.max_torque,
            head,
            weak,
            easing,
        )
        if not drive.consistent:
            # Moving faster than the motors can hold (after a knock, say): feeding forward the
            # swing's own loads, clipped, would fight the pivots and fling a long chain apart.
            # Gravity and the wanted acceleration alone, and pymunk's pivots find the rest.
            drive = fit_drive(hold, push, wanted_acceleration, self.max_torque, head, weak, easing)
        # _remember over arrays: the same products and comparisons.
        toward = drive.saturated & (drive.loads.torques * error > 0.0)
        self._pushing, self._straining = toward | np.asarray(self._straining), toward
        budgets = np.maximum(self.max_torque - np.abs(drive.loads.torques), 0.0)
        # A carried joint is at its limit: most ticks none is.
        if not self._sections and drive.saturated.any():
            carried = _overrun(
                self.inertia.parent_list,
                drive.saturated.tolist(),
                drive.loads.torques.tolist(),
                velocities.tolist(),
                error.tolist(),
                hard.tolist(),
                push.torques.tolist(),
                hold.torques.tolist(),
                self._limits,
                self.gain,
            )
            budgets = np.where(carried, 0.0, budgets)
        return ServoCommand(
            rates=velocities + drive.accelerations * dt,
            torques=drive.loads.torques,
            forces=drive.loads.forces,
            budgets=budgets,
        )

    def _command_floats(
        self,
        tree: FloatInertia,
        error: np.ndarray,
        world_angles: np.ndarray,
        velocities: np.ndarray,
        gravity: tuple[float, float] | np.ndarray,
        dt: float,
        goal_rates: np.ndarray | None,
        steered: bool,
        together: bool,
    ) -> ServoCommand:
        """:meth:`command` joint by joint over floats: the same steps, the same numbers."""
        pose = tree.pose(world_angles)
        limits, speeds, gain = self._limits, self._speeds, self.gain
        errors, now = error.tolist(), velocities.tolist()
        pull = (float(gravity[0]), float(gravity[1]))
        hold, coasting, inertia = pose.rest(pull, now)
        held = hold[0]
        # Each step as in command, with numpy's maximum, minimum and sign written out (the same
        # floats: a sign times a speed is the speed, its negation, zero or NaN).
        up, down, closing, carried, sides, weak_joints = [], [], [], [], [], []
        brake_share, stall_speed = BRAKE_SHARE, STALL_SPEED
        stall_time, stall_load, sqrt = STALL_TIME, STALL_LOAD, math.sqrt
        for lim, low, e, v, i, h, top, pushing, before, was_carried, was_stalled in zip(
            limits,
            self._floors,
            errors,
            now,
            inertia,
            held,
            speeds,
            self._pushing,
            self._velocities,
            self._carried,
            self._stalled,
            strict=True,
        ):
            u, d = lim - h, lim + h
            u = (0.0 if 0.0 > u else u) / i
            d = (0.0 if 0.0 > d else d) / i
            against = d if e > 0.0 else u
            floor = low / i
            brake = brake_share * (floor if floor > against else against)
            overloaded = not abs(h) <= lim
            if overloaded:
                u = d = (lim + abs(h)) / i
            up.append(u)
            down.append(d)
            # _sign(e), written out: this loop runs for every joint on every tick.
            side = 1.0 if e > 0.0 else -1.0 if e < 0.0 else 0.0 if e == 0.0 else e
            # The load (side * h) and the speed are worked out only where a stall is in question.
            if (
                pushing
                and v * e < 0.0
                and (
                    (speed_now := abs(v))
                    > (stall_speed if stall_speed > (slow := abs(before)) else slow)
                    or (side * h > lim and speed_now > stall_speed)
                )
            ):
                was_carried += dt
            else:
                was_carried = 0.0
            carried.append(was_carried)
            is_stalled = (was_stalled != 0.0 and was_stalled == side) or (
                was_carried >= stall_time and side * h >= stall_load * lim
            )
            # Those that gave their goal up, and those whose static load is past their limit,
            # give way at it rather than set the chain's one factor (see give_way).
            weak_joints.append(is_stalled or overloaded)
            sides.append(side if is_stalled else 0.0)
            size = 0.0 if is_stalled else abs(e)
            by_gain = gain * size
            speed = by_gain if by_gain < top else top
            by_brake = sqrt(2.0 * brake * size)
            speed = by_brake if by_brake < speed else speed
            c = speed if e > 0.0 else -speed if e < 0.0 else 0.0 * speed if e == 0.0 else e
            closing.append(c)
        self._carried, self._stalled, self._velocities = carried, sides, now
        if together:
            reach = None
            if pull[0] or pull[1]:
                # Without gravity no pose loads a joint, and none is waited for (see _paced).
                floors = [low / i for low, i in zip(self._floors, inertia, strict=True)]
                reach = _paced(
                    errors,
                    closing,
                    now,
                    _reach(errors, now, up, down, floors, dt),
                    held,
                    limits,
                    lambda turns: tree.pose(world_angles + np.array(tree.along(turns))).loads(
                        gravity=pull
                    )[0],
                )
            closing = _together(errors, closing, reach)
        stop_in, closing_total = _stopping(errors, closing)
        # The loads of braking and of spinning are evaluated only when a bound on them (see
        # _Quiet) leaves any joint short of room: otherwise their factor is 1, exactly.
        quiet, factor = self._quiet, 1.0
        if stop_in != math.inf and not quiet.brakes(closing_total / stop_in):
            halt = pose.turning([-c / stop_in for c in closing])[0]
            there = tree.pose(world_angles + np.array(tree.along(errors))).loads(gravity=pull)[0]
            factor = _fit_floats(halt, held, limits, BRAKE_SHARE, there)
        # Times 1.0 and plus -0.0 change no float: without a factor or goal rates, each closing
        # speed is clipped as it is.
        goals = [-0.0] * len(closing) if goal_rates is None else goal_rates.tolist()
        target, target_total = [], 0.0
        for c, g, s in zip(closing, goals, speeds, strict=True):
            t = c * factor + g
            t = -s if -s > t else t
            t = s if s < t else t
            target.append(t)
            target_total += abs(t)
        factor = 1.0
        if not quiet.spins(target_total):
            spin = pose.loads(omega=tree.along(target))[0]
            factor = _fit_floats(spin, held, limits, 1.0 - BRAKE_SHARE)
        accelerations, hard = [], []
        for t, v, d, u in zip(target, now, down, up, strict=True):
            wanted, slowest, fastest = t * factor, v - d * dt, v + u * dt
            hard.append(slowest > wanted if v > 0.0 else v < 0.0 and fastest < wanted)
            wanted = slowest if slowest > wanted else wanted
            wanted = fastest if fastest < wanted else wanted
            accelerations.append((wanted - v) / dt)
        push = pose.turning(accelerations)

        def near(k: int) -> Loads:
            return pose.turning([a if j <= k else 0.0 for j, a in enumerate(accelerations)])

        head = near if self._sections else None
        count = len(limits)

        def alone(k: int) -> Loads:
            return pose.turning([1.0 if j == k else 0.0 for j in range(count)])

        weak = (weak_joints, alone)
        easing = None if steered else pose.turning
        reached, loads, saturated, consistent = fit_floats(
            coasting, push, accelerations, limits, head, weak, easing
        )
        if not consistent:
            # See command: gravity and the wanted acceleration alone, pymunk's pivots the rest.
            reached, loads, saturated, _ = fit_floats(
                hold, push, accelerations, limits, head, weak, easing
            )
        torques = loads[0]
        self._remember(saturated, torques, errors)
        budgets = [
            0.0 if 0.0 > (left := lim - abs(t)) else left
            for lim, t in zip(limits, torques, strict=True)
        ]
        # A carried joint is at its limit: most ticks none is.
        if not self._sections and any(saturated):
            carried = _overrun(
                tree.parents, saturated, torques, now, errors, hard, push[0], held, limits, gain
            )
            if any(carried):
                budgets = [0.0 if c else b for c, b in zip(carried, budgets, strict=True)]
        return ServoCommand(
            rates=np.array([v + a * dt for v, a in zip(now, reached, strict=True)]),
            torques=np.array(torques),
            forces=np.array((loads[1], loads[2])).T,
            budgets=np.array(budgets),
        )


def _capacities(
    max_torque: np.ndarray, hold: np.ndarray, inertia: np.ndarray, positive: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """What each joint can change its velocity by, per second (rad/s^2): up and down, its
    braking floor, and its braking when it turns the ``positive`` way (True) or the other, from
    its torque limit and the load it ``hold``s, over its ``inertia``."""
    # Its load eats into the torque on one side and adds to it on the other (gravity helps a
    # lowering).
    up = np.maximum(max_torque - hold, 0.0) / inertia
    down = np.maximum(max_torque + hold, 0.0) / inertia
    # Braking takes the other side's capacity. A joint held at its torque limit has none there
    # at this pose, yet moving on changes its load; it plans with a floor so that it moves at
    # all rather than stay where its torque ran out.
    floor = BRAKE_FLOOR * max_torque / inertia
    return up, down, floor, BRAKE_SHARE * np.maximum(np.where(positive, down, up), floor)


def _stopping(errors: list[float], closing: list[float]) -> tuple[float, float]:
    """The time the first joint to stop needs to close its error (radians) from its
    ``closing`` velocity (rad/s) at a constant deceleration (s; inf when none moves), and the
    sum of the closing speeds."""
    stop_in, closing_total = math.inf, 0.0
    for e, c in zip(errors, closing, strict=True):
        magnitude = abs(c)
        closing_total += magnitude
        if magnitude > 1e-9:
            stop = 2.0 * abs(e) / magnitude
            stop_in = stop if stop < stop_in else stop_in
    return stop_in, closing_total


def _together(
    errors: list[float], closing: list[float], reach: list[float] | None = None
) -> list[float]:
    """Each joint's closing velocity (rad/s) slowed so that every joint closes its error
    (radians) in the same time: the longest any moving joint needs at its own velocity, or at
    the most it can close at by the next tick (``reach``, rad/s, if given), if less. A joint
    that is not closing (stalled, or on its goal) keeps its velocity and does not count.

    Each joint's own velocity is the most it may have (its speed limit, its gain, and what it
    can brake from), so none goes faster. Near the goal every joint's velocity is its gain times
    its error, one time for all, and nothing changes. Far from it the light joints at the end
    of a chain get up to speed sooner than the heavy ones near the base, and each alone would
    arrive first: the poses on the way, the outer joints bent and the inner ones not yet, can
    ask more than a weak motor has, where the straight line to the goal does not. Given each
    joint's ``reach`` (see :func:`_paced`), the others wait for one whose torque is nearly spent
    holding the chain.

    >>> _together([1.0, 0.1, 0.0], [2.0, 1.0, 0.0])
    [2.0, 0.2, 0.0]
    >>> _together([1.0, 0.1, 0.0], [2.0, 1.0, 0.0], [0.5, 3.0, 0.0])
    [0.5, 0.05, 0.0]
    """
    longest = 0.0
    for index, (e, c) in enumerate(zip(errors, closing, strict=True)):
        if abs(c) > 1e-9:
            speed = abs(c)
            if reach is not None and reach[index] < speed:
                speed = reach[index]
            time = abs(e) / speed if speed > 0.0 else math.inf
            longest = time if time > longest else longest
    if longest == 0.0:
        return closing
    return [e / longest if abs(c) > 1e-9 else c for e, c in zip(errors, closing, strict=True)]


def _reach(
    errors: list[float],
    velocities: list[float],
    up: list[float],
    down: list[float],
    floors: list[float],
    dt: float,
) -> list[float]:
    """The most each joint can close its error at (rad/s) by the next tick: its velocity
    toward its goal (none, if it moves away) and what its torque can add in a tick (``up``
    and ``down``, rad/s^2, the change it can make each way, at least its ``floors``: as the
    braking plans, a joint whose load takes all its torque here moves at all, and the motion
    changes its load)."""
    reach = []
    for e, v, u, d, low in zip(errors, velocities, up, down, floors, strict=True):
        toward = v if e > 0.0 else -v
        gain = u if e > 0.0 else d
        reach.append((toward if toward > 0.0 else 0.0) + (gain if gain > low else low) * dt)
    return reach


def _paced(
    errors: list[float],
    closing: list[float],
    velocities: list[float],
    reach: list[float],
    held: list[float],
    limits: list[float],
    loads_at: Callable[[list[float]], list[float]],
) -> list[float] | None:
    """``reach`` (see :func:`_reach`), or None for no pace by it: ``reach`` where the joint
    it holds back the most, not carried away from its goal (``velocities``, rad/s), has the
    torque to hold its load here (``held``, the static loads; ``limits``, the torque limits)
    but not the load the others would put on it, running on ahead toward their goals while
    it stays (``loads_at(turns)``: the static loads with the joints turned so much, radians,
    checked at :data:`PACE_STEPS` of the way); or where, its load leaving it at least its
    braking floor (:data:`BRAKE_FLOOR`) to come with, a joint beyond it that holds its own
    load here would not hold it there.

    Waiting for the joint whose torque holding the arm nearly spends keeps the chain on the
    straight line in joint space the motors were checked to hold along: an arm lifted over
    the top from out to the right (`69_heavy_gravity_weak_three`) whose far joints unfolded
    first grew longer than its base could lift, and lay on the floor. Where the far joints
    running on only lighten its load (folding in), or it cannot hold its load anyway (an arm
    sagging at its base's limit), or it is still carried the other way (by the swing toward
    the goal before), waiting for it keeps the load on: paced by the base all the way, the
    five weak links of `29_five_weak_links` took 2.6 s to swing up for their second target,
    and missed it.

    The joints beyond it running on ahead can also overload themselves: an arm swinging its
    weak wrist over the top (`80_heavy_weak_three_swing_over`) whose elbow, near its limit,
    lagged while the wrist turned in at its own speed tipped the wrist's link past the load
    its motor holds (1.19 of it), and the link fell onto its stop. Its pacer's load leaving
    it less than its braking floor, though, it has next to nothing to come with, and the
    waiting arm sags (29 again).

    >>> lever = lambda turns: [1.0 + turns[1], 0.0]  # the far joint turning on loads the base
    >>> rest = ([0.1, 3.0], [1.0, 0.0], [1.5, 1.0], lever)  # reach, held, limits, loads_at
    >>> _paced([1.0, 1.0], [2.0, 2.0], [0.0, 0.0], *rest)
    [0.1, 3.0]
    >>> _paced([1.0, -1.0], [2.0, -2.0], [0.0, 0.0], *rest) is None  # it turns the other way
    True
    >>> _paced([1.0, 1.0], [2.0, 2.0], [-0.5, 0.0], *rest) is None  # the base carried away
    True
    >>> tipping = lambda turns: [0.5, 0.5 + turns[1]]  # the far joint tips over on its own
    >>> _paced([1.0, 1.0], [2.0, 2.0], [0.0, 0.0], [0.1, 3.0], [0.5, 0.5], [1.5, 1.0], tipping)
    [0.1, 3.0]
    >>> spent = [1.4, 0.5]  # the base's load leaves it under its braking floor
    >>> _paced([1.0, 1.0], [2.0, 2.0], [0.0, 0.0], [0.1, 3.0], spent, [1.5, 1.0], tipping) is None
    True
    """
    longest, pacer, own = 0.0, -1, 0.0
    for index, (e, c, r) in enumerate(zip(errors, closing, reach, strict=True)):
        if abs(c) > 1e-9:
            time = abs(e) / abs(c)
            own = time if time > own else own
            if r < abs(c):
                time = abs(e) / r if r > 0.0 else math.inf
                if time > longest:
                    longest, pacer = time, index
    if longest <= own:
        return None  # no joint's reach holds the others back further than their own speeds
    side, limit = (1.0 if errors[pacer] > 0.0 else -1.0), limits[pacer]
    if side * velocities[pacer] < 0.0 or side * held[pacer] > limit:
        return None
    others = [0.0 if index == pacer else e for index, e in enumerate(errors)]
    # A chain's joints beyond the pacer come after it (a servo brings a chain in together).
    beyond = range(pacer + 1, len(errors))
    room = side * held[pacer] <= (1.0 - BRAKE_FLOOR) * limit
    for step in PACE_STEPS:
        loads = loads_at([step * e for e in others])
        if side * loads[pacer] > limit:
            return reach
        if room and any(abs(loads[k]) > limits[k] >= abs(held[k]) for k in beyond):
            return reach
    return None


class _Quiet:
    """Rates and accelerations too small for their loads to need room a joint lacks.

    Per link, the centre accelerates at most at the sum over all links of ``omega^2 L`` (or
    ``|alpha| L``), and each world rate is at most the sum ``S`` of the joints' absolute rates.
    So joint ``i``'s torque is at most ``A P_i`` plus, for accelerations, ``S`` times the
    moments beyond it, where ``A`` is ``S^2`` (or ``S``) times the total length and ``P_i`` sums
    ``L_k`` times the mass beyond ``k`` over the links beyond ``i``. The servo gives each joint
    at least its share of the floor of its torque limit: a bound within half of that (a
    margin far beyond rounding) means no joint is short, and the factor is 1 without the loads.
    """

    def __init__(self, tree: FloatInertia, limits: list[float]) -> None:
        reach = math.fsum(tree.lengths)
        lever = tree.beyond(
            [length * m for length, m in zip(tree.lengths, tree.mass_beyond, strict=True)]
        )
        self._spin = self._brake = math.inf
        for p, moments, limit in zip(lever, tree.moment_beyond, limits, strict=True):
            floor = BRAKE_FLOOR * limit
            spin, brake = 2.0 * reach * p, 2.0 * (reach * p + moments)
            if spin > 0.0:
                self._spin = min(self._spin, (1.0 - BRAKE_SHARE) * floor / spin)
            if brake > 0.0:
                self._brake = min(self._brake, BRAKE_SHARE * floor / brake)

    def spins(self, total: float) -> bool:
        """True when the loads of joint rates (rad/s, child - parent) whose magnitudes sum to
        ``total`` surely fit every joint's room for them; False when they might not."""
        return total * total <= self._spin

    def brakes(self, total: float) -> bool:
        """True when the loads of joint accelerations whose magnitudes sum to ``total``
        (rad/s^2) surely fit every joint's room for braking; False when they might not."""
        return total <= self._brake


def _overrun(
    parents: list[int],
    saturated: list[bool],
    torques: list[float],
    velocities: list[float],
    errors: list[float],
    hard: list[bool],
    pushed: list[float],
    held: list[float],
    limits: list[float],
    gain: float,
) -> list[bool]:
    """Joints whose motors should add no torque to correct their rates: those beyond a joint
    the others' braking carries on past its goal.

    Such a joint heads for its goal (the sign of its angle ``errors``) faster than the gain
    would bring it in, asks to brake with all it has (``hard``), yet the motion wanted of the
    whole chain (``pushed``, its own braking included) takes more than its torque limit the
    way it turns, and its torque (``torques``) is at that limit there: the far links'
    braking comes onto it and its motor cannot take it up. The motors beyond, correcting their
    rates with their spare torque, push it on further. Only where gravity (``held``, at the
    pose) takes less than half the limit of it and of every joint beyond: a motor holding
    more needs its correction against the sag. Torques are in mass px^2/s^2, rates rad/s,
    angles radians; ``gain`` is the servo's, /s.
    """
    light = [abs(h) < STALL_LOAD * lim for h, lim in zip(held, limits, strict=True)]
    for j in range(len(parents) - 1, -1, -1):
        if parents[j] >= 0 and not light[j]:
            light[parents[j]] = False
    carried = [
        lit
        and at
        and t * v > 0.0
        and p * v > lim * abs(v)
        and v * e > 0.0
        and h
        and abs(v) > gain * abs(e)
        for lit, at, t, p, lim, v, e, h in zip(
            light, saturated, torques, pushed, limits, velocities, errors, hard, strict=True
        )
    ]
    beyond = [False] * len(parents)
    for j, p in enumerate(parents):
        beyond[j] = p >= 0 and (carried[p] or beyond[p])
    return beyond


def _sign(value: float) -> float:
    """``np.sign`` of one float: 0.0 for either zero, NaN for NaN."""
    return 1.0 if value > 0.0 else -1.0 if value < 0.0 else 0.0 if value == 0.0 else value


def _fit_floats(
    loads: list[float],
    hold: list[float],
    limits: list[float],
    share: float,
    there: list[float] | None = None,
) -> float:
    """:func:`_fit` of ``loads`` within :meth:`Servo._room` over floats.

    A stop is planned on the ``share`` of the room the load ``hold`` leaves each joint where
    the chain is now, the rest kept as margin; given the load ``there`` where the stop ends
    (the goal), it takes no more than all the room left there either. Lowering an arm held
    out, the load on a weak joint grows on the way: on `61_heavy_gravity_weak_motors` (CCD,
    the third target) the second joint's load grew from 0.14 of its limit where it began to
    brake to 0.86 at the goal, the joint braked at its limit for the last 39 deg and still
    came in at 23 deg/s, and the tip ran on 32 px (10% of the approach) past.

    >>> _fit_floats([4.0], [0.0], [10.0], 0.5), _fit_floats([4.0], [0.0], [10.0], 0.5, [8.0])
    (1.0, 0.7071067811865476)
    """
    factor = math.inf
    for k, (load, held, lim) in enumerate(zip(loads, hold, limits, strict=True)):
        # _sign(load) * held, with the sign's product written out where it is exact.
        signed = held if load > 0.0 else -held if load < 0.0 else _sign(load) * held
        left, floor = lim - signed, BRAKE_FLOOR * lim
        room = share * (floor if floor > left else left)
        if there is not None:
            far = there[k]
            spare = lim - (far if load > 0.0 else -far if load < 0.0 else _sign(load) * far)
            spare = floor if floor > spare else spare
            room = spare if spare < room else room
        need = abs(load)
        if need > room:
            ratio = room / need
            factor = ratio if ratio < factor else factor
    return 1.0 if factor == math.inf else math.sqrt(factor)


def _fit(need: np.ndarray, room: np.ndarray) -> float:
    """The factor (0..1) on velocities that brings loads growing with their square, ``need``,
    within ``room``."""
    over = need > room
    if not np.any(over):
        return 1.0
    return math.sqrt(float(np.min(room[over] / need[over])))
