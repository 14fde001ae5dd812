"""The servo in the physics world: long chains settle, saturated arms rest, stretched arms brake."""

import math
from collections.abc import Callable

import numpy as np
import pytest

from ikgame.control import _floats, dynamics
from ikgame.control._floats import FloatInertia
from ikgame.control.dynamics import ChainInertia, Pose
from ikgame.control.servo import BRAKE_FLOOR, BRAKE_SHARE, Servo, ServoCommand
from ikgame.kinematics import forward_kinematics
from ikgame.level.model import Level
from ikgame.physics.world import build_skeleton
from ikgame.sim import Simulation


def _level(links, script, *, gravity=(0.0, -900.0), duration=10.0, **chain):
    return Level.model_validate(
        {
            "level": {"name": "servo", "duration": duration},
            "world": {"gravity": list(gravity)},
            "chain": {"angle": 90.0, "links": links, **chain},
            "script": script,
        }
    )


def _tip_track(sim, seconds):
    tips = []
    for _ in range(round(seconds / sim.dt)):
        sim.step()
        tips.append(sim.joint_positions()[-1].copy())
    return np.array(tips)


def test_a_thirty_link_chain_under_gravity_reaches_and_settles():
    link = {"length": 12.0, "mass": 0.2, "limits": [-120.0, 120.0], "max_torque": 4.0e6}
    level = _level([{**link, "repeat": 30}], [{"wait": 10.0}], iterations=12)
    rng = np.random.default_rng(7)
    pose = rng.uniform(-0.25, 0.25, 30)
    target = forward_kinematics(build_skeleton(level), pose)[0][-1]
    sim = Simulation(level, record=False)
    sim.target = target
    tips = _tip_track(sim, 4.0)
    last = tips[-round(0.5 / sim.dt) :]
    assert np.hypot(*(last[-1] - target)) < 1.0
    assert np.ptp(last, axis=0).max() < 0.5  # at rest, not writhing


def test_a_torque_saturated_arm_comes_to_rest_then_reaches_what_it_can():
    weak = {"length": 100.0, "mass": 2.0, "max_torque": 6.0e5, "max_speed": 180.0}
    level = _level([weak, {**weak, "max_torque": 5.0e5}], [{"wait": 20.0}], gravity=(0, -2000))
    sim = Simulation(level, record=False)
    sim.target = (200.0, 0.0)  # straight out sideways: more torque than the base has
    tips = _tip_track(sim, 5.0)
    last = tips[-round(0.5 / sim.dt) :]
    assert np.ptp(last, axis=0).max() < 1.0  # resting where its torque runs out, not swinging
    assert sim.last_tick.solver_status == "blocked"  # and saying that it cannot get there
    sim.target = (-60.0, -150.0)  # hanging below the base: within the torque budget
    tips = _tip_track(sim, 4.0)
    assert np.hypot(*(tips[-1] - (-60.0, -150.0))) < 1.0


def _hanging_arm(spec: list[tuple[float, float, float]], solver: str) -> Simulation:
    """Links of (length px, mass, max_torque) hanging straight down in gravity of 1500 px/s^2,
    limits +-160 deg, 150 deg/s."""
    links = [
        {"length": length, "mass": mass, "max_torque": torque, "limits": [-160.0, 160.0]}
        for length, mass, torque in spec
    ]
    links = [{**link, "max_speed": 150.0} for link in links]
    level = _level(links, [{"wait": 20.0}], gravity=(0, -1500), solver=solver)
    level = level.model_copy(update={"chain": level.chain.model_copy(update={"angle": -90.0})})
    return Simulation(level, record=False)


@pytest.mark.parametrize("solver", ["ccd", "fabrik"])
def test_three_weak_links_come_to_rest_where_their_torque_runs_out(solver):
    # Out nearly level, the base needs about 7e5 and has 6e5. The servo once propped the base
    # up with the outer joints' accelerations every other tick (it sagged at two thirds of its
    # torque), and its torque alternated between the limit and just under it from tick to tick,
    # so the anti-windup never saw it stall: the arm swung 28-48 px for good.
    sim = _hanging_arm([(110.0, 1.5, 6.0e5), (100.0, 1.2, 3.0e5), (80.0, 1.0, 1.5e5)], solver)
    sim.target = (270.0, -40.0)
    last = _tip_track(sim, 5.0)[-round(0.5 / sim.dt) :]
    assert np.ptp(last, axis=0).max() < 1.0


@pytest.mark.parametrize("solver", ["dls", "fabrik"])
def test_five_weak_links_come_to_rest_and_report_failure(solver):
    # Out just below the base, the base needs about 6.9e5 and has 6e5; the motors weaken
    # toward the tip. A joint gravity overloaded, braking or sagging at its limit, never
    # stalled and set the one acceleration factor of the whole chain, so the base could not
    # brake: the arm swung 109 px (DLS) and 86 px (FABRIK) for good, reporting success far
    # from the target. Then it sagged to rest at its torque limits, `blocked`; now it rests
    # in the pose nearest the target that the motors hold, a failure like a target out of
    # reach.
    spec = [(60.0, 1.0, 6.0e5), (60.0, 1.0, 4.0e5), (60.0, 1.0, 2.5e5), (50.0, 0.8, 1.2e5)]
    sim = _hanging_arm([*spec, (50.0, 0.6, 3.0e4)], solver)
    sim.target = (252.0, -40.0)
    last = _tip_track(sim, 5.5)[-round(0.5 / sim.dt) :]
    assert np.ptp(last, axis=0).max() < 1.0
    assert sim.last_tick.solver_status == "failure"
    assert sim.controller.solver.strain(sim.joint_angles()) < 1.0


def test_a_stretched_arm_brakes_in_time():
    link = {"length": 100.0, "mass": 1.0, "max_torque": 3.0e6, "max_speed": 360.0}
    level = _level([{**link, "repeat": 3}], [{"wait": 10.0}], angle=0.0, solver="dls")
    sim = Simulation(level, record=False)
    target = np.array([0.0, 300.0])  # full reach, straight up from straight out
    start = sim.joint_positions()[-1].copy()
    sim.target = target
    tips = _tip_track(sim, 4.0)
    approach = (target - start) / np.linalg.norm(target - start)
    past = float(np.max((tips - target) @ approach))
    assert past <= 0.05 * np.linalg.norm(target - start)
    assert np.hypot(*(tips[-1] - target)) < 1.0


def test_a_weak_joint_lowering_an_arm_brakes_for_the_load_it_meets_on_the_way(stress_simulation):
    # Four links in gravity of 1900 px/s^2, CCD, the third target (190, 140): lowering the
    # arm out to the right, the load on the weak second joint grows from 0.14 of its limit
    # where it begins to brake to 0.86 at the goal. Its stop planned on the room it had where
    # it began, the joint came in at 23 deg/s and the tip ran on 32 px past.
    sim = stress_simulation("61_heavy_gravity_weak_motors", "ccd")
    while sim.script.step_index < 2:
        sim.step()
    start, target = sim.joint_positions()[-1].copy(), np.array(sim.target)
    tips = []
    while sim.script.step_index < 3:
        sim.step()
        tips.append(sim.joint_positions()[-1].copy())
    approach = np.linalg.norm(target - start)
    past = float(np.max((np.array(tips) - target) @ ((target - start) / approach)))
    assert sim.script.outcomes[2].reached
    assert past <= 0.05 * approach


@pytest.mark.parametrize("solver", ["fabrik", "dls"])
def test_joints_brought_in_together_wait_for_a_base_the_arm_s_weight_nearly_spends(
    solver, stress_simulation
):
    # Three links in gravity of 2700 px/s^2, from (190, 150) on the right to (-200, 150) on
    # the left, over the top: holding the arm out to the right takes 0.92 of the base's torque,
    # and the straight line in joint space to the answer lifts it through poses the motors hold.
    # Paced by their own speeds, the light far joints unfolded while the base could not yet
    # lift, the arm grew longer than the base could hold, and it lay on the floor `blocked`.
    sim = stress_simulation("69_heavy_gravity_weak_three", solver)
    while sim.script.step_index < 3:
        sim.step()
    assert sim.script.outcomes[2].reached


@pytest.mark.parametrize("tick_rate", [120, 480])
def test_long_chain_timing_does_not_depend_on_the_tick_rate(tick_rate):
    def time_to_reach(rate):
        link = {"length": 12.0, "mass": 0.2, "limits": [-120.0, 120.0], "max_torque": 4.0e6}
        level = Level.model_validate(
            {
                "level": {"name": "rate", "duration": 6.0},
                "world": {"tick_rate": rate},
                "chain": {"angle": 90.0, "links": [{**link, "repeat": 30}]},
                "script": [{"reach": [150.0, 250.0], "timeout": 5.0}],
            }
        )
        outcome = Simulation(level, record=False).run().steps[0]
        assert outcome.reached
        return outcome.time_to_reach

    reference = time_to_reach(240)
    assert time_to_reach(tick_rate) == pytest.approx(reference, rel=0.15)
    assert math.isfinite(reference)


def _random_links(rng, n, parents):
    """``n`` links of random lengths and masses, as rods, in a chain or on ``parents``."""
    lengths, masses = rng.uniform(10, 60, n), rng.uniform(0.2, 2.0, n)
    return ChainInertia(
        lengths,
        masses,
        masses * lengths**2 / 12,
        parents=None if parents is None else np.array(parents),
    )


def _random_servo(rng: np.random.Generator, n: int) -> tuple[ChainInertia, Servo]:
    """A random chain of ``n`` links (see :func:`_random_links`) and a servo for it."""
    inertia = _random_links(rng, n, None)
    servo = Servo(
        inertia, max_torque=rng.uniform(2e4, 2e5, n), max_speed=np.full(n, 3.0), gain=12.0
    )
    return inertia, servo


@pytest.mark.parametrize("together", [False, True], ids=["each", "together"])
@pytest.mark.parametrize("sections", [False, True], ids=["one-factor", "sections"])
@pytest.mark.parametrize("parents", [None, [-1, 0, 0, 2, -1, 4]], ids=["chain", "tree"])
def test_the_float_servo_commands_what_the_numpy_servo_does(parents, sections, together):
    n = 6
    rng = np.random.default_rng(11)
    inertia = _random_links(rng, n, parents)
    limits = dict(max_torque=rng.uniform(2e4, 2e5, n), max_speed=np.full(n, 3.0), gain=12.0)
    fast, slow = Servo(inertia, **limits), Servo(inertia, **limits)
    slow._floats = None  # the numpy path, as chains longer than FLOAT_LINKS take
    # Both ways of fitting the torque limits, whichever a chain of this length would take.
    fast._sections = slow._sections = sections
    for tick in range(200):
        error = rng.normal(size=n) * (0.05 if tick % 3 else 1.0)
        angles, velocities = rng.uniform(-3, 3, n), rng.normal(size=n) * 2
        goal = None if tick % 2 else rng.normal(size=n)
        one = fast.command(
            error, angles, velocities, (0.0, -900.0), 1 / 240, goal, together=together
        )
        other = slow.command(
            error, angles, velocities, (0.0, -900.0), 1 / 240, goal, together=together
        )
        for field in ("rates", "torques", "forces", "budgets"):
            assert np.array_equal(getattr(one, field), getattr(other, field)), (tick, field)
        assert np.array_equal(fast.stalled, slow.stalled)


@pytest.mark.parametrize("n", [5, 40], ids=["floats", "numpy"])
def test_the_strain_slope_is_how_the_strain_changes_as_each_joint_turns(n):
    # Against central differences of the strain itself (over floats up to FLOAT_LINKS, over
    # numpy beyond), at poses where one joint strains clearly most.
    rng = np.random.default_rng(n)
    inertia, servo = _random_servo(rng, n)
    gravity = (20.0, -900.0)
    checked = 0
    for _ in range(8):
        turns = rng.uniform(-1.5, 1.5, n)
        shares = np.abs(Pose(inertia, inertia.along(turns)).loads(gravity=gravity).torques)
        shares = np.sort(shares / servo.max_torque)
        if shares[-1] - shares[-2] < 0.05:
            continue  # the largest is a corner of the strain: no one slope there
        nudges = 1e-6 * np.eye(n)
        differences = [
            (
                servo.strain(inertia.along(turns + d), gravity)
                - servo.strain(inertia.along(turns - d), gravity)
            )
            / 2e-6
            for d in nudges
        ]
        slope = servo.strain_slope(inertia.along(turns), gravity)
        np.testing.assert_allclose(slope, differences, rtol=1e-4, atol=1e-6)
        checked += 1
    assert checked >= 4


def _strain_the_base(floats, goal_side, gravity):
    """A two-link servo whose outer joint's big move needs more torque at the base than it
    has, for 0.17 s (beyond STALL_TIME): the base sits at its limit, the torque pointing the
    negative way, and drifts off the ``goal_side`` faster and faster. Returns the servo."""
    lengths, masses = np.array([40.0, 40.0]), np.array([1.0, 1.0])
    inertia = ChainInertia(lengths, masses, masses * lengths**2 / 12)
    servo = Servo(
        inertia, max_torque=np.array([2.0e3, 1.0e6]), max_speed=np.full(2, 20.0), gain=12.0
    )
    if not floats:
        servo._floats = None  # the numpy path, as chains longer than FLOAT_LINKS take
    for tick in range(40):
        error = np.array([0.05 * goal_side, -2.0])
        velocities = np.array([-goal_side * (0.1 + 0.05 * tick), 0.0])  # away, faster and faster
        command = servo.command(error, np.array([0.3, 0.5]), velocities, gravity, 1 / 240)
        assert command.torques[0] == pytest.approx(-2.0e3)
    return servo


@pytest.mark.parametrize("floats", [True, False], ids=["floats", "numpy"])
@pytest.mark.parametrize("toward", [True, False], ids=["toward-goal", "away-from-goal"])
def test_only_a_joint_at_its_limit_toward_its_goal_stalls(floats, toward):
    # Gravity pulls the base off its goal, with 75% of its torque limit. With the goal on the
    # side its torque points, the base pushes for it at its limit and cannot hold: it stalls.
    # With the goal on the other side, its own motor carries it off: no stall. Counted as one,
    # a joint of twenty links reaching low gave up its goal for good (FABRIK's chain ended
    # blocked 24 px short of the last target of the stress level).
    goal_side = -1.0 if toward else 1.0  # the base's torque points the negative way
    servo = _strain_the_base(floats, goal_side, (0.0, -20.0 * goal_side))
    assert servo.stalled.tolist() == [toward, False]


@pytest.mark.parametrize("floats", [True, False], ids=["floats", "numpy"])
def test_a_joint_the_chain_s_motion_carries_off_does_not_stall(floats):
    # No gravity: only the outer joint's move carries the base off its goal, and that passes.
    # Counted as a stall, the base of 200 links gave its goal up mid-swing and came to rest
    # 6.7 deg short of it with a sixth of its torque holding it there (CCD's chain ended
    # blocked 37 px short of the stress level's second target).
    servo = _strain_the_base(floats, -1.0, (0.0, 0.0))
    assert servo.stalled.tolist() == [False, False]


def _sagging_link(floats: bool) -> tuple[Servo, Callable[[float], ServoCommand]]:
    """One link held out level, needing 2e4 against gravity where its motor has 1.5e4, and
    sagging at a steady 0.1 rad/s: its servo, and a tick of it for an angle error (rad)."""
    one = ChainInertia(np.array([40.0]), np.array([1.0]), np.array([1600.0 / 12.0]))
    servo = Servo(one, max_torque=np.array([1.5e4]), max_speed=np.array([3.0]), gain=12.0)
    if not floats:
        servo._floats = None  # the numpy path, as chains longer than FLOAT_LINKS take

    def tick(error: float) -> ServoCommand:
        return servo.command(
            np.array([error]), np.zeros(1), np.array([-0.1]), (0.0, -1000.0), 1 / 240
        )

    return servo, tick


@pytest.mark.parametrize("floats", [True, False], ids=["floats", "numpy"])
def test_a_joint_gravity_overloads_stalls_while_it_sags_at_a_steady_speed(floats):
    # Held out level, the link pushes for its goal above at its limit and sags at a steady
    # 0.1 rad/s. A stall once needed the joint to be carried off faster and faster, so it
    # never stalled and, at its limit, went on setting the chain's one acceleration factor:
    # the arms of 29_five_weak_links swung.
    servo, tick = _sagging_link(floats)
    for _ in range(40):  # 0.17 s, past STALL_TIME
        assert tick(0.5).torques[0] == pytest.approx(1.5e4)
    assert servo.stalled.tolist() == [True]


@pytest.mark.parametrize("floats", [True, False], ids=["floats", "numpy"])
def test_a_stall_ends_when_the_goal_comes_to_lie_the_other_way(floats):
    # Stalled pushing up for a goal above, the link is given a goal below (a new answer for
    # the same target): gravity now helps it there. Kept stalled, a joint of five weak links
    # did not fold toward a new answer and the base lifted the arm unfolded, until it fell.
    servo, tick = _sagging_link(floats)
    for _ in range(41):
        tick(0.5)
    assert servo.stalled.tolist() == [True]  # the goal still above
    command = tick(-0.5)
    assert servo.stalled.tolist() == [False]
    assert command.rates[0] < -0.1  # heading for it


def test_four_weak_links_reach_out_in_a_pose_their_motors_hold():
    # The first target of 30_four_weak_links: CCD's answer asked the second joint for 1.07 to
    # 1.11 of its torque; the joint gave way and the arm fell 220 px below the target (later,
    # switched to a pose it could hold only once the tip was already there, it swung 57 px
    # away and back). The solver now looks for a pose within every motor's torque.
    spec = [(80.0, 1.0, 8.0e5), (80.0, 1.0, 4.0e5), (70.0, 1.0, 2.0e5), (60.0, 0.8, 6.0e4)]
    sim = _hanging_arm(spec, "ccd")
    target = np.array([261.0, -40.0])
    start = sim.joint_positions()[-1].copy()
    sim.target = target
    tips = _tip_track(sim, 4.0)
    approach = (target - start) / np.linalg.norm(target - start)
    assert float(np.max((tips - target) @ approach)) <= 0.05 * np.linalg.norm(target - start)
    last = tips[-round(0.5 / sim.dt) :]
    assert np.hypot(*(last[-1] - target)) < 6.0
    assert np.ptp(last, axis=0).max() < 0.5


def test_two_hundred_links_swing_over_to_the_other_side_within_their_limits():
    # The longest chain the format allows, under gravity (as the 200-link stress level, with
    # shorter holds): the second target is on the other side of the base. The base runs out of
    # torque for the whole chain's wanted motion on most ticks of the swing; scaled by one
    # factor with it, every joint got a few percent of its wanted acceleration, and CCD's chain
    # fell on past the target into its limits (46 deg past them), never reaching it. On the
    # swing the base pushed for its goal at its limit while the chain beyond carried it off,
    # which the anti-windup once took for a stall: the chain ended blocked 37 px short.
    level = Level.model_validate(
        {
            "level": {"name": "200 links", "duration": 6.0},
            "world": {"gravity": [0.0, -900.0]},
            "chain": {
                "angle": 90.0,
                "links": [
                    {
                        "length": 2.0,
                        "mass": 0.05,
                        "width": 3.0,
                        "limits": [-120.0, 120.0],
                        "max_torque": 4.0e6,
                        "repeat": 200,
                    }
                ],
            },
            "obstacles": [{"kind": "segment", "a": [-500.0, -20.0], "b": [500.0, -20.0]}],
            "script": [
                {"sequence": [[220.0, 200.0], [-180.0, 260.0]], "hold": 0.2, "timeout": 5.0}
            ],
        }
    )
    sim = Simulation(level, solver="ccd", record=False)
    limit = math.radians(120.0)
    worst = 0.0
    while len(sim.script.outcomes) < 2 and not sim.done:
        sim.step()
        worst = max(worst, float(np.max(np.abs(sim.joint_angles()))) - limit)
    assert [outcome.reached for outcome in sim.script.outcomes] == [True, True]
    assert math.degrees(worst) < 2.0


@pytest.mark.parametrize("parents", [None, [-1, 0, 0, 2, -1, 4]], ids=["chain", "tree"])
def test_loads_the_servo_skips_are_within_half_the_smallest_room(parents):
    # The servo leaves out the loads of braking and spinning when a bound says they fit: that
    # bound must hold (here with the room's floor halved, the margin it keeps), for any pose.
    n = 6
    rng = np.random.default_rng(7)
    inertia = _random_links(rng, n, parents)
    limits = rng.uniform(2e4, 2e5, n)
    servo = Servo(inertia, max_torque=limits, max_speed=np.full(n, 3.0), gain=12.0)
    quiet, floats = servo._quiet, FloatInertia(inertia)
    room = 0.5 * BRAKE_FLOOR * limits  # the least either share gives
    skipped = [0, 0]
    for _ in range(400):
        pose = floats.pose(rng.uniform(-3, 3, n))
        scale = 10.0 ** rng.uniform(-3, 1)
        rates = (rng.normal(size=n) * scale).tolist()
        if quiet.spins(sum(abs(r) for r in rates)):
            skipped[0] += 1
            torques = np.array(pose.loads(omega=floats.along(rates))[0])
            assert np.all(np.abs(torques) <= room / 2)
        accelerations = (rng.normal(size=n) * scale).tolist()
        if quiet.brakes(sum(abs(a) for a in accelerations)):
            skipped[1] += 1
            torques = np.array(pose.loads(alpha=floats.along(accelerations))[0])
            assert np.all(np.abs(torques) <= room / 2)
    assert min(skipped) > 20 and max(skipped) < 380  # both ways taken


@pytest.mark.parametrize("floats", [True, False], ids=["floats", "numpy"])
def test_a_goal_on_a_planned_way_keeps_the_motion_s_direction(floats, monkeypatch):
    # Four links hanging bent, the third joint held by gravity at 0.99 of its limit: the
    # motion sets the one factor there, and the base's acceleration, which eases that joint,
    # would be kept whole. On a way planned round obstacles only the lines were checked clear,
    # so a steered goal keeps one factor for all: what the servo commands with no easing.
    arm = ChainInertia(np.full(4, 60.0), np.full(4, 0.8), np.full(4, 0.8 * 60.0**2 / 12))
    world = np.radians([-60.0, -30.0, -80.0, -90.0])
    held = abs(Pose(arm, world).loads(gravity=(0.0, -1200.0)).torques[2])
    limit = np.array([1e7, 1e7, held / 0.99, 1e7])
    error, velocities = np.array([0.23, -0.39, -0.11, 0.02]), np.array([-0.3, 0.3, 1.0, 1.8])

    def rates(**steered):
        servo = Servo(arm, max_torque=limit, max_speed=np.full(4, 5.0), gain=12.0)
        if not floats:
            servo._floats = None  # the numpy path, as chains longer than FLOAT_LINKS take
        return servo.command(error, world, velocities, (0.0, -1200.0), 1 / 240, **steered).rates

    eased, steered = rates(), rates(steered=True)
    monkeypatch.setattr(dynamics, "ease", lambda *args: None)
    monkeypatch.setattr(_floats, "ease", lambda *args: None)
    assert steered.tolist() == rates().tolist()
    assert abs(eased[0] - velocities[0]) > 10 * abs(steered[0] - velocities[0])


# Twenty 15 px links of 35_twenty_links_under_shelf, folded back under the shelf, 60 ms before
# DLS's tip reached the third target: the base turns toward its goal, 3.7 deg off, at
# 1.21 rad/s, and the joints beyond it swing on (joint angles in degrees, errors in degrees,
# rates in rad/s, as measured).
_FOLDED = [-97, -10, 10, 19, 21, 15, 3, -4, -14, -27, -37, -37, -18, 12, 49, 59, 72, 46, 25, 11]
_FOLDED_ERRORS = [3.7, 3.3, 3.0, 2.7, 2.2, 1.7, 1.2, 0.7, 0.2, -0.3]
_FOLDED_ERRORS += [-0.7, -0.8, -0.6, -0.2, 0.1, -0.1, -0.6, -0.9, -0.7, -0.4]
_FOLDED_RATES = [1.21, 0.83, 0.74, 0.6, 0.37, 0.05, -0.3, -0.65, -1.0, -1.27]
_FOLDED_RATES += [-1.4, -1.31, -1.05, -0.76, -0.58, -0.64, -0.81, -0.76, -0.5, -0.2]


@pytest.mark.parametrize("floats", [True, False], ids=["floats", "numpy"])
@pytest.mark.parametrize("toward", [True, False], ids=["toward-goal", "away-from-goal"])
def test_motors_beyond_a_base_the_others_braking_carries_on_add_no_torque(floats, toward):
    # The motion wanted of the chain, the far joints' braking with the base's own, takes 6
    # times the base's limit the way it turns: at its limit, and asking to brake with all it
    # has, the base is carried on toward its goal. The far motors, correcting their rates with
    # their spare torque, pushed it on further: it sped up to 2.8 rad/s and stopped 2.1 deg
    # past its goal (the tip 10% of the approach past the target). With its goal behind it the
    # base is turning back, which is no overrun: the far motors keep their budgets.
    link = {"length": 15.0, "mass": 0.3, "limits": [-120.0, 120.0], "max_torque": 4.0e6}
    servo = Simulation(_level([{**link, "repeat": 20}], [{"wait": 1.0}]), record=False)
    servo = servo.controller.servo
    if not floats:
        servo._floats = None  # the numpy path, as chains longer than FLOAT_LINKS take
    world = np.radians(90.0 + np.cumsum(_FOLDED))
    error = np.radians(_FOLDED_ERRORS) * (1.0 if toward else -1.0)
    command = servo.command(error, world, np.array(_FOLDED_RATES), (0.0, -900.0), 1 / 240)
    if toward:
        assert command.torques[0] == pytest.approx(4.0e6)  # at its limit, the way it turns
        assert command.budgets[1:].tolist() == [0.0] * 19
    else:
        assert command.budgets[1:].min() > 1.0e5


@pytest.mark.parametrize("floats", [True, False], ids=["floats", "numpy"])
def test_joints_brought_in_together_close_their_errors_in_the_same_time(floats):
    # Three links at rest in zero gravity, far from their goal: each joint alone would close
    # at its own speed limit (the last, light and fast, first); together each closes its error
    # in the time the slowest needs, so the velocities asked for keep the errors' proportions.
    arm = ChainInertia(np.full(3, 60.0), np.full(3, 0.5), np.full(3, 0.5 * 60.0**2 / 12))
    servo = Servo(arm, max_torque=np.full(3, 1e9), max_speed=np.array([1.0, 2.0, 4.0]), gain=12.0)
    if not floats:
        servo._floats = None  # the numpy path, as chains longer than FLOAT_LINKS take
    error = np.array([1.0, -1.5, 2.0])
    for _ in range(240):
        drive = servo.command(error, np.zeros(3), np.zeros(3), (0.0, 0.0), 1 / 240, together=True)
        error = error - drive.rates / 240
    # The base at its 1 rad/s, the others at its pace: their errors stay in proportion.
    assert np.allclose(error / np.array([1.0, -1.5, 2.0]), error[0], rtol=1e-6)
    assert 0.0 < error[0] < 0.1


@pytest.mark.parametrize("links", [1, 4, 40])
def test_the_most_strain_bounds_every_pose_and_is_met_stretched_out_with_point_masses(links):
    # Random chains (seeded), many of them more than FLOAT_LINKS long: no pose asks more of
    # the motors than the bound, and the chain stretched out level asks at least half of it
    # (its centres lie half a link short of the ends the bound puts the weight at).
    rng = np.random.default_rng(links)
    lengths = rng.uniform(20.0, 90.0, links)
    masses = rng.uniform(0.2, 2.0, links)
    inertia = ChainInertia(lengths, masses, masses * lengths**2 / 12.0)
    servo = Servo(
        inertia,
        max_torque=rng.uniform(1e4, 1e6, links),
        max_speed=np.ones(links),
        gain=12.0,
    )
    gravity = (0.0, -1300.0)
    most = servo.most_strain(gravity)
    poses = rng.uniform(-math.pi, math.pi, (200, links))
    assert max(servo.strain(np.cumsum(pose), gravity) for pose in poses) <= most
    assert servo.strain(np.zeros(links), gravity) >= 0.5 * most
    assert servo.most_strain((0.0, 0.0)) == 0.0


@pytest.mark.parametrize("n", [5, 40], ids=["floats", "numpy"])
def test_braking_is_half_the_torque_left_against_the_motion_over_the_inertia(n):
    rng = np.random.default_rng(n)
    inertia, servo = _random_servo(rng, n)
    gravity = (0.0, -900.0)
    for _ in range(5):
        angles, velocities = inertia.along(rng.uniform(-2, 2, n)), rng.normal(size=n)
        pose = Pose(inertia, angles)
        held = pose.loads(gravity=gravity).torques
        # Stopping a joint turning up takes torque down, which its load adds to or eats into.
        left = np.where(velocities > 0, servo.max_torque + held, servo.max_torque - held)
        left = np.maximum(left, BRAKE_FLOOR * servo.max_torque)
        expected = BRAKE_SHARE * left / pose.inertia()
        np.testing.assert_allclose(servo.braking(angles, velocities, gravity), expected)
    # Level, a link rising stops sooner than one falling: its weight helps.
    one = Servo(
        _random_links(rng, 1, None), max_torque=np.array([5e4]), max_speed=np.ones(1), gain=12.0
    )
    rising = one.braking(np.zeros(1), np.ones(1), gravity)
    falling = one.braking(np.zeros(1), -np.ones(1), gravity)
    assert rising[0] > falling[0]
