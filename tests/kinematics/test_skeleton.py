"""Skeleton validation, forward kinematics against poses worked out by hand, clamp and reach."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from ikgame.kinematics import Skeleton, forward_kinematics

HALF_PI = math.pi / 2


def _skeleton(lengths, parents, lower=-np.inf, upper=np.inf, base=(0.0, 0.0), base_angle=0.0):
    return Skeleton(
        lengths=np.asarray(lengths, dtype=float),
        parents=np.asarray(parents),
        lower=np.asarray(lower, dtype=float),
        upper=np.asarray(upper, dtype=float),
        base=np.asarray(base, dtype=float),
        base_angle=base_angle,
    )


# -- forward kinematics: chains ------------------------------------------------------------------


def test_fk_straight_chain_lies_along_x():
    points, world = forward_kinematics(Skeleton.chain([10, 20, 30]), np.zeros(3))
    np.testing.assert_allclose(points, [[0, 0], [10, 0], [30, 0], [60, 0]], atol=1e-12)
    np.testing.assert_allclose(world, [0, 0, 0], atol=1e-12)


def test_fk_right_angles_make_a_staircase():
    # Local angles: up, then back to +x, then up again; world angles are the running sums.
    points, world = forward_kinematics(
        Skeleton.chain([10, 10, 10]), np.array([HALF_PI, -HALF_PI, HALF_PI])
    )
    np.testing.assert_allclose(points, [[0, 0], [0, 10], [10, 10], [10, 20]], atol=1e-12)
    np.testing.assert_allclose(world, [HALF_PI, 0.0, HALF_PI], atol=1e-12)


def test_fk_folded_chain_returns_to_the_base():
    points, world = forward_kinematics(Skeleton.chain([5, 5]), np.array([0.0, math.pi]))
    np.testing.assert_allclose(points, [[0, 0], [5, 0], [0, 0]], atol=1e-12)
    np.testing.assert_allclose(world, [0.0, math.pi], atol=1e-12)


def test_fk_base_angle_turns_the_whole_chain():
    skeleton = Skeleton.chain([10, 10], base_angle=HALF_PI)
    points, world = forward_kinematics(skeleton, np.array([0.0, -HALF_PI]))
    # The base points up (+y, world y is up), so the second link ends up pointing along +x.
    np.testing.assert_allclose(points, [[0, 0], [0, 10], [10, 10]], atol=1e-12)
    np.testing.assert_allclose(world, [HALF_PI, 0.0], atol=1e-12)


def test_fk_base_offset_translates_every_point():
    angles = np.array([0.3, -1.1, 2.0])
    at_origin, world0 = forward_kinematics(Skeleton.chain([7, 3, 5]), angles)
    moved, world1 = forward_kinematics(Skeleton.chain([7, 3, 5], base=(40.0, -25.0)), angles)
    np.testing.assert_allclose(moved, at_origin + [40.0, -25.0], atol=1e-12)
    np.testing.assert_array_equal(world0, world1)
    assert moved[0].tolist() == [40.0, -25.0]


def test_fk_base_offset_and_angle_together():
    skeleton = Skeleton.chain([2.0], base=(1.0, 1.0), base_angle=math.pi)
    points, world = forward_kinematics(skeleton, np.array([HALF_PI]))
    # pi + pi/2 points straight down.
    np.testing.assert_allclose(points, [[1, 1], [1, -1]], atol=1e-12)
    np.testing.assert_allclose(world, [1.5 * math.pi], atol=1e-12)


def test_fk_chain_point_count_and_world_angle_sums():
    rng = np.random.default_rng(7)
    lengths = rng.uniform(1, 50, size=6)
    angles = rng.uniform(-4, 4, size=6)
    points, world = forward_kinematics(Skeleton.chain(lengths, base_angle=0.25), angles)
    assert points.shape == (7, 2)
    np.testing.assert_allclose(world, 0.25 + np.cumsum(angles), atol=1e-12)
    # Each link's span has the link's length, whatever the pose.
    np.testing.assert_allclose(np.hypot(*np.diff(points, axis=0).T), lengths, rtol=1e-12)


# -- forward kinematics: trees -------------------------------------------------------------------


def test_fk_small_tree_hand_computed():
    #        3
    #        |
    #  0 --- * (end of link 0: links 1 and 2 start here)
    #        |
    #        2
    skeleton = _skeleton(lengths=[10, 5, 5, 2], parents=[-1, 0, 0, 1])
    assert not skeleton.is_chain
    points, world = forward_kinematics(skeleton, np.array([0.0, HALF_PI, -HALF_PI, 0.0]))
    starts, ends = points[:4], points[4:]
    np.testing.assert_allclose(starts, [[0, 0], [10, 0], [10, 0], [10, 5]], atol=1e-12)
    np.testing.assert_allclose(ends, [[10, 0], [10, 5], [10, -5], [10, 7]], atol=1e-12)
    np.testing.assert_allclose(world, [0.0, HALF_PI, -HALF_PI, HALF_PI], atol=1e-12)


def test_fk_tree_branch_matches_the_chain_along_it():
    angles = np.array([0.4, -0.9, 1.3, 0.2, 2.5])
    tree = _skeleton(
        lengths=[3, 4, 5, 6, 7], parents=[-1, 0, 0, 2, 3], base=(2.0, -1.0), base_angle=0.7
    )
    points, world = forward_kinematics(tree, angles)
    # Links 0, 2, 3, 4 form a path from the base to a leaf.
    path = [0, 2, 3, 4]
    chain = Skeleton.chain([3, 5, 6, 7], base=(2.0, -1.0), base_angle=0.7)
    chain_points, chain_world = forward_kinematics(chain, angles[path])
    starts, ends = points[:5], points[5:]
    np.testing.assert_allclose(starts[path], chain_points[:4], atol=1e-12)
    np.testing.assert_allclose(ends[4], chain_points[4], atol=1e-12)
    np.testing.assert_allclose(world[path], chain_world, atol=1e-12)


def test_fk_two_roots_both_start_at_the_base():
    skeleton = _skeleton(lengths=[1, 2], parents=[-1, -1], base=(3.0, 4.0))
    points, world = forward_kinematics(skeleton, np.array([0.0, math.pi]))
    np.testing.assert_allclose(points, [[3, 4], [3, 4], [4, 4], [1, 4]], atol=1e-12)
    np.testing.assert_allclose(world, [0.0, math.pi], atol=1e-12)


@pytest.mark.parametrize(
    ("angles", "message"),
    [
        (np.zeros(2), r"angles must have shape \(3,\), got shape \(2,\)"),
        (np.zeros((3, 1)), r"angles must have shape \(3,\), got shape \(3, 1\)"),
        (np.array([0.0, np.nan, 0.0]), r"angles must be finite"),
        (np.array([0.0, np.inf, 0.0]), r"angles must be finite"),
        (["a", "b", "c"], r"angles must be numbers"),
    ],
)
def test_fk_rejects_bad_angles(angles, message):
    with pytest.raises(ValueError, match=message):
        forward_kinematics(Skeleton.chain([1, 1, 1]), angles)


# -- validation ----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"lengths": []}, r"lengths must be a non-empty 1-D array, got shape \(0,\)"),
        ({"lengths": [[1.0, 2.0]]}, r"lengths must be a non-empty 1-D array, got shape \(1, 2\)"),
        ({"lengths": [1.0, 0.0]}, r"lengths must be finite and positive, got \[1.0, 0.0\]"),
        ({"lengths": [1.0, -2.0]}, r"lengths must be finite and positive"),
        ({"lengths": [1.0, np.nan]}, r"lengths must be finite and positive"),
        ({"lengths": [np.inf, 1.0]}, r"lengths must be finite and positive"),
        ({"parents": [-1]}, r"parents must have shape \(2,\), got shape \(1,\)"),
        ({"parents": [-1, 1]}, r"each parent index must be -1 or smaller than the link's own"),
        ({"parents": [0, 0]}, r"each parent index must be -1 or smaller than the link's own"),
        ({"parents": [-1, 5]}, r"each parent index must be -1 or smaller than the link's own"),
        ({"parents": [-2, 0]}, r"each parent index must be -1 or smaller than the link's own"),
        ({"lower": [0.5, 0.0], "upper": [0.4, 1.0]}, r"joint limits must satisfy lower <= upper"),
        ({"lower": [np.nan, 0.0]}, r"joint limits must satisfy lower <= upper"),
        ({"upper": [np.nan, 1.0]}, r"joint limits must satisfy lower <= upper"),
        ({"base": (0.0, np.nan)}, r"base must be finite"),
        ({"base": (0.0, 1.0, 2.0)}, r"base must have shape \(2,\), got shape \(3,\)"),
        ({"base_angle": np.nan}, r"base_angle must be finite"),
        ({"base_angle": np.inf}, r"base_angle must be finite"),
    ],
)
def test_skeleton_rejects_bad_fields(kwargs, message):
    fields = {"lengths": [1.0, 2.0], "parents": [-1, 0]} | kwargs
    with pytest.raises(ValueError, match=message):
        _skeleton(**fields)


@pytest.mark.parametrize(
    ("lengths", "limits", "message"),
    [
        ([], None, r"lengths must be a non-empty 1-D array"),
        ([1.0, -1.0], None, r"lengths must be finite and positive"),
        ([1.0, np.nan], None, r"lengths must be finite and positive"),
        ([1.0, 1.0], [None], r"limits must have one entry per link \(2\), got 1"),
        ([1.0], [(1.0, -1.0)], r"joint limits must satisfy lower <= upper"),
    ],
)
def test_chain_rejects_bad_arguments(lengths, limits, message):
    with pytest.raises(ValueError, match=message):
        Skeleton.chain(lengths, limits=limits)


def test_equal_limits_are_allowed_and_pin_the_joint():
    skeleton = Skeleton.chain([1.0], limits=[(0.25, 0.25)])
    assert skeleton.clamp(np.array([-3.0])).tolist() == [0.25]
    assert skeleton.limited.tolist() == [True]


def test_skeleton_is_frozen_and_its_arrays_are_read_only():
    skeleton = Skeleton.chain([1.0, 2.0], limits=[(-1.0, 1.0), None])
    with pytest.raises(dataclasses.FrozenInstanceError):
        skeleton.base_angle = 1.0  # type: ignore[misc]
    for name in ("lengths", "parents", "lower", "upper", "base"):
        with pytest.raises(ValueError, match="read-only"):
            getattr(skeleton, name)[0] = 0


def test_skeleton_does_not_share_memory_with_the_caller():
    storage = np.array([1.0, 2.0, 3.0])
    skeleton = _skeleton(lengths=storage[:2], parents=[-1, 0])
    storage[0] = -5.0
    assert skeleton.lengths.tolist() == [1.0, 2.0]
    # Nor does it make the caller's own arrays read-only.
    lengths = np.array([1.0, 2.0])
    base = np.array([3.0, 4.0])
    Skeleton.chain(lengths, base=base)
    lengths[0] = 7.0
    base[0] = 7.0


def test_chain_fields():
    skeleton = Skeleton.chain(
        [3, 4, 5], base=(1, 2), base_angle=0.5, limits=[None, (-1.0, 2.0), (-0.5, np.inf)]
    )
    assert skeleton.count == 3
    assert skeleton.is_chain
    assert skeleton.parents.tolist() == [-1, 0, 1]
    assert skeleton.lower.tolist() == [-np.inf, -1.0, -0.5]
    assert skeleton.upper.tolist() == [np.inf, 2.0, np.inf]
    assert skeleton.limited.tolist() == [False, True, True]
    assert skeleton.base.tolist() == [1.0, 2.0]
    assert skeleton.base_angle == 0.5


def test_scalar_limits_broadcast_to_every_joint():
    skeleton = _skeleton(lengths=[1, 1, 1], parents=[-1, 0, 1], lower=-1.0, upper=1.0)
    assert skeleton.lower.tolist() == [-1.0, -1.0, -1.0]
    assert skeleton.upper.tolist() == [1.0, 1.0, 1.0]


# -- clamp and reach -----------------------------------------------------------------------------


def test_clamp_clips_only_limited_joints():
    skeleton = Skeleton.chain([1, 1, 1, 1], limits=[(-0.5, 0.5), None, (0.0, 1.0), (-2.0, 2.0)])
    angles = np.array([2.0, 100.0, -1.0, 1.5])
    before = angles.copy()
    assert skeleton.clamp(angles).tolist() == [0.5, 100.0, 0.0, 1.5]
    np.testing.assert_array_equal(angles, before)


def test_clamp_does_not_wrap():
    # A limited joint at 3 rad past a 1 rad limit is clamped to the limit, not wrapped first.
    skeleton = Skeleton.chain([1.0], limits=[(-1.0, 1.0)])
    assert skeleton.clamp(np.array([2 * math.pi + 0.5])).tolist() == [1.0]


def test_reach_of_a_chain_is_the_sum_of_lengths():
    assert Skeleton.chain([10, 20, 30.5]).reach == pytest.approx(60.5)
    assert Skeleton.chain([4.0]).reach == 4.0


def test_reach_of_a_tree_is_the_longest_root_to_leaf_path():
    skeleton = _skeleton(lengths=[10, 5, 5, 2, 1], parents=[-1, 0, 0, 1, -1])
    assert skeleton.reach == pytest.approx(17.0)


def test_reach_ignores_the_pose_and_bounds_every_point():
    skeleton = Skeleton.chain([3, 1, 4, 1, 5], base=(10.0, -10.0), base_angle=2.0)
    rng = np.random.default_rng(11)
    for _ in range(50):
        points, _ = forward_kinematics(skeleton, rng.uniform(-np.pi, np.pi, size=5))
        assert np.all(np.hypot(*(points - skeleton.base).T) <= skeleton.reach + 1e-9)
    straight, _ = forward_kinematics(skeleton, np.zeros(5))
    assert np.hypot(*(straight[-1] - skeleton.base)) == pytest.approx(skeleton.reach)


def test_moved_to_changes_only_the_base():
    skeleton = Skeleton.chain([3.0, 4.0], base=(1, 2), base_angle=0.5, limits=[None, (-1.0, 1.0)])
    moved = skeleton.moved_to((10.0, -5.0))
    assert moved.base.tolist() == [10.0, -5.0]
    assert skeleton.base.tolist() == [1.0, 2.0]
    for name in ("lengths", "parents", "lower", "upper"):
        assert np.array_equal(getattr(moved, name), getattr(skeleton, name))
    assert moved.base_angle == 0.5 and moved.is_chain
    points, _ = forward_kinematics(moved, np.zeros(2))
    assert points[0].tolist() == [10.0, -5.0]
    with pytest.raises(ValueError, match="base must be finite"):
        skeleton.moved_to((np.nan, 0.0))
    with pytest.raises(ValueError, match="read-only"):
        moved.base[0] = 0.0


# -- trees: structure, root offsets, forward kinematics ------------------------------------------

HIPS = Skeleton.tree(
    [50.0, 40.0, 50.0, 40.0, 30.0],
    [-1, 0, -1, 2, 2],
    root_offsets=[(-30.0, 0.0), (0.0, 0.0), (30.0, 10.0), (0.0, 0.0), (0.0, 0.0)],
)


def test_tree_structure():
    assert HIPS.children == ((1,), (), (3, 4), (), ())
    assert HIPS.effectors.tolist() == [1, 3, 4]
    assert HIPS.roots.tolist() == [0, 0, 2, 2, 2]
    assert HIPS.ancestors.astype(int).tolist() == [
        [1, 0, 0, 0, 0],
        [1, 1, 0, 0, 0],
        [0, 0, 1, 0, 0],
        [0, 0, 1, 1, 0],
        [0, 0, 1, 0, 1],
    ]
    assert not HIPS.is_chain and HIPS.has_root_offsets
    for name in ("effectors", "ancestors", "roots", "root_offsets"):
        assert not getattr(HIPS, name).flags.writeable


def test_a_chain_has_one_effector_and_zero_root_offsets():
    chain = Skeleton.chain([1.0, 2.0, 3.0])
    assert chain.effectors.tolist() == [2]
    assert chain.root_offsets.tolist() == [[0.0, 0.0]] * 3
    assert not chain.has_root_offsets


def test_tree_limits_are_in_link_order():
    tree = Skeleton.tree([1.0, 1.0], [-1, 0], limits=[None, (-0.5, 0.25)])
    assert tree.lower.tolist() == [-np.inf, -0.5]
    assert tree.upper.tolist() == [np.inf, 0.25]


def test_fk_root_offsets_sit_in_the_base_frame():
    # Base turned a quarter: the offset's x points up, its y to the left (-x).
    tree = Skeleton.tree(
        [10.0, 10.0],
        [-1, -1],
        base=(100.0, 0.0),
        base_angle=HALF_PI,
        root_offsets=[(5.0, 0.0), (0.0, 3.0)],
    )
    points, world = forward_kinematics(tree, np.array([0.0, -HALF_PI]))
    np.testing.assert_allclose(points, [[100, 5], [97, 0], [100, 15], [107, 0]], atol=1e-12)
    np.testing.assert_allclose(world, [HALF_PI, 0.0])


def test_fk_chain_with_a_root_offset_starts_there():
    chain = Skeleton.tree([10.0, 10.0], [-1, 0], base=(1.0, 2.0), root_offsets=[(3, 4), (0, 0)])
    points, _ = forward_kinematics(chain, np.zeros(2))
    np.testing.assert_allclose(points, [[4, 6], [14, 6], [24, 6]])


def test_fk_of_random_trees_matches_a_walk_link_by_link():
    rng = np.random.default_rng(17)
    for _ in range(50):
        n = int(rng.integers(1, 15))
        parents = [-1] + [int(rng.integers(-1, i)) for i in range(1, n)]
        offsets = rng.normal(0, 20, (n, 2)) * (np.array(parents) < 0)[:, None]
        base_angle = float(rng.uniform(-4, 4))
        tree = Skeleton.tree(
            rng.uniform(1, 50, n),
            parents,
            base=rng.normal(0, 50, 2),
            base_angle=base_angle,
            root_offsets=offsets,
        )
        angles = rng.uniform(-4, 4, n)
        rotation = np.array(
            [
                [math.cos(base_angle), -math.sin(base_angle)],
                [math.sin(base_angle), math.cos(base_angle)],
            ]
        )
        starts, ends, world = np.zeros((n, 2)), np.zeros((n, 2)), np.zeros(n)
        for i, p in enumerate(parents):
            starts[i] = tree.base + rotation @ offsets[i] if p < 0 else ends[p]
            world[i] = (base_angle if p < 0 else world[p]) + angles[i]
            ends[i] = starts[i] + tree.lengths[i] * np.array(
                [math.cos(world[i]), math.sin(world[i])]
            )
        points, got_world = forward_kinematics(tree, angles)
        np.testing.assert_allclose(got_world, world, atol=1e-12)
        if tree.is_chain:
            np.testing.assert_allclose(points, np.vstack((starts[:1], ends)), atol=1e-9)
        else:
            np.testing.assert_allclose(points, np.vstack((starts, ends)), atol=1e-9)


def test_reach_counts_the_root_offsets():
    tree = Skeleton.tree([10.0, 10.0], [-1, -1], root_offsets=[(3, 4), (0, 1)])
    assert tree.reach == pytest.approx(15.0)
    points, _ = forward_kinematics(tree, np.array([0.9, -0.3]))
    assert np.all(np.hypot(*(points - tree.base).T) <= tree.reach + 1e-9)


def test_moved_to_keeps_the_root_offsets():
    moved = HIPS.moved_to((10.0, 20.0))
    assert moved.root_offsets is HIPS.root_offsets
    np.testing.assert_allclose(moved.root_points()[0], [-20.0, 20.0])


@pytest.mark.parametrize("skeleton", [HIPS, Skeleton.tree([1.0, 1.0], [-1, 0])])
def test_root_points_follow_every_move_of_the_base(skeleton):
    # Root points are worked out once per skeleton: a moved copy must not keep the old ones.
    before = skeleton.root_points()
    moved = skeleton.moved_to((10.0, 20.0), 0.5)
    turned = Skeleton.tree(
        skeleton.lengths,
        skeleton.parents,
        base=(10.0, 20.0),
        base_angle=0.5,
        root_offsets=skeleton.root_offsets,
    )
    assert np.array_equal(moved.root_points(), turned.root_points())
    assert np.array_equal(skeleton.root_points(), before)
    assert np.array_equal(moved.moved_to(skeleton.base, 0.0).root_points(), before)


@pytest.mark.parametrize(
    ("offsets", "message"),
    [
        ([(0.0, 0.0)], r"root_offsets must have shape \(2, 2\), got shape \(1, 2\)"),
        ([(0.0, 0.0), (1.0, 0.0)], r"root_offsets must be zero for links with a parent"),
        ([(np.nan, 0.0), (0.0, 0.0)], r"root_offsets must be finite"),
        ("far", r"root_offsets must be \(x, y\) rows of numbers"),
    ],
)
def test_bad_root_offsets_are_refused(offsets, message):
    with pytest.raises(ValueError, match=message):
        Skeleton.tree([1.0, 1.0], [-1, 0], root_offsets=offsets)
