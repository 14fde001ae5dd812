"""Inverse dynamics of a planar chain against the textbook two-link arm, and torque limits."""

import math

import numpy as np
import pytest

from ikgame.control._floats import FloatInertia, fit_floats
from ikgame.control.dynamics import (
    ChainInertia,
    Pose,
    fit_drive,
    inverse_dynamics,
    plan_drive,
)

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


def _head(pose, chain, wanted):
    """The loads of the wanted accelerations of joints 0..k alone, as the servo gives them."""
    joints = np.arange(chain.count)
    return lambda k: pose.loads(alpha=chain.along(np.where(joints <= k, wanted, 0.0)))


def test_the_joints_up_to_the_one_that_runs_out_keep_their_acceleration():
    chain = _chain(8)
    angles = np.cumsum(np.full(8, 0.3))
    wanted = np.full(8, 50.0)
    pose = Pose(chain, angles)
    bias = pose.loads(gravity=(0, -900))
    push = pose.loads(alpha=chain.along(wanted))
    head = _head(pose, chain, wanted)
    # The base can give its own acceleration, but not the others' on top of it.
    limit = np.full(8, 1e9)
    limit[0] = 0.5 * (
        abs(bias.torques[0] + head(0).torques[0]) + abs(bias.torques[0] + push.torques[0])
    )
    drive = fit_drive(bias, push, wanted, limit, head)
    assert drive.consistent and drive.saturated.tolist() == [True] + [False] * 7
    assert drive.accelerations[0] == wanted[0]
    ratio = drive.accelerations[1:] / wanted[1:]
    np.testing.assert_allclose(ratio, ratio[0])
    assert 0.0 < ratio[0] < 1.0
    check = inverse_dynamics(chain, angles, np.zeros(8), np.cumsum(drive.accelerations), (0, -900))
    np.testing.assert_allclose(check.torques, drive.loads.torques, rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(check.forces, drive.loads.forces, rtol=1e-9, atol=1e-6)
    # Without the split every joint, the base's too, gets one factor.
    together = fit_drive(bias, push, wanted, limit)
    assert together.accelerations[0] < wanted[0]
    np.testing.assert_allclose(together.accelerations / wanted, together.accelerations[0] / 50.0)


def test_joints_past_a_limit_on_their_own_are_scaled_while_the_rest_coast():
    # The base and the next joint turn one way, the far joints the other, and the first two
    # cannot have even their own accelerations: scaling every joint by one factor gave all of
    # them a few percent of theirs, the first two too.
    chain = _chain(8)
    angles = np.cumsum(np.full(8, 0.3))
    wanted = np.array([40.0] + [-60.0] * 7)
    pose = Pose(chain, angles)
    bias = pose.loads(gravity=(0, -90))
    push = pose.loads(alpha=chain.along(wanted))
    head = _head(pose, chain, wanted)
    limit = np.full(8, 1e9)
    limit[0], limit[1] = 0.5 * abs(bias.torques[0] + head(0).torques[0]), 2e5
    assert np.any(np.abs((bias + head(1)).torques) > limit)
    drive = fit_drive(bias, push, wanted, limit, head)
    assert drive.consistent and drive.saturated.tolist() == [False, True] + [False] * 6
    # Joint 1 pushes at its limit the way its own acceleration asks.
    assert drive.loads.torques[1] == pytest.approx(-limit[1])
    lead = drive.accelerations[:2] / wanted[:2]
    assert lead[0] == pytest.approx(lead[1]) and 0.9 < lead[0] < 1.0
    np.testing.assert_allclose(drive.accelerations[2:], 0.0, atol=1e-12)
    check = inverse_dynamics(chain, angles, np.zeros(8), np.cumsum(drive.accelerations), (0, -90))
    np.testing.assert_allclose(check.torques, drive.loads.torques, rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(check.forces, drive.loads.forces, rtol=1e-9, atol=1e-6)
    # One factor for all gives the first two a small fraction of theirs.
    together = fit_drive(bias, push, wanted, limit)
    assert together.accelerations[0] / wanted[0] < 0.1
    # The float path takes the same split, to the last bit.
    floats = FloatInertia(chain)
    fast, listed = floats.pose(angles), wanted.tolist()
    reached, loads, _, _ = fit_floats(
        fast.loads(gravity=(0.0, -90.0)),
        fast.loads(alpha=floats.along(listed)),
        listed,
        limit.tolist(),
        lambda k: fast.loads(
            alpha=floats.along([a if j <= k else 0.0 for j, a in enumerate(listed)])
        ),
    )
    assert list(reached) == drive.accelerations.tolist()
    assert loads[0] == drive.loads.torques.tolist()


def test_the_float_fit_gives_the_same_floats_as_numpy():
    rng = np.random.default_rng(5)
    chain = _chain(7, seed=5)
    floats = FloatInertia(chain)
    split = 0
    for _ in range(100):
        angles = np.cumsum(rng.normal(size=7))
        pose, fast = Pose(chain, angles), floats.pose(angles)
        wanted, omega = rng.normal(size=7) * 200.0, rng.normal(size=7)
        limit = rng.uniform(1e3, 4e5, 7)
        bias = pose.loads(omega=chain.along(omega), gravity=(0.0, -900.0))
        push = pose.loads(alpha=chain.along(wanted))
        drive = fit_drive(bias, push, wanted, limit, _head(pose, chain, wanted))
        together = fit_drive(bias, push, wanted, limit)
        split += not np.array_equal(drive.accelerations, together.accelerations)
        listed = wanted.tolist()

        def head(k, listed=listed, fast=fast):
            return fast.loads(
                alpha=floats.along([a if j <= k else 0.0 for j, a in enumerate(listed)])
            )

        reached, loads, saturated, consistent = fit_floats(
            fast.loads(omega=floats.along(omega.tolist()), gravity=(0.0, -900.0)),
            fast.loads(alpha=floats.along(listed)),
            listed,
            limit.tolist(),
            head,
        )
        assert list(reached) == drive.accelerations.tolist()
        assert loads[0] == drive.loads.torques.tolist()
        assert loads[1] == drive.loads.forces[:, 0].tolist()
        assert loads[2] == drive.loads.forces[:, 1].tolist()
        assert saturated == drive.saturated.tolist() and consistent == drive.consistent
    assert split  # the split was taken, not only the one factor


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


def test_a_joint_that_cannot_hold_is_not_propped_up_by_the_others_accelerations():
    # Held out sideways the base needs 8e5 against gravity and has 6e5. Swinging the outer link
    # down hard enough would offload it for an instant (its reaction on the base), and a
    # fraction of that swing fits every limit; but no joint can keep accelerating, and a servo
    # that props the base up that way one tick and not the next lets the arm sag at two thirds
    # of its torque. The base gives all it has instead.
    arm = ChainInertia(np.array([100.0, 100.0]), np.full(2, 2.0), np.full(2, 2.0 * 100.0**2 / 12))
    pose = Pose(arm, np.zeros(2))
    bias = pose.loads(gravity=(0.0, -2000.0))
    limit = np.array([6.0e5, 1.0e7])
    wanted = np.array([0.0, -400.0])
    push = pose.loads(alpha=arm.along(wanted))
    rescue = bias.torques[0] + np.linspace(0.0, 1.0, 11) * push.torques[0]
    assert np.any(np.abs(rescue) <= limit[0]) and abs(rescue[-1]) > limit[0]
    drive = fit_drive(bias, push, wanted, limit)
    assert drive.saturated[0] and not drive.consistent
    assert drive.loads.torques[0] == pytest.approx(np.sign(bias.torques[0]) * limit[0])
    floats = FloatInertia(arm).pose(np.zeros(2))
    _, loads, saturated, consistent = fit_floats(
        floats.loads(gravity=(0.0, -2000.0)),
        floats.loads(alpha=FloatInertia(arm).along(wanted.tolist())),
        wanted.tolist(),
        limit.tolist(),
    )
    assert loads[0] == drive.loads.torques.tolist() and saturated[0] and not consistent


# -- trees -------------------------------------------------------------------------------------

Y_PARENTS = np.array([-1, 0, 0])  # a stem with two branches at its end
TREE_PARENTS = np.array([-1, 0, 1, 1, -1, 4, 0, 6])  # two roots, a fork, a side branch


def _tree(parents, seed=0):
    n = len(parents)
    rng = np.random.default_rng(seed)
    lengths = rng.uniform(8, 40, n)
    masses = rng.uniform(0.1, 1.0, n)
    return ChainInertia(lengths, masses, masses * lengths**2 / 12, parents=np.asarray(parents))


def _centres(chain, offsets, q):
    """Reference forward kinematics, link by link: centre and world angle of each link."""
    n = chain.count
    angle, joint, end = np.zeros(n), np.zeros((n, 2)), np.zeros((n, 2))
    for i, p in enumerate(chain.parents):
        angle[i] = q[i] + (angle[p] if p >= 0 else 0.0)
        joint[i] = end[p] if p >= 0 else offsets[i]
        end[i] = joint[i] + chain.lengths[i] * np.array([np.cos(angle[i]), np.sin(angle[i])])
    return (joint + end) / 2, angle, joint


def _virtual_work_torques(chain, offsets, q, qd, qdd, gravity):
    """Joint torques by d'Alembert's principle with finite differences: no Newton-Euler at all.

    tau_i = sum_j m_j (a_j - g) . dc_j/dq_i + I_j alpha_j dtheta_j/dq_i, with each centre's
    acceleration a_j the second difference of its path under q(t) = q + qd t + qdd t^2 / 2.
    """
    n, h, dq = chain.count, 1e-3, 1e-6
    path = [_centres(chain, offsets, q + qd * t + qdd * t * t / 2)[0] for t in (-h, 0.0, h)]
    accel = (path[0] - 2 * path[1] + path[2]) / h**2
    _, angle, _ = _centres(chain, offsets, q)
    alpha = _centres(chain, offsets, qdd)[1]  # world angular accelerations: sums along the tree
    torques = np.zeros(n)
    for i in range(n):
        step = np.zeros(n)
        step[i] = dq
        dc = (_centres(chain, offsets, q + step)[0] - _centres(chain, offsets, q - step)[0]) / (
            2 * dq
        )
        turns = (_centres(chain, offsets, q + step)[1] - angle) / dq  # 0 or 1: exact
        torques[i] = np.sum(chain.masses[:, None] * (accel - gravity) * dc)
        torques[i] += np.sum(chain.moments * alpha * np.round(turns))
    return torques, accel, angle


@pytest.mark.parametrize("parents", [Y_PARENTS, TREE_PARENTS], ids=["y", "tree"])
@pytest.mark.parametrize("seed", range(3))
def test_tree_loads_match_virtual_work_wherever_the_roots_sit(parents, seed):
    chain = _tree(parents, seed)
    n = chain.count
    rng = np.random.default_rng(10 + seed)
    q, qd, qdd = rng.uniform(-2, 2, n), rng.normal(size=n), rng.normal(size=n) * 5
    offsets = rng.uniform(-30, 30, (n, 2))  # where each root's joint sits on the still base
    gravity = np.array([0.0, -GRAVITY])
    torques, accel, angle = _virtual_work_torques(chain, offsets, q, qd, qdd, gravity)
    loads = inverse_dynamics(chain, angle, chain.along(qd), chain.along(qdd), gravity)
    np.testing.assert_allclose(loads.torques, torques, rtol=1e-6, atol=1e-3 * np.abs(torques).max())
    # The pivot at each joint carries what accelerates everything beyond it, against gravity.
    forces = chain.masses[:, None] * (accel - gravity)
    for i in range(n - 1, -1, -1):
        if parents[i] >= 0:
            forces[parents[i]] += forces[i]
    np.testing.assert_allclose(loads.forces, forces, rtol=1e-6, atol=1e-6 * np.abs(forces).max())


@pytest.mark.parametrize("parents", [None, Y_PARENTS, TREE_PARENTS], ids=["chain", "y", "tree"])
@pytest.mark.parametrize("seed", range(3))
def test_the_held_slope_is_how_each_joint_s_turn_changes_a_held_load(parents, seed):
    # Against central differences of the loads themselves: each joint turned (with all that
    # hangs from it) a little either way, the world angles it carries turned with it.
    chain = _tree(np.arange(8) - 1 if parents is None else parents, seed)
    n = chain.count
    rng = np.random.default_rng(20 + seed)
    q = rng.uniform(-2, 2, n)
    gravity = np.array([35.0, -GRAVITY])
    for joint in range(n):

        def held(turns, joint=joint):
            return Pose(chain, chain.along(turns)).loads(gravity=gravity).torques[joint]

        nudges = 1e-5 * np.eye(n)
        differences = [(held(q + d) - held(q - d)) / 2e-5 for d in nudges]
        slope = Pose(chain, chain.along(q)).held_slope(joint, gravity)
        np.testing.assert_allclose(slope, differences, rtol=1e-5, atol=1e-5 * GRAVITY)
        assert np.any(slope != 0.0)


def test_tree_inertia_is_everything_beyond_each_joint_held_rigid():
    chain = _tree(TREE_PARENTS, seed=5)
    q = np.random.default_rng(5).uniform(-2, 2, chain.count)
    centres, angle, joints = _centres(chain, np.zeros((chain.count, 2)), q)
    beyond = [{i} for i in range(chain.count)]
    for i in range(chain.count - 1, -1, -1):
        if TREE_PARENTS[i] >= 0:
            beyond[TREE_PARENTS[i]] |= beyond[i]
    expected = [
        sum(chain.moments[j] + chain.masses[j] * np.sum((centres[j] - joints[i]) ** 2) for j in b)
        for i, b in enumerate(beyond)
    ]
    np.testing.assert_allclose(Pose(chain, angle).inertia(), expected, rtol=1e-9)


def test_a_chain_given_its_parents_is_the_same_chain_to_the_last_bit():
    chain = _chain(12, seed=7)
    serial = ChainInertia(chain.lengths, chain.masses, chain.moments, parents=np.arange(12) - 1)
    rng = np.random.default_rng(7)
    angles, omega, alpha = (rng.normal(size=12) for _ in range(3))
    for a, b in [(Pose(chain, angles), Pose(serial, angles))]:
        assert np.array_equal(a.inertia(), b.inertia())
        one, other = a.loads(omega, alpha, (0.0, -900.0)), b.loads(omega, alpha, (0.0, -900.0))
        assert np.array_equal(one.torques, other.torques)
        assert np.array_equal(one.forces, other.forces)
    assert np.array_equal(serial.along(alpha), np.cumsum(alpha))
    assert np.array_equal(serial.beyond(alpha), np.cumsum(alpha[::-1])[::-1])


@pytest.mark.parametrize("parents", [None, Y_PARENTS, TREE_PARENTS], ids=["chain", "y", "tree"])
def test_the_float_path_gives_the_same_floats_as_numpy(parents):
    chain = _chain(9, seed=1) if parents is None else _tree(parents, seed=1)
    n = chain.count
    floats = FloatInertia(chain)
    rng = np.random.default_rng(3)
    for _ in range(20):
        angles, omega, alpha = (rng.normal(size=n) * 2 for _ in range(3))
        pose, fast = Pose(chain, angles), floats.pose(angles)
        assert fast.inertia() == pose.inertia().tolist()
        for kwargs in (
            {"gravity": (0.0, -900.0)},
            {"omega": omega},
            {"alpha": alpha},
            {"omega": omega, "alpha": alpha, "gravity": (3.0, -900.0)},
        ):
            loads = pose.loads(**{k: np.asarray(v) for k, v in kwargs.items()})
            torques, fx, fy = fast.loads(
                **{k: v.tolist() if isinstance(v, np.ndarray) else v for k, v in kwargs.items()}
            )
            assert torques == loads.torques.tolist()
            assert fx == loads.forces[:, 0].tolist() and fy == loads.forces[:, 1].tolist()
        assert floats.along(omega.tolist()) == chain.along(omega).tolist()
        assert floats.beyond(omega.tolist()) == chain.beyond(omega).tolist()


@pytest.mark.parametrize("parents", [[0], [-1, 1], [-2, 0], [-1, 0, 3]])
def test_parents_must_come_first(parents):
    n = len(parents)
    with pytest.raises(ValueError, match="parents"):
        ChainInertia(np.ones(n), np.ones(n), np.ones(n), parents=np.array(parents))


def _three_links_out_sideways():
    """Three 100 px links of mass 2 held out level in gravity of 2000 px/s^2: the base needs
    about 1.8e6 to hold them and has 1.2e6."""
    arm = ChainInertia(np.full(3, 100.0), np.full(3, 2.0), np.full(3, 2.0 * 100.0**2 / 12))
    pose = Pose(arm, np.zeros(3))
    limit = np.array([1.2e6, 8.0e5, 4.0e5])
    wanted = np.array([50.0, -30.0, 20.0])
    bias = pose.loads(gravity=(0.0, -2000.0))
    push = pose.loads(alpha=arm.along(wanted))
    joints = np.arange(3)

    def alone(k):
        return pose.loads(alpha=arm.along((joints == k).astype(float)))

    return arm, pose, limit, wanted, bias, push, alone


def test_a_weak_joint_gives_way_at_its_limit_and_the_others_keep_their_motion():
    # The base is overloaded by gravity. Without giving way no factor fits (coasting alone is
    # past its limit), and the others would be left to the physics engine; a weak base gives
    # way at its limit, its acceleration what that torque gives with the others' motion, and
    # the others keep theirs whole.
    arm, pose, limit, wanted, bias, push, alone = _three_links_out_sideways()
    assert abs(bias.torques[0]) > limit[0]
    plain = fit_drive(bias, push, wanted, limit)
    assert not plain.consistent
    drive = fit_drive(bias, push, wanted, limit, weak=([True, False, False], alone))
    assert drive.consistent and drive.saturated[0]
    assert drive.loads.torques[0] == pytest.approx(math.copysign(limit[0], bias.torques[0]))
    assert drive.accelerations[1:].tolist() == wanted[1:].tolist()
    assert drive.accelerations[0] < wanted[0]  # less than asked: all its torque gives
    # The loads are those of the motion: nothing left for the physics engine to reconcile.
    again = pose.loads(alpha=arm.along(drive.accelerations), gravity=(0.0, -2000.0))
    np.testing.assert_allclose(again.torques, drive.loads.torques, rtol=1e-9, atol=1e-3)
    np.testing.assert_allclose(again.forces, drive.loads.forces, rtol=1e-9, atol=1e-6)


def test_giving_way_over_floats_gives_the_same_numbers():
    arm, _, limit, wanted, bias, push, alone = _three_links_out_sideways()
    fast = FloatInertia(arm).pose(np.zeros(3))
    weak = [True, False, False]
    drive = fit_drive(bias, push, wanted, limit, weak=(weak, alone))
    reached, loads, saturated, consistent = fit_floats(
        fast.loads(gravity=(0.0, -2000.0)),
        fast.turning(wanted.tolist()),
        wanted.tolist(),
        limit.tolist(),
        weak=(weak, lambda k: fast.turning(np.eye(3)[k].tolist())),
    )
    assert list(reached) == drive.accelerations.tolist()
    assert loads[0] == drive.loads.torques.tolist()
    assert saturated == drive.saturated.tolist() and consistent


def test_a_joint_nearer_the_base_that_eases_the_one_at_its_limit_keeps_its_acceleration():
    # Four links hanging bent, the third joint held by gravity at 0.99 of its limit. The base
    # brakes, which eases that joint, and the second joint's acceleration loads it. Scaled by
    # one factor with the rest, the base's braking gave back the room it made, and the second
    # joint got 1% of its acceleration. The last joint eases it too, but by its reaction, from
    # beyond it: kept whole, such joints prop a joint up and whip the light links beyond it.
    arm = ChainInertia(np.full(4, 60.0), np.full(4, 0.8), np.full(4, 0.8 * 60.0**2 / 12))
    world = np.radians([-60.0, -30.0, -80.0, -90.0])
    pose = Pose(arm, world)
    bias = pose.loads(gravity=(0.0, -1200.0))
    limit = np.array([1e7, 1e7, abs(bias.torques[2]) / 0.99, 1e7])
    wanted = np.array([-0.4, 2.0, 0.0, -1.0])
    push = pose.loads(alpha=arm.along(wanted))

    def turning(accelerations):
        return pose.loads(alpha=arm.along(accelerations))

    def unit(k):
        return turning(np.eye(4)[k])

    eases = unit(2).torques * wanted * np.sign(bias.torques[2] + push.torques[2]) < 0.0
    assert eases.tolist() == [True, False, False, True]
    one = fit_drive(bias, push, wanted, limit)
    scale = one.accelerations[1] / wanted[1]
    assert scale < 0.02 and one.accelerations[0] == pytest.approx(scale * wanted[0])
    drive = fit_drive(bias, push, wanted, limit, turning=turning)
    assert drive.consistent and drive.saturated.tolist() == [False, False, True, False]
    assert drive.accelerations[0] == wanted[0]
    factor = drive.accelerations[1] / wanted[1]
    assert factor > 10 * scale
    assert drive.accelerations[3] / wanted[3] == pytest.approx(factor)
    assert np.all(np.abs(drive.loads.torques) <= limit * (1 + 1e-9))
    again = pose.loads(alpha=arm.along(drive.accelerations), gravity=(0.0, -1200.0))
    np.testing.assert_allclose(again.torques, drive.loads.torques, rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(again.forces, drive.loads.forces, rtol=1e-9, atol=1e-6)
    # The float path keeps the same acceleration whole, to the last bit.
    fast = FloatInertia(arm).pose(world)
    reached, loads, saturated, consistent = fit_floats(
        fast.loads(gravity=(0.0, -1200.0)),
        fast.turning(wanted.tolist()),
        wanted.tolist(),
        limit.tolist(),
        turning=fast.turning,
    )
    assert list(reached) == drive.accelerations.tolist()
    assert loads[0] == drive.loads.torques.tolist()
    assert saturated == drive.saturated.tolist() and consistent
    # Held at 0.4 of a larger limit, with the motion itself overloading it, that joint keeps
    # the one factor: the motion's direction.
    limit[2] = abs(bias.torques[2]) / 0.4
    harder = pose.loads(alpha=arm.along(3.0 * wanted))
    one = fit_drive(bias, harder, 3.0 * wanted, limit)
    assert one.saturated[2] and one.accelerations[0] > 3.0 * wanted[0]
    drive = fit_drive(bias, harder, 3.0 * wanted, limit, turning=turning)
    assert drive.accelerations.tolist() == one.accelerations.tolist()
