"""Catching a chain's end on its way: when, and where it stops."""

import numpy as np
import pytest

from ikgame.control.catching import HEADING, catch_pose, time_to_nearest


def test_the_time_to_nearest_is_when_the_end_passes_nearest_the_target():
    rng = np.random.default_rng(3)
    checked = 0
    for _ in range(200):
        offset, velocity = rng.normal(size=2) * 100, rng.normal(size=2) * 500
        ahead = time_to_nearest(tuple(offset), tuple(velocity))
        toward = offset @ velocity
        sideways = abs(offset[0] * velocity[1] - offset[1] * velocity[0])
        if toward <= 0 or sideways > HEADING * toward:
            assert ahead is None  # going away, or going by
            continue
        # Nearest: the way left to the target is square to the end's velocity.
        assert (offset - velocity * ahead) @ velocity == pytest.approx(0.0, abs=1e-6)
        checked += 1
    assert checked > 20


@pytest.mark.parametrize("seed", range(5))
def test_a_steady_approach_is_caught_with_half_of_every_joint_s_braking_to_spare(seed):
    rng = np.random.default_rng(seed)
    n, dt = int(rng.integers(1, 8)), 1 / 240
    velocities, braking = rng.normal(size=n) * 2.0, rng.uniform(5.0, 60.0, n)
    speed = rng.uniform(100.0, 1500.0)  # px/s, straight at the target
    distance, pose, ahead = 400.0, None, None
    while pose is None:
        ahead = time_to_nearest((distance, 0.0), (speed, 0.0))
        pose = catch_pose(np.zeros(n), velocities, ahead, braking, dt)
        distance -= speed * dt
        assert distance > 0.0, "never caught"
    # Stopping evenly in twice the time the end needs to get there, each joint slows by
    # |v| / (2 ahead): within half of what it has, and the joints turn on together.
    assert np.all(np.abs(velocities) / (2.0 * ahead) <= 0.5 * braking)
    np.testing.assert_allclose(pose, velocities * ahead)
    # Not early: within a tick or two of the time some joint would ask more than half.
    assert ahead <= np.max(np.abs(velocities) / braking) + 2.0 * dt
