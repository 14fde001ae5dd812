"""Rigid-body dynamics of a planar chain or tree of links, in closed form over numpy arrays.

The controller uses it for feed-forward: the joint torques that give the motion it wants
(inverse dynamics), the torque that gravity alone asks of each joint, and the inertia each joint
turns when it moves alone. With those the motors only correct small errors, so the constraint
solver of the physics engine has little to converge on however long the chain is.

Each link is a rigid body whose centre of mass is the middle of the segment from its joint to
the next one. Angles are radians, lengths px, masses in the level's mass unit, torques
mass px^2/s^2, world y up. Link ``i`` hangs from joint ``i``, which sits at the end of its parent
link (``parents[i] < i``) or, for a root (``parents[i] == -1``), on the base; the base holds still,
so where on it a root's joint sits changes none of the loads. A serial chain
(``parents[i] == i - 1``) is the tree whose sums along the links are cumulative sums.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from typing import Final

import numpy as np

__all__ = [
    "ChainInertia",
    "Drive",
    "JointLoads",
    "Pose",
    "fit_drive",
    "inverse_dynamics",
    "plan_drive",
]

EASED_LOAD: Final = 0.5
"""Share of its torque limit the load a joint holds (coasting: gravity and the swing) must take
for the accelerations nearer the base that ease it to be kept whole when its limit sets the one
factor (see :func:`ease`): the motion on top of a load it can barely hold is what binds there.
Where the motion itself asks more than the joint has (a chain knocked by what it strikes), the
one factor keeps its direction."""


@dataclass(frozen=True, eq=False)
class ChainInertia:
    """Mass properties of a chain's or a tree's links, and how they hang together.

    >>> ChainInertia(np.array([10.0]), np.array([2.0]), np.array([5.0])).count
    1
    >>> y = ChainInertia(np.ones(3), np.ones(3), np.ones(3), parents=np.array([-1, 0, 0]))
    >>> y.along(np.array([1.0, 2.0, 3.0])).tolist(), y.beyond(np.array([1.0, 2.0, 3.0])).tolist()
    ([1.0, 3.0, 4.0], [6.0, 2.0, 3.0])

    Attributes:
        lengths: (n,) joint-to-joint length of each link, px.
        masses: (n,) mass of each link.
        moments: (n,) moment of inertia of each link about its own centre, mass px^2.
        parents: (n,) int, the link each link's joint sits at the end of (an earlier one), or -1
            for a link whose joint sits on the base; None (the default) for a serial chain.
    """

    lengths: np.ndarray
    masses: np.ndarray
    moments: np.ndarray
    parents: np.ndarray | None = None

    def __post_init__(self) -> None:
        shapes = {np.shape(a) for a in (self.lengths, self.masses, self.moments)}
        if len(shapes) != 1 or len(next(iter(shapes))) != 1:
            raise ValueError(f"lengths, masses and moments must be (n,) arrays, got {shapes}")
        if self.parents is not None:
            parents = np.asarray(self.parents)
            index = np.arange(len(self.lengths))
            if (
                parents.shape != index.shape
                or not np.issubdtype(parents.dtype, np.integer)
                or np.any(parents < -1)
                or np.any(parents >= index)
            ):
                raise ValueError(
                    "parents must be (n,) ints, each -1 (on the base) or an earlier link's index, "
                    f"got {self.parents!r}"
                )

    @property
    def count(self) -> int:
        """Number of links."""
        return len(self.lengths)

    @cached_property
    def _tree(self) -> _Tree:
        return _Tree(
            None if self.parents is None else np.asarray(self.parents).tolist(), self.count
        )

    @property
    def is_chain(self) -> bool:
        """True for a serial chain: each link hangs from the one before it, the first from the
        base."""
        return self._tree.chain

    @property
    def parent_list(self) -> list[int]:
        """Each link's parent index (-1 on the base), as Python ints."""
        return self._tree.parents

    def along(self, values: np.ndarray) -> np.ndarray:
        """Per-joint ``values`` (n,) or (n, k) summed from the base out to each link: relative
        joint rates become world angular velocities (a cumulative sum for a chain)."""
        return self._tree.along(np.asarray(values, dtype=float))

    def beyond(self, values: np.ndarray) -> np.ndarray:
        """Per-link ``values`` (n,) or (n, k) summed over each link and everything hanging from
        it (a reverse cumulative sum for a chain)."""
        return self._tree.beyond(np.asarray(values, dtype=float))

    @cached_property
    def mass_beyond(self) -> np.ndarray:
        """(n,) mass of each link and everything hanging from it."""
        return self.beyond(self.masses)

    @cached_property
    def moment_beyond(self) -> np.ndarray:
        """(n,) sum of the own moments of each link and everything hanging from it, mass px^2."""
        return self.beyond(self.moments)


_accumulate: Final = np.add.accumulate


class _Tree:
    """Sums along a tree's links, as numpy cumulative sums over its runs: maximal stretches of
    consecutive links each hanging from the one before. A chain is one run, so its sums are
    exactly ``np.cumsum`` and its reverse; a tree's are the same additions in the same order as a
    link-by-link loop. The sums are ``np.add.accumulate``, which is what ``np.cumsum`` calls on
    floats, without its dispatch (which cost more than the sums at 100 links)."""

    def __init__(self, parents: list[int] | None, count: int) -> None:
        serial = list(range(-1, count - 1))
        self.parents: list[int] = serial if parents is None else parents
        self.chain = self.parents == serial
        starts = [i for i in range(count) if self.parents[i] != i - 1 or i == 0]
        self.runs = [
            (start, stop, self.parents[start])
            for start, stop in zip(starts, [*starts[1:], count], strict=True)
        ]
        # Children from the last to the first, the order a link-by-link loop adds them in.
        hanging = [i for i in range(count - 1, -1, -1) if self.parents[i] >= 0]
        self._children = np.array(hanging, dtype=int)
        self._their_parents = np.array([self.parents[i] for i in hanging], dtype=int)

    def along(self, values: np.ndarray) -> np.ndarray:
        if self.chain:
            return _accumulate(values, axis=0)
        out = np.empty_like(values)
        for start, stop, parent in self.runs:
            if parent < 0:
                out[start:stop] = _accumulate(values[start:stop], axis=0)
            else:
                # Start the run's sum from its parent's, as a link-by-link loop adds them.
                first = values[start:stop].copy()
                first[0] += out[parent]
                out[start:stop] = _accumulate(first, axis=0)
        return out

    def beyond(self, values: np.ndarray) -> np.ndarray:
        if self.chain:
            return _accumulate(values[::-1], axis=0)[::-1]
        own = values.copy()
        out = np.empty_like(values)
        for start, stop, parent in reversed(self.runs):
            out[start:stop] = _accumulate(own[start:stop][::-1], axis=0)[::-1]
            if parent >= 0:
                own[parent] += out[start]
        return out

    def with_children(self, values: np.ndarray) -> np.ndarray:
        """Each link's value plus those of the links hanging from its end."""
        out = values.copy()
        if self.chain:
            out[:-1] += values[1:]
        else:
            np.add.at(out, self._their_parents, values[self._children])
        return out


@dataclass(frozen=True, eq=False)
class JointLoads:
    """What the chain asks of its joints at one instant.

    Loads add up: those of gravity, of the chain's swing and of an acceleration, each computed
    alone, sum to those of all three at once.

    Attributes:
        torques: (n,) torque the motor of each joint must apply to its child (the parent takes
            the reaction), mass px^2/s^2.
        forces: (n, 2) force the parent exerts on its child at each joint, mass px/s^2; the
            pivots carry these whatever the motors do.
    """

    torques: np.ndarray
    forces: np.ndarray

    def __add__(self, other: JointLoads) -> JointLoads:
        return JointLoads(self.torques + other.torques, self.forces + other.forces)

    def __sub__(self, other: JointLoads) -> JointLoads:
        return JointLoads(self.torques - other.torques, self.forces - other.forces)

    def scaled(self, factor: float) -> JointLoads:
        """These loads times ``factor``."""
        return JointLoads(factor * self.torques, factor * self.forces)


class Pose:
    """A chain's geometry at one instant, computed once for every load asked of it.

    >>> Pose(ChainInertia(np.array([10.0]), np.ones(1), np.ones(1)), np.zeros(1)).links.tolist()
    [[10.0, 0.0]]
    """

    def __init__(self, chain: ChainInertia, world_angles: np.ndarray) -> None:
        self.chain = chain
        cos, sin = np.cos(world_angles), np.sin(world_angles)
        self.links = np.empty((chain.count, 2))
        self.links[:, 0] = chain.lengths * cos
        self.links[:, 1] = chain.lengths * sin
        self.halves = 0.5 * self.links
        self.normals = np.empty_like(self.links)  # each link turned a quarter turn
        self.normals[:, 0] = -self.links[:, 1]
        self.normals[:, 1] = self.links[:, 0]

    def loads(
        self,
        omega: np.ndarray | None = None,
        alpha: np.ndarray | None = None,
        gravity: tuple[float, float] | np.ndarray | None = None,
    ) -> JointLoads:
        """Joint torques and pivot forces for per-link world angular velocities ``omega``
        (rad/s) and accelerations ``alpha`` (rad/s^2) under ``gravity`` (px/s^2); a term left
        out is zero."""
        chain = self.chain
        tree = chain._tree
        accel = np.zeros((chain.count, 2))
        if alpha is not None:
            accel += alpha[:, None] * self.normals
        if omega is not None:
            accel -= (omega * omega)[:, None] * self.links
        # Each joint accelerates with everything before it; each centre with half its own link.
        centre = tree.along(accel) - 0.5 * accel
        if gravity is not None:
            centre -= np.asarray(gravity, dtype=float)
        forces = tree.beyond(chain.masses[:, None] * centre)
        spin = _cross(self.halves, tree.with_children(forces))
        if alpha is not None:
            spin += chain.moments * alpha
        return JointLoads(tree.beyond(spin), forces)

    def held_slope(self, joint: int, gravity: tuple[float, float] | np.ndarray) -> np.ndarray:
        """(n,) how the torque that holding this pose still under ``gravity`` (px/s^2) takes
        of ``joint`` changes as each joint turns, everything beyond it turning with it: mass
        px^2/s^2 per radian. Closed form, in one pass over the links.

        >>> upright = Pose(ChainInertia(np.full(2, 10.0), np.ones(2), np.ones(2)), np.full(2, np.pi / 2))
        >>> upright.held_slope(0, (0.0, -10.0)).tolist()
        [-200.0, -50.0]

        The held torque of a joint is ``S x (-g)``, where ``S`` sums each link beyond it by its
        mass times its centre's offset from the joint. Turning a joint at or before it turns
        that whole sum; turning one beyond it turns only that joint's own sum. A quarter turn
        of ``S`` crossed with ``-g`` is ``S . g``: so a joint's slope is ``S . g`` of whichever
        of the two joints is the further out.
        """
        chain = self.chain
        tree = chain._tree
        joints, _, first = self._first_moments()
        turned = (first - chain.mass_beyond[:, None] * joints) @ np.asarray(gravity, dtype=float)
        alone = np.zeros(chain.count)
        alone[joint] = 1.0
        # Joints on the way from the base to ``joint`` (beyond() of its indicator), and those
        # hanging from it (along() of it) less ``joint`` itself.
        return tree.beyond(alone) * turned[joint] + (tree.along(alone) - alone) * turned

    def inertia(self) -> np.ndarray:
        """(n,) moment of inertia about each joint of everything beyond it, held rigid,
        mass px^2: what the joint's motor turns when it moves alone."""
        chain = self.chain
        joints, centres, first = self._first_moments()
        second = chain._tree.beyond(chain.masses * np.einsum("ij,ij->i", centres, centres))
        # sum_j m_j |c_j - p_i|^2, expanded so that it is three cumulative sums.
        spread = (
            second
            - 2.0 * np.einsum("ij,ij->i", joints, first)
            + chain.mass_beyond * np.einsum("ij,ij->i", joints, joints)
        )
        return chain.moment_beyond + np.maximum(spread, 0.0)

    def _first_moments(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(n, 2) each joint's place and each link's centre, relative to the base (roots'
        offsets left out: each sum over what hangs from a joint stays within one root's links,
        and moves with them), and the mass-weighted sum of the centres beyond each joint."""
        chain = self.chain
        tree = chain._tree
        joints = tree.along(self.links) - self.links
        centres = joints + self.halves
        return joints, centres, tree.beyond(chain.masses[:, None] * centres)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]


def inverse_dynamics(
    chain: ChainInertia,
    world_angles: np.ndarray,
    omega: np.ndarray,
    alpha: np.ndarray,
    gravity: tuple[float, float] | np.ndarray,
) -> JointLoads:
    """Joint torques and forces that give each link the angular acceleration ``alpha``.

    ``world_angles``, ``omega`` and ``alpha`` are per link in the world frame (radians, rad/s,
    rad/s^2); ``gravity`` is px/s^2; the base holds still. This is the recursive Newton-Euler
    algorithm with its two passes written as cumulative sums along the links (:meth:`Pose.loads`).

    A horizontal link of mass 2 and length 10 held still under gravity needs m g L / 2 at its
    joint:

    >>> one = ChainInertia(np.array([10.0]), np.array([2.0]), np.array([50.0 / 3.0]))
    >>> loads = inverse_dynamics(one, np.zeros(1), np.zeros(1), np.zeros(1), (0.0, -900.0))
    >>> loads.torques.round(6).tolist(), loads.forces.round(6).tolist()
    ([9000.0], [[0.0, 1800.0]])
    """
    return Pose(chain, world_angles).loads(omega, alpha, gravity)


@dataclass(frozen=True, eq=False)
class Drive:
    """A motion the motors can deliver this instant, and the loads that deliver it.

    Attributes:
        accelerations: (n,) joint accelerations (child relative to parent), rad/s^2.
        loads: the joint torques (within the limits) and pivot forces of that motion.
        saturated: (n,) bool, joints whose torque sits at its limit.
        consistent: whether the loads are exactly those of the motion (False when no motion
            fit the limits and the physics engine is left to find one).
    """

    accelerations: np.ndarray
    loads: JointLoads
    saturated: np.ndarray
    consistent: bool = True


def plan_drive(
    chain: ChainInertia,
    world_angles: np.ndarray,
    omega: np.ndarray,
    wanted: np.ndarray,
    gravity: tuple[float, float] | np.ndarray,
    max_torque: np.ndarray,
) -> Drive:
    """The closest motion to the ``wanted`` joint accelerations (rad/s^2) within the torque limits.

    Torques are affine in the accelerations, so scaling every wanted acceleration by one factor
    keeps the motion's direction: the largest factor up to 1 that keeps every joint within its
    limit wins, and the joint that sets it is saturated. Clipping each joint's torque on its own
    instead would fling the light far end of a long chain about with the torques it was given
    for a motion its base cannot follow. The pivot forces come out consistent with the motion,
    which leaves the physics engine nothing to reconcile.

    When even coasting needs more torque than some joint has (a load beyond a weak motor, a
    knock from an obstacle), no factor is taken: a fraction of the other joints' accelerations
    could offload it for a tick, but they cannot keep accelerating, and propping a joint up that
    way one tick and not the next lets it sag with torque to spare. The chain is then given the
    loads of coasting, the overloaded joints' clipped to their limits, the accelerations stay
    the wanted ones for the motors to strive for with what torque they have left, and the
    physics engine finds how the chain gives way: its implicit constraint solver is stable where
    an explicit answer from here (forward dynamics with clipped torques) flings the light links
    of a long chain about.

    >>> one = ChainInertia(np.array([10.0]), np.array([2.0]), np.array([50.0 / 3.0]))
    >>> drive = plan_drive(one, np.zeros(1), np.zeros(1), np.array([300.0]), (0.0, 0.0),
    ...                    np.array([1000.0]))
    >>> drive.accelerations.round(6).tolist(), drive.saturated.tolist()
    ([15.0], [True])
    """
    pose = Pose(chain, world_angles)
    wanted = np.asarray(wanted, dtype=float)
    bias = pose.loads(omega=omega, gravity=gravity)
    return fit_drive(bias, pose.loads(alpha=chain.along(wanted)), wanted, max_torque)


def fit_drive(
    bias: JointLoads,
    push: JointLoads,
    wanted: np.ndarray,
    max_torque: np.ndarray,
    head: Callable[[int], JointLoads] | None = None,
    weak: tuple[list[bool] | np.ndarray, Callable[[int], JointLoads]] | None = None,
    turning: Callable[[np.ndarray], JointLoads] | None = None,
) -> Drive:
    """:func:`plan_drive` from its parts: ``bias``, the loads of coasting (gravity and the
    swing), and ``push``, those of the ``wanted`` accelerations alone.

    With ``head``, a function giving the loads of the wanted accelerations of joints ``0..k``
    alone, the joints up to the one that runs out of torque keep their wanted accelerations and
    only those beyond it are scaled (see :func:`plan_drive`); without it, every joint's. Where
    the joints up to it are past a limit even alone, they are scaled by the largest factor
    that fits with those beyond coasting, and those beyond by the largest that fits then.

    With ``weak``, which joints may give way and a function giving the loads of a unit
    acceleration of joint ``k`` alone, a weak joint the motion would take past its limit gives
    way at it instead of setting the factor for everyone (see :func:`give_way`).

    With ``turning``, a function giving the loads of any joint accelerations alone, the wanted
    accelerations of joints nearer the base that ease the joint setting the one factor are kept
    whole, and only the others are scaled (see :func:`ease`).
    """
    limit = np.asarray(max_torque, dtype=float)
    full = bias + push
    if np.all(np.abs(full.torques) <= limit):
        return Drive(wanted, full, np.zeros(len(limit), dtype=bool))
    # give_way's first test, over arrays (the same sums and comparisons): whether any weak joint
    # is past its limit. On most ticks none is, and its lists cost more than the rest.
    if weak is not None and np.any(np.asarray(weak[0]) & ~(np.abs(full.torques) <= limit)):
        mask, column = weak
        gave = give_way(
            _listed(bias),
            _listed(push),
            wanted.tolist(),
            limit.tolist(),
            np.asarray(mask).tolist(),
            lambda k: _listed(column(k)),
        )
        if gave is not None:
            accelerations, (torques, fx, fy), saturated = gave
            loads = JointLoads(np.array(torques), np.column_stack((fx, fy)))
            return Drive(np.array(accelerations), loads, np.array(saturated))
    scale, binding = None, 0
    if np.all(np.abs(bias.torques) <= limit):
        scale, binding = _largest_factor(bias, push, limit)
    if head is not None and scale is not None and binding < len(limit) - 1:
        near = head(binding)
        start = bias + near
        rest = push - near
        tail, _ = _largest_factor(start, rest, limit)
        lead: float | None = 1.0
        if tail is None:
            # The joints up to it are past a limit on their own (one braking the long chain
            # beyond it, say): they take the largest factor that fits with the rest coasting,
            # and the rest what is left. One factor for all left such a joint at its limit the
            # other way, pushed by the far joints' reaction, and it swung on past its goal.
            lead, _ = _largest_factor(bias, near, limit)
            if lead is not None:
                start = bias + near.scaled(lead)
                tail, _ = _largest_factor(start, rest, limit)
        if tail is not None and lead is not None:
            accelerations = wanted.copy()
            accelerations[: binding + 1] *= lead
            accelerations[binding + 1 :] *= tail
            return _drive(accelerations, start + rest.scaled(tail), limit)
    if scale is not None:
        if turning is not None and scale < 1.0:
            eased = ease(
                _listed(bias),
                _listed(push),
                wanted.tolist(),
                limit.tolist(),
                binding,
                scale,
                lambda accelerations: _listed(turning(np.array(accelerations))),
            )
            if eased is not None:
                accelerations, (torques, fx, fy), saturated = eased
                loads = JointLoads(np.array(torques), np.column_stack((fx, fy)))
                return Drive(np.array(accelerations), loads, np.array(saturated))
        return _drive(scale * wanted, bias + push.scaled(scale), limit)
    return _drive(
        wanted, JointLoads(np.clip(bias.torques, -limit, limit), bias.forces), limit, False
    )


def _drive(
    accelerations: np.ndarray, loads: JointLoads, limit: np.ndarray, consistent: bool = True
) -> Drive:
    saturated = np.abs(loads.torques) >= limit * (1.0 - 1e-9)
    return Drive(accelerations, loads, saturated, consistent)


def _largest_factor(
    bias: JointLoads, push: JointLoads, limit: np.ndarray
) -> tuple[float | None, int]:
    """The largest factor up to 1 on ``push`` that keeps ``bias`` plus it within every joint's
    limit, and the first joint that allows no more; None for the factor if none does."""
    slope = push.torques
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        to_upper = (limit - bias.torques) / slope
        to_lower = (-limit - bias.torques) / slope
    moving = slope != 0.0
    low = np.max(np.where(moving, np.minimum(to_upper, to_lower), -np.inf))
    highs = np.where(moving, np.maximum(to_upper, to_lower), np.inf)
    binding = int(np.argmin(highs))
    high = float(highs[binding])
    holds = np.all(moving | (np.abs(bias.torques) <= limit))
    # Every joint allows the factors in [low, high]; the largest one up to 1 that all allow wins.
    if holds and low <= high and low <= 1.0 and high >= 0.0:
        return min(1.0, high), binding
    return None, binding


ListLoads = tuple[list[float], list[float], list[float]]
"""Joint torques, then the x and y of the pivot forces, per joint, as lists."""


def _listed(loads: JointLoads) -> ListLoads:
    return loads.torques.tolist(), loads.forces[:, 0].tolist(), loads.forces[:, 1].tolist()


def give_way(
    bias: ListLoads,
    push: ListLoads,
    wanted: list[float],
    limits: list[float],
    weak: list[bool],
    column: Callable[[int], ListLoads],
) -> tuple[list[float], ListLoads, list[bool]] | None:
    """The motion in which the ``weak`` joints the ``wanted`` one takes past their limits give
    way at them, and every other joint's acceleration is scaled by the largest factor up to 1
    that keeps it within its own: the accelerations, the loads and which joints are saturated;
    None when no weak joint is past its limit or no such motion fits.

    A joint gravity overloads (or one that gave its goal up) cannot have the acceleration it is
    asked for whatever the others do. Taken as the one factor for the whole chain, its shortfall
    leaves the other joints a fraction of their torque to brake with, and an arm whose weak
    joint sags swings like a pendulum about it. Here its torque is held at its limit (the side
    the motion asked for) and its acceleration is whatever that torque gives with the others'
    motion: the loads are affine in the accelerations, so the weak joints' own accelerations
    come from a small linear system (their block of the joint-space inertia, positive
    definite), and the loads stay those of one motion, which leaves the physics engine nothing
    to reconcile. ``column(k)`` gives the loads of a unit acceleration of joint ``k`` alone
    (rad/s^2, child - parent); torques are in mass px^2/s^2.

    >>> one = ([1.0], [0.0], [0.0])
    >>> give_way(([3.0], [0.0], [0.0]), ([1.0], [0.0], [0.0]), [1.0], [2.0], [True],
    ...          lambda k: one)
    ([-1.0], ([2.0], [0.0], [0.0]), [True])
    """
    over = [
        k
        for k, (b, p, lim, w) in enumerate(zip(bias[0], push[0], limits, weak, strict=True))
        if w and not abs(b + p) <= lim
    ]
    if not over:
        return None
    columns = [column(k) for k in over]
    # The others' push: the wanted motion less the weak joints' own share of it.
    rest = push
    for k, col in zip(over, columns, strict=True):
        rest = plus_loads(rest, col, -wanted[k])
    block = [[col[0][k] for col in columns] for k in over]
    at = [math.copysign(limits[k], bias[0][k] + push[0][k]) for k in over]
    fixed = _solve(block, [a - bias[0][k] for a, k in zip(at, over, strict=True)])
    slope = _solve(block, [-rest[0][k] for k in over])
    start, scaled = bias, rest
    for col, x0, x1 in zip(columns, fixed, slope, strict=True):
        start, scaled = plus_loads(start, col, x0), plus_loads(scaled, col, x1)
    for k, a in zip(over, at, strict=True):
        start[0][k], scaled[0][k] = a, 0.0
    if not all(abs(b) <= lim for b, lim in zip(start[0], limits, strict=True)):
        return None
    low, high = -math.inf, math.inf
    for b, s, lim in zip(start[0], scaled[0], limits, strict=True):
        if s != 0.0:
            to_upper, to_lower = (lim - b) / s, (-lim - b) / s
            low, high = max(low, min(to_upper, to_lower)), min(high, max(to_upper, to_lower))
    if not (low <= high and low <= 1.0 and high >= 0.0):
        return None
    factor = min(1.0, high)
    accelerations = [factor * w for w in wanted]
    for k, x0, x1 in zip(over, fixed, slope, strict=True):
        accelerations[k] = x0 + factor * x1
    loads = plus_loads(start, scaled, factor)
    return accelerations, loads, at_limits(loads[0], limits)


def ease(
    bias: ListLoads,
    push: ListLoads,
    wanted: list[float],
    limits: list[float],
    binding: int,
    scale: float,
    turning: Callable[[list[float]], ListLoads],
) -> tuple[list[float], ListLoads, list[bool]] | None:
    """The motion in which the ``wanted`` accelerations of joints nearer the base that ease the
    ``binding`` joint (the one whose limit sets the one factor ``scale`` on them all) are kept
    whole, and the others take the largest factor up to 1 that keeps every joint within its
    limit with them: the accelerations, the loads and which joints are saturated; None when
    none eases it, when the load the binding joint holds in ``bias`` takes less than
    :data:`EASED_LOAD` of its limit, or when that factor is no larger than ``scale`` (no joint
    gets less than the one factor gives).

    Scaled with the rest, an acceleration that eases the binding joint gives back the room it
    made there. On an arm of weakening motors hanging in heavy gravity, a far joint held at
    0.99 of its torque by the pose set the one factor while the second joint, coming in late,
    had to brake: the base's own braking eased that far joint, and scaled with the rest it left
    the second joint a quarter of its deceleration (0.2 rad/s^2 of 0.7), so it ran 0.2 deg past
    its goal and the arm settled for another half second. Only joints nearer the base (in a
    tree, its ancestors; the others' accelerations put nothing on it or come from beyond it):
    a joint beyond it eases it by its reaction, propping it up, and kept whole that whipped the
    light links beyond it round (a 30-link chain's reach took a fifth longer at 480 ticks/s
    than at 240). ``turning(accelerations)`` gives the loads of joint accelerations (rad/s^2,
    child - parent) alone. The joint-space inertia is symmetric, so the torques of a unit
    acceleration of the binding joint alone are, joint by joint, what a unit acceleration of
    each joint puts on it.

    >>> inertia = [[3.0, 1.0, 1.0], [1.0, 2.0, -1.0], [1.0, -1.0, 2.0]]
    >>> def turning(a):
    ...     return [sum(m * x for m, x in zip(row, a)) for row in inertia], [0.0] * 3, [0.0] * 3
    >>> held, wanted = ([0.0, 0.0, 0.4], [0.0] * 3, [0.0] * 3), [-1.0, -2.0, 0.0]
    >>> accelerations, loads, saturated = ease(held, turning(wanted), wanted, [9.0, 9.0, 0.5],
    ...                                        2, 0.1, turning)
    >>> [round(a, 6) for a in accelerations], [round(t, 6) for t in loads[0]], saturated
    ([-1.0, -1.1, 0.0], [-4.1, -3.2, 0.5], [False, False, True])
    """
    held = bias[0][binding]
    if not abs(held) >= EASED_LOAD * limits[binding]:
        return None
    over = held + push[0][binding]
    unit = turning([1.0 if k == binding else 0.0 for k in range(len(wanted))])[0]
    easing = [
        k < binding and u * w * over < 0.0
        for k, (u, w) in enumerate(zip(unit, wanted, strict=True))
    ]
    if not any(easing):
        return None
    eased = turning([w if e else 0.0 for w, e in zip(wanted, easing, strict=True)])
    start, rest = plus_loads(bias, eased, 1.0), plus_loads(push, eased, -1.0)
    factor, _ = listed_factor(start[0], rest[0], limits)
    if factor is None or factor <= scale:
        return None
    accelerations = [w if e else factor * w for w, e in zip(wanted, easing, strict=True)]
    loads = plus_loads(start, rest, factor)
    return accelerations, loads, at_limits(loads[0], limits)


def listed_factor(
    bias: list[float], push: list[float], limits: list[float]
) -> tuple[float | None, int]:
    """:func:`_largest_factor` over lists of torques.

    >>> listed_factor([0.0, 1.0], [2.0, 1.0], [1.0, 3.0])
    (0.5, 0)
    """
    low, high, holds, binding = -math.inf, math.inf, True, 0
    for j, (b, s, lim) in enumerate(zip(bias, push, limits, strict=True)):
        if s != 0.0:
            to_upper, to_lower = (lim - b) / s, (-lim - b) / s
            low = max(low, min(to_upper, to_lower))
            most = max(to_upper, to_lower)
            if most < high:
                high, binding = most, j
        elif not abs(b) <= lim:
            holds = False
    # The largest factor up to 1 that every joint allows, as in fit_drive.
    if holds and low <= high and low <= 1.0 and high >= 0.0:
        return min(1.0, high), binding
    return None, binding


def plus_loads(a: ListLoads, b: ListLoads, factor: float) -> ListLoads:
    """``a + factor b``, list by list (with the factor 1 or -1, exactly a sum or a difference).

    >>> plus_loads(([1.0], [2.0], [3.0]), ([1.0], [1.0], [1.0]), -1.0)
    ([0.0], [1.0], [2.0])
    """
    return (
        [x + factor * y for x, y in zip(a[0], b[0], strict=True)],
        [x + factor * y for x, y in zip(a[1], b[1], strict=True)],
        [x + factor * y for x, y in zip(a[2], b[2], strict=True)],
    )


def at_limits(torques: list[float], limits: list[float]) -> list[bool]:
    """Which joints' ``torques`` are at their ``limits`` (to within rounding)."""
    return [abs(t) >= lim * (1.0 - 1e-9) for t, lim in zip(torques, limits, strict=True)]


def _solve(matrix: list[list[float]], rhs: list[float]) -> list[float]:
    """``matrix x = rhs`` for a small symmetric positive definite ``matrix``, by elimination
    without pivoting (stable for such a matrix), over floats."""
    size = len(rhs)
    rows = [[*row, r] for row, r in zip(matrix, rhs, strict=True)]
    for i in range(size):
        pivot = rows[i][i]
        for j in range(i + 1, size):
            ratio = rows[j][i] / pivot
            rows[j] = [x - ratio * y for x, y in zip(rows[j], rows[i], strict=True)]
    x = [0.0] * size
    for i in reversed(range(size)):
        row = rows[i]
        x[i] = (row[size] - math.fsum(row[j] * x[j] for j in range(i + 1, size))) / row[i]
    return x
