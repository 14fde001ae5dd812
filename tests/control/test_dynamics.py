"""Inverse dynamics of a planar chain against the textbook two-link arm, and torque limits."""

import math

import numpy as np
import pytest

from ikgame.control.dynamics import ChainInertia, Pose, inverse_dynamics, plan_drive

GRAVITY = 900.0


def _two_link_torques(lengths, masses, moments, q, qd, qdd):
    """The two-link planar arm's closed-form dynamics (centres of mass at mid-link, g along -y)."""
    l1, _ = lengths
    m1, m2 = masses
    i1, i2 = moments
    c1, c2 = lengths[0] / 2, lengths[1] / 2
    cos2, sin2 = math.cos(q[1]), math.sin(q[1])
    m11 = i1 + i2 + m1 * c1**2 + m2 * (l1**2 + c2**2 + 2 * l1 * c2 * cos2)
    m12 = i2 + m2 * (c2**2 + l1 * c2 * cos2)
    m22 = i2 + m2 * c2**2
    h = -m2 * l1 * c2 * sin2
    g1 = (m1 * c1 + m2 * l1) * GRAVITY * math.cos(q[0]) + m2 * c2 * GRAVITY * math.cos(q[0] + q[1])
    g2 = m2 * c2 * GRAVITY * math.cos(q[0] + q[1])
    tau1 = m11 * qdd[0] + m12 * qdd[1] + h * qd[1] ** 2 + 2 * h * qd[0] * qd[1] + g1
    tau2 = m12 * qdd[0] + m22 * qdd[1] - h * qd[0] ** 2 + g2
    return np.array([tau1, tau2])


@pytest.mark.parametrize("seed", range(5))
def test_inverse_dynamics_matches_the_two_link_arm(seed):
    rng = np.random.default_rng(seed)
    lengths, masses, moments = rng.uniform(5, 50, 2), rng.uniform(0.1, 3, 2), rng.uniform(1, 80, 2)
    q, qd, qdd = rng.uniform(-3, 3, 2), rng.normal(size=2), rng.normal(size=2) * 10
    chain = ChainInertia(lengths, masses, moments)
    loads = inverse_dynamics(chain, np.cumsum(q), np.cumsum(qd), np.cumsum(qdd), (0, -GRAVITY))
    expected = _two_link_torques(lengths, masses, moments, q, qd, qdd)
    np.testing.assert_allclose(loads.torques, expected, rtol=1e-9, atol=1e-6)
    # The base pivot carries the whole arm's weight plus what accelerates it.
    assert loads.forces.shape == (2, 2)


def test_inertia_beyond_a_straight_chain_is_the_rod_about_its_end():
    n, length, mass = 10, 12.0, 0.2
    rod = ChainInertia(np.full(n, length), np.full(n, mass), np.full(n, mass * length**2 / 12))
    total = n * mass
    assert Pose(rod, np.zeros(n)).inertia()[0] == pytest.approx(total * (n * length) ** 2 / 3)


def test_loads_add_up_term_by_term():
    chain = _chain(5, seed=2)
    rng = np.random.default_rng(4)
    angles, omega, alpha = (rng.normal(size=5) for _ in range(3))
    pose = Pose(chain, angles)
    whole = pose.loads(omega, alpha, (0.0, -900.0))
    parts = pose.loads(omega=omega) + pose.loads(alpha=alpha) + pose.loads(gravity=(0.0, -900.0))
    np.testing.assert_allclose(parts.torques, whole.torques, rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(parts.forces, whole.forces, rtol=1e-9, atol=1e-6)


def _chain(n, seed=0):
    rng = np.random.default_rng(seed)
    lengths = rng.uniform(8, 40, n)
    masses = rng.uniform(0.1, 1.0, n)
    return ChainInertia(lengths, masses, masses * lengths**2 / 12)


def test_plan_drive_delivers_what_the_limits_allow():
    chain = _chain(6)
    angles = np.cumsum(np.full(6, 0.3))
    wanted = np.full(6, 50.0)
    free = plan_drive(chain, angles, np.zeros(6), wanted, (0, -900), np.full(6, 1e9))
    np.testing.assert_allclose(free.accelerations, wanted)
    assert not free.saturated.any()
    limit = np.abs(free.loads.torques) * 0.5 + 1.0
    tight = plan_drive(chain, angles, np.zeros(6), wanted, (0, -900), limit)
    assert np.all(np.abs(tight.loads.torques) <= limit * (1 + 1e-9))
    assert tight.saturated.any()
    # Scaled together: the motion keeps its direction.
    ratio = tight.accelerations / wanted
    np.testing.assert_allclose(ratio, ratio[0])
    assert 0.0 < ratio[0] < 1.0
    # And the loads are the inverse dynamics of that motion, so the pivots agree with it.
    check = inverse_dynamics(chain, angles, np.zeros(6), np.cumsum(tight.accelerations), (0, -900))
    np.testing.assert_allclose(check.torques, tight.loads.torques, rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(check.forces, tight.loads.forces, rtol=1e-9, atol=1e-6)


def test_a_joint_that_cannot_hold_its_load_pushes_at_its_limit_and_the_rest_coast():
    chain = _chain(4, seed=3)
    angles = np.zeros(4)  # horizontal: the most gravity torque
    hold = inverse_dynamics(chain, angles, np.zeros(4), np.zeros(4), (0, -900))
    limit = np.abs(hold.torques) * 2.0
    limit[0] = abs(hold.torques[0]) * 0.5
    wanted = np.full(4, 3.0)
    drive = plan_drive(chain, angles, np.zeros(4), wanted, (0, -900), limit)
    assert drive.saturated.tolist() == [True, False, False, False]
    assert drive.loads.torques[0] == pytest.approx(np.sign(hold.torques[0]) * limit[0])
    np.testing.assert_allclose(drive.loads.torques[1:], hold.torques[1:])
    np.testing.assert_allclose(drive.loads.forces, hold.forces)
    # The motors still strive for the wanted motion with the torque they have left.
    np.testing.assert_allclose(drive.accelerations, wanted)


def test_chain_inertia_checks_its_shapes():
    with pytest.raises(ValueError, match="must be"):
        ChainInertia(np.ones(2), np.ones(3), np.ones(2))


def test_no_factor_is_taken_that_leaves_a_joint_past_its_limit():
    # Held out sideways the base needs 8e5 against gravity and has 6e5: coasting is past the
    # limit, and so is the barely different wanted motion. The torques must still be within it.
    arm = ChainInertia(np.array([100.0, 100.0]), np.full(2, 2.0), np.full(2, 2.0 * 100.0**2 / 12))
    angles = np.array([0.0, 0.0])
    limit = np.array([6.0e5, 5.0e5])
    sag = np.array([-1e-3, 0.0])  # a hair downward: the factor that would fit is huge
    drive = plan_drive(arm, angles, np.zeros(2), sag, (0.0, -2000.0), limit)
    assert np.all(np.abs(drive.loads.torques) <= limit * (1 + 1e-9))
    assert drive.saturated[0]
