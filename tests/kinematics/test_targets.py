"""TargetSet checks and the stacked Jacobian against finite differences."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ikgame.kinematics import Skeleton, TargetSet, forward_kinematics, stacked_jacobian
from ikgame.kinematics.jacobian import jacobian


def test_weights_default_to_one_and_arrays_are_read_only():
    targets = TargetSet([3, 1], [(1, 2), (3, 4)])
    assert targets.weights.tolist() == [1.0, 1.0]
    assert targets.links.tolist() == [3, 1] and len(targets) == 2
    for name in ("links", "points", "weights"):
        assert not getattr(targets, name).flags.writeable


def test_target_set_does_not_share_memory_with_the_caller():
    points = np.zeros((1, 2))
    targets = TargetSet([0], points)
    points[0, 0] = 5.0
    assert targets.points.tolist() == [[0.0, 0.0]]


@pytest.mark.parametrize(
    ("links", "points", "weights", "message"),
    [
        ([], np.zeros((0, 2)), None, r"links must be a non-empty 1-D array"),
        ([0.5], [(0, 0)], None, r"links must be integer link indices"),
        ([1, 1], [(0, 0), (1, 1)], None, r"links must be distinct indices >= 0, got \[1, 1\]"),
        ([-1], [(0, 0)], None, r"links must be distinct indices >= 0"),
        ([0, 1], [(0, 0)], None, r"points must have shape \(2, 2\), got shape \(1, 2\)"),
        ([0], [(math.nan, 0)], None, r"points must be finite"),
        ([0], [(0, 0)], [0.0], r"weights must be finite and > 0, got \[0.0\]"),
        ([0], [(0, 0)], [1.0, 2.0], r"weights must have shape \(1,\)"),
        ([0], "x", None, r"targets must be link indices and \(x, y\) points"),
    ],
)
def test_bad_target_sets_are_refused(links, points, weights, message):
    with pytest.raises(ValueError, match=message):
        TargetSet(links, points, weights)


def test_stacked_jacobian_matches_finite_differences_on_random_trees():
    rng = np.random.default_rng(23)
    for _ in range(30):
        n = int(rng.integers(1, 10))
        parents = [-1] + [int(rng.integers(-1, i)) for i in range(1, n)]
        offsets = rng.normal(0, 20, (n, 2)) * (np.array(parents) < 0)[:, None]
        tree = Skeleton.tree(
            rng.uniform(1, 50, n),
            parents,
            base=rng.normal(0, 50, 2),
            base_angle=float(rng.uniform(-3, 3)),
            root_offsets=offsets,
        )
        angles = rng.uniform(-3, 3, n)
        links = rng.permutation(n)[: int(rng.integers(1, n + 1))]

        def ends(a: np.ndarray, tree: Skeleton = tree, links: np.ndarray = links) -> np.ndarray:
            points = forward_kinematics(tree, a)[0]
            return (points[1:] if tree.is_chain else points[tree.count :])[links].reshape(-1)

        h = 1e-6
        numeric = np.column_stack(
            [(ends(angles + h * e) - ends(angles - h * e)) / (2 * h) for e in np.eye(n)]
        )
        np.testing.assert_allclose(stacked_jacobian(tree, angles, links), numeric, atol=1e-5)


def test_stacked_jacobian_of_a_chain_tip_is_the_chain_jacobian():
    chain = Skeleton.chain([30.0, 20.0, 10.0], base=(5.0, -2.0), base_angle=0.4)
    angles = np.array([0.3, -1.2, 2.0])
    np.testing.assert_allclose(stacked_jacobian(chain, angles, [2]), jacobian(chain, angles))


def test_stacked_jacobian_refuses_links_outside_the_skeleton():
    with pytest.raises(ValueError, match=r"target links must be < 2"):
        stacked_jacobian(Skeleton.chain([1.0, 1.0]), np.zeros(2), [0, 2])
