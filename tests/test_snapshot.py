"""Scene and Snapshot: a chain's and a tree's joints read the same way through the helpers."""

from __future__ import annotations

import numpy as np
import pytest

from ikgame.kinematics.skeleton import Skeleton, forward_kinematics
from ikgame.snapshot import Scene, Snapshot, effector_positions, link_segments

PARENTS = np.array([-1, 0, 1, 0, 3])


def _scene(**overrides) -> Scene:
    fields = dict(
        level_name="t",
        segments=np.zeros((0, 5)),
        circles=np.zeros((0, 3)),
        link_widths=np.full(5, 6.0),
        reach=100.0,
    )
    return Scene(**(fields | overrides))


def _tree(**overrides) -> Scene:
    fields = dict(parents=PARENTS, effector_links=np.array([2, 4]), effector_names=("l", "r"))
    return _scene(**(fields | overrides))


def _snap(joints: np.ndarray, n: int = 5, **overrides) -> Snapshot:
    return Snapshot(0.0, 0, joints, np.zeros(n), np.zeros(n), **overrides)


def test_a_trees_segments_and_effectors_match_its_forward_kinematics():
    n = len(PARENTS)
    skeleton = Skeleton(
        np.array([30.0, 20.0, 10.0, 25.0, 15.0]),
        PARENTS,
        np.full(n, -np.inf),
        np.full(n, np.inf),
        np.array([5.0, -3.0]),
    )
    angles = np.array([1.2, 0.4, -0.3, -0.6, 0.5])
    joints, _ = forward_kinematics(skeleton, angles)
    scene, snap = _tree(), _snap(joints)
    starts, ends = link_segments(scene, snap)
    np.testing.assert_allclose(np.linalg.norm(ends - starts, axis=1), skeleton.lengths)
    for i, p in enumerate(PARENTS):
        np.testing.assert_array_equal(starts[i], ends[p] if p >= 0 else skeleton.base)
    np.testing.assert_array_equal(effector_positions(scene, snap), ends[[2, 4]])
    assert scene.is_tree and scene.effectors.tolist() == [2, 4]
    assert scene.link_parents.tolist() == PARENTS.tolist()


def test_a_chains_helpers_read_its_joints_as_before():
    joints = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]])
    scene, snap = _scene(link_widths=np.ones(2)), _snap(joints, 2, target=np.array([3.0, 4.0]))
    starts, ends = link_segments(scene, snap)
    np.testing.assert_array_equal(starts, joints[:-1])
    np.testing.assert_array_equal(ends, joints[1:])
    assert effector_positions(scene, snap).tolist() == [[10.0, 10.0]]
    assert scene.effector_names == ("tip",) and not scene.is_tree
    assert scene.link_parents.tolist() == [-1, 0] and scene.effectors.tolist() == [1]
    assert snap.target_points.tolist() == [[3.0, 4.0]]
    assert np.isnan(snap.effector_errors).all() and snap.effector_errors.shape == (1,)
    assert [t.tolist() for t in scene.target_lists] == [[]]


def test_a_trees_snapshot_gives_one_row_per_effector():
    targets = np.array([[1.0, 2.0], [np.nan, np.nan]])
    snap = _snap(np.zeros((10, 2)), targets=targets, errors=np.array([0.5, np.nan]))
    np.testing.assert_array_equal(snap.target_points, targets)
    np.testing.assert_array_equal(snap.effector_errors, [0.5, np.nan])


@pytest.mark.parametrize(
    "overrides, message",
    [
        (dict(parents=np.array([-1, 0, 1])), "parents has 3 entries for 5 link widths"),
        (dict(parents=np.array([-1, 0, 2, 0, 3])), r"parents\[2\] = 2"),
        (dict(parents=np.array([-1, 0, 1, 0, 3.0])), "1-D array of ints"),
        (dict(effector_links=np.array([2, 2])), "distinct effector_links"),
        (dict(effector_links=np.array([2, 5])), "link indices 0..4"),
        (dict(effector_names=("l",)), "expected 2 distinct effector names"),
        (dict(effector_names=("l", "l")), "expected 2 distinct effector names"),
        (dict(effector_targets=(np.zeros((1, 2)),)), "1 arrays for 2 effectors"),
        (dict(effector_targets=(np.zeros((1, 3)), np.zeros((0, 2)))), r"shape \(t, 2\)"),
    ],
)
def test_a_tree_that_does_not_add_up_raises(overrides, message):
    with pytest.raises(ValueError, match=message):
        _tree(**overrides)


def test_tree_fields_on_a_chain_raise():
    with pytest.raises(ValueError, match="are for trees"):
        _scene(effector_links=np.array([4]))
    with pytest.raises(ValueError, match="expected 1 distinct effector names"):
        _scene(effector_names=("a", "b"))


def test_joints_of_the_wrong_layout_raise():
    with pytest.raises(ValueError, match=r"a tree of 5 links needs \(10, 2\)"):
        link_segments(_tree(), _snap(np.zeros((6, 2))))
    with pytest.raises(ValueError, match="5 link widths for a chain of 9 links"):
        link_segments(_scene(), _snap(np.zeros((10, 2))))
