"""The pymunk world: motor sign, joint reads, limits, collisions, divergence."""

import math
from pathlib import Path

import numpy as np
import pymunk
import pytest

from ikgame.kinematics import forward_kinematics
from ikgame.level.loader import load_level
from ikgame.level.model import Level
from ikgame.physics.world import (
    FLOAT_LINKS,
    MAX_STEP_S,
    SWEEP_LINKS,
    World,
    _Stops,
    build_skeleton,
)
from ikgame.sim import Simulation

LEVELS = Path(__file__).parents[2] / "levels"


def _level(links, *, gravity=(0.0, 0.0), obstacles=(), angle=90.0, base=(0.0, 0.0)) -> Level:
    return Level.model_validate(
        {
            "level": {"name": "test", "duration": 5.0},
            "world": {"gravity": list(gravity), "damping": 1.0},
            "chain": {"base": list(base), "angle": angle, "links": links},
            "obstacles": list(obstacles),
            "script": [{"wait": 1.0}],
        }
    )


def test_initial_pose_matches_forward_kinematics():
    level = _level([{"length": 100.0}, {"length": 50.0, "limits": [20.0, 90.0]}], base=(10, 20))
    world = World(level)
    angles = world.joint_angles()
    assert angles == pytest.approx([0.0, math.radians(20.0)])
    points, _ = forward_kinematics(build_skeleton(level), angles)
    assert world.joint_positions() == pytest.approx(points)
    assert world.end_effector() == pytest.approx(points[-1])


def test_motor_rate_turns_the_child_counterclockwise_relative_to_the_parent():
    # pymunk's SimpleMotor drives b.w - a.w toward -rate; set_rates must hide that sign.
    world = World(_level([{"length": 100.0}, {"length": 100.0}]))
    world.set_rates(np.array([0.0, 1.0]))
    for _ in range(60):
        world.step(1 / 60)
    assert world.joint_velocities()[1] == pytest.approx(1.0, rel=1e-3)
    # One space step of lag (a 1/60 s tick is four of MAX_STEP_S): the first integrates the
    # position before the motor has acted.
    assert world.joint_angles()[1] == pytest.approx(1.0 - MAX_STEP_S, rel=1e-3)
    assert world.joint_angles()[0] == pytest.approx(0.0, abs=1e-3)


def test_raw_simple_motor_sign_is_what_the_world_compensates():
    space = pymunk.Space()
    a = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
    b = pymunk.Body(1.0, 10.0)
    motor = pymunk.SimpleMotor(a, b, 2.0)
    space.add(a, b, motor)
    space.step(0.01)
    assert b.angular_velocity == pytest.approx(-2.0)


def test_a_tick_longer_than_the_longest_space_step_is_stepped_in_parts():
    # Three limited links under gravity, driven by the same motor rates and joint torques
    # every tick, the last into its stop: at 120 ticks/s each tick is two steps of MAX_STEP_S
    # with the tick's loads in both, so the chain moves exactly as at 240 ticks/s. In one step
    # of 1/120 s a tick, it ended 0.2 deg elsewhere.
    links = [{"length": 60.0, "mass": 1.0, "limits": [-90.0, 90.0], "max_torque": 3e5}] * 3

    rates, torques = np.array([0.5, -1.0, 2.0]), np.array([2e4, 0.0, -5e3])

    def run(tick: float) -> np.ndarray:
        world = World(_level(links, gravity=(0.0, -900.0), angle=20.0))
        for _ in range(round(1.0 / tick)):
            world.drive(rates, torques, np.zeros((3, 2)), np.full(3, 2e5))
            world.step(tick)
        return world.joint_angles()

    assert MAX_STEP_S == 1 / 240
    assert run(1 / 120).tolist() == run(1 / 240).tolist()
    still = World(_level(links, gravity=(0.0, -900.0), angle=20.0))
    before = still.joint_angles()
    still.step(0.0)  # no time, no step
    assert still.joint_angles().tolist() == before.tolist()


def test_rotary_limit_holds_a_joint_driven_past_it():
    world = World(_level([{"length": 100.0}, {"length": 100.0, "limits": [-30.0, 30.0]}]))
    world.set_rates(np.array([0.0, 3.0]))
    for _ in range(240):
        world.step(1 / 240)
    assert world.joint_angles()[1] <= math.radians(30.0) + math.radians(1.0)


def test_torque_limit_is_reported_when_gravity_wins():
    level = _level(
        [{"length": 200.0, "mass": 5.0, "max_torque": 1000.0}], gravity=(0, -900), angle=0.0
    )
    world = World(level)
    world.set_rates(np.zeros(1))
    world.step(1 / 240)
    assert world.torque_limited().tolist() == [True]
    assert world.motor_torques()[0] == pytest.approx(1000.0, rel=1e-6)


def test_chain_links_do_not_collide_with_each_other_but_hit_obstacles():
    level = _level(
        [{"length": 100.0, "max_torque": 1.0}],
        gravity=(0, -900),
        angle=0.0,
        obstacles=[{"kind": "segment", "a": [50, -40], "b": [150, -40], "radius": 2}],
    )
    world = World(level)
    for _ in range(480):
        world.step(1 / 240)
    # The link swings down and rests on the obstacle instead of hanging straight down.
    assert world.end_effector()[1] > -60.0


def test_divergence_is_detected():
    world = World(_level([{"length": 100.0}]))
    assert not world.diverged()
    world.bodies[0].position = (math.nan, 0.0)
    assert world.diverged()


def test_base_joint_limit_is_relative_to_the_mount_direction():
    level = _level([{"length": 100.0, "limits": [-20.0, 20.0]}], angle=90.0)
    world = World(level)
    world.set_rates(np.array([-3.0]))
    for _ in range(240):
        world.step(1 / 240)
    assert world.joint_angles()[0] == pytest.approx(math.radians(-20.0), abs=math.radians(1.0))


def test_a_prop_blowing_up_counts_as_divergence():
    level = Level.model_validate(
        {
            "level": {"name": "t", "duration": 1.0},
            "chain": {"links": [{"length": 50.0}]},
            "props": [{"kind": "ball", "name": "b", "position": [80, 0], "radius": 5}],
            "script": [{"wait": 1.0}],
        }
    )
    world = World(level)
    assert not world.diverged()
    world.prop_bodies[0].position = (math.inf, 0.0)
    assert world.diverged()


def test_a_short_chain_gets_the_loads_over_floats_that_numpy_gives(monkeypatch):
    world = World(_level([{"length": 40.0, "repeat": 6}], gravity=(0.0, -900.0)))
    rng = np.random.default_rng(4)
    for _ in range(5):
        world.step(1 / 240)
        world.joint_state()
        torques, forces = rng.normal(size=6) * 1e4, rng.normal(size=(6, 2)) * 1e3
        world.drive(np.zeros(6), torques, forces, np.full(6, 1e5))
        floats = world._rows.loads.copy()
        monkeypatch.setattr("ikgame.physics.world.FLOAT_LINKS", 0)
        world.drive(np.zeros(6), torques, forces, np.full(6, 1e5))
        monkeypatch.undo()
        assert np.any(floats) and np.array_equal(floats, world._rows.loads)


@pytest.mark.parametrize("speed", np.linspace(5.0, 60.0, 12).tolist())
def test_a_joint_knocked_toward_its_stop_halts_at_it_not_a_step_past_it(speed):
    # pymunk's limit acts only once a joint is past it, after the velocity the step before left
    # it with has moved it on: unbraced, these knocks (far faster than the joint's motor turns
    # it) carried the joint up to 1.9 deg past its stop, and the push back sent it 3 deg away.
    # Halted, the joint creeps on into the stop (the base link's spin carries it) slower than
    # its speed limit, which passes a stop by less than a tick's travel, as unbraced joints do.
    limited = {"length": 100.0, "limits": [-30.0, 30.0], "max_speed": 30.0}
    world = World(_level([{"length": 100.0}, limited]))
    world.motors[1].max_force = 0.0  # nothing but the stop brakes the joint
    world.bodies[1].angular_velocity = speed  # rad/s
    angles = []
    for _ in range(120):
        world.step(1 / 240)
        angles.append(world.joint_angles()[1])
    assert max(angles) <= math.radians(30.0) + math.radians(30.0) / 240
    assert angles[-1] == pytest.approx(math.radians(30.0), abs=math.radians(0.5))


def test_a_joint_whipped_by_a_floor_strike_halts_at_its_stop(stress_simulation):
    # The stress level that found it: thirty light links swept low, the 24th strikes the
    # floor, and joints 21 and 22 whip round at about 2,300 deg/s for ten ticks. The contact's
    # own correction of its overlap held joint 21 back within the step its stop was braced
    # in, short of a stop braced where its velocity alone would have put it; the limit stayed
    # idle and the next step carried the joint 3.9 deg past its real stop.
    sim = stress_simulation("48_chain30_gravity", "dls")
    # The obstacle planner's share of a tick when the whip was found: the same way to it.
    sim.controller.avoider.budget = 600
    world = sim.world
    lower = np.array([j.min for j in world.limit_joints])
    upper = np.array([j.max for j in world.limit_joints])
    past, fastest = 0.0, 0.0
    for tick in range(1645):
        sim.step()
        if tick >= 1620:
            angles = world.joint_angles()
            past = max(past, float(np.max(np.maximum(lower - angles, angles - upper))))
            fastest = max(fastest, float(np.abs(world.joint_velocities()).max()))
    assert fastest > math.radians(2000.0)  # the whip this test is about
    assert past < math.radians(0.5)


def test_a_chain_longer_than_the_solver_iterations_comes_to_rest_on_its_target():
    # 150 links under gravity in 100 solver iterations. Solved base to tip only, a correction
    # travels back one joint per iteration, and this chain rocks by 7 to 11 px (2 px even at 150
    # iterations); the return sweep carries it the whole way back in each.
    level = Level.model_validate(
        {
            "level": {"name": "test", "duration": 2.0},
            "chain": {
                "angle": 60.0,
                "links": [{"length": 2.0, "mass": 0.05, "limits": [-150, 150], "repeat": 150}],
            },
            "script": [{"reach": [150.0, 200.0], "tolerance": 1.0, "timeout": 2.0}],
        }
    )
    sim = Simulation(level, record=False)
    assert sim.world.space.iterations == SWEEP_LINKS
    tips = []
    for _ in range(480):
        sim.step()
        tips.append(sim.world.end_effector())
    assert sim.step().error <= 1.0
    assert np.ptp(np.array(tips[-120:]), axis=0).max() < 0.05


def test_a_long_chain_s_two_motor_halves_give_the_whole_torque_limit_and_no_more():
    level = _level(
        [{"length": 4.0, "mass": 1.0, "max_torque": 5000.0, "repeat": SWEEP_LINKS + 1}],
        gravity=(0, -900),
        angle=0.0,
    )
    world = World(level)
    world.set_rates(np.zeros(SWEEP_LINKS + 1))
    world.step(1 / 240)
    assert world.torque_limited()[0]
    assert world.motor_torques()[0] == pytest.approx(5000.0, rel=1e-6)


def test_touching_answers_as_asking_every_link_for_its_contacts():
    # The cached arbiters it reads first outlive the contacts (a prop pushed away, a link that
    # left the floor): on every tick it must answer what asking every link would.
    sim = Simulation(load_level(LEVELS / "12_push_the_ball.toml"), record=False)
    answers = []
    for _ in range(1500):
        sim.step()
        world = sim.world
        asked = False
        for body in world.bodies:
            contacts: list[object] = []
            body.each_arbiter(contacts.append)
            asked = asked or bool(contacts)
        assert world.touching() is asked
        answers.append(asked)
    assert any(answers) and not all(answers)


def test_touching_asks_no_link_while_no_contact_is_cached(monkeypatch):
    # A long chain in open space: one batch read of the cached arbiters, not a call per link.
    world = World(_level([{"length": 10.0, "repeat": 100}], gravity=(0.0, -900.0)))
    for _ in range(5):
        world.step(1 / 240)
    asked = []
    monkeypatch.setattr(pymunk.Body, "each_arbiter", lambda body, func: asked.append(body))
    assert world.touching() is False
    assert asked == []


def test_a_long_chains_stops_are_braced_as_joint_by_joint():
    # Screened over arrays first, the same joints braced at the same angles as the loop over
    # every limited joint, knocked ones, free ones and NaN among them.
    rng = np.random.default_rng(5)
    count = 3 * FLOAT_LINKS
    bodies = [pymunk.Body(1.0, 1.0) for _ in range(count + 1)]

    def stops(screened):
        limits = [
            None if i % 4 == 0 else pymunk.RotaryLimitJoint(bodies[i], bodies[i + 1], -1.0, 1.2)
            for i in range(count)
        ]
        made = _Stops(limits, np.full(count, 3.0))
        if not screened:
            made._screen = None
        return made, limits

    for _ in range(50):
        angles = rng.uniform(-1.1, 1.3, count)
        velocities = rng.uniform(-400.0, 400.0, count) * (rng.random(count) < 0.2)
        velocities[rng.integers(count)] = math.nan
        (screened, limits), (looped, reference) = stops(True), stops(False)
        assert screened._screen is not None
        braced = screened.brace(angles, velocities, 1 / 240)
        assert braced == looped.brace(angles, velocities, 1 / 240)
        assert braced
        for joint, other in zip(limits, reference, strict=True):
            if joint is not None:
                assert (joint.min, joint.max) == (other.min, other.max)
