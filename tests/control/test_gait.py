"""The gait on made-up bodies and terrains: planted feet hold, groups take turns, steps land on
the ground and clear it on the way; and the terrain's ray cast against hand-computed hits."""

import math

import numpy as np
import pytest

from ikgame.control import FootState, Gait, GaitParams, Terrain, default_groups

DT = 1.0 / 240
SPEED = 120.0
HIGH = 1e6
PARAMS = GaitParams(stride=60.0, step_height=20.0, step_time=0.25, threshold=30.0)
# Left/right pairs front to back, the near and far legs a little apart in the side view.
QUAD = {"fl": (40.0, -80.0), "fr": (30.0, -80.0), "hl": (-30.0, -80.0), "hr": (-40.0, -80.0)}
HEX = {"l0": (65.0, -80.0), "r0": (60.0, -80.0), "l1": (15.0, -80.0), "r1": (10.0, -80.0)}
HEX |= {"l2": (-35.0, -80.0), "r2": (-40.0, -80.0)}
# The ground's top at y = 0, far wider than any walk.
FLOOR = [-3000.0, -10.0, 3000.0, -10.0, 10.0]


class Record:
    """Every tick of a walk: targets, feet states and the stepping group."""

    def __init__(self, gait, poses, spots=QUAD):
        self.gait = gait
        targets, planted, points, swinging, rest = [], [], [], [], []
        spots = np.array([spots[leg] for leg in gait.legs])
        for tick, (position, angle) in enumerate(poses, 1):
            out = gait.update(tick * DT, DT, position, angle)
            feet = gait.feet
            targets.append([out[leg] for leg in gait.legs])
            planted.append([feet[leg].planted for leg in gait.legs])
            points.append([feet[leg].point for leg in gait.legs])
            swinging.append(gait.swinging)
            c, s = math.cos(angle), math.sin(angle)
            rest.append(np.asarray(position) + spots @ np.array([[c, s], [-s, c]]))
        self.targets = np.array(targets)
        self.planted = np.array(planted)
        self.points = np.array(points)
        self.swinging = swinging
        self.rest = np.array(rest)

    def lifts(self):
        """(tick, leg index) of every foot leaving the ground."""
        was = np.vstack([np.ones((1, self.planted.shape[1]), bool), self.planted[:-1]])
        return np.argwhere(was & ~self.planted)

    def landings(self):
        """(tick, leg index) of every foot coming down."""
        return np.argwhere(~self.planted[:-1] & self.planted[1:]) + [1, 0]


def _line(start, end, *, y=80.0, speed=SPEED):
    ticks = round(abs(end - start) / speed / DT)
    return [((start + (end - start) * k / ticks, y), 0.0) for k in range(1, ticks + 1)]


def _still(position, seconds, angle=0.0):
    return [(position, angle)] * round(seconds / DT)


def _check(record, terrain, *, on_ground=True):
    """What holds for every walk: planted feet do not move, one group steps at a time, a
    step stays above the terrain and lands exactly where it was planned, on the ground."""
    gait, targets, planted = record.gait, record.targets, record.planted
    both = planted[1:] & planted[:-1]
    assert np.array_equal(targets[1:][both], targets[:-1][both])
    assert np.array_equal(targets[planted], record.points[planted])
    groups = [set(g) for g in gait.groups]
    for tick, group in enumerate(record.swinging):
        stepping = {leg for leg, p in zip(gait.legs, planted[tick], strict=True) if not p}
        assert stepping == (set() if group is None else groups[group])
    swing = targets[~planted]
    ground = terrain.heights(swing[:, 0], HIGH)
    has = ~np.isnan(ground)
    assert np.all(swing[has, 1] >= ground[has])
    # Every step takes step_time (to the tick): a group never lands and lifts again unseen.
    step = round(gait.params.step_time / DT)
    for (lifted, leg), (landed, other) in zip(record.lifts(), record.landings(), strict=False):
        assert leg == other and landed - lifted in (step, step + 1)
    for tick, leg in record.landings():
        foot = targets[tick, leg]
        assert np.array_equal(foot, record.points[tick - 1, leg])
        if on_ground:
            assert foot[1] == terrain.ground_below(foot[0], HIGH)


def _quad(terrain, start=(0.0, 80.0), **kwargs):
    return Gait(PARAMS, QUAD, terrain, position=start, **kwargs)


@pytest.mark.parametrize(
    "params", [PARAMS, GaitParams(stride=80.0, step_height=10.0, step_time=0.2, threshold=20.0)]
)
def test_walking_on_flat_ground_plants_and_steps_every_foot_in_alternating_pairs(params):
    terrain = Terrain(segments=[FLOOR])
    record = Record(Gait(params, QUAD, terrain, position=(0.0, 80.0)), _line(0.0, 1000.0))
    _check(record, terrain)
    lifts = record.lifts()
    assert set(lifts[:, 1]) == {0, 1, 2, 3}
    order = [record.swinging[tick] for tick in sorted(set(lifts[:, 0]))]
    assert order == [k % 2 for k in range(len(order))]
    assert record.gait.groups == (("fl", "hr"), ("fr", "hl"))
    # A planted foot lands half a stride ahead of its rest spot and steps once the body has
    # carried the rest spot past it by the threshold (plus at most the other pair's step).
    gap = record.rest[..., 0] - record.targets[..., 0]
    slack = SPEED * 2 * DT
    planted = gap[record.planted]
    assert planted.min() >= -params.stride / 2 - slack
    assert planted.max() <= params.threshold + SPEED * params.step_time + slack
    landed = np.array([gap[tick, leg] for tick, leg in record.landings()])
    assert np.all(np.abs(landed + params.stride / 2) <= slack)
    # ... so a foot that has landed stands until the body has carried it that far.
    stand = (params.stride / 2 + params.threshold) / SPEED - 2 * DT
    for tick, leg in record.landings():
        lifts = [t for t, g in record.lifts() if g == leg and t > tick]
        assert not lifts or (lifts[0] - tick) * DT >= stand


def test_six_legs_walk_in_alternating_tripods():
    terrain = Terrain(segments=[FLOOR])
    gait = Gait(PARAMS, HEX, terrain, position=(0.0, 80.0))
    record = Record(gait, _line(0.0, 600.0), HEX)
    _check(record, terrain)
    assert gait.groups == (("l0", "r1", "l2"), ("r0", "l1", "r2"))
    assert set(record.lifts()[:, 1]) == set(range(6))


def test_groups_take_turns_in_order_when_all_are_due():
    terrain = Terrain(segments=[FLOOR])
    pairs = [["l0", "r0"], ["l1", "r1"], ["l2", "r2"]]
    gait = Gait(PARAMS, HEX, terrain, position=(0.0, 80.0), groups=pairs)
    # Fast enough that every pair is due again before the other two have stepped.
    record = Record(gait, _line(0.0, 1500.0, speed=300.0), HEX)
    _check(record, terrain)
    order = [record.swinging[tick] for tick in sorted(set(record.lifts()[:, 0]))]
    assert len(order) > 10 and order == [k % 3 for k in range(len(order))]


def test_standing_still_takes_no_step():
    terrain = Terrain(segments=[FLOOR])
    gait = _quad(terrain)
    record = Record(gait, _still((0.0, 80.0), 3.0))
    assert all(group is None for group in record.swinging)
    assert np.all(record.targets == record.targets[0])
    assert np.array_equal(record.targets[0, :, 0], [40.0, 30.0, -30.0, -40.0])
    assert np.all(record.targets[..., 1] == 0.0)


def test_a_foot_left_far_away_steps_back_under_a_still_body_and_stays():
    terrain = Terrain(segments=[FLOOR])
    feet = {"fl": (-60.0, 0.0), "fr": (30.0, 0.0), "hl": (-30.0, 0.0), "hr": (-40.0, 0.0)}
    record = Record(_quad(terrain, feet=feet), _still((0.0, 80.0), 2.0))
    _check(record, terrain)
    assert [leg for _, leg in record.lifts()] == [0, 3]  # the far foot's pair, once
    assert np.array_equal(record.targets[-1, :, 0], [40.0, 30.0, -30.0, -40.0])


def test_uneven_ground_steps_onto_a_block_a_steep_platform_and_a_bump_and_clears_them():
    terrain = Terrain(
        segments=[
            FLOOR,
            [400.0, 20.0, 600.0, 20.0, 20.0],  # a rounded block, top 40
            [800.0, 0.0, 800.0, 50.0, 0.0],  # a platform with sheer sides, top 50
            [800.0, 50.0, 1000.0, 50.0, 0.0],
            [1000.0, 50.0, 1000.0, 0.0, 0.0],
        ],
        circles=[[1300.0, -20.0, 60.0]],  # a bump, top 40
    )
    record = Record(_quad(terrain, (0.0, 110.0)), _line(0.0, 1600.0, y=110.0))
    _check(record, terrain)
    landed = np.array([record.targets[tick, leg] for tick, leg in record.landings()])
    assert np.any((landed[:, 0] > 400) & (landed[:, 0] < 600) & (landed[:, 1] == 40.0))
    assert np.any((landed[:, 0] > 800) & (landed[:, 0] < 1000) & (landed[:, 1] == 50.0))
    bump = (landed[:, 0] > 1240) & (landed[:, 0] < 1360)
    assert np.any(bump & (landed[:, 1] > 0.0))
    # Every foot steps up onto the platform and back down.
    for leg in range(4):
        ys = record.targets[record.planted[:, leg], leg, 1]
        assert 50.0 in ys and ys[-1] == 0.0


def test_walking_back_and_forth_steps_ahead_in_each_direction():
    terrain = Terrain(segments=[FLOOR])
    there = _line(0.0, 400.0)
    back = _line(400.0, -400.0)
    record = Record(_quad(terrain), there + back)
    _check(record, terrain)
    slack = SPEED * 2 * DT
    turned = len(there) + round(1.0 / DT)
    ahead = {True: [], False: []}  # landings once the body goes left / while it goes right
    for tick, leg in record.landings():
        if tick < len(there) or tick >= turned:
            ahead[tick >= turned].append(record.targets[tick, leg, 0] - record.rest[tick, leg, 0])
    assert np.all(np.abs(np.array(ahead[False]) - PARAMS.stride / 2) <= slack)
    assert np.all(np.abs(np.array(ahead[True]) + PARAMS.stride / 2) <= slack)
    late = {leg for tick, leg in record.landings() if tick >= turned}
    assert late == {0, 1, 2, 3} and len(ahead[False]) >= 4


def test_turning_in_place_steps_the_feet_after_their_rest_spots_then_stands():
    terrain = Terrain(segments=[FLOOR])
    turn = [((0.0, 80.0), 0.6 * k / 480) for k in range(1, 481)]
    record = Record(_quad(terrain), turn + _still((0.0, 80.0), 1.5, angle=0.6))
    _check(record, terrain)
    assert set(record.lifts()[:, 1]) == {0, 1, 2, 3}
    # Every rest spot moves to the right as the body turns: the feet land half a stride ahead.
    ahead = [record.targets[t, leg, 0] - record.rest[t, leg, 0] for t, leg in record.landings()]
    assert np.allclose(ahead, PARAMS.stride / 2, atol=0.5)
    assert all(group is None for group in record.swinging[-round(1.0 / DT) :])
    gap = np.abs(record.rest[-1, :, 0] - record.targets[-1, :, 0])
    assert np.all(gap <= max(PARAMS.threshold, PARAMS.stride / 2))


def test_a_wall_higher_than_the_body_stops_the_feet_short_of_it():
    wall = [400.0, 0.0, 400.0, 300.0, 5.0]
    terrain = Terrain(segments=[FLOOR, wall])
    record = Record(_quad(terrain), _line(0.0, 340.0) + _still((340.0, 80.0), 1.0))
    _check(record, terrain)
    assert record.targets[..., 0].max() < 395.0
    landed = [record.targets[tick, leg, 0] for tick, leg in record.landings() if leg < 2]
    assert max(landed) > 380.0


def test_without_ground_or_beyond_reach_feet_keep_the_rest_height():
    record = Record(_quad(Terrain()), _line(0.0, 300.0))
    _check(record, Terrain(), on_ground=False)
    assert len(record.landings()) > 0
    assert np.all(record.targets[record.planted][:, 1] == 0.0)
    # A ledge ending at x = 300 over ground 400 px below.
    ledge = Terrain(segments=[[-3000.0, -10.0, 300.0, -10.0, 10.0], [-3000, -410, 3000, -410, 10]])
    for reach, below in ((150.0, 0.0), (None, -400.0)):
        record = Record(_quad(ledge, reach=reach), _line(0.0, 700.0))
        _check(record, ledge, on_ground=reach is None)
        past = [record.targets[t, leg] for t, leg in record.landings()]
        past = np.array([foot for foot in past if foot[0] > 320.0])
        assert len(past) and np.all(past[:, 1] == below)


def _depth(points, capsules):
    """How deep each point lies inside the deepest capsule ``(ax, ay, bx, by, radius)``, px
    (negative: outside them all)."""
    a, d = capsules[:, 0:2], capsules[:, 2:4] - capsules[:, 0:2]
    squared = np.where((d * d).sum(1) > 0, (d * d).sum(1), 1.0)
    t = np.clip(((points[:, None] - a) * d).sum(-1) / squared, 0.0, 1.0)
    gap = np.hypot(*np.moveaxis(points[:, None] - a - t[..., None] * d, -1, 0))
    return (capsules[:, 4] - gap).max(axis=1)


@pytest.mark.parametrize("seed", range(4))
def test_on_random_cluttered_ground_a_stepping_foot_stays_out_of_every_obstacle(seed):
    rng = np.random.default_rng(seed)
    start, angle = rng.uniform([0, -10], [1000, 60], (15, 2)), rng.uniform(-3.0, 3.0, 15)
    end = start + rng.uniform(0, 120, 15)[:, None] * np.column_stack([np.cos(angle), np.sin(angle)])
    planks = np.column_stack([start, end, rng.uniform(0, 15, 15)])
    circles = np.column_stack([rng.uniform([0, -60], [1000, 20], (5, 2)), rng.uniform(5, 60, 5)])
    terrain = Terrain(np.vstack([FLOOR, planks]), circles)
    speed = rng.uniform(40.0, 200.0)
    record = Record(_quad(terrain, (0.0, 150.0)), _line(0.0, 1000.0, y=150.0, speed=speed))
    capsules = np.vstack([FLOOR, planks, np.column_stack([circles[:, :2], circles])])
    # The arc is checked against the terrain at 64 points, so between them it may graze.
    assert _depth(record.targets[~record.planted], capsules).max() < 0.1
    assert set(record.lifts()[:, 1]) == {0, 1, 2, 3}


def test_ray_casts_against_hand_computed_hits():
    flat = Terrain(segments=[[0.0, 0.0, 100.0, 0.0, 10.0]])
    assert flat.ground_below(50.0, 100.0) == 10.0
    assert flat.ground_below(105.0, 100.0) == pytest.approx(math.sqrt(75.0))  # the end cap
    assert flat.ground_below(111.0, 100.0) is None
    assert flat.ground_below(50.0, 3.0) == 3.0  # starts inside
    assert flat.ground_below(50.0, -20.0) is None  # starts below
    slope = Terrain(segments=[[0.0, 0.0, 100.0, 100.0, 5.0]])
    assert slope.ground_below(50.0, 500.0) == pytest.approx(50.0 + 5.0 * math.sqrt(2.0))
    thin = Terrain(segments=[[50.0, 0.0, 50.0, 100.0, 0.0]])
    assert thin.ground_below(50.0, 150.0) == 100.0
    assert thin.ground_below(50.0, 40.0) == 40.0
    assert thin.ground_below(50.001, 150.0) is None
    circle = Terrain(circles=[[0.0, 0.0, 10.0]])
    assert circle.ground_below(6.0, 50.0) == 8.0
    assert circle.ground_below(-10.0, 50.0) == 0.0
    # A floor under a ceiling: the ray meets whichever lies first below its start.
    both = Terrain(segments=[[-100.0, 0.0, 100.0, 0.0, 0.0], [-100.0, 200.0, 100.0, 200.0, 0.0]])
    assert both.ground_below(0.0, 100.0) == 0.0
    assert both.ground_below(0.0, 300.0) == 200.0
    assert Terrain().ground_below(0.0, 0.0) is None
    assert np.array_equal(
        both.heights([[0.0, 0.0], [500.0, 0.0]], [[100.0, 300.0]]),
        [[0.0, 200.0], [np.nan, 200.0]],
        equal_nan=True,
    )


def _reference_hit(x, y_from, capsule):
    """The ray's hit on one capsule, by bisection on the distance to its segment (convex along
    the ray): an independent answer to check the vectorised cast against."""
    ax, ay, bx, by, r = (float(v) for v in capsule)
    dx, dy = bx - ax, by - ay
    squared = dx * dx + dy * dy

    def distance(y):
        t = min(max(((x - ax) * dx + (y - ay) * dy) / squared, 0.0), 1.0) if squared else 0.0
        return math.hypot(x - ax - t * dx, y - ay - t * dy)

    lo, hi = min(ay, by) - r - 1.0, max(ay, by) + r + 1.0
    for _ in range(80):
        m1, m2 = lo + (hi - lo) / 3, hi - (hi - lo) / 3
        lo, hi = (lo, m2) if distance(m1) < distance(m2) else (m1, hi)
    nearest = (lo + hi) / 2
    if distance(nearest) > r:
        return None
    edges = []
    for far in (max(ay, by) + r + 1.0, min(ay, by) - r - 1.0):
        inner, outer = nearest, far
        for _ in range(80):
            mid = (inner + outer) / 2
            inner, outer = (mid, outer) if distance(mid) <= r else (inner, mid)
        edges.append(inner)
    top, bottom = edges
    return top if top <= y_from else y_from if bottom <= y_from else None


def test_the_vectorised_cast_matches_an_independent_one_on_random_obstacles():
    rng = np.random.default_rng(11)
    segments = np.hstack([rng.uniform(-200, 200, (12, 4)), rng.uniform(0, 15, (12, 1))])
    segments[0, 2:4] = segments[0, 0:2]  # a zero-length segment is a disc
    circles = np.hstack([rng.uniform(-200, 200, (6, 2)), rng.uniform(1, 40, (6, 1))])
    terrain = Terrain(segments, circles)
    capsules = list(segments) + [[x, y, x, y, r] for x, y, r in circles]
    xs, tops = rng.uniform(-220, 220, 200), rng.uniform(-250, 250, 200)
    heights = terrain.heights(xs, tops)
    for x, top, height in zip(xs.tolist(), tops.tolist(), heights, strict=True):
        hits = [h for c in capsules if (h := _reference_hit(x, top, c)) is not None]
        expected = max(hits) if hits else np.nan
        assert height == pytest.approx(expected, abs=1e-6, nan_ok=True)


def test_a_few_rays_cast_one_by_one_give_the_batch_cast_to_the_bit():
    # A tick casts a handful of rays in Python floats, a step plan many at once with numpy:
    # the two must agree exactly, or a run would depend on how many feet it checks.
    rng = np.random.default_rng(5)
    segments = np.hstack([rng.uniform(-200, 200, (12, 4)), rng.uniform(0, 15, (12, 1))])
    segments[0, 2:4] = segments[0, 0:2]  # a zero-length segment
    segments[1, 2] = segments[1, 0]  # a vertical one
    segments[2, 4] = 0.0  # a bare segment
    circles = np.hstack([rng.uniform(-200, 200, (6, 2)), rng.uniform(1, 40, (6, 1))])
    terrain = Terrain(segments, circles)
    corners = terrain._edge_start[..., 0].ravel()
    cuts = np.array(terrain._cuts)  # where the one-by-one cast changes the parts it looks at
    xs = np.concatenate([rng.uniform(-220, 220, 400), corners, segments[:, [0, 2]].ravel(), cuts])
    tops = rng.uniform(-250, 250, xs.shape[0])
    many = terrain.heights(xs, tops)
    few = np.concatenate(
        [terrain.heights(xs[i : i + 3], tops[i : i + 3]) for i in range(0, len(xs), 3)]
    )
    assert np.isnan(many).any() and not np.isnan(many).all()
    assert np.array_equal(few, many, equal_nan=True)
    assert np.array_equal(np.signbit(few), np.signbit(many))


def test_default_groups_alternate_down_each_side():
    assert default_groups(["a"]) == (("a",),)
    assert default_groups(["l", "r"]) == (("l",), ("r",))
    assert default_groups(["fl", "fr", "hl", "hr"]) == (("fl", "hr"), ("fr", "hl"))
    with pytest.raises(ValueError, match="at least one leg"):
        default_groups([])
    with pytest.raises(ValueError, match="unique"):
        default_groups(["a", "a"])


def test_bad_input_is_refused_with_a_message():
    with pytest.raises(ValueError, match="step_time must be > 0"):
        GaitParams(stride=60.0, step_height=20.0, step_time=0.0, threshold=30.0)
    with pytest.raises(ValueError, match="stride must be >= 0"):
        GaitParams(stride=-1.0, step_height=20.0, step_time=0.2, threshold=30.0)
    with pytest.raises(ValueError, match="threshold must be a finite number"):
        GaitParams(stride=60.0, step_height=20.0, step_time=0.2, threshold=math.nan)
    with pytest.raises(ValueError, match=r"segments must be a finite \(ax, ay, bx, by, radius\)"):
        Terrain(segments=[[0.0, 0.0, 1.0, 1.0]])
    with pytest.raises(ValueError, match="radius must be >= 0"):
        Terrain(circles=[[0.0, 0.0, -1.0]])
    terrain = Terrain()
    with pytest.raises(ValueError, match="each leg in exactly one"):
        Gait(PARAMS, QUAD, terrain, position=(0.0, 80.0), groups=[["fl", "fr"], ["hl"]])
    with pytest.raises(ValueError, match="each leg in exactly one"):
        Gait(PARAMS, QUAD, terrain, position=(0.0, 80.0), groups=[["fl", "fr", "hl", "hr"], []])
    with pytest.raises(ValueError, match="feet must give a point for each leg"):
        Gait(PARAMS, QUAD, terrain, position=(0.0, 80.0), feet={"fl": (0.0, 0.0)})
    with pytest.raises(ValueError, match="at least one leg"):
        Gait(PARAMS, {}, terrain, position=(0.0, 80.0), groups=[])
    with pytest.raises(ValueError, match="rest spot of 'a'"):
        Gait(PARAMS, {"a": (0.0,)}, terrain, position=(0.0, 80.0))
    gait = Gait(PARAMS, QUAD, terrain, position=(0.0, 80.0))
    with pytest.raises(ValueError, match="dt must be a positive"):
        gait.update(0.0, 0.0, (0.0, 80.0), 0.0)
    state = gait.feet["fl"]
    assert isinstance(state, FootState) and state.planted and state.progress == 0.0
