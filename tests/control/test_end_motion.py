"""A short chain's end and its velocity over floats against the numpy kinematics."""

import numpy as np
import pytest

from ikgame.control._floats import end_motion
from ikgame.kinematics import Skeleton, forward_kinematics
from ikgame.kinematics.jacobian import jacobian


@pytest.mark.parametrize("n", [1, 3, 12, 30])
def test_a_chain_s_end_and_its_velocity_are_the_kinematics_and_the_jacobian_s(n):
    rng = np.random.default_rng(n)
    for _ in range(10):
        lengths = rng.uniform(5.0, 80.0, n)
        base, base_angle = rng.normal(size=2) * 100.0, float(rng.uniform(-3.0, 3.0))
        skeleton = Skeleton.chain(lengths, base=base, base_angle=base_angle)
        angles, rates = rng.uniform(-3.0, 3.0, n), rng.normal(size=n) * 2.0
        end, velocity = end_motion(
            lengths.tolist(), tuple(base.tolist()), base_angle, angles.tolist(), rates.tolist()
        )
        np.testing.assert_allclose(end, forward_kinematics(skeleton, angles)[0][-1], atol=1e-9)
        np.testing.assert_allclose(velocity, jacobian(skeleton, angles) @ rates, atol=1e-9)
