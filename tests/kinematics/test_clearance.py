import math
from collections.abc import Generator
from typing import TypeVar

import numpy as np
import pytest

from ikgame.kinematics import (
    Skeleton,
    Solution,
    SolveStatus,
    TargetSet,
    clearance,
    forward_kinematics,
)
from ikgame.kinematics.clearance import (
    ITERATION_UNITS,
    LEAD,
    PINNED_S,
    SEARCH_RATE,
    SLIDE_ROOM,
    SLIDE_STEP,
    TREE_FIRST,
    Avoider,
    Clearance,
    Obstacles,
    _capped,
    _finish,
    _least_gap,
)

UP = math.pi / 2
NO_CIRCLES = np.empty((0, 3))
NO_SEGMENTS = np.empty((0, 5))


def _shelf_room() -> Clearance:
    """Three 120 px links mounted straight up, a floor 20 px below the base, and a shelf 130 px
    up to the right (the stress level under a shelf)."""
    arm = Skeleton.chain([120.0, 120.0, 120.0], base_angle=UP, limits=[(-2.618, 2.618)] * 3)
    obstacles = Obstacles.from_arrays(
        np.array([[-400.0, -20.0, 500.0, -20.0, 0.0], [130.0, 130.0, 420.0, 130.0, 6.0]]),
        NO_CIRCLES,
    )
    return Clearance(arm, np.full(3, 6.0), obstacles)


def _sampled_gaps(room: Clearance, angles: np.ndarray) -> np.ndarray:
    """Each link's gap by brute force: 400 points along the link against 400 along each
    obstacle, signed negative when the centre lines cross (within the sampling's precision)."""
    pts = room.points(angles)
    u = np.linspace(0.0, 1.0, 400)[:, None]
    gaps = []
    for i in range(room.skeleton.count):
        link = pts[i] + u * (pts[i + 1] - pts[i])
        best = math.inf
        for ax, ay, bx, by, r in room.obstacles.capsules:
            obstacle = np.array([ax, ay]) + u * np.array([bx - ax, by - ay])
            d = np.hypot(*(link[:, None, :] - obstacle[None, :, :]).T).min()
            best = min(best, d - room.radii[i] - r)
        gaps.append(best)
    return np.array(gaps)


def _move_as_told(
    guide: Avoider,
    measured: np.ndarray,
    answer: Solution,
    target: np.ndarray | TargetSet,
    ticks: int,
) -> np.ndarray:
    """The pose after following the avoider's commands for ``ticks`` ticks as a skeleton with
    ideal motors would (straight in joint space, 0.05 rad a tick at most), each command
    checked to be a clear straight line from where the skeleton is."""
    for _ in range(ticks):
        command = guide.steer(measured, answer, target, 0.5)
        assert guide.clearance.path_clear(measured, command.angles)
        step = command.angles - measured
        measured = measured + step * min(1.0, 0.05 / max(np.abs(step).max(), 1e-12))
    return measured


def test_obstacles_take_segments_and_circles_and_reject_bad_arrays():
    obs = Obstacles.from_arrays(np.array([[0, 0, 1, 0, 2]]), np.array([[3, 4, 5]]))
    assert obs.capsules.tolist() == [[0, 0, 1, 0, 2], [3, 4, 3, 4, 5]]
    assert len(Obstacles.from_arrays(NO_SEGMENTS, NO_CIRCLES)) == 0
    with pytest.raises(ValueError, match="segments"):
        Obstacles.from_arrays(np.zeros((1, 4)), NO_CIRCLES)
    with pytest.raises(ValueError, match="radii"):
        Obstacles.from_arrays(np.array([[0, 0, 1, 0, -1]]), NO_CIRCLES)


def test_gaps_of_a_link_beside_a_segment_and_a_disc():
    arm = Skeleton.chain([100.0])  # along +x from the origin
    obstacles = Obstacles.from_arrays(
        np.array([[20.0, 30.0, 80.0, 30.0, 2.0]]), np.array([[150.0, 0.0, 10.0]])
    )
    room = Clearance(arm, np.array([5.0]), obstacles)
    assert room.gaps(np.zeros(1)).tolist() == pytest.approx([30.0 - 5.0 - 2.0])
    # Turned up 90 deg the link passes the segment's left end 20 px away, and the disc is far.
    assert room.gaps(np.array([UP])).tolist() == pytest.approx([20.0 - 5.0 - 2.0])


def test_a_link_through_an_obstacle_has_a_negative_gap():
    room = _shelf_room()
    straight_right = np.array([-UP, 0.0, 0.0])
    assert room.gaps(straight_right).min() >= 0.0  # lying along y = 0, under the shelf
    through = np.array([-0.9, 0.0, 0.0])  # pointing up-right, through the shelf
    assert room.gaps(through).min() < -6.0
    assert not room.is_clear(through)


def test_gaps_match_brute_force_sampling():
    room = _shelf_room()
    rng = np.random.default_rng(5)
    for pose in rng.uniform(-2.5, 2.5, (40, 3)):
        exact = room.gaps(pose)
        sampled = _sampled_gaps(room, pose)
        clear = sampled > 0.0
        # Sampling only overestimates a distance, by at most a sample spacing (about 2 px).
        assert np.all(exact[clear] <= sampled[clear] + 1e-9)
        assert np.all(exact[clear] >= sampled[clear] - 2.5)
        # Overlapping links (sampled distance inside the radii) are negative exactly too.
        assert np.all(exact[sampled < -1.0] < 0.0)


def test_batch_gaps_equal_the_single_pose_gaps():
    room = _shelf_room()
    poses = np.random.default_rng(6).uniform(-2.5, 2.5, (25, 3))
    batch = room.smallest_gaps(poses)
    assert batch.tolist() == pytest.approx([room.gaps(p).min() for p in poses])


@pytest.mark.parametrize("tree", [False, True])
def test_gaps_among_discs_and_segments_are_the_least_of_each_alone(tree):
    # Discs are measured apart from segments (no ends of their own, nothing crosses them).
    segments = np.array([[-400.0, -20.0, 500.0, -20.0, 0.0], [130.0, 130.0, 420.0, 130.0, 6.0]])
    discs = np.array([[60.0, 150.0, 25.0], [-120.0, 90.0, 40.0]])
    if tree:
        sk = Skeleton.tree([120.0, 90.0, 90.0], [-1, 0, 0], base_angle=UP)
    else:
        sk = Skeleton.chain([120.0, 120.0, 120.0], base_angle=UP)
    radii = np.full(sk.count, 6.0)
    room = Clearance(sk, radii, Obstacles.from_arrays(segments, discs))
    alone = [Clearance(sk, radii, Obstacles.from_arrays(s[None], NO_CIRCLES)) for s in segments]
    alone += [Clearance(sk, radii, Obstacles.from_arrays(NO_SEGMENTS, d[None])) for d in discs]
    poses = np.random.default_rng(8).uniform(-2.5, 2.5, (30, sk.count))
    least = np.min([other._link_gaps(poses) for other in alone], axis=0)
    assert np.array_equal(room._link_gaps(poses), least)
    assert np.array_equal([room.gaps(p) for p in poses], least)
    some = np.array([0, 2])
    assert np.array_equal(room._gaps(room.points(poses), some), least[:, some])


def test_swept_bounds_how_far_any_point_moves():
    room = _shelf_room()
    rng = np.random.default_rng(7)
    for _ in range(20):
        a, b = rng.uniform(-2.5, 2.5, (2, 3))
        line = a + np.linspace(0.0, 1.0, 200)[:, None] * (b - a)
        pts = room.points(line)
        moved = np.hypot(*(pts - pts[0]).T).max()
        assert moved <= room.swept(a, b) + 1e-9


def test_swept_links_bounds_each_links_own_move_and_never_exceeds_swept():
    arms = Skeleton.tree([100.0, 80.0, 60.0, 80.0], [-1, 0, 1, 0], base_angle=UP)
    room = Clearance(arms, np.full(4, 5.0), Obstacles.from_arrays(NO_SEGMENTS, NO_CIRCLES))
    rng = np.random.default_rng(8)
    for _ in range(20):
        a, b = rng.uniform(-2.5, 2.5, (2, 4))
        line = a + np.linspace(0.0, 1.0, 200)[:, None] * (b - a)
        off = room.points(line) - room.points(a)  # link starts, then link ends
        moved = np.hypot(off[..., 0], off[..., 1]).max(axis=0)
        # A point inside a link moves by a blend of its ends' moves: no farther than they do.
        each = room.swept_links(a, b)
        assert np.all(np.maximum(moved[:4], moved[4:]) <= each + 1e-9)
        assert each.max() <= room.swept(a, b) + 1e-9
    # Turning only the second arm moves neither the torso nor the first arm.
    assert room.swept_links(np.zeros(4), np.array([0.0, 0.0, 0.0, 1.0])).tolist() == [
        0.0,
        0.0,
        0.0,
        80.0,
    ]


def test_a_torso_on_the_floor_does_not_hold_its_swinging_arm_to_measuring_again(monkeypatch):
    floor = Obstacles.from_arrays(np.array([[-500.0, -20.0, 500.0, -20.0, 0.0]]), NO_CIRCLES)
    # A torso standing 2 px above the floor, and an arm swinging high above it.
    torso = Skeleton.tree([100.0, 80.0], [-1, 0], base_angle=UP, limits=[(-0.5, 0.5), None])
    room = Clearance(torso, np.array([18.0, 5.0]), floor)
    guide = Avoider(room)
    calls = []
    measure = room.gaps
    monkeypatch.setattr(room, "gaps", lambda angles: calls.append(1) or measure(angles))
    aim = TargetSet([1], [(-60.0, 150.0)])
    for swing in np.linspace(0.0, 1.0, 30):
        pose = np.array([0.0, swing])
        answer = Solution(np.array([0.0, swing + 0.05]), SolveStatus.SUCCESS, 3, 1.0)
        assert guide.steer(pose, answer, aim, 0.5) is answer
    assert len(calls) == 1


def test_polish_turns_an_answer_through_the_shelf_into_a_clear_one_that_arrives():
    room = _shelf_room()
    target = np.array([290.0, 45.0])  # under the shelf, near its far end
    through = np.array([-0.3, -1.2, -0.6])
    assert not room.is_clear(through)
    sol = room.polish(through, target, tolerance=0.5)
    assert sol.status is SolveStatus.SUCCESS
    assert room.is_clear(sol.angles)
    assert np.hypot(*(room.points(sol.angles)[-1] - target)) <= 0.5
    assert np.all(sol.angles >= room.skeleton.lower) and np.all(sol.angles <= room.skeleton.upper)


@pytest.mark.parametrize("target", [(149.1, 16.2), (-150.0, 100.0), (175.7, 143.5)])
def test_a_long_chain_polished_toward_a_far_target_gets_there_in_short_steps(target):
    # One long damped step toward a far target flings sixty light links into the floor, the
    # polish never improves on its start and gives up where it began, 300 px short.
    arm = Skeleton.chain([6.0] * 60, base_angle=UP, limits=[(-1.745, 1.745)] * 60)
    floor = Obstacles.from_arrays(np.array([[-2000.0, -20.0, 2000.0, -20.0, 0.0]]), NO_CIRCLES)
    room = Clearance(arm, np.full(60, 5.0), floor)
    high = room.polish(np.zeros(60), np.array([45.9, 321.7])).angles
    sol = room.polish(high, np.array(target))
    assert sol.status is SolveStatus.SUCCESS
    assert room.is_clear(sol.angles)
    assert room.path_clear(high, sol.angles)


def test_clear_answer_beside_a_shelfs_end_comes_from_a_random_seed_near_the_target():
    # Three 140 px links and a shelf to the left: from the arm's pose to the right, and from
    # the solver's answer through the shelf, every deliberate seed's polish hooks a link round
    # the shelf's end and stalls; so do random poses drawn anywhere, but not the ones nearest.
    arm = Skeleton.chain([140.0] * 3, base_angle=UP, limits=[(-2.618, 2.618)] * 3)
    obstacles = Obstacles.from_arrays(
        np.array([[-600.0, -20.0, 500.0, -20.0, 0.0], [-480.0, 150.0, -150.0, 150.0, 6.0]]),
        NO_CIRCLES,
    )
    room = Clearance(arm, np.full(3, 6.0), obstacles)
    measured = np.radians([-0.1, 7.7, -88.7])
    through = np.radians([104.5, -36.0, -144.6])
    target = np.array([-130.0, 50.0])
    found = room.clear_answer(measured, through, target, 0.5)
    assert found is not None
    assert room.is_clear(found)
    assert room.misses(found, target)[0] <= 0.5


def test_clear_answer_reaches_under_the_shelf_and_gives_up_inside_an_obstacle():
    room = _shelf_room()
    measured = np.array([0.5, 0.3, 0.2])  # up and to the left, clear
    for target in ([200.0, 50.0], [290.0, 45.0], [170.0, 40.0]):
        pose = room.clear_answer(measured, measured, np.array(target), 0.5)
        assert pose is not None
        assert room.is_clear(pose)
        assert np.hypot(*(room.points(pose)[-1] - target)) <= 0.5
    inside_the_shelf = np.array([250.0, 130.0])
    assert room.clear_answer(measured, measured, inside_the_shelf, 0.5) is None


def test_clear_answer_folds_a_chain_in_a_low_corridor_to_reach_near_its_base():
    # Ten 34 px links pointing along a corridor 58 px high: 340 px of chain into the first
    # 160 px of it takes a zig-zag of every joint, which no polish of the answer, the curls or
    # the random poses found.
    arm = Skeleton.chain([34.0] * 10, limits=[(-2.443, 2.443)] * 10)
    walls = np.array([[-200.0, -30.0, 560.0, -30.0, 4.0], [-200.0, 36.0, 560.0, 36.0, 4.0]])
    room = Clearance(arm, np.full(10, 5.0), Obstacles.from_arrays(walls, NO_CIRCLES))
    stretched = np.zeros(10)
    for target in ([160.0, 0.0], [180.0, -12.0]):
        pose = room.clear_answer(stretched, stretched, np.array(target), 1.0)
        assert pose is not None
        assert room.is_clear(pose)
        assert np.hypot(*(room.points(pose)[-1] - target)) <= 1.0


def test_clear_answer_over_a_shelf_starts_from_one_found_for_an_earlier_target_there():
    # Eleven 33 px links folded under a thin shelf to the left; (-230, 150) lies over its far
    # side. Every seed of the target's own (the chain's pose, the solver's answer, its bends
    # reversed, the curls, the random poses, the zig-zags) stalls short of it or ends in the
    # shelf; the clear answer found for (-130, 155), over the shelf too, polishes onto it.
    arm = Skeleton.chain([33.0] * 11, base_angle=math.pi / 2, limits=[(-2.653, 2.653)] * 11)
    walls = np.array([[-550.0, -20.0, 550.0, -20.0, 0.0], [-45.0, 108.0, -275.0, 108.0, 2.0]])
    under = np.radians([-36.0, -16.0, 13.0, 38.0, 51.0, 45.0, 26.0, 3.0, -13.0, 1.0, -3.0])
    answer = np.radians([-15.0, 5.0, 32.0, 52.0, 46.0, 17.0, -18.0, -46.0, -46.0, 0.0, 31.0])
    far = np.array([-230.0, 150.0])

    def room() -> Clearance:
        return Clearance(arm, np.full(11, 4.5), Obstacles.from_arrays(walls, NO_CIRCLES))

    assert room().clear_answer(under, answer, far, 0.5) is None
    earlier = room()
    over = earlier.clear_answer(np.zeros(11), np.zeros(11), np.array([-130.0, 155.0]), 0.5)
    assert over is not None
    assert np.array_equal(earlier.seeds(under, answer, far)[-1], over)
    pose = earlier.clear_answer(under, answer, far, 0.5)
    assert pose is not None
    assert earlier.is_clear(pose) and earlier.misses(pose, far)[0] <= 0.5


def test_clear_answer_is_one_the_motors_hold_when_a_seed_arrives_at_one():
    # Two links and a floor far below: the target is reached with the elbow bent either way,
    # both clear. A stand-in strain the motors hold only with the elbow bent down (negative):
    # from the elbow-up answer, the clear answer is the elbow-down one; with no pose they hold,
    # the clear one they do not.
    arm = Skeleton.chain([100.0, 100.0], base_angle=0.0, limits=[(-2.6, 2.6)] * 2)
    floor = Obstacles.from_arrays(np.array([[-500.0, -300.0, 500.0, -300.0, 0.0]]), NO_CIRCLES)
    room = Clearance(arm, np.full(2, 5.0), floor)
    target = np.array([120.0, 60.0])
    up = room.polish(np.array([-0.3, 1.2]), target).angles
    assert up[1] > 0.0 and room.misses(up, target)[0] <= 0.5
    assert room.clear_answer(up, up, target, 0.5)[1] > 0.0
    room.strain = lambda angles: 2.0 if angles[1] > 0.0 else 0.5
    held = room.clear_answer(up, up, target, 0.5)
    assert held[1] < 0.0 and room.misses(held, target)[0] <= 0.5 and room.is_clear(held)
    room.strain = lambda angles: 2.0
    assert room.clear_answer(up, up, target, 0.5)[1] > 0.0


def _assert_clear_route(room, start, goal, way):
    """``way`` ends on ``goal`` and each of its straight pieces from ``start`` on is clear."""
    assert way is not None
    assert np.array_equal(way[-1], goal)
    for a, b in zip([start, *way], way, strict=False):
        assert room.path_clear(a, b)


def test_route_goes_round_the_shelf_in_clear_straight_pieces():
    room = _shelf_room()
    start = np.array([0.5, 0.3, 0.2])  # up-left
    goal = room.clear_answer(start, start, np.array([290.0, 45.0]), 0.5)
    assert not room.path_clear(start, goal)  # straight there sweeps the arm through the shelf
    _assert_clear_route(room, start, goal, room.route(start, goal))


def test_a_clear_answer_no_way_leads_to_is_traded_for_a_clear_answer_of_the_seeds(monkeypatch):
    room = _shelf_room()
    start = np.array([0.5, 0.3, 0.2])  # up-left
    target = np.array([290.0, 45.0])
    found = room.clear_answer(start, start, target, 0.5)
    polished = [room.polish(seed, target) for seed in room.seeds(start, start, target)]
    shut_in = next(
        sol.angles
        for sol in polished
        if sol.status is SolveStatus.SUCCESS and np.abs(sol.angles - found).max() > 0.5
    )
    assert room.is_clear(shut_in) and not room.path_clear(start, shut_in)
    connect = Clearance._connect

    def no_way_to_it(self, a, b, slide=False):
        if np.array_equal(b, shut_in):  # as if the limits shut it in behind the shelf
            yield ITERATION_UNITS
            return None
        return (yield from connect(self, a, b, slide=slide))

    monkeypatch.setattr(Clearance, "_connect", no_way_to_it)
    guide = Avoider(room, budget=math.inf)
    solver = Solution(shut_in, SolveStatus.SUCCESS, 1, 0.0)
    steered = guide.steer(start, solver, target, 0.5)
    # Given up on, the target would get the solver's answer, through the shelf.
    assert not guide.planning
    assert not np.array_equal(steered.angles, shut_in)
    assert room.path_clear(start, steered.angles)


def test_a_chain_hooked_round_a_shelfs_end_gets_a_way_in_under_it_within_half_a_second():
    # Four 100 px links (the stress level under a low shelf): the second link stands up past
    # the shelf's near end, the last two fold back down beside it, and the target is 100 px in
    # under the shelf. Random poses almost never fall in the narrow band under it.
    arm = Skeleton.chain([100.0] * 4, base_angle=UP, limits=[(-2.618, 2.618)] * 4)
    obstacles = Obstacles.from_arrays(
        np.array([[-500.0, -20.0, 600.0, -20.0, 4.0], [120.0, 110.0, 450.0, 110.0, 6.0]]),
        NO_CIRCLES,
    )
    room = Clearance(arm, np.full(4, 6.0), obstacles)
    hooked = np.radians([-64.0, 53.0, 128.0, 115.0])
    target = np.array([220.0, 40.0])
    through = Solution(np.radians([-30.0, -60.0, 60.0, 0.0]), SolveStatus.SUCCESS, 10, 0.0)
    assert room.is_clear(hooked) and not room.is_clear(through.angles)
    guide = Avoider(room)
    commands = _settle(guide, hooked, through, target)
    assert len(commands) <= 120  # half a second at 240 ticks/s
    assert not np.array_equal(commands[-1].angles, through.angles)  # not given up
    arrived = _move_as_told(guide, hooked, through, target, 600)
    assert room.is_clear(arrived)
    assert room.misses(arrived, target)[0] <= 0.5


def _rock_room() -> Clearance:
    """Three 100 px links mounted straight up, a floor 20 px below the base and a round rock
    (radius 45 px) to the right whose bottom is 35 px above the floor (the stress level round a
    rock)."""
    arm = Skeleton.chain([100.0] * 3, base_angle=UP, limits=[(-2.618, 2.618)] * 3)
    obstacles = Obstacles.from_arrays(
        np.array([[-700.0, -20.0, 700.0, -20.0, 4.0]]), np.array([[170.0, 60.0, 45.0]])
    )
    return Clearance(arm, np.full(3, 6.0), obstacles)


UP_LEFT = np.array([0.006, 0.029, 1.23])
"""The end up to the left, the arm standing."""

UNDER = np.array([-0.994, -1.227, 0.913])
"""The end low beyond the rock: the middle link passes its lower left, the last runs under it
through the 35 px between rock and floor."""

WAY_IN = [
    *(
        np.array(pose)
        for pose in (
            [0.77, -1.96, -0.76],
            [0.74, -2.02, -0.79],
            [0.68, -2.17, -0.64],
            [0.44, -2.32, -0.4],
            [-0.28, -2.08, 0.47],
            [-0.67, -1.69, 0.65],
        )
    ),
    UNDER,
]
"""Via poses from ``UP_LEFT`` to ``UNDER``, each reached from the one before in a clear straight
line (traced on a grid of joint space): the end comes down the rock's left side and slides
right along the floor under it."""


def test_the_way_in_under_the_rock_is_found_from_the_arm_standing():
    # A narrow passage that random trees in joint space seldom sample: the search needs more
    # than 1,500 of their nodes.
    room = _rock_room()
    assert room.is_clear(UNDER) and not room.path_clear(UP_LEFT, UNDER)
    _assert_clear_route(room, UP_LEFT, UNDER, room.route(UP_LEFT, UNDER))


def test_a_chain_led_in_under_the_rock_is_led_out_the_way_it_came(monkeypatch):
    room = _rock_room()
    way_in = WAY_IN
    assert all(room.path_clear(a, b) for a, b in zip([UP_LEFT, *way_in], way_in, strict=False))
    searched = []

    def only_the_way_in(self, a, b, slide=False):
        # The trees found the way in; back out, from the last links under the rock, they find
        # none (none in 1,500 nodes on the stress level).
        searched.append(b)
        yield ITERATION_UNITS
        return [pose.copy() for pose in way_in] if np.array_equal(b, UNDER) else None

    monkeypatch.setattr(Clearance, "_connect", only_the_way_in)
    guide = Avoider(room)
    beyond = room.points(UNDER)[-1]
    inside = _move_as_told(
        guide, UP_LEFT, Solution(UNDER, SolveStatus.SUCCESS, 1, 0.0), beyond, 400
    )
    assert room.misses(inside, beyond)[0] <= 0.5
    up = room.points(UP_LEFT)[-1]
    out = _move_as_told(guide, inside, Solution(UP_LEFT, SolveStatus.SUCCESS, 1, 0.0), up, 400)
    assert room.misses(out, up)[0] <= 0.5
    # The trees found no way out: it is the way in walked back, tried before sliding trees.
    assert len(searched) == 2


OTHER_BEND = np.array([-0.3, 0.7, 0.733])
"""The end up to the left as Jacobian transpose brings it there: the first link leans right, the
other two bend back left (UP_LEFT's bend the other way)."""


T = TypeVar("T")


def _worked(work: Generator[float, None, T]) -> tuple[T, float]:
    """What a search in steps of work returns, and the units of work it took."""
    units = 0.0
    while True:
        try:
            units += next(work)
        except StopIteration as done:
            return done.value, units


def test_from_the_other_bend_the_sliding_trees_find_the_way_in_under_the_rock():
    # The trees of straight steps find none from here (63,000 units of work, 2,500 tries):
    # the way in runs with the middle joint on its stop and the last link in the band under
    # the rock. Sliding along the rock, the floor and the stop, the trees find it.
    room = _rock_room()
    way, units = _worked(room._connect(OTHER_BEND, UNDER, slide=True))
    assert way is not None and np.array_equal(way[-1], UNDER)
    _assert_clear_route(room, OTHER_BEND, UNDER, way)
    assert units < 20_000


def test_the_sliding_trees_search_once_the_walk_finds_none_but_not_for_a_jammed_goal(
    monkeypatch,
):
    room = _rock_room()
    share = math.ceil(TREE_FIRST / ITERATION_UNITS)
    log: list[str] = []

    def trees(self, a, b, slide=False):
        for _ in range(1 if slide else share + 5):
            log.append("slide" if slide else "tree")
            yield ITERATION_UNITS
        return [b.copy()] if slide else None

    def no_walk(self, a, b):
        log.append("walk")
        yield ITERATION_UNITS

    monkeypatch.setattr(Clearance, "_connect", trees)
    monkeypatch.setattr(Clearance, "_walking", no_walk)
    assert not room.path_clear(OTHER_BEND, UNDER)
    way = room.route(OTHER_BEND, UNDER)
    assert way is not None and np.array_equal(way[-1], UNDER)
    # The straight trees did their share, the walk found nothing, the sliding trees found it.
    assert log == ["tree"] * share + ["walk", "slide"]
    log.clear()
    assert _finish(room._routing(OTHER_BEND, UNDER, slide=False)) is None
    assert log == ["tree"] * share + ["walk"] + ["tree"] * 5


def test_a_sliding_step_turns_along_the_obstacle_it_would_press_into():
    # Two links lying right, a little down, 7 px above a floor: asked to turn the first down
    # and the second up, the step holds the first off the floor (at the margin and the room
    # beyond it, to first order) and turns the second up as far as a step goes.
    arm = Skeleton.chain([100.0, 100.0], limits=[(-2.0, 2.0)] * 2)
    floor = Obstacles.from_arrays(np.array([[-300.0, -15.0, 300.0, -15.0, 0.0]]), NO_CIRCLES)
    room = Clearance(arm, np.full(2, 5.0), floor)
    here = np.array([-0.03, 0.03])
    asked = np.array([-0.2, 0.4])
    assert room.gaps(here + asked * SLIDE_STEP / 0.4).min() < 0.0  # a straight step: into it
    step = _finish(room._sliding(here, asked)) - here
    assert abs(step[0]) < 0.02 and step[1] == pytest.approx(SLIDE_STEP)
    assert room.gaps(here + step).min() >= room.margin + SLIDE_ROOM - 0.1
    # Nothing near: the step asked, cut to SLIDE_STEP, or the pose itself when that short.
    far = Clearance(arm, np.full(2, 5.0), Obstacles.from_arrays(NO_SEGMENTS, [[0.0, 500.0, 9.0]]))
    assert np.allclose(_finish(far._sliding(here, asked)), here + asked * SLIDE_STEP / 0.4)
    assert np.array_equal(_finish(far._sliding(here, asked / 4.0)), here + asked / 4.0)


def test_a_chain_away_from_the_end_of_its_last_route_is_not_sent_back_along_it():
    room = _rock_room()
    back = [*WAY_IN[::-1], UP_LEFT]
    near = UNDER + 0.01
    way = _finish(room._retracing(near, UP_LEFT, back))
    assert way is not None and np.array_equal(way[0], UNDER) and np.array_equal(way[-1], UP_LEFT)
    # A chain that has left the end of the route is not sent back to it on its way elsewhere,
    # however clear the lines to it and on from it.
    beside, on = WAY_IN[0], WAY_IN[1]
    assert room.path_clear(UP_LEFT, beside) and room.path_clear(beside, on)
    assert _finish(room._retracing(UP_LEFT, on, [beside, UP_LEFT])) is None


def _thirty_links_rock_room() -> Clearance:
    """Thirty 10 px links mounted straight up, a floor 20 px below the base and a round rock
    (radius 40 px) to the right whose bottom is 50 px above the floor (the stress level of
    thirty links round a rock)."""
    limits = [(-math.radians(120.0), math.radians(120.0))] * 30
    arm = Skeleton.chain([10.0] * 30, base_angle=UP, limits=limits)
    obstacles = Obstacles.from_arrays(
        np.array([[-900.0, -20.0, 900.0, -20.0, 0.0]]), np.array([[130.0, 70.0, 40.0]])
    )
    return Clearance(arm, np.full(30, 2.5), obstacles)


LOW_BEYOND = np.array([200.0, 10.0])
"""The stress level's target low beyond the rock."""


def _up_left_and_low(room: Clearance) -> tuple[np.ndarray, np.ndarray]:
    """The thirty links reaching up to the left, and a clear answer low beyond the rock."""
    left = room.polish(np.zeros(30), np.array([-120.0, 220.0])).angles
    low = room.clear_answer(left, left, LOW_BEYOND, 0.5)
    assert room.is_clear(left) and low is not None and not room.path_clear(left, low)
    return left, low


def _no_tree(searched: list[np.ndarray]):
    def connect(self, a, b):
        # The trees in thirty joint dimensions: none found in 2,500 nodes (7.5 million units).
        searched.append(b)
        yield ITERATION_UNITS

    return connect


def test_the_tip_path_keeps_to_the_side_of_the_rock_the_goals_links_pass():
    room = _thirty_links_rock_room()
    left, low = _up_left_and_low(room)
    way = room.tip_path(left, low)
    assert np.array_equal(way[0], room.points(left)[-1])
    assert np.array_equal(way[-1], room.points(low)[-1])
    # Under the rock, as the goal's links pass it: over it the chain is 16 px too short to go
    # round and down to the target.
    below = (way[:, 0] > 90.0) & (way[:, 0] < 170.0)
    assert below.any() and np.all(way[below, 1] < 30.0)
    assert len(way) < 10  # pulled taut, not the two poses' 61 points


def test_with_nothing_in_the_way_the_tip_path_is_one_straight_piece():
    arm = Skeleton.chain([50.0] * 4, base_angle=UP)
    room = Clearance(arm, np.full(4, 2.0), Obstacles.from_arrays(NO_SEGMENTS, NO_CIRCLES))
    bent = np.array([0.5, 0.5, 0.5, 0.5])
    way = room.tip_path(np.zeros(4), bent)
    assert np.allclose(way, [room.points(np.zeros(4))[-1], room.points(bent)[-1]])


def test_a_tip_path_is_for_a_chain():
    arms = Skeleton.tree([100.0, 80.0, 80.0], [-1, 0, 0], base_angle=UP)
    floor = Obstacles.from_arrays(np.array([[-300.0, -20.0, 300.0, -20.0, 0.0]]), NO_CIRCLES)
    with pytest.raises(ValueError, match="chain"):
        Clearance(arms, np.full(3, 5.0), floor).tip_path(np.zeros(3), np.ones(3))


def test_a_long_chain_is_led_round_the_rock_by_its_end_where_the_trees_find_no_way(monkeypatch):
    room = _thirty_links_rock_room()
    left, low = _up_left_and_low(room)
    searched: list[np.ndarray] = []
    monkeypatch.setattr(Clearance, "_connect", _no_tree(searched))
    way, units = _worked(room._routing(left, low))
    assert way is not None and len(searched) == 1  # the trees gave up; the walk found it
    assert all(room.path_clear(a, b) for a, b in zip([left, *way], way, strict=False))
    assert room.misses(way[-1], LOW_BEYOND)[0] <= 1.0
    assert units < 50_000  # the trees gave up after 7.5 million


def test_the_trees_search_first_and_the_walk_takes_over_once_they_have_done_their_share(
    monkeypatch,
):
    room = _thirty_links_rock_room()
    left, low = _up_left_and_low(room)
    log: list[str] = []

    def searching_trees(self, a, b):
        while True:
            log.append("tree")
            yield ITERATION_UNITS

    walking = Clearance._walking

    def logged_walk(self, a, b):
        log.append("walk")
        return (yield from walking(self, a, b))

    monkeypatch.setattr(Clearance, "_connect", searching_trees)
    monkeypatch.setattr(Clearance, "_walking", logged_walk)
    way = room.route(left, low)
    assert way is not None
    # The trees did their share, then the walk found the way and they were stopped.
    assert log == ["tree"] * math.ceil(TREE_FIRST / ITERATION_UNITS) + ["walk"]


def test_the_avoider_takes_thirty_links_from_up_left_to_low_beyond_the_rock(monkeypatch):
    room = _thirty_links_rock_room()
    left, _ = _up_left_and_low(room)
    monkeypatch.setattr(Clearance, "_connect", _no_tree([]))
    # The solver's own answer runs through the rock.
    through = room.polish(left, LOW_BEYOND, avoid=False)
    assert not room.is_clear(through.angles)
    guide = Avoider(room)
    arrived = _move_as_told(guide, left, through, LOW_BEYOND, 600)
    assert room.is_clear(arrived)
    assert room.misses(arrived, LOW_BEYOND)[0] <= 0.5


def test_on_a_route_the_chain_is_sent_along_its_line_just_ahead_of_its_slowest_joint():
    room = _shelf_room()
    guide = Avoider(room)
    start = np.array([0.5, 0.3, 0.2])  # up-left, the way in under the shelf not straight
    target = np.array([290.0, 45.0])
    through = Solution(np.array([-0.3, -1.2, -0.6]), SolveStatus.SUCCESS, 10, 0.0)
    lead = _settle(guide, start, through, target)[-1].angles - start
    # Not the first via pose, a far swing away, but LEAD along the line toward it.
    assert np.abs(lead).max() == pytest.approx(LEAD)
    # The outer joints ran on twice as far as the first (they turn less mass): the command is
    # one lead ahead of the first, the laggard, on the same line, and holds the others back.
    ahead = start + lead * np.array([1.0, 2.0, 2.0])
    command = guide.steer(ahead, through, target, 0.5).angles
    assert np.allclose(command, start + 2.0 * lead)
    assert room.path_clear(ahead, command)


def test_a_straight_way_to_a_far_goal_is_led_along_its_line_too():
    # Sent to a far goal in one go, the joints with far to turn lag the others, and the end can
    # reach the target with a joint still far off and swing on past it.
    room = _shelf_room()
    guide = Avoider(room)
    start = np.array([0.5, 0.3, 0.2])
    on_its_way = Solution(np.array([1.0, 0.5, 0.5]), SolveStatus.PROCESSING, 10, 50.0)
    target = np.array([-250.0, 30.0])  # low on the left, over the floor
    command = _settle(guide, start, on_its_way, target)[-1].angles
    goal = guide._goal.copy()
    span = goal - start
    assert len(guide._way) == 1 and np.abs(span).max() > 2 * LEAD  # one straight piece, far
    assert np.allclose(command, start + LEAD / np.abs(span).max() * span)
    # The elbow ran on two leads, the wrist half of one: the command is one lead ahead of the
    # wrist, and holds the elbow back on the line.
    ahead = start + (command - start) * np.array([1.0, 2.0, 0.5])
    held = guide.steer(ahead, on_its_way, target, 0.5).angles
    assert np.allclose(held, start + 1.5 * (command - start))
    arrived = _move_as_told(guide, start, on_its_way, target, 60)
    assert np.allclose(arrived, goal) and room.misses(arrived, target)[0] <= 0.5


def test_a_chain_turns_on_at_a_via_pose_without_braking_to_rest_where_the_line_on_is_clear():
    # A servo that closes its error at 12/s, as the default gain does, brakes within LEAD of
    # the pose it is sent to. Turning on only once nearly there, the chain slowed at every via
    # pose of a long way to under a third of its speed.
    room = _shelf_room()
    guide = Avoider(room)
    through = Solution(np.array([-0.3, -1.2, -0.6]), SolveStatus.SUCCESS, 10, 0.0)
    target = np.array([290.0, 45.0])  # under the shelf
    pose, rates, dt, gain = np.array([0.5, 0.3, 0.2]), np.zeros(3), 1.0 / 240.0, 12.0
    pieces, turning_speeds = None, []
    for _ in range(1000):
        command = guide.steer(pose, through, target, 0.5)
        if not guide.planning:
            if pieces is not None and len(guide._way) < pieces:
                turning_speeds.append(float(np.abs(rates).max()))
            pieces = len(guide._way)
        rates = np.clip(gain * (command.angles - pose), -4.2, 4.2)
        pose = pose + rates * dt
        assert room.is_clear(pose)
    assert room.misses(pose, target)[0] <= 0.5
    assert len(turning_speeds) >= 2 and max(turning_speeds) > 0.5 * gain * LEAD


def test_a_line_past_a_half_turn_of_a_free_joint_is_followed_to_its_end():
    # The way round the post is the long way, past -pi on the free base joint, which the
    # controller measures within [-pi, pi].
    arm = Skeleton.chain([100.0, 100.0])
    post = Obstacles.from_arrays(NO_SEGMENTS, np.array([[150.0, 100.0, 25.0]]))
    room = Clearance(arm, np.full(2, 4.0), post)
    guide = Avoider(room, budget=math.inf)
    target = np.array([60.0, 170.0])
    # CCD's answer on its way, the elbow swung round through the post.
    through = Solution(np.array([0.75, 0.96]), SolveStatus.PROCESSING, 10, 3.0)
    assert not room.path_clear(np.zeros(2), through.angles)
    measured, base = np.zeros(2), []
    for _ in range(200):
        command = guide.steer(measured, through, target, 0.5).angles
        base.append(command[0])
        # As the servo turns a free joint: the short way to its command.
        step = (command - measured + math.pi) % (2.0 * math.pi) - math.pi
        measured = measured + step * min(1.0, 0.05 / max(np.abs(step).max(), 1e-12))
        measured = (measured + math.pi) % (2.0 * math.pi) - math.pi
        assert room.is_clear(measured)
    assert min(base) < -math.pi  # sent the long way round
    assert room.misses(measured, target)[0] <= 0.5 and room.is_clear(measured)


def test_a_route_past_the_target_and_back_is_cut_where_the_end_passes_nearest():
    arm = Skeleton.chain([100.0, 100.0], base_angle=UP)
    far = Obstacles.from_arrays(NO_SEGMENTS, np.array([[1000.0, 1000.0, 10.0]]))
    room = Clearance(arm, np.full(2, 5.0), far)
    target = np.array([0.0, 200.0])  # the arm straight up
    start, past = np.array([0.6, 0.0]), np.array([-0.6, 0.0])
    goal = np.array([0.05, -0.1])  # another pose reaching the target
    way = _finish(room._trimming(start, [past, goal], target, 0.5))
    # The arm swings through the target on its way to ``past``: it stops there instead.
    assert len(way) == 2 and not any(np.array_equal(pose, past) for pose in way)
    assert np.abs(way[0] - np.zeros(2)).max() < 0.02  # on the first piece, nearest the target
    assert room.misses(way[1], target)[0] <= 0.5
    assert room.path_clear(start, way[0]) and room.path_clear(way[0], way[1])
    # A route whose end comes nearest at its last piece is left as it is.
    assert _finish(room._trimming(start, [goal, past], target, 0.5)) == [goal, past]


def _reaching(target: np.ndarray, first: float) -> np.ndarray:
    """The pose of three 100 px links whose first joint is at ``first`` (radians) and whose
    other two reach ``target`` with their elbow bent the positive way."""
    elbow = 100.0 * np.array([math.cos(UP + first), math.sin(UP + first)])
    dx, dy = target - elbow
    bend = math.acos((dx * dx + dy * dy - 2.0e4) / 2.0e4)
    second = math.atan2(dy, dx) - math.atan2(math.sin(bend), 1.0 + math.cos(bend)) - UP - first
    return np.array([first, second, bend])


def test_a_route_s_last_piece_past_the_target_and_back_is_cut_where_the_end_passes():
    arm = Skeleton.chain([100.0, 100.0, 100.0], base_angle=UP)
    far = Obstacles.from_arrays(NO_SEGMENTS, np.array([[1000.0, 1000.0, 10.0]]))
    room = Clearance(arm, np.full(3, 5.0), far)
    target = np.array([0.0, 250.0])
    passing, goal = _reaching(target, 0.5), _reaching(target, -0.5)
    via = 2.0 * passing - goal  # the line from it to the goal runs through ``passing``
    start = via + 0.3 * (via - passing)
    # Between the two poses that reach the target the line bends the end 19 px off it.
    assert room.misses((passing + goal) / 2.0, target)[0] > 15.0
    way = _finish(room._trimming(start, [via, goal], target, 0.5))
    assert len(way) == 3 and np.array_equal(way[0], via)
    assert np.abs(way[1] - passing).max() < 0.02  # where the end passes the target
    assert room.misses(way[2], target)[0] <= 0.5
    assert room.path_clear(via, way[1]) and room.path_clear(way[1], way[2])
    # A last piece that comes in without passing the target is left as it is.
    assert _finish(room._trimming(start, [via, passing], target, 0.5)) == [via, passing]


def test_route_is_none_when_the_limits_leave_no_way_round():
    arm = Skeleton.chain([100.0], base_angle=UP, limits=[(-1.0, 1.0)])
    post = Obstacles.from_arrays(NO_SEGMENTS, np.array([[0.0, 80.0, 10.0]]))
    room = Clearance(arm, np.array([5.0]), post)
    assert room.route(np.array([-0.8]), np.array([0.8])) is None


def test_the_avoider_steers_round_the_shelf_and_passes_clear_answers_through():
    room = _shelf_room()
    guide = Avoider(room)
    target = np.array([290.0, 45.0])
    through = Solution(np.array([-0.3, -1.2, -0.6]), SolveStatus.SUCCESS, 10, 0.0)
    measured = _move_as_told(guide, np.array([0.5, 0.3, 0.2]), through, target, 400)
    assert room.is_clear(measured)
    assert np.hypot(*(room.points(measured)[-1] - target)) <= 0.5
    # Far from everything, the solver's answer comes back as it is.
    open_air = Avoider(room)
    up = np.array([0.1, 0.1, 0.1])
    answer = Solution(np.array([0.12, 0.1, 0.1]), SolveStatus.SUCCESS, 3, 0.2)
    assert open_air.steer(up, answer, np.array([-50.0, 350.0]), 0.5) is answer


def test_a_straight_line_is_judged_as_its_sampled_poses_judge_it(monkeypatch):
    room = _shelf_room()
    rng = np.random.default_rng(7)
    floor = room.margin / 2.0
    verdicts, touching = set(), 0
    for _ in range(200):
        a, b = rng.uniform(-1.5, 1.5, (2, 3))
        # Every link sampled at every pose of the line, the start's gap setting the least.
        gaps = room.smallest_gaps(room._samples(a, b))
        sampled = bool(np.all(gaps[1:] >= _least_gap(floor, float(gaps[0]))))
        # A fresh avoider each time: no line checked before to go by.
        assert Avoider(room)._clear_way(a, b) == sampled
        assert room.path_clear(a, b) == _finish(room._checking(a, b)) == sampled
        verdicts.add(sampled)
        touching += gaps[0] < 0.0
    assert verdicts == {True, False}
    assert touching > 10  # lines starting with a link in an obstacle are judged alike too
    # Links whose gaps at both ends outweigh how far they sweep are clear without sampling.
    calls = []
    samples = room._samples
    monkeypatch.setattr(room, "_samples", lambda a, b: calls.append(1) or samples(a, b))
    a, b = np.array([0.0, 0.1, 0.0]), np.array([0.2, 0.0, 0.1])
    assert Avoider(room)._clear_way(a, b) and room.path_clear(a, b)
    assert calls == []


def test_a_line_blocked_near_its_far_end_is_found_blocked_from_that_end():
    room = _shelf_room()
    rng = np.random.default_rng(3)
    size = clearance.PATH_CHUNK
    found = 0
    for _ in range(400):
        a, b = rng.uniform(-2.0, 2.0, (2, 3))
        poses = room._samples(a, b)
        gaps = room.smallest_gaps(poses)
        blocked = np.flatnonzero(gaps[1:] < _least_gap(room.margin / 2.0, float(gaps[0]))) + 1
        last = (len(poses) - 1) // size * size  # where the last chunk starts
        if len(poses) <= 3 * size or not len(blocked) or blocked[0] < last:
            continue
        # The first chunk, then the last: not the whole line.
        chunks = [size, len(poses) - last]
        units = sum(clearance.CHECK_UNITS + n * room._pose_units for n in chunks)
        assert _worked(room._checking(a, b)) == (False, pytest.approx(units))
        found += 1
    assert found > 3


def test_a_chain_at_rest_in_the_open_is_not_measured_again(monkeypatch):
    room = _shelf_room()
    guide = Avoider(room)
    calls = []
    measure = room.gaps
    monkeypatch.setattr(room, "gaps", lambda angles: calls.append(1) or measure(angles))
    pose = np.array([0.1, 0.1, 0.1])
    answer = Solution(pose.copy(), SolveStatus.SUCCESS, 0, 0.1)
    for _ in range(50):
        assert guide.steer(pose, answer, np.array([-50.0, 350.0]), 0.5) is answer
    assert len(calls) == 1


def test_clearance_takes_one_radius_per_link():
    none = Obstacles.from_arrays(NO_SEGMENTS, NO_CIRCLES)
    with pytest.raises(ValueError, match="radii"):
        Clearance(Skeleton.chain([1.0, 1.0]), np.ones(3), none)


def test_while_the_base_moves_the_solver_answers_and_the_plan_is_dropped():
    room = _shelf_room()
    guide = Avoider(room)
    target = np.array([290.0, 45.0])
    measured = np.array([0.5, 0.3, 0.2])
    through = Solution(np.array([-0.3, -1.2, -0.6]), SolveStatus.SUCCESS, 10, 0.0)
    assert guide.steer(measured, through, target, 0.5) is not through  # planned round
    room.skeleton = room.skeleton.moved_to((5.0, 0.0))
    assert guide.steer(measured, through, target, 0.5) is through  # stale for a moving base
    # Standing still again, it plans afresh for where the base is now.
    replanned = guide.steer(measured, through, target, 0.5)
    assert replanned is not through and room.is_clear(replanned.angles)


def test_while_the_base_carries_a_link_nearer_an_obstacle_the_pose_is_held_off_it():
    # The base slides right under an upright answer (as a solver at rest on the target hands on
    # the pose it measures): the middle link closes in on the shelf's end, then runs into it.
    room = _shelf_room()
    guide = Avoider(room)
    upright = Solution(np.zeros(3), SolveStatus.SUCCESS, 10, 0.0)
    target = np.array([110.0, 350.0])
    handed_on = []
    for x in np.arange(108.0, 126.0, 2.0):
        room.skeleton = room.skeleton.moved_to((x, 0.0))
        steered = guide.steer(np.zeros(3), upright, target, 0.5)
        assert not guide.planning
        handed_on.append(steered is upright)
        if x >= 114.0:
            assert room.gaps(steered.angles).min() > room.margin - 0.5
            assert room.misses(steered.angles, target)[0] <= 0.5
    assert room.gaps(upright.angles).min() < -5.0
    # Handed on while no link comes within 10 px (the reach of the polish's clearance rows),
    # held off from the first measure that sees the link closing in.
    assert handed_on == [True, True] + [False] * 7


def _two_arms_room() -> Clearance:
    """A torso of two links with two arms of three links each (the stress level with two arms),
    standing 20 px above a floor."""
    deg = math.radians
    limits = [(-30, 30), (-25, 25), (0, 170), (-10, 150), (-60, 60), (-170, 0), (-150, 10)]
    body = Skeleton.tree(
        [80.0, 70.0, 80.0, 70.0, 35.0, 80.0, 70.0, 35.0],
        [-1, 0, 1, 2, 3, 1, 5, 6],
        base_angle=UP,
        limits=[(deg(a), deg(b)) for a, b in [*limits, (-60, 60)]],
    )
    floor = Obstacles.from_arrays(np.array([[-500.0, -20.0, 500.0, -20.0, 4.0]]), NO_CIRCLES)
    return Clearance(body, np.array([13.0, 12.0, 6.0, 6.0, 5.0, 6.0, 6.0, 5.0]), floor)


# Both arms raised, and the pose the solver heads for with the left hand low on the left: the
# straight way there swings the left arm through the floor.
RAISED = np.array([0.282, -0.312, 2.967, 2.176, 0.017, -2.133, -2.618, -0.651])
HEADING = np.array([-0.204, -0.436, 2.845, 0.066, -0.126, -2.967, -2.618, -0.511])
HANDS_LOW_AND_HIGH = TargetSet([4, 7], [(-110.0, 10.0), (90.0, 300.0)], weights=[2.0, 1.0])


def test_a_trees_links_start_at_their_parents_ends():
    body = Skeleton.tree(
        [50.0, 40.0, 30.0, 45.0], [-1, 0, 0, -1], root_offsets=[(0, 10), (0, 0), (0, 0), (5, -10)]
    )
    obstacles = Obstacles.from_arrays(np.array([[-300.0, 60.0, 300.0, 60.0, 3.0]]), NO_CIRCLES)
    room = Clearance(body, np.full(4, 4.0), obstacles)
    poses = np.random.default_rng(8).uniform(-2.0, 2.0, (30, 4))
    for pose in poses:
        assert room.points(pose) == pytest.approx(forward_kinematics(body, pose)[0])
        starts, ends = room.points(pose)[:4], room.points(pose)[4:]
        u = np.linspace(0.0, 1.0, 400)[:, None]
        sampled = []
        for i in range(4):
            link = starts[i] + u * (ends[i] - starts[i])
            sampled.append(np.abs(link[:, 1] - 60.0).min() - 4.0 - 3.0)
        # The obstacle is wide enough that the nearest points are never beyond its ends.
        clear = np.array(sampled) > 0.0
        assert room.gaps(pose)[clear] == pytest.approx(np.array(sampled)[clear], abs=0.5)
    assert room.points(poses) == pytest.approx(np.array([room.points(p) for p in poses]))
    rng = np.random.default_rng(9)
    for _ in range(20):
        a, b = rng.uniform(-2.0, 2.0, (2, 4))
        line = room.points(a + np.linspace(0.0, 1.0, 200)[:, None] * (b - a))
        assert np.hypot(*(line - line[0]).T).max() <= room.swept(a, b) + 1e-9


def test_a_chain_is_the_one_effector_case_of_a_target_set():
    room = _shelf_room()
    target = np.array([290.0, 45.0])
    through = np.array([-0.3, -1.2, -0.6])
    as_point = room.polish(through, target)
    as_set = room.polish(through, TargetSet([2], [target]))
    assert np.array_equal(as_point.angles, as_set.angles)
    assert as_point.status is as_set.status is SolveStatus.SUCCESS


def test_a_tree_whose_straight_way_dips_into_the_floor_gets_a_clear_answer_and_route():
    room = _two_arms_room()
    assert room.is_clear(RAISED) and room.is_clear(HEADING)
    assert not room.path_clear(RAISED, HEADING)
    pose = room.clear_answer(RAISED, HEADING, HANDS_LOW_AND_HIGH, 0.5)
    assert pose is not None and room.is_clear(pose)
    assert np.all(room.misses(pose, HANDS_LOW_AND_HIGH) <= 0.5)
    way = room.route(RAISED, HEADING)
    assert way is not None and len(way) > 1
    for a, b in zip([RAISED, *way], way, strict=False):
        assert room.path_clear(a, b)


def test_the_avoider_brings_both_hands_to_their_targets_without_touching_the_floor():
    room = _two_arms_room()
    guide = Avoider(room)
    on_its_way = Solution(HEADING, SolveStatus.PROCESSING, 10, 150.0)
    measured = _move_as_told(guide, RAISED, on_its_way, HANDS_LOW_AND_HIGH, 300)
    assert room.is_clear(measured)
    assert np.all(room.misses(measured, HANDS_LOW_AND_HIGH) <= 0.5)


def test_a_set_out_of_joint_reach_settles_clear_but_not_through_the_floor():
    room = _two_arms_room()
    apart = TargetSet([4, 7], [(-400.0, 150.0), (400.0, 150.0)], weights=[2.0, 1.0])
    pose = room.clear_answer(RAISED, RAISED, apart, 0.5)
    assert pose is not None and room.is_clear(pose)
    # The least squares without obstacles, from there, brings neither hand nearer.
    free = room.polish(pose, apart, iterations=400, avoid=False).angles
    assert np.all(room.misses(free, apart) >= room.misses(pose, apart) - 0.5)
    under_the_floor = TargetSet([4, 7], [(-110.0, -60.0), (90.0, 300.0)])
    assert room.clear_answer(RAISED, RAISED, under_the_floor, 0.5) is None


PINNED_CALLS = round(PINNED_S * 240)  # calls at the default 240 a second


def _shelf_route(
    replan: bool = False, tick_rate: float = 240.0
) -> tuple[Clearance, Avoider, Solution, np.ndarray]:
    """The shelf room, an avoider (with ``replan`` or not, called ``tick_rate`` times a
    second) that has planned a route in under the shelf from the arm held up, the solver's
    answer and the target."""
    room = _shelf_room()
    guide = Avoider(room, replan=replan, tick_rate=tick_rate)
    target = np.array([290.0, 45.0])
    through = Solution(np.array([-0.3, -1.2, -0.6]), SolveStatus.SUCCESS, 10, 0.0)
    while guide.steer(np.array([0.5, 0.3, 0.2]), through, target, 0.5) and guide.planning:
        pass
    return room, guide, through, target


@pytest.mark.parametrize("replan", [False, True])
def test_with_replan_a_chain_carried_off_its_route_gets_a_new_one_from_where_it_is(replan):
    room, guide, through, target = _shelf_route(replan)
    # Carried off the line, reaching in under the shelf: straight on to the via pose (the arm
    # folded up on the left) it would sweep through the shelf.
    off = np.array([0.0, -1.8, 0.0])
    assert room.is_clear(off)
    command = guide.steer(off, through, target, 0.5)
    while guide.planning:  # a new route is searched for while the chain holds where it is
        assert np.array_equal(command.angles, off)
        command = guide.steer(off, through, target, 0.5)
    assert room.path_clear(off, command.angles) is replan


@pytest.mark.parametrize("tick_rate", [30.0, 240.0])
@pytest.mark.parametrize("pressed", [False, True])
def test_a_chain_pinned_against_an_obstacle_off_its_route_gets_a_new_one(pressed, tick_rate):
    room, guide, through, target = _shelf_route(tick_rate=tick_rate)
    first = guide._way[0].copy()
    # Off the line, the straight way on to the via pose blocked either way; pressed, the last
    # link lies 1.6 px into the shelf, where the motors hold it. PINNED_S is 24 calls at 240
    # ticks a second and 3 at 30: well inside the half second after which a chain that makes
    # no progress is judged blocked, at any tick rate.
    off = np.array([0.3, -1.85, 0.0]) if pressed else np.array([0.0, -1.8, 0.0])
    assert bool(room.gaps(off).min() < 0.0) is pressed
    for _ in range(round(PINNED_S * tick_rate) - 1):
        guide.steer(off, through, target, 0.5)
    assert np.array_equal(guide._way[0], first)  # it may yet move on
    guide.steer(off, through, target, 0.5)
    while guide.planning:
        guide.steer(off, through, target, 0.5)
    assert np.array_equal(guide._way[0], first) is not pressed


def test_a_chain_brushing_an_obstacle_on_its_way_keeps_its_route():
    room, guide, through, target = _shelf_route()
    first = guide._way[0].copy()
    # Pressed into the shelf, but moving: a link dragged along it.
    for k in range(3 * PINNED_CALLS):
        off = np.array([0.3, -1.85, 0.0 + 0.02 * (k % 2)])
        assert room.gaps(off).min() < 0.0
        guide.steer(off, through, target, 0.5)
    assert np.array_equal(guide._way[0], first)


def test_a_chain_that_comes_to_rest_pressed_in_is_found_pinned():
    room, guide, through, target = _shelf_route()
    first = guide._way[0].copy()
    # Moving in from clear poses (whose gaps prove the next few clear unmeasured) until the
    # last link lies 1.6 px into the shelf, and resting there.
    clear, pressed = np.array([0.3, -1.6, 0.0]), np.array([0.3, -1.85, 0.0])
    assert room.gaps(clear).min() > 0.0 > room.gaps(pressed).min()
    for s in np.linspace(0.0, 1.0, 11):
        guide.steer(clear + s * (pressed - clear), through, target, 0.5)
    assert np.array_equal(guide._way[0], first)
    for _ in range(PINNED_CALLS):
        guide.steer(pressed, through, target, 0.5)
    while guide.planning:
        guide.steer(pressed, through, target, 0.5)
    assert not np.array_equal(guide._way[0], first)


def _settle(guide: Avoider, measured: np.ndarray, answer: Solution, target: np.ndarray) -> list:
    """Every command while the avoider searches, the chain not moving, then the first after."""
    commands = [guide.steer(measured, answer, target, 0.5)]
    while guide.planning:
        commands.append(guide.steer(measured, answer, target, 0.5))
    return commands


def test_one_steer_call_searches_no_more_than_its_budget(monkeypatch):
    room = _shelf_room()
    guide = Avoider(room)
    iterations = []
    polish_once = room._pairs
    monkeypatch.setattr(room, "_pairs", lambda pts: iterations.append(1) or polish_once(pts))
    through = Solution(np.array([-0.3, -1.2, -0.6]), SolveStatus.SUCCESS, 10, 0.0)
    measured = np.array([0.5, 0.3, 0.2])
    calls = []
    for _ in range(400):
        iterations.clear()
        guide.steer(measured, through, np.array([290.0, 45.0]), 0.5)
        calls.append(len(iterations))
        if not guide.planning:
            break
    # The whole search polishes hundreds of times; a call stops once the budget is spent.
    assert sum(calls) > 5 * guide.budget / ITERATION_UNITS
    assert max(calls) <= guide.budget // ITERATION_UNITS + 1
    assert not guide.planning


def test_a_search_spread_over_calls_finds_what_one_call_finds():
    for room, start, answer, target in (
        (_shelf_room(), np.array([0.5, 0.3, 0.2]), np.array([-0.3, -1.2, -0.6]), [290.0, 45.0]),
        (_two_arms_room(), RAISED, HEADING, HANDS_LOW_AND_HIGH),
    ):
        aim = target if isinstance(target, TargetSet) else np.array(target)
        status = SolveStatus.PROCESSING if isinstance(target, TargetSet) else SolveStatus.SUCCESS
        solution = Solution(answer, status, 10, 0.0)
        at_once = Avoider(room, budget=math.inf)
        spread = Avoider(room, budget=ITERATION_UNITS)
        assert len(_settle(at_once, start, solution, aim)) == 1
        commands = _settle(spread, start, solution, aim)
        assert len(commands) > 10
        assert np.array_equal(commands[-1].angles, at_once.steer(start, solution, aim, 0.5).angles)
        # The chain follows the same plan after it.
        assert np.array_equal(
            _move_as_told(spread, start, solution, aim, 300),
            _move_as_told(at_once, start, solution, aim, 300),
        )


def test_while_it_searches_the_chain_holds_the_pose_it_started_from():
    room = _shelf_room()
    guide = Avoider(room, budget=ITERATION_UNITS)
    through = Solution(np.array([-0.3, -1.2, -0.6]), SolveStatus.SUCCESS, 10, 0.0)
    start = np.array([0.5, 0.3, 0.2])
    first = guide.steer(start, through, np.array([290.0, 45.0]), 0.5)
    assert guide.planning
    assert first.status is SolveStatus.PROCESSING and np.array_equal(first.angles, start)
    # Drifting a little while it waits, it is brought back where the route will start.
    drifted = guide.steer(start + 0.01, through, np.array([290.0, 45.0]), 0.5)
    assert guide.planning and np.array_equal(drifted.angles, start)
    # Once the solver's own answer is clear and clear to turn to, the search is dropped.
    clear = Solution(np.array([0.45, 0.3, 0.2]), SolveStatus.SUCCESS, 3, 0.0)
    assert guide.steer(start, clear, np.array([-50.0, 350.0]), 0.5) is clear
    assert not guide.planning


def test_a_target_that_moves_every_call_still_gets_a_plan_and_is_followed():
    room = _shelf_room()
    guide = Avoider(room)
    through = Solution(np.array([-0.3, -1.2, -0.6]), SolveStatus.SUCCESS, 10, 0.0)
    measured = np.array([0.5, 0.3, 0.2])
    start = measured
    for tick in range(300):
        # Creeping along under the shelf, a new target every call: searched afresh every call,
        # a search that takes many calls would never end.
        target = np.array([290.0 - 0.02 * tick, 45.0])
        command = guide.steer(measured, through, target, 0.5)
        assert room.path_clear(measured, command.angles)
        step = command.angles - measured
        measured = measured + step * min(1.0, 0.05 / max(np.abs(step).max(), 1e-12))
    assert not np.array_equal(measured, start)
    assert room.is_clear(measured)
    assert np.hypot(*(room.points(measured)[-1] - target)) <= 5.0


def test_the_budget_is_a_positive_amount_of_work_and_the_tick_rate_a_positive_rate():
    with pytest.raises(ValueError, match="budget"):
        Avoider(_shelf_room(), budget=0)
    for rate in (0.0, -240.0, math.inf, math.nan):
        with pytest.raises(ValueError, match="tick_rate"):
            Avoider(_shelf_room(), tick_rate=rate)
    # By default a call does its tick's share of a simulated second's work.
    assert Avoider(_shelf_room(), tick_rate=120.0).budget == SEARCH_RATE / 120


def _holding_up(budget: float) -> tuple[Avoider, np.ndarray, Solution, np.ndarray]:
    """An avoider of the shelf room with ``budget``, its chain resting on a clear answer for a
    first target; the solver's answer for the next one, in under the shelf, and that target."""
    guide = Avoider(_shelf_room(), budget=budget)
    rest = np.array([0.5, 0.3, 0.2])
    guide.steer(rest, Solution(rest, SolveStatus.SUCCESS, 0, 0.0), np.array([-50.0, 350.0]), 0.5)
    through = Solution(np.array([-0.3, -1.2, -0.6]), SolveStatus.SUCCESS, 10, 0.0)
    return guide, rest, through, np.array([290.0, 45.0])


def _holding_on(guide: Avoider, rest: np.ndarray, calls: int, upcoming=None, answer=None) -> None:
    """``calls`` calls of a chain resting on its first target (see :func:`_holding_up`), each
    planning ahead for ``upcoming`` with the solver's ``answer``, if given."""
    holding = Solution(rest, SolveStatus.SUCCESS, 0, 0.0)
    for _ in range(calls):
        guide.steer(rest, holding, np.array([-50.0, 350.0]), 0.5)
        if upcoming is not None:
            guide.foresee(rest, upcoming, 0.5, lambda pose, target: answer)


def test_a_way_planned_ahead_is_taken_up_when_its_target_comes():
    at_once, rest, through, target = _holding_up(math.inf)
    searched = _settle(at_once, rest, through, target)
    assert len(searched) == 1 and searched[0].status is SolveStatus.PROCESSING
    spread = _holding_up(ITERATION_UNITS)[0]
    assert len(_settle(spread, rest, through, target)) > 10
    ahead = _holding_up(ITERATION_UNITS)[0]
    _holding_on(ahead, rest, 1000, target, through)
    # The search was done while the chain held its first target: none is left to wait for,
    # and the chain follows the plan one search in one call finds.
    assert len(_settle(ahead, rest, through, target)) == 1 and not ahead.planning
    assert np.array_equal(
        _move_as_told(ahead, rest, through, target, 300),
        _move_as_told(at_once, rest, through, target, 300),
    )


def test_a_way_planned_ahead_is_searched_on_from_where_it_stopped():
    guide, rest, through, target = _holding_up(ITERATION_UNITS)
    _holding_on(guide, rest, 10, target, through)
    fresh = _holding_up(ITERATION_UNITS)[0]
    assert (
        0
        < len(_settle(guide, rest, through, target))
        < len(_settle(fresh, rest, through, target)) - 9
    )


def test_a_way_planned_ahead_from_another_pose_is_not_taken_up():
    guide, rest, through, target = _holding_up(math.inf)
    _holding_on(guide, rest, 1, target, through)
    elsewhere = rest + np.array([0.0, 0.0, 0.1])
    moved = _holding_up(math.inf)[0]
    # The chain never came to rest where the way planned ahead starts: it is searched afresh,
    # from where it is, as it is without planning ahead.
    assert np.array_equal(
        _move_as_told(guide, elsewhere, through, target, 300),
        _move_as_told(moved, elsewhere, through, target, 300),
    )


def test_a_way_planned_ahead_is_dropped_once_the_solvers_answer_needs_none():
    guide, rest, through, target = _holding_up(ITERATION_UNITS)
    on_its_way = Solution(through.angles, SolveStatus.PROCESSING, 10, 40.0)
    beside = Solution(rest + 0.05, SolveStatus.SUCCESS, 10, 0.0)  # clear, and clear to turn to
    answers = iter([on_its_way] * 3 + [beside] * 1000)
    asked = []
    for _ in range(500):
        guide.steer(
            rest, Solution(rest, SolveStatus.SUCCESS, 0, 0.0), np.array([-50.0, 350.0]), 0.5
        )
        guide.foresee(rest, target, 0.5, lambda pose, aim: asked.append(1) or next(answers))
    # Asked again while its answer was on its way, then no more; and the search it would have
    # dropped is not taken up: the target's own search begins as without planning ahead.
    assert len(asked) == 4
    alone = _holding_up(ITERATION_UNITS)[0]
    waits = len(_settle(alone, rest, on_its_way, target))
    assert waits > 10 and len(_settle(guide, rest, on_its_way, target)) == waits


def test_a_plan_taken_up_the_call_before_the_solvers_answer_arrives_clear_gives_way_to_it():
    beside = Solution(np.array([0.55, 0.35, 0.25]), SolveStatus.SUCCESS, 10, 0.0)
    follows = []
    for calls_after in (0, 1):
        guide, rest, through, target = _holding_up(ITERATION_UNITS)
        on_its_way = Solution(through.angles, SolveStatus.PROCESSING, 10, 40.0)
        _settle(guide, rest, on_its_way, target)  # the last call takes the plan up
        for _ in range(calls_after):
            guide.steer(rest, on_its_way, target, 0.5)
        command = guide.steer(rest, beside, target, 0.5)  # arrived: clear, clear to turn to
        follows.append(not guide.idle)
        if calls_after == 0:
            # As if the search had ended one call later: dropped, as the search would be.
            assert guide.idle and np.array_equal(command.angles, beside.angles)
    # A call later the chain is on its way, and keeps to it.
    assert follows == [False, True]


def test_planning_ahead_takes_only_calls_that_did_no_search_work():
    guide, rest, through, target = _holding_up(ITERATION_UNITS)
    searching = guide.steer(rest, through, target, 0.5)
    assert guide.planning and searching.status is SolveStatus.PROCESSING
    asked = []
    guide.foresee(
        rest, np.array([-200.0, 45.0]), 0.5, lambda pose, aim: asked.append(aim) or through
    )
    assert not asked


def test_while_it_searches_the_chain_keeps_to_the_clear_pose_it_was_last_sent_to():
    room = _shelf_room()
    guide = Avoider(room, budget=ITERATION_UNITS)
    measured = np.array([0.5, 0.3, 0.2])
    heading = Solution(np.array([0.4, 0.3, 0.2]), SolveStatus.SUCCESS, 3, 0.0)
    assert guide.steer(measured, heading, np.array([-50.0, 350.0]), 0.5) is heading
    through = Solution(np.array([-0.3, -1.2, -0.6]), SolveStatus.SUCCESS, 10, 0.0)
    waiting = guide.steer(measured + 0.02, through, np.array([290.0, 45.0]), 0.5)
    assert guide.planning and waiting.status is SolveStatus.PROCESSING
    assert np.array_equal(waiting.angles, heading.angles)


def test_while_it_searches_the_chain_heads_for_an_answer_on_its_way_that_is_clear_to_turn_to():
    room = _shelf_room()
    guide = Avoider(room, budget=ITERATION_UNITS)
    start = np.array([0.5, 0.3, 0.2])
    through = Solution(np.array([-0.3, -1.2, -0.6]), SolveStatus.SUCCESS, 10, 0.0)
    guide.steer(start, through, np.array([290.0, 45.0]), 0.5)
    assert guide.planning
    # Carried under the shelf meanwhile, the solver still on its way to a clear pose below it.
    under = np.array([-0.503, -1.265, -0.115])
    on_its_way = Solution(under + [0.0, -0.2, 0.0], SolveStatus.PROCESSING, 10, 30.0)
    assert room.is_clear(on_its_way.angles) and room.path_clear(under, on_its_way.angles)
    command = guide.steer(under, on_its_way, np.array([290.0, 45.0]), 0.5)
    assert guide.planning and command.status is SolveStatus.PROCESSING
    assert np.array_equal(command.angles, on_its_way.angles)
    # An answer on its way through the shelf is not: the chain holds meanwhile.
    blocked = Solution(through.angles, SolveStatus.PROCESSING, 10, 30.0)
    assert np.array_equal(guide.steer(start, blocked, np.array([290.0, 45.0]), 0.5).angles, start)


def test_a_target_just_above_the_floor_gets_a_clear_answer_though_polishes_stall_near_it():
    # Three 90 px links, a floor 4 px thick 20 px below the base, a target far out 8 px above it.
    # A clear pose reaches it (the last link nearly level), but polished toward it the end stalls
    # a px short from every seed, the pull on it balanced by the push off the floor.
    limits = [(-math.radians(150.0), math.radians(150.0))] * 3
    arm = Skeleton.chain([90.0, 90.0, 90.0], base_angle=UP, limits=limits)
    floor = Obstacles.from_arrays(np.array([[-2000.0, -20.0, 2000.0, -20.0, 4.0]]), NO_CIRCLES)
    room = Clearance(arm, np.full(3, 6.0), floor)
    target = np.array([227.6, -7.9])
    # Where the chain rests after the target before, and the solver's first answer from there.
    measured = np.array([0.1906533166386981, 0.5010200025199336, 1.9912164180919678])
    answer = np.array([-1.0818936394657892, 2.6179938779914944, 2.6179938779914944])
    pose = room.clear_answer(measured, answer, target, 0.5)
    assert pose is not None and room.is_clear(pose)
    assert np.hypot(*(forward_kinematics(arm, pose)[0][-1] - target)) <= 0.5


def _under_the_floor() -> tuple[Clearance, np.ndarray, np.ndarray, Solution]:
    """The shelf room, the arm up and to the left, a target 60 px under the floor and the
    solver's answer for it, which reaches it through the floor."""
    room = _shelf_room()
    measured = np.array([0.5, 0.3, 0.2])
    target = np.array([200.0, -80.0])
    through = room.polish(np.zeros(3), target, iterations=200, avoid=False)
    assert through.status is SolveStatus.SUCCESS and not room.is_clear(through.angles)
    return room, measured, target, Solution(through.angles, SolveStatus.SUCCESS, 10, 0.0)


def test_a_target_no_clear_pose_reaches_sends_the_chain_to_the_nearest_clear_one():
    room, measured, target, through = _under_the_floor()
    assert room.clear_answer(measured, through.angles, target, 0.5) is None
    guide = Avoider(room)
    # Every command is a clear straight line from where the arm is: never the answer through
    # the floor, which the avoider handed on when it gave the target up.
    rest = _move_as_told(guide, measured, through, target, 400)
    assert guide.jammed and not guide.planning
    assert room.is_clear(rest)
    assert np.array_equal(guide.steer(rest, through, target, 0.5).angles, rest)
    # Within a few px of as near as the floor, the link's radius and the margin let it come
    # (60 + 6 + 4 px).
    assert room.misses(rest, target)[0] < 80.0
    guide.steer(rest, through, np.array([150.0, 150.0]), 0.5)
    assert not guide.jammed


def test_a_jammed_search_out_of_work_settles_for_the_polish_from_where_the_chain_is(
    monkeypatch,
):
    room, _, target, through = _under_the_floor()
    measured = np.array([-1.0, -0.3, -0.2])  # out to the right, above the floor
    monkeypatch.setattr(clearance, "JAMMED_WORK", 0.0)
    guide = Avoider(room)
    rest = _move_as_told(guide, measured, through, target, 400)
    assert guide.jammed and room.is_clear(rest)
    # Not the route to the nearest clear pose, but the polish from the start toward the target:
    # nearer the target than the start, reached in one clear straight line.
    near = room.polish(measured, target)
    assert np.allclose(rest, near.angles)
    assert room.misses(rest, target)[0] < room.misses(measured, target)[0]


def test_capped_work_gives_up_once_past_its_units():
    def work():
        for _ in range(10):
            yield 10.0
        return "done"

    assert _finish(_capped(work(), 100.0)) == "done"
    steps = []
    capped = _capped(work(), 35.0)
    with pytest.raises(StopIteration) as stop:
        while True:
            steps.append(next(capped))
    assert stop.value.value is None and len(steps) == 4


def _left_shelf_room() -> Clearance:
    """Five 90 px links (limits +-150 deg) mounted straight up over a floor, a shelf 130 px up
    to the left from x = -110 px (the stress level with five links under a shelf to the left)."""
    limit = math.radians(150.0)
    arm = Skeleton.chain([90.0] * 5, base_angle=UP, limits=[(-limit, limit)] * 5)
    obstacles = Obstacles.from_arrays(
        np.array([[-600.0, -20.0, 600.0, -20.0, 0.0], [-450.0, 130.0, -110.0, 130.0, 6.0]]),
        NO_CIRCLES,
    )
    return Clearance(arm, np.full(5, 6.0), obstacles)


UNDER_SHELF = np.radians([42.0, -16.0, -86.0, -129.0, -36.0])  # the tip low under its end
DEEPER = np.array([-220.0, 50.0])


def test_a_clear_answer_on_a_stop_is_taken_only_when_none_off_the_stops_is_found(monkeypatch):
    room = _left_shelf_room()
    answer = np.radians([67.0, -15.0, -116.0, -150.0, -50.0])  # through the shelf
    found = room.clear_answer(UNDER_SHELF, answer, DEEPER, 0.5)
    # The clear answer a straight turn away is a fold with its third joint on its stop, from
    # which a target deeper under the shelf was 3 s of route away: one off the stops is taken.
    assert room.off_stops(found) and room.is_clear(found)
    assert room.misses(found, DEEPER)[0] <= 0.5
    monkeypatch.setattr(Clearance, "off_stops", lambda self, angles: False)
    pressed = room.clear_answer(UNDER_SHELF, answer, DEEPER, 0.5)
    # With none off the stops, the first one the chain can turn to in a straight line it is.
    assert room.path_clear(UNDER_SHELF, pressed) and room.misses(pressed, DEEPER)[0] <= 0.5


def test_a_solvers_clear_answer_on_a_stop_is_routed_to_only_when_none_off_the_stops_is_found(
    monkeypatch,
):
    room = _left_shelf_room()
    start = np.radians([33.0, 4.0, -99.0, -124.0, -42.0])
    answer = np.radians([60.0, 2.0, -131.0, -150.0, -51.0])  # clear, its fourth joint on its stop
    assert room.is_clear(answer) and not room.path_clear(start, answer)
    goals = []

    def straight_there(self, a, b, back=None, slide=True):
        goals.append(b)
        yield ITERATION_UNITS
        return [b]

    monkeypatch.setattr(Clearance, "_routing", straight_there)
    guide = Avoider(room, budget=math.inf)
    goal = _finish(guide._planning(start, answer, DEEPER, 0.5, answer))[0]
    assert room.off_stops(goal) and room.misses(goal, DEEPER)[0] <= 0.5
    assert len(goals) == 1 and np.array_equal(goals[0], goal)
    # With no way to it, the way to the solver's answer.
    roomy = goal

    def none_to_it(self, a, b, back=None, slide=True):
        goals.append(b)
        yield ITERATION_UNITS
        return None if np.array_equal(b, roomy) else [b]

    monkeypatch.setattr(Clearance, "_routing", none_to_it)
    goals.clear()
    goal = _finish(guide._planning(start, answer, DEEPER, 0.5, answer))[0]
    assert np.array_equal(goal, answer) and len(goals) == 2
    # With no clear answer off the stops, the way to the solver's is searched for, as before.
    monkeypatch.setattr(Clearance, "off_stops", lambda self, angles: False)
    goals.clear()
    goal = _finish(guide._planning(start, answer, DEEPER, 0.5, answer))[0]
    assert np.array_equal(goal, answer) and len(goals) == 1


def _deep_shelf_room() -> Clearance:
    """Five 80 px links (limits +-150 deg) mounted straight up over a floor 20 px below the
    base, and a shelf 100 px up to the right from x = 110 px (a stress level under a shelf)."""
    limit = math.radians(150.0)
    arm = Skeleton.chain([80.0] * 5, base_angle=UP, limits=[(-limit, limit)] * 5)
    obstacles = Obstacles.from_arrays(
        np.array([[-600.0, -20.0, 600.0, -20.0, 0.0], [110.0, 100.0, 450.0, 100.0, 6.0]]),
        NO_CIRCLES,
    )
    return Clearance(arm, np.full(5, 6.0), obstacles)


def _retreat_end(room: Clearance, root: np.ndarray, **kind: bool) -> np.ndarray:
    """Where the end of a tree grown from ``root`` along its retreat (``slide``, ``walk``) ends
    up, px, every piece of the tree checked clear."""
    tree = clearance._Tree(root, room._link_gaps(root[None])[0])
    last = _finish(room._retreating(tree, **kind))
    for child in range(1, tree.size):
        assert room.path_clear(tree.poses[tree.parents[child]], tree.poses[child])
    return room.points(tree.poses[last])[-1]


# The tip at (190, 35) under the shelf, the links out along it without a fold back.
SPREAD_UNDER = np.radians([0.7, -7.6, -118.9, -26.9, 58.1])


def test_a_sliding_retreat_leads_out_from_under_the_shelf_where_the_polish_steps_stop():
    room = _deep_shelf_room()
    assert room.is_clear(SPREAD_UNDER)
    ends = {slide: _retreat_end(room, SPREAD_UNDER, slide=slide) for slide in (False, True)}
    # The polish's own steps press the end into the shelf's underside: the tree stops there.
    assert ends[False][0] > 110.0 and ends[False][1] < 100.0
    # Sliding along it, the tree reaches the retreat point, half the reach straight up.
    assert math.dist(ends[True], (0.0, 200.0)) < 1.0


# The tip at (290, 40) deep under the shelf, the third joint bending the links back down into
# the gap between the shelf's end and the base before they run out under it.
FOLDED_DEEP = np.radians([-8.4, -61.6, -77.4, 57.3, 0.7])


def test_a_walked_retreat_draws_the_chain_out_from_under_the_shelf_the_way_its_links_lie():
    room = _deep_shelf_room()
    assert room.is_clear(FOLDED_DEEP)
    ends = {walk: _retreat_end(room, FOLDED_DEEP, slide=True, walk=walk) for walk in (False, True)}
    # Drawn straight at the retreat point, the end stops under the shelf.
    assert ends[False][0] > 110.0 and ends[False][1] < 100.0
    # Led back along its own links to the base, the chain comes out and reaches it.
    assert math.dist(ends[True], (0.0, 200.0)) < 1.0


def test_a_walked_retreat_whose_end_falls_behind_stops_there():
    # Four 80 px links reaching along the floor in under a round rock to its far side: drawn
    # back toward the base, the fold under the rock comes to its stop and the end is caught.
    limit = math.radians(150.0)
    arm = Skeleton.chain([80.0] * 4, base_angle=UP, limits=[(-limit, limit)] * 4)
    floor = np.array([[-600.0, -20.0, 600.0, -20.0, 4.0]])
    room = Clearance(arm, np.full(4, 6.0), Obstacles.from_arrays(floor, [[155.0, 70.0, 42.0]]))
    under = np.radians([-94.4, 90.8, -136.7, 53.0])
    assert room.is_clear(under)
    tree = clearance._Tree(under, room._link_gaps(under[None])[0])
    last, units = _worked(room._retreating(tree, slide=True, walk=True))
    assert room.points(tree.poses[last])[-1][1] < 70.0  # still under the rock
    line = np.concatenate((room.points(under)[::-1], [[0.0, 160.0]]))
    marks = clearance._marks(_finish(room._taut(line)), clearance.WALK_STEP)
    # Polished toward every mark of the way out, it took 49,000 units; it gives up within a few.
    assert units < 0.2 * len(marks) * clearance.WALK_ITERATIONS * ITERATION_UNITS


@pytest.mark.parametrize("seed", range(5))
def test_the_route_trees_draw_poses_from_the_start_as_far_as_the_goal(seed):
    room = _deep_shelf_room()
    rng = np.random.default_rng(seed)
    sk = room.skeleton
    start, goal = rng.uniform(sk.lower, sk.upper, (2, sk.count))
    start[2], goal[2] = sk.upper[2], sk.lower[2] + 0.5  # a goal bent the other way from a stop
    low, high = room._sampled_box(start, goal)
    assert np.all((low <= start) & (start <= high)) and np.all((low <= goal) & (goal <= high))
    assert np.all(low >= sk.lower) and np.all(high <= sk.upper)
    assert np.all(low >= np.minimum(start - math.pi, goal))
