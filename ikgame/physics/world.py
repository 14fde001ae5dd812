"""The pymunk world of a level: a motorised chain, its joints and limits, static obstacles and
dynamic props.

Each link is a dynamic body centred on the link, with a thick segment shape. Consecutive links
are pinned by a ``PivotJoint``, driven by a ``SimpleMotor`` whose ``max_force`` is the joint's
torque limit, and held in range by a ``RotaryLimitJoint`` where the level sets limits (braced, so
that a joint knocked toward a stop halts within a step short of it, not a step past it). Link 0
hangs off a kinematic base body, so a script can move the base smoothly (:meth:`World.move_base`).
Links of one chain never collide with each other; they do collide with obstacles and props, and
props collide with everything.

pymunk bounces two shapes with the product of their elasticities. Links have 0 (they never
bounce), obstacles 1, so a prop bounces off an obstacle with exactly its own elasticity.

The space steps at most ``MAX_STEP_S`` at once: a longer :meth:`World.step` is stepped in equal
parts with the same loads and motor settings.

Angles are radians, lengths px, times s, world y up.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass
from typing import TYPE_CHECKING, Final

import numpy as np
import pymunk
import pymunk.batch
from pymunk import _chipmunk_cffi as _chipmunk

from ikgame.kinematics import Skeleton
from ikgame.level.model import BallProp, BoxProp, CircleObstacle, Level, SegmentObstacle

if TYPE_CHECKING:
    from ikgame.physics._motors import CompiledMotors

__all__ = ["World", "build_skeleton"]

SPACE_ITERATIONS: Final = 60
"""pymunk solver iterations per step, and at least one per link up to :data:`SWEEP_LINKS`: long
motorised chains need more than the default 10 to stay stiff under gravity, and pymunk solves the
joints in the order they were added, base to tip, so each sweep carries a correction from the
tip one joint further back (200 links at 60 rocked at rest by 1 to 6 px)."""

SWEEP_LINKS: Final = 100
"""Chains of more links than this get a return sweep: every pivot and motor a second time, tip to
base, so that one iteration carries a correction the whole length of the chain both ways and
this many iterations hold a chain of any length (200 links hold as still as with 200 plain
iterations, at 5/6 of the cost; a 1000-link chain's step costs a sixth of 1000 iterations). Each
motor's torque limit is shared equally by its two halves. Shorter chains keep the plain sweep:
up to this length one pass per link costs less."""

FLOAT_LINKS: Final = 30
"""Chains up to this many links get their loads written link by link over Python floats,
longer ones and trees over numpy arrays: the same numbers either way, whichever is faster."""

MAX_STEP_S: Final = 1.0 / 240.0
"""Longest step the space takes at once, s: a longer tick is stepped in equal parts, with the
tick's loads and motor settings in each. pymunk moves the bodies before it solves the joints and
contacts, so a chain's stiffness and a contact's push depend on the step: at 120 ticks/s in one
step, 150 links lying onto the floor had their middle joints kicked to 16 and then 96 rad/s within
five ticks and wound thousands of degrees past their stops."""

DIVERGENCE_LIMIT: Final = 1.0e6
"""A body farther than this from the origin (px), or turned this many radians, has blown up."""

_STATE: Final = (
    pymunk.batch.BodyFields.POSITION
    | pymunk.batch.BodyFields.ANGLE
    | pymunk.batch.BodyFields.ANGULAR_VELOCITY
)
"""What one batch read takes from every body: a row of x, y, angle, angular velocity."""
_LOADS: Final = pymunk.batch.BodyFields.FORCE | pymunk.batch.BodyFields.TORQUE
"""What one batch write gives every body: a row of force x, y and torque."""
_ARBITER_BODIES: Final = pymunk.batch.ArbiterFields.BODY_A_ID | pymunk.batch.ArbiterFields.BODY_B_ID
"""What one batch read takes from every cached arbiter: the ids of its two bodies."""
_SET_RATE: Final = _chipmunk.lib.cpSimpleMotorSetRate
_SET_MAX_FORCE: Final = _chipmunk.lib.cpConstraintSetMaxForce
_IMPULSE: Final = _chipmunk.lib.cpConstraintGetImpulse
"""Chipmunk's own motor setters and getter, called per motor each tick on the motors' C structs
(what pymunk's properties call, without a Python call in between: half the cost on a long
chain)."""
_LOCAL_TO_WORLD: Final = _chipmunk.lib.cpBodyLocalToWorld
_GRAVITY: Final = _chipmunk.lib.cpSpaceGetGravity
"""What ``Body.local_to_world`` and ``Space.gravity`` call, without pymunk's ``Vec2d`` around
the answer."""

_AT_LIMIT: Final = 1.0 - 1e-6
"""Share of its torque limit past which a joint counts as at its limit."""

_CHAIN_GROUP: Final = 1
_LINK_TYPE: Final = 1
"""The collision type of every link's shape."""
_OBSTACLE_ELASTICITY: Final = 1.0
"""So that a prop's own elasticity is its bounce off an obstacle (pymunk multiplies the two)."""


@dataclass
class _BaseMove:
    """A move of the kinematic base under way: from ``start`` to ``end`` (px) and from
    ``start_angle`` to ``end_angle`` (radians) in ``over`` s."""

    start: np.ndarray
    end: np.ndarray
    start_angle: float
    end_angle: float
    over: float
    elapsed: float = 0.0

    def at(self, elapsed: float) -> tuple[np.ndarray, float, bool]:
        """Where the base should be ``elapsed`` s into the move: position (px), angle
        (radians), and whether the move is over then."""
        # Ticks add up to the move's time only to within rounding: finish on the last one.
        fraction = 1.0 if elapsed >= self.over - 1e-9 else elapsed / self.over
        eased = fraction * fraction * (3.0 - 2.0 * fraction)
        position = self.start + (self.end - self.start) * eased
        angle = self.start_angle + (self.end_angle - self.start_angle) * eased
        return position, angle, fraction >= 1.0


def build_skeleton(level: Level) -> Skeleton:
    """The level's chain as a kinematic :class:`~ikgame.kinematics.Skeleton` (radians, px).

    >>> from ikgame.level.model import Level
    >>> lvl = Level.model_validate({"level": {"name": "x", "duration": 1.0},
    ...     "chain": {"links": [{"length": 50.0, "repeat": 3}]},
    ...     "script": [{"wait": 1.0}]})
    >>> build_skeleton(lvl).reach
    150.0
    """
    links = level.chain.expanded_links
    return Skeleton.tree(
        [link.length for link in links],
        [link.parent_index for link in links],
        base=level.chain.base,
        base_angle=math.radians(level.chain.angle),
        limits=[link.limits_rad for link in links],
        root_offsets=[link.at for link in links],
    )


class World:
    """A pymunk space built from a level, with joint-level reads and motor commands.

    >>> from ikgame.level.model import Level
    >>> lvl = Level.model_validate({"level": {"name": "x", "duration": 1.0},
    ...     "chain": {"links": [{"length": 50.0}]}, "script": [{"wait": 1.0}]})
    >>> World(lvl).end_effector().round(6).tolist()
    [0.0, 50.0]
    """

    def __init__(self, level: Level) -> None:
        self.skeleton = build_skeleton(level)
        self.space = pymunk.Space()
        links = level.chain.expanded_links
        self.space.iterations = max(SPACE_ITERATIONS, min(len(links), SWEEP_LINKS))
        self.space.gravity = level.world.gravity
        self.space.damping = level.world.damping

        self.base_body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        self.base_body.position = level.chain.base
        self.base_body.angle = self.skeleton.base_angle
        self.space.add(self.base_body)

        initial = self.skeleton.clamp(np.radians([link.angle for link in links]))
        self.max_torque = np.array([link.max_torque for link in links])
        self.max_speed = np.radians([link.max_speed for link in links])
        self.link_widths = np.array([link.width for link in links])
        self._halves = [link.length / 2.0 for link in links]
        self.last_dt = 1.0 / level.world.tick_rate
        self._space_dt = self.last_dt / _parts(self.last_dt)
        """The length of the space's last step, s: the motors' impulses are over it."""
        self._loaded = False  # loads written by drive() since the last step
        self.bodies: list[pymunk.Body] = []
        self.motors: list[pymunk.SimpleMotor] = []
        self.limit_joints: list[pymunk.RotaryLimitJoint | None] = []
        pivots: list[pymunk.PivotJoint] = []
        collide = level.chain.branches_collide
        # Links share a group that never collides with itself, unless the tree's branches are
        # to collide: then a handler lets through only pairs of links from different branches.
        shape_filter = pymunk.ShapeFilter(group=0 if collide else _CHAIN_GROUP)

        self.parents = self.skeleton.parents
        """(n,) parent link index, -1 for a link on the base."""
        self.effector_links = np.array(level.chain.effector_links, dtype=np.int64)
        """(k,) the links whose tips are end effectors."""
        self.is_tree = level.chain.bones is not None
        """True for a level of named bones (read its joints in the tree layout), False for a
        chain of links."""
        base_direction = _direction(self.skeleton.base_angle)
        base_normal = np.array((-base_direction[1], base_direction[0]))
        ends = np.empty((len(links), 2))
        world_angles = np.empty(len(links))
        for i, link in enumerate(links):
            half = link.length / 2.0
            p = int(self.parents[i])
            if p < 0:
                offset = self.skeleton.root_offsets[i]
                parent, parent_anchor = self.base_body, (float(offset[0]), float(offset[1]))
                joint = np.asarray(level.chain.base, dtype=float)
                if np.any(offset):
                    joint = joint + offset[0] * base_direction + offset[1] * base_normal
                world_angle = self.skeleton.base_angle + initial[i]
            else:
                parent, parent_anchor = self.bodies[p], (self._halves[p], 0.0)
                joint, world_angle = ends[p], world_angles[p] + initial[i]
            direction = _direction(world_angle)
            world_angles[i] = world_angle
            ends[i] = joint + link.length * direction
            radius = link.width / 2.0
            body = pymunk.Body(
                link.mass, pymunk.moment_for_segment(link.mass, (-half, 0), (half, 0), radius)
            )
            body.position = tuple(joint + half * direction)
            body.angle = world_angle
            shape = pymunk.Segment(body, (-half, 0), (half, 0), radius)
            shape.filter = shape_filter
            shape.collision_type = _LINK_TYPE
            shape.friction = 0.8
            pivot = pymunk.PivotJoint(parent, body, parent_anchor, (-half, 0))
            # SimpleMotor drives (b.w - a.w) toward -rate; commands go through set_rates.
            motor = pymunk.SimpleMotor(parent, body, 0.0)
            motor.max_force = link.max_torque
            self.space.add(body, shape, pivot, motor)
            limit_joint = None
            if link.limits is not None:
                # b.angle - a.angle is the local angle: the base body carries base_angle.
                limit_joint = pymunk.RotaryLimitJoint(parent, body, *link.limits_rad)
                self.space.add(limit_joint)
            self.bodies.append(body)
            pivots.append(pivot)
            self.motors.append(motor)
            self.limit_joints.append(limit_joint)
        self._returns: list[pymunk.SimpleMotor] = []
        """The return sweep's motors, in link order (empty for a chain of the plain sweep)."""
        if len(links) > SWEEP_LINKS:
            for pivot, motor in zip(reversed(pivots), reversed(self.motors), strict=True):
                twin = pymunk.SimpleMotor(motor.a, motor.b, 0.0)
                twin.max_force = motor.max_force = 0.5 * motor.max_force
                self.space.add(pymunk.PivotJoint(pivot.a, pivot.b, pivot.anchor_a, pivot.anchor_b))
                self.space.add(twin)
                self._returns.append(twin)
            self._returns.reverse()
        self._motor_structs = [motor._constraint for motor in self.motors]
        self._return_structs = [motor._constraint for motor in self._returns]
        self._compiled: tuple[CompiledMotors, CompiledMotors] | None = None
        """The motors and their return twins written and read in one compiled call each, for
        a chain with the return sweep (see :mod:`ikgame.physics._motors`), where numba can."""
        if self._returns:
            from ikgame.physics._motors import compiled_motors

            motors = compiled_motors(self._motor_structs)
            returns = compiled_motors(self._return_structs)
            if motors is not None and returns is not None:
                self._compiled = (motors, returns)
        self._links_by_id = {body.id: body for body in self.bodies}
        self._arbiter_reads = pymunk.batch.Buffer()

        if collide:
            apart = _apart(self.skeleton)
            index = {shape: i for i, body in enumerate(self.bodies) for shape in body.shapes}

            def begin(arbiter: pymunk.Arbiter, _space: pymunk.Space, _data: object) -> None:
                a, b = arbiter.shapes
                arbiter.process_collision = bool(apart[index[a], index[b]])

            self.space.on_collision(_LINK_TYPE, _LINK_TYPE, begin=begin)

        for obstacle in level.obstacles:
            self.space.add(_obstacle_shape(self.space.static_body, obstacle))

        self.prop_bodies: list[pymunk.Body] = []
        for prop in level.props:
            body, shape = _prop_body(prop)
            self.space.add(body, shape)
            self.prop_bodies.append(body)
        self._base_move: _BaseMove | None = None
        self.link_masses = np.array([b.mass for b in self.bodies], dtype=float)
        """(n,) mass of each link."""
        self.link_moments = np.array([b.moment for b in self.bodies], dtype=float)
        """(n,) moment of inertia of each link about its centre, mass px^2."""
        self._lengths = 2.0 * np.array(self._halves, dtype=float)
        self._halves_array = 0.5 * self._lengths
        self._feed_forward: list[float] | np.ndarray = [0.0] * self.count
        self._cp_space = self.space._space  # the C space, for chipmunk's own calls
        self._reads = pymunk.batch.Buffer()
        self._rows: _Rows | None = None
        self._link_angles: np.ndarray | None = None
        self._joints: tuple[np.ndarray, np.ndarray] | None = None
        self._effector_ends = [
            (self.bodies[i]._body, (self._halves[i], 0.0)) for i in self.effector_links.tolist()
        ]
        self._stops = _Stops(self.limit_joints, self.max_speed)
        self._at_limit = self.max_torque * _AT_LIMIT
        """The torque past which each joint counts as at its limit (see :meth:`torque_limited`)."""

    @property
    def count(self) -> int:
        """Number of links."""
        return len(self.bodies)

    def joint_angles(self) -> np.ndarray:
        """(n,) measured local joint angles, radians.

        Read from the continuous body angles, so a free joint that has turned 1.5 times reads
        3 pi; limited joints read in the same frame as their limits.
        """
        state, rows = self._state()
        return state[rows.links, 2] - state[rows.parents, 2]

    @property
    def gravity(self) -> tuple[float, float]:
        """Gravity now, ``(x, y)`` px/s^2."""
        gravity = _GRAVITY(self._cp_space)
        return gravity.x, gravity.y

    def joint_velocities(self) -> np.ndarray:
        """(n,) relative angular velocity of each joint (child - parent), rad/s."""
        state, rows = self._state()
        return state[rows.links, 3] - state[rows.parents, 3]

    def joint_state(self) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`joint_angles` and :meth:`joint_velocities` from one read of the bodies.

        >>> from ikgame.level.model import Level
        >>> world = World(Level.model_validate({"level": {"name": "x", "duration": 1.0},
        ...     "chain": {"links": [{"length": 50.0}]}, "script": [{"wait": 1.0}]}))
        >>> [a.tolist() for a in world.joint_state()]
        [[0.0], [0.0]]
        """
        state, rows = self._state()
        links, parents = state[rows.links], state[rows.parents]
        # The tick's drive applies its loads along the links as read here (a copy: the read's
        # buffer is reused).
        self._link_angles = links[:, 2].copy()
        # So does the step's bracing of the stops (nothing moves the bodies in between).
        self._joints = (links[:, 2] - parents[:, 2], links[:, 3] - parents[:, 3])
        return self._joints

    def _state(self) -> tuple[np.ndarray, _Rows]:
        """Every body's x, y, angle and angular velocity in one read (a view of a buffer the
        next read reuses), and which rows are whose."""
        batch = self._reads
        batch.clear()
        pymunk.batch.get_space_bodies(self.space, _STATE, batch)
        state = np.frombuffer(batch.float_buf()).reshape(-1, 4)
        rows = self._rows
        if rows is None or rows.count != len(state):
            rows = self._rows = _Rows(self, len(state))
        return state, rows

    def joint_positions(self) -> np.ndarray:
        """World positions of the joints, px: for a chain (n + 1, 2), joint 0 .. joint n-1 then
        the end effector; for a tree of bones (2n, 2), the n link starts then the n link ends
        (see :attr:`is_tree`)."""
        starts = [
            b.local_to_world((-h, 0.0)) for b, h in zip(self.bodies, self._halves, strict=True)
        ]
        if not self.is_tree:
            return np.array([*starts, self.end_effector()], dtype=float)
        ends = [b.local_to_world((h, 0.0)) for b, h in zip(self.bodies, self._halves, strict=True)]
        return np.array(starts + ends, dtype=float)

    def end_effector(self) -> np.ndarray:
        """(2,) world position of the first end effector (a chain's tip), px."""
        return self.effector_positions()[0]

    def effector_positions(self) -> np.ndarray:
        """(k, 2) world position of each end effector, px, in :attr:`effector_links` order."""
        ends = [_LOCAL_TO_WORLD(body, end) for body, end in self._effector_ends]
        return np.array([(end.x, end.y) for end in ends], dtype=float)

    def link_ends(self, links: np.ndarray) -> np.ndarray:
        """(m, 2) world position of the far end of each of ``links`` (indices), px."""
        return np.array(
            [self.bodies[i].local_to_world((self._halves[i], 0.0)) for i in links], dtype=float
        )

    def set_rates(self, rates: np.ndarray) -> None:
        """Ask each joint's motor for a relative angular velocity (child - parent), rad/s.

        Each motor may use its whole torque limit; :meth:`drive` shares the limit with
        feed-forward torques instead.
        """
        self.drive(rates, np.zeros(self.count), np.zeros((self.count, 2)), self.max_torque)

    def drive(
        self,
        rates: np.ndarray,
        torques: np.ndarray,
        forces: np.ndarray,
        budgets: np.ndarray,
    ) -> None:
        """Apply feed-forward joint loads for the next step and let the motors correct the rest.

        ``torques`` (n,) act on each child with the reaction on its parent; ``forces`` (n, 2) are
        the pivot forces, parent on child at the joint (world frame): the pivots would carry
        them anyway, so giving them here only saves the constraint solver from finding them.
        The base body is kinematic and takes the reactions of joint 0. Each motor then holds
        its ``rates`` entry (rad/s) with at most its ``budgets`` entry of torque, so that a
        joint's feed-forward torque and its motor's never add up to more than its limit. The
        loads act along the links as :meth:`joint_state` last read them since the last step
        (the tick reads the bodies once), else as they are now.

        >>> from ikgame.level.model import Level
        >>> world = World(Level.model_validate({"level": {"name": "x", "duration": 1.0},
        ...     "world": {"gravity": [0.0, 0.0]}, "chain": {"links": [{"length": 50.0}]},
        ...     "script": [{"wait": 1.0}]}))
        >>> about_joint = world.link_moments[0] + world.link_masses[0] * 25.0**2
        >>> torque = about_joint * 4.0 * 240.0  # to reach 4 rad/s in one 1/240 s tick
        >>> world.drive(np.zeros(1), np.array([torque]), np.zeros((1, 2)), np.zeros(1))
        >>> world.step(1 / 240)
        >>> round(float(world.joint_velocities()[0]), 6)
        4.0
        """
        angles = self._link_angles
        if angles is None:
            state, rows = self._state()
            angles = state[rows.links, 2]
        rows = self._rows
        loads = rows.loads
        # Each body takes its joint's loads and the reactions of the joints at its end, all
        # acting at the link's ends, so the pivot forces turn it about its centre too. Bodies
        # other than links get no load: pymunk clears applied loads after every step.
        feed_forward = None
        if rows.consecutive and self.count <= FLOAT_LINKS:
            # A short chain, link by link over floats (numpy's calls cost more than its sums):
            # the same operations as the arrays below.
            cos, sin = np.cos(angles).tolist(), np.sin(angles).tolist()
            t, halves = torques.tolist(), self._halves
            # The x and y columns as two lists (the servo's forces are a transposed (2, n)).
            f_x, f_y = forces.T.tolist()
            values: list[float] = []
            # Each link but the last, with the joint at its end (zip stops one short).
            for fx, next_x, fy, next_y, torque, next_t, h, c, s in zip(
                f_x, f_x[1:], f_y, f_y[1:], t, t[1:], halves, cos, sin, strict=False
            ):
                pair_x, pair_y = fx + next_x, fy + next_y
                hx, hy = h * c, h * s
                values += fx - next_x, fy - next_y, (torque - next_t) - (hx * pair_y - hy * pair_x)
            fx, fy = f_x[-1], f_y[-1]
            hx, hy = halves[-1] * cos[-1], halves[-1] * sin[-1]
            values += fx, fy, t[-1] - (hx * fy - hy * fx)
            # Packed straight into the links' rows (consecutive): numpy converts a list of
            # floats one by one, at twice the cost.
            rows.link_rows.pack_into(loads, rows.link_offset, *values)
            feed_forward = t
        elif rows.consecutive:
            hx, hy = self._halves_array * np.cos(angles), self._halves_array * np.sin(angles)
            pair = forces.copy()
            pair[:-1] += forces[1:]
            body = loads[rows.links]  # a view: the links are consecutive rows
            body[:, :2] = forces
            body[:-1, :2] -= forces[1:]
            body[:, 2] = torques
            body[:-1, 2] -= torques[1:]
            body[:, 2] -= hx * pair[:, 1] - hy * pair[:, 0]
        else:
            hx, hy = self._halves_array * np.cos(angles), self._halves_array * np.sin(angles)
            pair = forces.copy()
            beyond_forces, beyond_torques = np.zeros((self.count, 2)), np.zeros(self.count)
            np.add.at(beyond_forces, rows.hanging_parents, forces[rows.hanging])
            np.add.at(beyond_torques, rows.hanging_parents, torques[rows.hanging])
            pair += beyond_forces
            loads[rows.links, :2] = forces - beyond_forces
            loads[rows.links, 2] = torques - beyond_torques - (hx * pair[:, 1] - hy * pair[:, 0])
        compiled = self._compiled
        if compiled is not None:
            self._feed_forward = np.array(torques, dtype=float)
            pymunk.batch.set_space_bodies(self.space, _LOADS, rows.writes)
            self._loaded = True
            # The same calls as the loops below, in the same order, with the same floats.
            motors, returns = compiled
            shares = 0.5 * np.asarray(budgets, dtype=float)
            returns.write(rates, shares)
            motors.write(rates, shares)
            return
        if feed_forward is None:
            feed_forward = np.asarray(torques, dtype=float).tolist()
        self._feed_forward = feed_forward
        pymunk.batch.set_space_bodies(self.space, _LOADS, rows.writes)
        self._loaded = True
        wanted, shares = rates.tolist(), budgets.tolist()
        if self._returns:
            shares = [0.5 * b for b in shares]
            for motor, rate, budget in zip(self._return_structs, wanted, shares, strict=True):
                _SET_RATE(motor, -rate)
                _SET_MAX_FORCE(motor, budget)
        for motor, rate, budget in zip(self._motor_structs, wanted, shares, strict=True):
            # SimpleMotor drives (b.w - a.w) toward -rate.
            _SET_RATE(motor, -rate)
            _SET_MAX_FORCE(motor, budget)

    def motor_torques(self) -> np.ndarray:
        """(n,) magnitude of the torque each joint applied during the last step: feed-forward
        plus its motor's correction (the motor's impulse / dt)."""
        if self._compiled is not None:
            return self._applied_compiled(*self._compiled)
        return np.array(self._applied())

    def torque_limited(self) -> np.ndarray:
        """(n,) bool: which joints were at their torque limit during the last step."""
        if self._compiled is not None:
            return self._applied_compiled(*self._compiled) >= self._at_limit
        return np.array(self._applied()) >= self._at_limit

    def _applied(self) -> list[float]:
        """:meth:`motor_torques` as floats (a tick asks for them joint by joint)."""
        dt = self._space_dt
        if self._returns:
            return [
                abs(f + (_IMPULSE(m) + _IMPULSE(r)) / dt)
                for f, m, r in zip(
                    self._feed_forward, self._motor_structs, self._return_structs, strict=True
                )
            ]
        return [
            abs(f + _IMPULSE(m) / dt)
            for f, m in zip(self._feed_forward, self._motor_structs, strict=True)
        ]

    def _applied_compiled(self, motors: CompiledMotors, returns: CompiledMotors) -> np.ndarray:
        """:meth:`_applied` of a chain with compiled motors: the same sums over arrays."""
        return np.abs(
            self._feed_forward + (motors.impulses() + returns.impulses()) / self._space_dt
        )

    def touching(self) -> bool:
        """True when any link of the chain is in contact with an obstacle or a prop."""
        # A body's contacts are the arbiters of the last step that involve it, and chipmunk
        # keeps every one of those among the space's cached arbiters (with some of the steps
        # before): one batch read of the cached arbiters' bodies leaves only the links named
        # there to ask, where asking every link took a call into pymunk each.
        reads = self._arbiter_reads
        reads.clear()
        pymunk.batch.get_space_arbiters(self.space, _ARBITER_BODIES, reads)
        links = self._links_by_id
        for body_id in dict.fromkeys(np.frombuffer(reads.int_buf(), dtype=np.uintp).tolist()):
            body = links.get(body_id)
            if body is not None:
                contacts: list[object] = []
                body.each_arbiter(contacts.append)
                if contacts:
                    return True
        return False

    def set_gravity(self, gravity: tuple[float, float]) -> None:
        """Change gravity from now on, px/s^2."""
        self.space.gravity = gravity

    def move_base(
        self, to: tuple[float, float] | None, over: float, angle: float | None = None
    ) -> None:
        """Move the chain's base to ``to`` (px) and turn it to ``angle`` (radians, the shorter
        way round) over the next ``over`` seconds, then stop there; None keeps either as is.

        The kinematic base body is given the velocity that keeps it on a smoothstep profile (at
        rest at both ends, so the chain is not jerked), which pymunk integrates exactly; the last
        step lands it on ``to``. :attr:`skeleton` follows the base while it moves.

        >>> from ikgame.level.model import Level
        >>> world = World(Level.model_validate({"level": {"name": "x", "duration": 1.0},
        ...     "chain": {"links": [{"length": 50.0}]}, "script": [{"wait": 1.0}]}))
        >>> world.move_base((30.0, 0.0), 0.5)
        >>> for _ in range(60): world.step(1 / 120)
        >>> world.skeleton.base.tolist()
        [30.0, 0.0]
        """
        if not (math.isfinite(over) and over > 0):
            raise ValueError(f"over must be a positive number of seconds, got {over!r}")
        start = np.array(self.base_body.position)
        end = start if to is None else np.asarray(to, dtype=float)
        start_angle = float(self.base_body.angle)
        end_angle = start_angle
        if angle is not None:
            end_angle = start_angle + math.remainder(angle - start_angle, math.tau)
        self._base_move = _BaseMove(start, end, start_angle, end_angle, float(over))

    def base_motion(self) -> tuple[np.ndarray, float] | None:
        """The base's velocity (px/s) and spin (rad/s) over the next step, or None while it
        stands still."""
        move = self._base_move
        if move is None:
            return None
        # The step sets the velocity that lands the base on its profile at the step's end.
        position, angle, _ = move.at(move.elapsed + self.last_dt)
        velocity = (position - np.array(self.base_body.position)) / self.last_dt
        return velocity, (angle - float(self.base_body.angle)) / self.last_dt

    def prop_states(self) -> np.ndarray:
        """(p, 3) each prop's ``(x, y, angle)``: centre in px, angle in radians.

        >>> from ikgame.level.model import Level
        >>> World(Level.model_validate({"level": {"name": "x", "duration": 1.0},
        ...     "chain": {"links": [{"length": 50.0}]}, "script": [{"wait": 1.0}],
        ...     "props": [{"kind": "ball", "name": "b", "position": [80, 0], "radius": 5}]}
        ...     )).prop_states().tolist()
        [[80.0, 0.0, 0.0]]
        """
        return np.array([(*b.position, b.angle) for b in self.prop_bodies], dtype=float).reshape(
            -1, 3
        )

    def step(self, dt: float) -> None:
        """Advance the world by ``dt`` seconds (in equal parts of at most :data:`MAX_STEP_S`)."""
        self.last_dt = dt
        read, self._joints, self._link_angles = self._joints, None, None
        move = self._base_move
        if move is None:
            self._step_space(dt, read)
            return
        move.elapsed += dt
        wanted, wanted_angle, done = move.at(move.elapsed)
        self.base_body.velocity = tuple((wanted - np.array(self.base_body.position)) / dt)
        turning = move.end_angle != move.start_angle
        if turning:
            self.base_body.angular_velocity = (wanted_angle - self.base_body.angle) / dt
        self._step_space(dt, read)
        if done:
            self.base_body.velocity = (0.0, 0.0)
            self.base_body.position = tuple(move.end)
            self.base_body.angular_velocity = 0.0
            if turning:
                self.base_body.angle = move.end_angle
            self._base_move = None
        # Solvers need the base where it is now; the Skeleton is frozen, so a new one. A base
        # dragged off by a blow-up keeps the old skeleton: :meth:`diverged` reports it.
        if np.all(np.isfinite(self.base_body.position)) and math.isfinite(self.base_body.angle):
            self.skeleton = self.skeleton.moved_to(
                self.base_body.position, self.base_body.angle if turning else None
            )

    def _step_space(self, dt: float, read: tuple[np.ndarray, np.ndarray] | None) -> None:
        """Step the space by ``dt`` s, in parts of at most :data:`MAX_STEP_S`, with the joint
        stops braced (see :class:`_Stops`), from the tick's :meth:`joint_state` (``read``;
        None: the bodies are read here) and then from each part's."""
        loaded, self._loaded = self._loaded, False
        if dt <= MAX_STEP_S:
            self._space_dt = dt
            self._step_part(dt, read)
            return
        parts = _parts(dt)
        part = self._space_dt = dt / parts
        self._step_part(part, read)
        for _ in range(parts - 1):
            if loaded:
                # pymunk clears the applied loads after every step: the tick's loads act over
                # all of it.
                pymunk.batch.set_space_bodies(self.space, _LOADS, self._rows.writes)
            self._step_part(part, None)

    def _step_part(self, dt: float, read: tuple[np.ndarray, np.ndarray] | None) -> None:
        """One step of the space, ``dt`` s, with the joint stops braced from ``read`` (the
        joints' angles and velocities; None: the bodies are read here)."""
        stops = self._stops
        if not stops.joints:
            self.space.step(dt)
            return
        if read is None:
            read = self.joint_state()
            self._joints = self._link_angles = None
        braced = stops.brace(*read, dt)
        self.space.step(dt)
        stops.release(braced)

    def diverged(self) -> bool:
        """True when any link's, prop's or the base's pose is NaN, infinite, or absurdly far.

        A blow-up shows in positions within a tick or two, so velocities are not read.
        """
        state, _ = self._state()
        # NaN fails the comparison too.
        return not float(np.abs(state[:, :3]).max()) < DIVERGENCE_LIMIT

    def divergence(self) -> str | None:
        """The first body that blew up (``"link 3"``, ``"prop 2"``, ``"base"``; counting from
        1), or None while the world holds together.

        >>> from ikgame.level.model import Level
        >>> World(Level.model_validate({"level": {"name": "x", "duration": 1.0},
        ...     "chain": {"links": [{"length": 50.0}]}, "script": [{"wait": 1.0}]})).divergence()
        """
        named = [("base", self.base_body)]
        named += [(f"link {i + 1}", b) for i, b in enumerate(self.bodies)]
        named += [(f"prop {i + 1}", b) for i, b in enumerate(self.prop_bodies)]
        sane = _sane(_poses([body for _, body in named]))
        return next((name for (name, _), ok in zip(named, sane, strict=True) if not ok), None)


def _apart(skeleton: Skeleton) -> np.ndarray:
    """(n, n) bool: which pairs of links may collide: neither hangs from the other and they do
    not share a joint (siblings, or roots on the base)."""
    related = skeleton.ancestors | skeleton.ancestors.T
    parents = skeleton.parents
    siblings = parents[:, None] == parents[None, :]
    return ~(related | siblings)


def _direction(angle: float) -> np.ndarray:
    """(2,) unit vector at ``angle`` radians."""
    return np.array((math.cos(angle), math.sin(angle)))


class _Rows:
    """Which row of a batch read of the space's bodies is which body of the world."""

    def __init__(self, world: World, count: int) -> None:
        batch = pymunk.batch.Buffer()
        pymunk.batch.get_space_bodies(world.space, pymunk.batch.BodyFields.BODY_ID, batch)
        ids = np.frombuffer(batch.int_buf(), dtype=np.uintp).tolist()
        if len(ids) != count:
            raise ValueError(f"the space has {len(ids)} bodies, a read gave {count} rows")
        row = {body_id: i for i, body_id in enumerate(ids)}
        self.count = count
        links = [row[b.id] for b in world.bodies]
        base = row[world.base_body.id]
        parents = world.parents.tolist()
        above = [base if p < 0 else links[p] for p in parents]
        self.links: slice | np.ndarray = np.array(links, dtype=int)
        self.parents: slice | np.ndarray = np.array(above, dtype=int)
        # A chain's links built in order are consecutive rows after the base: slices, views.
        first = links[0]
        self.consecutive = (
            parents == list(range(-1, len(parents) - 1))
            and links == list(range(first, first + len(links)))
            and base == first - 1
        )
        if self.consecutive:
            self.links = slice(first, first + len(links))
            self.parents = slice(base, base + len(links))
        # Links hanging from another link's end, last first: the order their loads add up in.
        hanging = [i for i in reversed(range(len(parents))) if parents[i] >= 0]
        self.hanging = np.array(hanging, dtype=int)
        self.hanging_parents = np.array([parents[i] for i in hanging], dtype=int)
        self.loads = np.zeros((count, 3))
        """Force x, y and torque per row, written to the space each tick."""
        self.link_rows = struct.Struct(f"{3 * len(links)}d")
        """Packs the links' rows (x, y, torque per link) into :attr:`loads` at
        :attr:`link_offset`, for consecutive rows."""
        self.link_offset = first * self.loads.strides[0]
        self.writes = pymunk.batch.Buffer()
        self.writes.set_float_buf(self.loads)


class _Stops:
    """The joints' limits, braced against a joint knocked toward one.

    pymunk moves every body by its velocity first and then solves the constraints for the
    velocities of the next step, and a ``RotaryLimitJoint`` acts only on a joint already past
    its limit. So the velocity a step leaves a joint with can carry it past its stop by up to
    one step's travel before the limit notices. A joint its motor turns moves at most at its
    speed limit, which keeps that small (and the motor drives it on into the stop anyway); a
    joint knocked faster (a hand struck back by the floor at 1000 deg/s, 4 deg a tick at 240
    ticks/s) is not bounded. A limit joint can hold a joint at a bound or push it back from one,
    but not let it close in by a set amount, so where a joint turning faster than its speed
    limit would pass a stop in the step after this one (from where this step moves it), its
    stop is moved to that angle for this step: the solver stops it there with the limit's full
    force, short of the stop by less than a step's travel, a tick early rather than a tick late.
    """

    def __init__(
        self, limit_joints: list[pymunk.RotaryLimitJoint | None], max_speed: np.ndarray
    ) -> None:
        self.joints = {i: j for i, j in enumerate(limit_joints) if j is not None}
        """Each limited joint's limit joint, by link index."""
        self.lower = [-math.inf if j is None else float(j.min) for j in limit_joints]
        self.upper = [math.inf if j is None else float(j.max) for j in limit_joints]
        self.max_speed: list[float] = np.asarray(max_speed, dtype=float).tolist()
        # A long chain's joints are screened over arrays first (the same comparisons of the
        # same floats): on most ticks none is knocked, and a loop over them all cost more.
        self._screen = (
            (np.array(self.lower), np.array(self.upper), np.array(self.max_speed))
            if len(self.joints) > FLOAT_LINKS
            else None
        )

    def brace(self, angles: np.ndarray, velocities: np.ndarray, dt: float) -> list[int]:
        """Move the stops of the knocked joints that the next ``dt`` s step would leave heading
        past one; ``angles`` (radians) and ``velocities`` (rad/s) are every joint's before it.
        Returns the braced joints, for :meth:`release`."""
        # Joint by joint over floats (the same sums as over arrays), the limited ones only: a
        # free joint's bounds are infinite, never passed.
        a, v = angles.tolist(), velocities.tolist()
        lower, upper, speeds, twice = self.lower, self.upper, self.max_speed, 2.0 * dt
        joints = self.joints
        screen = self._screen
        if screen is not None:
            low_at, high_at, fastest = screen
            ahead_at = angles + twice * velocities
            knocked = ((ahead_at < low_at) | (ahead_at > high_at)) & (np.abs(velocities) > fastest)
            # Free joints' bounds are infinite: never passed, as the loop below finds too.
            joints = {i: joints[i] for i in np.flatnonzero(knocked).tolist() if i in joints}
        braced = []
        for i, joint in joints.items():
            rate = v[i]
            # Most joints turn within their speed limit, and those are never braced: asked first.
            if not abs(rate) > speeds[i]:
                continue
            angle = a[i]
            ahead = angle + twice * rate
            low = ahead < lower[i]
            if not (low or ahead > upper[i]):
                continue
            moved = angle + dt * rate
            # A joint already past its stop is the limit joint's to push back, not to brace.
            # The braced stop is halfway along this step's travel: a contact's own correction of
            # its overlap moves the bodies in the same step, and a joint the floor held back
            # landed short of where its velocity alone put it, short of a stop braced there,
            # so the limit stayed idle and the next step carried the joint 3.9 deg past its
            # real stop. Anywhere in the travel's second half, the joint is past the braced one.
            halfway = angle + 0.5 * dt * rate
            if low:
                if moved >= lower[i]:
                    braced.append(i)
                    joint.min = halfway
            elif moved <= upper[i]:
                braced.append(i)
                joint.max = halfway
        return braced

    def release(self, braced: list[int]) -> None:
        """Put the stops of the ``braced`` joints back at their limits."""
        for i in braced:
            joint = self.joints[i]
            joint.min, joint.max = self.lower[i], self.upper[i]


def _poses(bodies: list[pymunk.Body]) -> np.ndarray:
    """(k, 3) each body's ``(x, y, angle)``."""
    values = np.fromiter(
        (v for b in bodies for v in (*b.position, b.angle)), float, 3 * len(bodies)
    )
    return values.reshape(-1, 3)


def _sane(poses: np.ndarray) -> np.ndarray:
    """(k,) bool: which poses are finite and within :data:`DIVERGENCE_LIMIT`."""
    with np.errstate(invalid="ignore"):
        return np.all(np.isfinite(poses) & (np.abs(poses) < DIVERGENCE_LIMIT), axis=1)


def _obstacle_shape(
    static: pymunk.Body, obstacle: SegmentObstacle | CircleObstacle
) -> pymunk.Shape:
    if isinstance(obstacle, SegmentObstacle):
        shape: pymunk.Shape = pymunk.Segment(static, obstacle.a, obstacle.b, obstacle.radius)
    else:
        shape = pymunk.Circle(static, obstacle.radius, obstacle.center)
    shape.friction = obstacle.friction
    shape.elasticity = _OBSTACLE_ELASTICITY
    return shape


def _prop_body(prop: BallProp | BoxProp) -> tuple[pymunk.Body, pymunk.Shape]:
    if isinstance(prop, BallProp):
        body = pymunk.Body(prop.mass, pymunk.moment_for_circle(prop.mass, 0.0, prop.radius))
        shape: pymunk.Shape = pymunk.Circle(body, prop.radius)
    else:
        body = pymunk.Body(prop.mass, pymunk.moment_for_box(prop.mass, prop.size))
        shape = pymunk.Poly.create_box(body, prop.size)
    body.position = prop.position
    body.angle = math.radians(prop.angle)
    shape.friction = prop.friction
    shape.elasticity = prop.elasticity
    return body, shape


def _parts(dt: float) -> int:
    """How many equal steps of at most :data:`MAX_STEP_S` the space takes for a tick of ``dt``
    s (one for a tick no longer, or of no length).

    >>> _parts(1 / 240), _parts(1 / 120), _parts(1 / 100), _parts(0.0)
    (1, 2, 3, 1)
    """
    return max(1, math.ceil(dt / MAX_STEP_S - 1e-9))
