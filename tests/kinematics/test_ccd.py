"""CCD: the article's iteration reproduced exactly, worked examples, bad input, the limit-aware loop.

The reference below is transcribed from Ryan Juckett's C# ``CalcIK_2D_CCD`` and ``SimplifyAngle``
("Cyclic Coordinate Descent in 2D", 2009; the seed text in the project's shared notes), statement
for statement, without calling ikgame. ``ccd_iteration`` must agree with it on random chains.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ikgame.kinematics import Skeleton, SolveStatus, forward_kinematics, solve_ccd
from ikgame.kinematics.ccd import (
    EPSILON,
    TRIVIAL_ARC_LENGTH,
    ccd_iteration,
    ccd_iteration_limited,
    wrap_angle,
)

PI = math.pi

# -- the article's code, transcribed -------------------------------------------------------------


def _cs_min(a: float, b: float) -> float:
    # C#'s Math.Min returns NaN when either argument is NaN; Python's min() does not.
    if math.isnan(a) or math.isnan(b):
        return math.nan
    return a if a <= b else b


def _cs_max(a: float, b: float) -> float:
    if math.isnan(a) or math.isnan(b):
        return math.nan
    return a if a >= b else b


def _simplify_angle(angle: float) -> float:
    # C#'s % on doubles is IEEE fmod: the result keeps the dividend's sign.
    angle = math.fmod(angle, 2.0 * math.pi)
    if angle < -math.pi:
        angle += 2.0 * math.pi
    elif angle > math.pi:
        angle -= 2.0 * math.pi
    return angle


def _world_bones(bones: list[list[float]]) -> list[list[float]]:
    """The article's Bone_2D_CCD_World list: [x, y, angle, cosAngle, sinAngle] per bone."""
    root_angle = bones[0][2]
    world = [[bones[0][0], bones[0][1], root_angle, math.cos(root_angle), math.sin(root_angle)]]
    for bone_idx in range(1, len(bones)):
        px, py, pangle, pcos, psin = world[bone_idx - 1]
        lx, ly, langle = bones[bone_idx]
        new_x = px + pcos * lx - psin * ly
        new_y = py + psin * lx + pcos * ly
        new_angle = pangle + langle
        world.append([new_x, new_y, new_angle, math.cos(new_angle), math.sin(new_angle)])
    return world


def _calc_ik_2d_ccd(
    bones: list[list[float]], target_x: float, target_y: float, arrival_dist: float
) -> str:
    """CalcIK_2D_CCD: updates the angles in ``bones`` in place, returns the CCDResult name."""
    epsilon = 0.0001
    trivial_arc_length = 0.00001
    num_bones = len(bones)
    assert num_bones > 0
    arrival_dist_sqr = arrival_dist * arrival_dist

    world_bones = _world_bones(bones)

    end_x = world_bones[num_bones - 1][0]
    end_y = world_bones[num_bones - 1][1]

    modified_bones = False
    for bone_idx in range(num_bones - 2, -1, -1):
        wx, wy = world_bones[bone_idx][0], world_bones[bone_idx][1]
        cur_to_end_x = end_x - wx
        cur_to_end_y = end_y - wy
        cur_to_end_mag = math.sqrt(cur_to_end_x * cur_to_end_x + cur_to_end_y * cur_to_end_y)

        cur_to_target_x = target_x - wx
        cur_to_target_y = target_y - wy
        cur_to_target_mag = math.sqrt(
            cur_to_target_x * cur_to_target_x + cur_to_target_y * cur_to_target_y
        )

        end_target_mag = cur_to_end_mag * cur_to_target_mag
        if end_target_mag <= epsilon:
            cos_rot_ang = 1.0
            sin_rot_ang = 0.0
        else:
            cos_rot_ang = (
                cur_to_end_x * cur_to_target_x + cur_to_end_y * cur_to_target_y
            ) / end_target_mag
            sin_rot_ang = (
                cur_to_end_x * cur_to_target_y - cur_to_end_y * cur_to_target_x
            ) / end_target_mag

        clamped = _cs_max(-1.0, _cs_min(1.0, cos_rot_ang))
        rot_ang = math.nan if math.isnan(clamped) else math.acos(clamped)
        if sin_rot_ang < 0.0:
            rot_ang = -rot_ang

        end_x = wx + cos_rot_ang * cur_to_end_x - sin_rot_ang * cur_to_end_y
        end_y = wy + sin_rot_ang * cur_to_end_x + cos_rot_ang * cur_to_end_y

        bones[bone_idx][2] = _simplify_angle(bones[bone_idx][2] + rot_ang)

        end_to_target_x = target_x - end_x
        end_to_target_y = target_y - end_y
        if end_to_target_x * end_to_target_x + end_to_target_y * end_to_target_y <= (
            arrival_dist_sqr
        ):
            return "Success"

        if not modified_bones and abs(rot_ang) * cur_to_end_mag > trivial_arc_length:
            modified_bones = True

    if modified_bones:
        return "Processing"
    return "Failure"


_STATUS = {
    "Success": SolveStatus.SUCCESS,
    "Processing": SolveStatus.PROCESSING,
    "Failure": SolveStatus.FAILURE,
}


def _reference(bones, target, arrival_dist):
    rows = [[float(v) for v in row] for row in bones]
    result = _calc_ik_2d_ccd(rows, float(target[0]), float(target[1]), float(arrival_dist))
    return _STATUS[result], [row[2] for row in rows]


def _end_effector(bones) -> tuple[float, float]:
    world = _world_bones([[float(v) for v in row] for row in bones])
    return world[-1][0], world[-1][1]


def test_reference_reproduces_the_article_example():
    # Bend the middle joint a quarter turn and the tip lands on (1, 1).
    status, angles = _reference([(0, 0, 0), (1, 0, 0), (1, 0, 0)], (1, 1), 1e-3)
    assert status is SolveStatus.SUCCESS
    assert angles == [0.0, PI / 2, 0.0]


def test_constants_are_the_articles():
    assert EPSILON == 0.0001
    assert TRIVIAL_ARC_LENGTH == 0.00001


# -- ccd_iteration against the reference ---------------------------------------------------------


def _random_case(rng: np.random.Generator):
    n = int(rng.integers(1, 13))
    bones = np.empty((n, 3))
    bones[:, :2] = rng.normal(0.0, 60.0, size=(n, 2))
    # Zero offsets put two joints on one point: the article's epsilon branch.
    bones[rng.random(n) < 0.1, :2] = 0.0
    angle_kind = rng.integers(4)
    if angle_kind == 0:
        bones[:, 2] = rng.uniform(-PI, PI, size=n)
    elif angle_kind == 1:
        bones[:, 2] = rng.uniform(-50.0, 50.0, size=n)
    elif angle_kind == 2:
        bones[:, 2] = rng.uniform(-1e6, 1e6, size=n)
    else:
        bones[:, 2] = rng.choice([0.0, PI, -PI, 2 * PI, PI / 2], size=n)

    world = _world_bones(bones.tolist())
    target_kind = rng.integers(6)
    if target_kind == 0:
        target = (world[0][0], world[0][1])  # on the base
    elif target_kind == 1:
        joint = world[int(rng.integers(n))]
        target = (joint[0], joint[1])  # on a joint, or the end effector itself
    elif target_kind == 2:
        target = tuple(rng.uniform(-1e6, 1e6, size=2))  # far out of reach
    else:
        target = tuple(rng.normal(0.0, 150.0, size=2))

    arrival = rng.choice([0.0, 1e-9, 1e-3, 1.0, 10.0, 1e3, float(rng.uniform(0, 50))])
    return bones, target, float(arrival)


def test_ccd_iteration_matches_the_article_on_random_chains():
    rng = np.random.default_rng(20090211)
    seen = dict.fromkeys(SolveStatus, 0)
    for _ in range(3000):
        bones, target, arrival = _random_case(rng)
        want_status, want_angles = _reference(bones, target, arrival)
        status, angles = ccd_iteration(bones, target, arrival)
        assert status is want_status, (bones.tolist(), target, arrival)
        np.testing.assert_allclose(angles, want_angles, rtol=0, atol=1e-9)
        seen[status] += 1
    # The sample must exercise every branch, or agreement proves little.
    assert min(seen.values()) >= 300, seen


def test_ccd_iteration_matches_the_article_when_iterated():
    rng = np.random.default_rng(5)
    for _ in range(100):
        bones, target, arrival = _random_case(rng)
        ref = bones.copy()
        for _ in range(20):
            want_status, ref[:, 2] = _reference(ref, target, arrival)
            status, bones[:, 2] = ccd_iteration(bones, target, arrival)
            assert status is want_status
            np.testing.assert_allclose(bones[:, 2], ref[:, 2], rtol=0, atol=1e-9)
            if status is not SolveStatus.PROCESSING:
                break


# -- worked examples -----------------------------------------------------------------------------


def _iterate(bones, target, arrival, max_iterations=500):
    bones = np.array(bones, dtype=float)
    for used in range(1, max_iterations + 1):
        status, bones[:, 2] = ccd_iteration(bones, target, arrival)
        if status is not SolveStatus.PROCESSING:
            return status, bones, used
    return status, bones, max_iterations


THREE_LINKS = [(0, 0, 0), (100, 0, 0.3), (100, 0, 0.3), (100, 0, 0)]


def test_reachable_target_succeeds_within_a_few_iterations():
    status, bones, used = _iterate(THREE_LINKS, (150, 120), 1e-3)
    assert status is SolveStatus.SUCCESS
    assert used <= 6
    end = _end_effector(bones)
    assert math.dist(end, (150, 120)) <= 1e-3 + 1e-9


def test_first_joint_to_reach_the_target_ends_the_iteration():
    # The last joint alone brings the tip onto the target; the root is never visited, so its
    # angle comes back as given, not wrapped.
    bones = [(0, 0, 2 * PI), (1, 0, 0), (1, 0, 0)]
    status, angles = ccd_iteration(bones, (1, 1), 1e-6)
    assert status is SolveStatus.SUCCESS
    assert angles[0] == 2 * PI
    assert angles[1] == pytest.approx(PI / 2, abs=1e-15)


def test_target_beyond_reach_stretches_the_chain_and_fails():
    target = (1000.0, 500.0)
    status, bones, used = _iterate(THREE_LINKS, target, 0.5)
    assert status is SolveStatus.FAILURE
    assert used < 500
    end = _end_effector(bones)
    assert math.atan2(end[1], end[0]) == pytest.approx(math.atan2(500, 1000), abs=1e-6)
    assert math.hypot(*end) == pytest.approx(300.0, abs=1e-6)
    np.testing.assert_allclose(bones[1:, 2], 0.0, atol=1e-6)


def test_target_on_the_base_gives_finite_angles():
    # Joint 0 sits on the target: zero distance, so the epsilon branch must leave it alone.
    bones = [(0, 0, 0.2), (1, 0, 0), (2, 0, 0)]
    status, angles = ccd_iteration(bones, (0, 0), 1e-3)
    assert status is SolveStatus.PROCESSING
    assert np.all(np.isfinite(angles))
    assert angles[0] == 0.2
    assert abs(angles[1]) == pytest.approx(PI)
    status, bones_after, _ = _iterate(bones, (0, 0), 1e-3)
    assert status is SolveStatus.FAILURE
    assert np.all(np.isfinite(bones_after))


def test_folding_chain_reaches_a_target_on_its_base():
    status, angles = ccd_iteration([(0, 0, 0), (1, 0, 0), (1, 0, 0)], (0, 0), 0.0)
    assert status is SolveStatus.SUCCESS
    assert angles.tolist() == [0.0, PI, 0.0]


def test_epsilon_boundary_is_inclusive():
    # |end - joint| * |target - joint| = 1 * 1e-4 is exactly EPSILON: the article's `<=` skips
    # the joint; a hair further away, the joint turns a quarter turn toward the target.
    bones = [(0, 0, 0), (1, 0, 0)]
    assert ccd_iteration(bones, (0, 1e-4), 0.0)[0] is SolveStatus.FAILURE
    status, angles = ccd_iteration(bones, (0, 1.0001e-4), 0.0)
    assert status is SolveStatus.PROCESSING
    assert angles[0] == pytest.approx(PI / 2)


def test_all_joints_on_one_point_take_the_epsilon_branch():
    bones = [(5, 5, 0.5), (0, 0, -0.5), (0, 0, 1.0)]
    status, angles = ccd_iteration(bones, (100, -3), 1.0)
    assert status is SolveStatus.FAILURE
    assert angles.tolist() == [0.5, -0.5, 1.0]


@pytest.mark.parametrize("arrival", [0.0, 1.0, 1e9])
def test_one_bone_chain_always_fails_and_changes_nothing(arrival):
    # The article's joint loop starts at numBones - 2 = -1: no joint is visited, so not even a
    # target lying on the end effector counts as success, and the angle is not wrapped.
    status, angles = ccd_iteration([(3, 4, 10.0)], (3, 4), arrival)
    assert status is SolveStatus.FAILURE
    assert angles.tolist() == [10.0]


def test_end_effector_bone_angle_is_never_changed():
    status, angles = ccd_iteration([(0, 0, 0), (1, 0, 0), (1, 0, 9.0)], (0, 1.5), 1e-6)
    assert status is SolveStatus.PROCESSING
    assert angles[-1] == 9.0


def test_input_is_not_mutated():
    bones = np.array(THREE_LINKS, dtype=float)
    before = bones.copy()
    status, angles = ccd_iteration(bones, (150, 120), 1e-3)
    np.testing.assert_array_equal(bones, before)
    assert not np.shares_memory(angles, bones)
    as_lists = [list(row) for row in THREE_LINKS]
    ccd_iteration(as_lists, (150, 120), 1e-3)
    assert as_lists == [list(row) for row in THREE_LINKS]


def test_accepts_tuples_and_integer_input():
    status, angles = ccd_iteration(((0, 0, 0), (1, 0, 0), (1, 0, 0)), [1, 1], 0)
    assert status is SolveStatus.SUCCESS
    assert angles.dtype == np.float64


# -- wrap_angle ----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("angle", "expected"),
    [
        (0.0, 0.0),
        (PI, PI),  # the boundary stays where it is on both sides
        (-PI, -PI),  # Python's % would give +pi here
        (3 * PI, PI),
        (-3 * PI, -PI),
        (2 * PI, 0.0),
        (7.0, 7.0 - 2 * PI),
        (-7.0, -7.0 + 2 * PI),
        (4.0, 4.0 - 2 * PI),
        (-4.0, -4.0 + 2 * PI),
        (1.5 * PI, -0.5 * PI),
        (-1.5 * PI, 0.5 * PI),
    ],
)
def test_wrap_angle_edge_cases(angle, expected):
    assert wrap_angle(angle) == pytest.approx(expected, abs=1e-15)
    assert wrap_angle(angle) == _simplify_angle(angle)


def test_wrap_angle_keeps_the_sign_of_zero_like_fmod():
    assert math.copysign(1.0, wrap_angle(-2 * PI)) == -1.0
    assert math.copysign(1.0, wrap_angle(-0.0)) == -1.0
    assert math.copysign(1.0, wrap_angle(2 * PI)) == 1.0


def test_wrap_angle_propagates_nan():
    assert math.isnan(wrap_angle(math.nan))


@settings(derandomize=True, max_examples=300, deadline=None)
@given(st.floats(-1e12, 1e12))
def test_wrap_angle_is_the_articles_and_lands_in_range(angle):
    wrapped = wrap_angle(angle)
    assert wrapped == _simplify_angle(angle)
    assert -PI <= wrapped <= PI
    assert wrap_angle(wrapped) == wrapped


@settings(derandomize=True, max_examples=200, deadline=None)
@given(st.floats(-100.0, 100.0))
def test_wrap_angle_is_the_same_rotation(angle):
    wrapped = wrap_angle(angle)
    assert math.cos(wrapped) == pytest.approx(math.cos(angle), abs=1e-12)
    assert math.sin(wrapped) == pytest.approx(math.sin(angle), abs=1e-12)


# -- bad input -----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("bones", "message"),
    [
        ([], r"bones must have shape \(n, 3\) of \(x, y, angle\), got shape \(0,\)"),
        (np.empty((0, 3)), r"bones must hold at least one bone, got none"),
        ([1.0, 2.0, 3.0], r"bones must have shape \(n, 3\).*got shape \(3,\)"),
        ([[1.0, 2.0]], r"bones must have shape \(n, 3\).*got shape \(1, 2\)"),
        ([[1.0, 2.0, 3.0, 4.0]], r"bones must have shape \(n, 3\).*got shape \(1, 4\)"),
        (np.zeros((2, 3, 1)), r"bones must have shape \(n, 3\).*got shape \(2, 3, 1\)"),
        ([[0, 0, 0], [1, 0]], r"bones must be rows of numbers \(x, y, angle\)"),
        ([["a", 0, 0]], r"bones must be rows of numbers \(x, y, angle\)"),
        ([[0, 0, 0], [np.nan, 0, 0]], r"bones must be finite \(no NaN or infinity\)"),
        ([[0, 0, 0], [1, np.inf, 0]], r"bones must be finite \(no NaN or infinity\)"),
        ([[0, 0, -np.inf], [1, 0, 0]], r"bones must be finite \(no NaN or infinity\)"),
    ],
)
def test_ccd_iteration_rejects_bad_bones(bones, message):
    with pytest.raises(ValueError, match=message):
        ccd_iteration(bones, (1.0, 1.0), 0.1)


@pytest.mark.parametrize(
    ("target", "message"),
    [
        ((np.nan, 0.0), r"target must be finite"),
        ((0.0, np.inf), r"target must be finite"),
        ((1.0, 2.0, 3.0), r"target must have shape \(2,\), got shape \(3,\)"),
        (1.0, r"target must have shape \(2,\), got shape \(\)"),
        (("x", "y"), r"target must be a pair of numbers \(x, y\)"),
    ],
)
def test_ccd_iteration_rejects_bad_targets(target, message):
    with pytest.raises(ValueError, match=message):
        ccd_iteration(THREE_LINKS, target, 0.1)


@pytest.mark.parametrize("arrival", [-1e-9, -1.0, math.nan, math.inf])
def test_ccd_iteration_rejects_bad_arrival_distances(arrival):
    with pytest.raises(ValueError, match=r"arrival distance must be finite and >= 0 px"):
        ccd_iteration(THREE_LINKS, (1.0, 1.0), arrival)


def test_solve_ccd_rejects_bad_arguments():
    chain = Skeleton.chain([1.0, 1.0])
    with pytest.raises(ValueError, match=r"max_iterations must be >= 1, got 0"):
        solve_ccd(chain, np.zeros(2), np.array([1.0, 1.0]), max_iterations=0)
    with pytest.raises(ValueError, match=r"target must be finite"):
        solve_ccd(chain, np.zeros(2), np.array([np.nan, 1.0]))
    with pytest.raises(ValueError, match=r"arrival distance must be finite and >= 0 px"):
        solve_ccd(chain, np.zeros(2), np.array([1.0, 1.0]), tolerance=-1.0)
    tree = Skeleton(
        lengths=np.ones(3),
        parents=np.array([-1, 0, 0]),
        lower=np.full(3, -np.inf),
        upper=np.full(3, np.inf),
        base=np.zeros(2),
    )
    with pytest.raises(ValueError, match=r"this solver needs a serial chain"):
        solve_ccd(tree, np.zeros(3), np.array([1.0, 1.0]))


# -- the limit-aware iteration -------------------------------------------------------------------


def _as_bones(skeleton: Skeleton, angles: np.ndarray) -> np.ndarray:
    lengths = skeleton.lengths
    bones = [(skeleton.base[0], skeleton.base[1], angles[0])]
    bones += [(lengths[i - 1], 0.0, angles[i]) for i in range(1, skeleton.count)]
    bones.append((lengths[-1], 0.0, 0.0))
    return np.array(bones)


def test_limited_iteration_equals_the_article_on_free_chains():
    rng = np.random.default_rng(31)
    for _ in range(1000):
        n = int(rng.integers(1, 10))
        skeleton = Skeleton.chain(rng.uniform(0.5, 80.0, size=n), base=rng.normal(0, 50, size=2))
        angles = rng.uniform(-PI, PI, size=n) if rng.random() < 0.7 else rng.uniform(-20, 20, n)
        target = rng.normal(0.0, 120.0, size=2) if rng.random() < 0.8 else skeleton.base.copy()
        arrival = float(rng.choice([0.0, 1e-3, 1.0, 25.0]))
        status, new = ccd_iteration_limited(skeleton, angles, target, arrival)
        want_status, want = ccd_iteration(_as_bones(skeleton, angles), target, arrival)
        assert status is want_status
        np.testing.assert_array_equal(new, want[:n])


def test_limited_iteration_clamps_instead_of_wrapping():
    # 2.9 rad plus the 0.5 rad CCD asks for is 3.4 rad, which wraps to -2.88: inside the
    # limits, but reaching it would swing the joint through its 3 rad stop.
    target = np.array([math.cos(3.4), math.sin(3.4)])
    limited = Skeleton.chain([1.0], limits=[(-3.0, 3.0)])
    status, angles = ccd_iteration_limited(limited, np.array([2.9]), target, 1e-6)
    assert angles.tolist() == [3.0]
    assert status is SolveStatus.PROCESSING
    free = Skeleton.chain([1.0])
    status, angles = ccd_iteration_limited(free, np.array([2.9]), target, 1e-6)
    assert angles[0] == pytest.approx(3.4 - 2 * PI)
    assert status is SolveStatus.SUCCESS


def test_limited_iteration_moves_the_end_by_the_clamped_rotation():
    # Joint 1 is stopped at 0.5 rad; joint 0 must then aim the tip from where it really is.
    skeleton = Skeleton.chain([1.0, 1.0], limits=[None, (-0.5, 0.5)])
    target = np.array([0.0, 2.0])
    status, angles = ccd_iteration_limited(skeleton, np.zeros(2), target, 1e-9)
    assert angles[1] == 0.5
    points, _ = forward_kinematics(skeleton, angles)
    direction = points[-1] - points[0]
    assert math.atan2(direction[1], direction[0]) == pytest.approx(PI / 2, abs=1e-12)


@pytest.mark.parametrize(
    ("angles", "message"),
    [
        # np.clip would broadcast a single angle to every joint; it must be rejected instead.
        (np.zeros(1), r"angles must have shape \(2,\), got shape \(1,\)"),
        (np.zeros(3), r"angles must have shape \(2,\), got shape \(3,\)"),
        (np.array([np.nan, 0.0]), r"angles must be finite"),
    ],
)
def test_solve_ccd_rejects_a_bad_warm_start(angles, message):
    with pytest.raises(ValueError, match=message):
        solve_ccd(Skeleton.chain([1.0, 1.0]), angles, np.array([1.0, 1.0]))


def test_pinned_chain_fails_at_once():
    skeleton = Skeleton.chain([1.0, 1.0], limits=[(0.0, 0.0), (0.5, 0.5)])
    solution = solve_ccd(skeleton, np.zeros(2), np.array([0.0, 2.0]))
    assert solution.status is SolveStatus.FAILURE
    assert solution.iterations == 1
    assert solution.angles.tolist() == [0.0, 0.5]


def test_solve_ccd_clamps_the_warm_start():
    skeleton = Skeleton.chain([1.0, 1.0], limits=[(-0.1, 0.1), (-0.2, 0.2)])
    solution = solve_ccd(skeleton, np.array([5.0, -5.0]), np.array([-3.0, 0.0]), max_iterations=1)
    assert -0.1 <= solution.angles[0] <= 0.1
    assert -0.2 <= solution.angles[1] <= 0.2


def test_solve_ccd_reaches_a_reachable_target():
    skeleton = Skeleton.chain([100, 100, 100])
    solution = solve_ccd(skeleton, np.zeros(3), np.array([150.0, 120.0]), tolerance=0.5)
    assert solution.status is SolveStatus.SUCCESS
    assert 1 <= solution.iterations <= 10
    assert solution.error <= 0.5
    points, _ = forward_kinematics(skeleton, solution.angles)
    assert math.dist(points[-1], (150.0, 120.0)) == pytest.approx(solution.error)


def test_solve_ccd_leaves_an_arrived_pose_alone():
    # Unlike the article's iteration, which would still turn the last joint onto the target,
    # the loop returns a pose already within tolerance as it is, with zero iterations.
    skeleton = Skeleton.chain([100, 100])
    angles = np.array([0.3, 0.4])
    points, _ = forward_kinematics(skeleton, angles)
    target = points[-1] + [0.6, 0.0]
    solution = solve_ccd(skeleton, angles, target, tolerance=1.0)
    assert solution.status is SolveStatus.SUCCESS
    assert solution.iterations == 0
    assert solution.angles.tolist() == angles.tolist()
    assert solution.error == pytest.approx(0.6)
    # Straightening a bent chain by a fraction of a pixel is CCD's slow case: give it room.
    moved = solve_ccd(skeleton, angles, target, tolerance=0.1, max_iterations=100)
    assert moved.status is SolveStatus.SUCCESS
    assert 1 <= moved.iterations < 100
    assert moved.error <= 0.1


def test_solve_ccd_out_of_reach():
    skeleton = Skeleton.chain([100, 100, 100], base=(10.0, 20.0), base_angle=1.0)
    target = np.array([1010.0, 520.0])
    short = solve_ccd(skeleton, np.zeros(3), target)
    assert short.status is SolveStatus.PROCESSING
    assert short.iterations == 10
    long = solve_ccd(skeleton, np.zeros(3), target, max_iterations=500)
    assert long.status is SolveStatus.FAILURE
    assert long.error == pytest.approx(math.hypot(1000, 500) - 300, abs=1e-6)
    points, world = forward_kinematics(skeleton, long.angles)
    np.testing.assert_allclose(world, math.atan2(500, 1000), atol=1e-6)


# -- properties ----------------------------------------------------------------------------------

_coord = st.floats(-100.0, 100.0, allow_nan=False)
_bone = st.tuples(_coord, _coord, st.floats(-1e3, 1e3))
_target = st.one_of(
    st.tuples(st.floats(-500.0, 500.0), st.floats(-500.0, 500.0)),
    st.tuples(st.floats(-1e6, 1e6), st.floats(-1e6, 1e6)),
)
_arrival = st.one_of(st.just(0.0), st.floats(0.0, 50.0))


@settings(derandomize=True, max_examples=200, deadline=None)
@given(st.lists(_bone, min_size=1, max_size=10), _target, _arrival)
def test_visited_joints_end_in_range_and_the_rest_are_untouched(bones, target, arrival):
    # The article wraps only the joints its pass visits (n-2 down to wherever it succeeds) and
    # never touches the end effector bone, so an angle out of [-pi, pi] in the output must be
    # an input angle the pass stopped short of.
    status, angles = ccd_iteration(bones, target, arrival)
    before = [b[2] for b in bones]
    assert angles[-1] == before[-1]
    for i in range(len(bones) - 1):
        if not -PI <= angles[i] <= PI:
            assert status is SolveStatus.SUCCESS
            assert angles[: i + 1].tolist() == before[: i + 1]


@settings(derandomize=True, max_examples=200, deadline=None)
@given(
    st.lists(st.tuples(_coord, _coord, st.floats(-2 * PI, 2 * PI)), min_size=1, max_size=10),
    _target,
    _arrival,
)
def test_all_joints_wrapped_when_the_pass_completes(bones, target, arrival):
    status, angles = ccd_iteration(bones, target, arrival)
    if status is not SolveStatus.SUCCESS:
        assert all(-PI <= a <= PI for a in angles[:-1])
        assert all(a == _simplify_angle(a) for a in angles[:-1])


@settings(derandomize=True, max_examples=200, deadline=None)
@given(
    st.lists(st.tuples(_coord, _coord, st.floats(-2 * PI, 2 * PI)), min_size=1, max_size=10),
    st.tuples(st.floats(-500.0, 500.0), st.floats(-500.0, 500.0)),
)
def test_one_iteration_never_moves_the_end_further_from_the_target(bones, target):
    _, angles = ccd_iteration(bones, target, 0.0)
    after = [(x, y, a) for (x, y, _), a in zip(bones, angles, strict=True)]
    before_error = math.dist(_end_effector(bones), target)
    after_error = math.dist(_end_effector(after), target)
    assert after_error <= before_error + 1e-9


_limit = st.one_of(
    st.none(),
    st.tuples(st.floats(-PI, PI), st.floats(0.0, PI)).map(lambda t: (t[0], t[0] + t[1])),
    st.tuples(st.floats(-4.0, 0.0), st.floats(0.0, 4.0)),
    st.floats(-PI, PI).map(lambda hi: (-math.inf, hi)),
    st.floats(-PI, PI).map(lambda lo: (lo, math.inf)),
)


@st.composite
def _limited_problem(draw):
    n = draw(st.integers(1, 8))
    lengths = draw(st.lists(st.floats(1.0, 100.0), min_size=n, max_size=n))
    limits = draw(st.lists(_limit, min_size=n, max_size=n))
    base = draw(st.tuples(_coord, _coord))
    base_angle = draw(st.floats(-PI, PI))
    skeleton = Skeleton.chain(lengths, base=base, base_angle=base_angle, limits=limits)
    angles = np.array(draw(st.lists(st.floats(-10.0, 10.0), min_size=n, max_size=n)))
    target = np.array(draw(_target))
    if draw(st.booleans()):
        target = skeleton.base.copy()
    iterations = draw(st.integers(1, 30))
    tolerance = draw(_arrival)
    return skeleton, angles, target, iterations, tolerance


@settings(derandomize=True, max_examples=200, deadline=None)
@given(_limited_problem())
def test_solve_ccd_respects_limits_and_stays_finite(problem):
    skeleton, angles, target, iterations, tolerance = problem
    solution = solve_ccd(skeleton, angles, target, max_iterations=iterations, tolerance=tolerance)
    assert solution.angles.shape == (skeleton.count,)
    assert not np.any(np.isnan(solution.angles))
    assert np.all(np.isfinite(solution.angles))
    assert np.all(solution.angles >= skeleton.lower)
    assert np.all(solution.angles <= skeleton.upper)
    assert math.isfinite(solution.error)
    assert 0 <= solution.iterations <= iterations
    if solution.iterations == 0:
        assert solution.status is SolveStatus.SUCCESS
        np.testing.assert_array_equal(solution.angles, skeleton.clamp(angles))
    if solution.status is SolveStatus.SUCCESS:
        assert solution.error <= tolerance + 1e-9
    # The loop tracks the error through the pass instead of running FK again: the two agree.
    points, _ = forward_kinematics(skeleton, solution.angles)
    assert solution.error == pytest.approx(math.dist(points[-1], target), rel=1e-9, abs=1e-6)
    if solution.status is SolveStatus.PROCESSING:
        assert solution.iterations == iterations


@pytest.mark.parametrize("target", [(150.0, 0.0), (-150.0, 0.0), (0.0, 0.0)])
def test_solve_ccd_escapes_a_straight_chain_aimed_along_its_own_line(target):
    # Every joint sees the end and the target on one ray: plain CCD has nothing to rotate.
    chain = Skeleton.chain([100.0, 100.0, 100.0])
    angles, status = np.zeros(3), SolveStatus.PROCESSING
    for _ in range(20):
        status, angles = ccd_iteration_limited(chain, angles, np.array(target), 0.5)
        if status is not SolveStatus.PROCESSING:
            break
    assert status is SolveStatus.FAILURE
    solution = solve_ccd(chain, np.zeros(3), np.array(target), max_iterations=20, tolerance=0.5)
    assert solution.status is SolveStatus.SUCCESS
    assert solution.error <= 0.5
