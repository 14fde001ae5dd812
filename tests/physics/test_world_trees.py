"""The pymunk world of a tree of bones: roots on the body at their offsets, joint reads along
the parents, feed-forward loads shared among a link's children, a base that turns."""

import math

import numpy as np
import pytest

from ikgame.control.dynamics import ChainInertia
from ikgame.control.servo import Servo
from ikgame.kinematics import forward_kinematics
from ikgame.level.model import Level
from ikgame.physics.world import World, build_skeleton

_MOTOR = {"max_torque": 4.0e7, "max_speed": 360.0}


def _fork(*, gravity=(0.0, -900.0), angle=0.0) -> Level:
    """A body with a leg at each end, the front leg forked at its knee."""
    return Level.model_validate(
        {
            "level": {"name": "fork", "duration": 5.0},
            "world": {"gravity": list(gravity)},
            "chain": {
                "base": [0.0, 200.0],
                "angle": angle,
                "bones": [
                    {"name": "front", "at": [60.0, 0.0], "angle": -70.0, "length": 80.0} | _MOTOR,
                    {"name": "toe", "parent": "front", "angle": 40.0, "length": 50.0} | _MOTOR,
                    {"name": "heel", "parent": "front", "angle": -40.0, "length": 40.0} | _MOTOR,
                    {"name": "back", "at": [-60.0, 0.0], "angle": -110.0, "length": 90.0} | _MOTOR,
                ],
            },
            "script": [{"wait": 1.0}],
        }
    )


def test_the_start_pose_is_the_skeletons_forward_kinematics():
    level = _fork()
    world = World(level)
    skeleton = build_skeleton(level)
    angles = world.joint_angles()
    assert angles == pytest.approx(np.radians([-70.0, 40.0, -40.0, -110.0]))
    points, _ = forward_kinematics(skeleton, angles)
    assert world.joint_positions() == pytest.approx(points)
    # The roots sit on the body at their offsets, the branches at their parent's tip.
    assert points[0] == pytest.approx([60.0, 200.0])
    assert points[3] == pytest.approx([-60.0, 200.0])
    assert points[1] == pytest.approx(points[4]) and points[2] == pytest.approx(points[4])
    assert world.effector_positions() == pytest.approx(points[[5, 6, 7]])


def test_joint_angles_and_velocities_are_relative_to_each_links_parent():
    world = World(_fork(gravity=(0.0, 0.0)))
    world.set_rates(np.array([0.0, 1.0, -1.0, 0.5]))
    for _ in range(120):
        world.step(1 / 240)
    # Each joint turned by its own rate, whatever its parent did.
    assert world.joint_velocities() == pytest.approx([0.0, 1.0, -1.0, 0.5], abs=1e-6)
    assert world.joint_angles() == pytest.approx(
        np.radians([-70.0, 40.0, -40.0, -110.0]) + 0.5 * np.array([0.0, 1.0, -1.0, 0.5]),
        abs=0.01,  # the motors take a tick to get up to speed
    )


@pytest.mark.parametrize("angle", [0.0, 30.0])
def test_feed_forward_holds_a_tree_still_under_gravity(angle):
    # The servo's inverse dynamics over the parents gives every joint the torque its subtree
    # needs, and the pivots their forces: the motors have next to nothing left to correct.
    level = _fork(angle=angle)
    world = World(level)
    inertia = ChainInertia(
        build_skeleton(level).lengths,
        world.link_masses,
        world.link_moments,
        parents=world.parents,
    )
    servo = Servo(inertia, max_torque=world.max_torque, max_speed=world.max_speed, gain=12.0)
    start = world.joint_angles()
    for _ in range(480):
        command = servo.command(
            start - world.joint_angles(),
            build_skeleton(level).ancestors @ world.joint_angles() + math.radians(angle),
            world.joint_velocities(),
            world.gravity,
            1 / 240,
            None,
        )
        world.drive(command.rates, command.torques, command.forces, command.budgets)
        world.step(1 / 240)
    assert np.degrees(np.abs(world.joint_angles() - start)).max() < 0.05
    # The motors only correct: what they add is a sliver of what the feed-forward gives.
    motors = np.array([m.impulse * 240 for m in world.motors])
    assert np.abs(motors).max() < 0.01 * np.abs(command.torques).max()


def test_the_base_turns_smoothly_and_carries_the_tree():
    world = World(_fork(gravity=(0.0, 0.0)))
    before = world.joint_angles()
    world.move_base(None, 0.5, math.radians(90.0))
    for _ in range(120):
        world.step(1 / 240)
    assert world.skeleton.base_angle == pytest.approx(math.radians(90.0))
    assert world.base_body.angle == pytest.approx(math.radians(90.0))
    # The front hip, 60 px along the body, is now above the body's centre.
    assert world.joint_positions()[0] == pytest.approx([0.0, 260.0], abs=1.0)
    assert world.joint_angles() == pytest.approx(before, abs=0.05)


def test_a_turn_takes_the_shorter_way_round():
    world = World(_fork(gravity=(0.0, 0.0), angle=170.0))
    world.move_base(None, 0.25, math.radians(-170.0))
    for _ in range(60):
        world.step(1 / 240)
    # From 170 deg to -170 deg is 20 deg through 180, not 340 the other way.
    assert world.base_body.angle == pytest.approx(math.radians(190.0))


def _cousins(collide: bool) -> World:
    """A spine with two arms bent toward each other: their forearms are cousins."""
    arm = {"length": 60.0, "width": 12.0, "max_torque": 4.0e6}
    return World(
        Level.model_validate(
            {
                "level": {"name": "cousins", "duration": 5.0},
                "world": {"gravity": [0.0, 0.0]},
                "chain": {
                    "angle": 90.0,
                    "branches_collide": collide,
                    "bones": [
                        {"name": "spine", "length": 50.0, "width": 12.0},
                        {"name": "a", "parent": "spine", "angle": 60.0} | arm,
                        {"name": "a2", "parent": "a", "angle": -60.0} | arm,
                        {"name": "b", "parent": "spine", "angle": -60.0} | arm,
                        {"name": "b2", "parent": "b", "angle": 60.0} | arm,
                    ],
                },
                "script": [{"wait": 1.0}],
            }
        )
    )


def _gap(world: World) -> float:
    """Closest distance between the axes of the two forearms, px (sampled)."""
    points = world.joint_positions()
    n = world.count
    s = np.linspace(0.0, 1.0, 41)[:, None]
    a = points[2] + s * (points[n + 2] - points[2])
    b = points[4] + s * (points[n + 4] - points[4])
    return float(np.hypot(*(a[:, None, :] - b[None, :, :]).transpose(2, 0, 1)).min())


@pytest.mark.parametrize("collide", [False, True])
def test_branches_collide_only_when_the_level_asks(collide):
    world = _cousins(collide)
    # Both forearms swing in toward the spine's axis, and past it.
    world.set_rates(np.array([0.0, 0.0, -2.0, 0.0, 2.0]))
    gaps = []
    for _ in range(240):
        world.step(1 / 240)
        gaps.append(_gap(world))
    if collide:
        assert min(gaps) > 12.0 - 1.0  # two 6 px radii, less pymunk's contact slop
    else:
        assert min(gaps) < 1.0  # they pass through each other
