"""The kinematics' float helpers give what their numpy counterparts give, float for float."""

import math

import numpy as np
import pytest

from ikgame.kinematics import Skeleton
from ikgame.kinematics._floats import FloatChain, float_angles, float_point


def test_clamp_over_floats_is_the_skeletons_clamp_even_at_signed_zeros():
    limits = [(-0.0, 1.0), (0.0, 1.0), (-1.0, 0.0), (-1.0, -0.0), None, (-0.5, 0.5)]
    skeleton = Skeleton.chain([1.0] * len(limits), limits=limits)
    chain = FloatChain(skeleton)
    rng = np.random.default_rng(2)
    for angles in (
        [0.0, -0.0, 0.0, -0.0, -0.0, 0.5],
        [-0.0, 0.0, -0.0, 0.0, 0.0, -0.5],
        *(rng.normal(size=len(limits)).tolist() for _ in range(50)),
    ):
        expected = skeleton.clamp(np.array(angles)).tolist()
        got = chain.clamp(angles)
        assert got == expected
        assert [math.copysign(1.0, v) for v in got] == [math.copysign(1.0, v) for v in expected]


def test_the_float_checks_refuse_what_the_numpy_checks_refuse():
    assert float_angles(np.array([0.5, -1.0]), 2) == [0.5, -1.0]
    assert float_point((1.0, 2.0)) == (1.0, 2.0) and float_point(np.array([3.0, 4.0])) == (3.0, 4.0)
    with pytest.raises(ValueError, match="finite"):
        float_angles(np.array([0.5, math.nan]), 2)
    with pytest.raises(ValueError, match="shape"):
        float_angles(np.zeros(3), 2)
    with pytest.raises(ValueError, match="finite"):
        float_point((math.inf, 0.0))
