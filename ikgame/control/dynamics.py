"""Rigid-body dynamics of a planar serial chain, in closed form over numpy arrays.

The controller uses it for feed-forward: the joint torques that give the motion it wants
(inverse dynamics), the torque that gravity alone asks of each joint, and the inertia each joint
turns when it moves alone. With those the motors only correct small errors, so the constraint
solver of the physics engine has little to converge on however long the chain is.

Each link is a rigid body whose centre of mass is the middle of the segment from its joint to
the next one. Angles are radians, lengths px, masses in the level's mass unit, torques
mass px^2/s^2, world y up. Link ``i`` hangs from joint ``i``; joint 0 sits on the base.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["ChainInertia", "Drive", "JointLoads", "inverse_dynamics", "plan_drive"]


@dataclass(frozen=True, eq=False)
class ChainInertia:
    """Mass properties of a chain's links.

    >>> ChainInertia(np.array([10.0]), np.array([2.0]), np.array([5.0])).count
    1

    Attributes:
        lengths: (n,) joint-to-joint length of each link, px.
        masses: (n,) mass of each link.
        moments: (n,) moment of inertia of each link about its own centre, mass px^2.
    """

    lengths: np.ndarray
    masses: np.ndarray
    moments: np.ndarray

    def __post_init__(self) -> None:
        shapes = {np.shape(a) for a in (self.lengths, self.masses, self.moments)}
        if len(shapes) != 1 or len(next(iter(shapes))) != 1:
            raise ValueError(f"lengths, masses and moments must be (n,) arrays, got {shapes}")

    @property
    def count(self) -> int:
        """Number of links."""
        return len(self.lengths)


@dataclass(frozen=True, eq=False)
class JointLoads:
    """What the chain asks of its joints at one instant.

    Attributes:
        torques: (n,) torque the motor of each joint must apply to its child (the parent takes
            the reaction), mass px^2/s^2.
        forces: (n, 2) force the parent exerts on its child at each joint, mass px/s^2; the
            pivots carry these whatever the motors do.
        inertia: (n,) moment of inertia about each joint of everything beyond it, held rigid,
            mass px^2: what the joint's motor turns when it moves alone.
    """

    torques: np.ndarray
    forces: np.ndarray
    inertia: np.ndarray


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _perp(v: np.ndarray) -> np.ndarray:
    return np.stack((-v[..., 1], v[..., 0]), axis=-1)


def _reverse_cumsum(a: np.ndarray) -> np.ndarray:
    return np.cumsum(a[::-1], axis=0)[::-1]


def inverse_dynamics(
    chain: ChainInertia,
    world_angles: np.ndarray,
    omega: np.ndarray,
    alpha: np.ndarray,
    gravity: tuple[float, float] | np.ndarray,
    base_acceleration: tuple[float, float] | np.ndarray = (0.0, 0.0),
) -> JointLoads:
    """Joint torques and forces that give each link the angular acceleration ``alpha``.

    ``world_angles``, ``omega`` and ``alpha`` are per link in the world frame (radians, rad/s,
    rad/s^2); ``gravity`` and ``base_acceleration`` are px/s^2. This is the recursive
    Newton-Euler algorithm with its two passes written as cumulative sums.

    A horizontal link of mass 2 and length 10 held still under gravity needs m g L / 2 at its
    joint:

    >>> one = ChainInertia(np.array([10.0]), np.array([2.0]), np.array([50.0 / 3.0]))
    >>> loads = inverse_dynamics(one, np.zeros(1), np.zeros(1), np.zeros(1), (0.0, -900.0))
    >>> loads.torques.round(6).tolist(), loads.forces.round(6).tolist()
    ([9000.0], [[0.0, 1800.0]])
    """
    directions = np.stack((np.cos(world_angles), np.sin(world_angles)), axis=-1)
    links = chain.lengths[:, None] * directions
    halves = 0.5 * links
    omega2 = (omega * omega)[:, None]
    # Acceleration of each joint: the base's plus what every link before it adds.
    link_terms = alpha[:, None] * _perp(links) - omega2 * links
    joint_acc = np.asarray(base_acceleration, dtype=float) + np.concatenate(
        (np.zeros((1, 2)), np.cumsum(link_terms, axis=0)[:-1])
    )
    centre_acc = joint_acc + alpha[:, None] * _perp(halves) - omega2 * halves
    net = chain.masses[:, None] * (centre_acc - np.asarray(gravity, dtype=float))
    forces = _reverse_cumsum(net)
    beyond = np.concatenate((forces[1:], np.zeros((1, 2))))
    torques = _reverse_cumsum(chain.moments * alpha + _cross(halves, forces + beyond))
    return JointLoads(torques, forces, _inertia_beyond(chain, links, halves))


def _inertia_beyond(chain: ChainInertia, links: np.ndarray, halves: np.ndarray) -> np.ndarray:
    joints = np.concatenate((np.zeros((1, 2)), np.cumsum(links, axis=0)[:-1]))
    centres = joints + halves
    m = chain.masses
    mass = _reverse_cumsum(m)
    first = _reverse_cumsum(m[:, None] * centres)
    second = _reverse_cumsum(m * np.einsum("ij,ij->i", centres, centres))
    # sum_j m_j |c_j - p_i|^2, expanded so that it is three cumulative sums.
    spread = (
        second
        - 2.0 * np.einsum("ij,ij->i", joints, first)
        + mass * np.einsum("ij,ij->i", joints, joints)
    )
    return _reverse_cumsum(chain.moments) + np.maximum(spread, 0.0)


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

    When even coasting needs more torque than some joint has (a load beyond a weak motor), no
    factor helps: the torques are clipped joint by joint and the physics engine finds the motion
    (the chain sags where its motors give out). Computing that motion here instead (forward
    dynamics through the mass matrix) is exact for one tick but explicit, and the light links of
    a long chain make it unstable at game tick rates.

    >>> one = ChainInertia(np.array([10.0]), np.array([2.0]), np.array([50.0 / 3.0]))
    >>> drive = plan_drive(one, np.zeros(1), np.zeros(1), np.array([300.0]), (0.0, 0.0),
    ...                    np.array([1000.0]))
    >>> drive.accelerations.round(6).tolist(), drive.saturated.tolist()
    ([15.0], [True])
    """
    limit = np.asarray(max_torque, dtype=float)
    wanted = np.asarray(wanted, dtype=float)
    full = inverse_dynamics(chain, world_angles, omega, np.cumsum(wanted), gravity)
    if np.all(np.abs(full.torques) <= limit):
        return Drive(wanted, full, np.zeros(chain.count, dtype=bool))
    consistent = True
    bias = inverse_dynamics(chain, world_angles, omega, np.zeros(chain.count), gravity)
    slope = full.torques - bias.torques
    with np.errstate(divide="ignore", invalid="ignore"):
        to_upper = (limit - bias.torques) / slope
        to_lower = (-limit - bias.torques) / slope
    moving = slope != 0.0
    low = np.max(np.where(moving, np.minimum(to_upper, to_lower), -np.inf))
    high = np.min(np.where(moving, np.maximum(to_upper, to_lower), np.inf))
    holds = np.all(moving | (np.abs(bias.torques) <= limit))
    if holds and low <= high and high >= 0.0:
        scale = max(0.0, min(1.0, high)) if low <= 0.0 else min(1.0, low)
        accelerations = scale * wanted
        loads = JointLoads(
            bias.torques + scale * slope,
            bias.forces + scale * (full.forces - bias.forces),
            full.inertia,
        )
    else:
        accelerations, consistent = wanted, False
        loads = JointLoads(np.clip(bias.torques, -limit, limit), bias.forces, bias.inertia)
    saturated = np.abs(loads.torques) >= limit * (1.0 - 1e-9)
    return Drive(accelerations, loads, saturated, consistent)
