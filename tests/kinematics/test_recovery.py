"""RobustSolver: restarts that get every solver out of limit traps, the cache, the hysteresis.

Reachable targets are the forward kinematics of poses drawn inside the limits, so some pose
within the limits reaches each one exactly. Every random draw comes from a seeded generator.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ikgame.kinematics import (
    SOLVERS,
    TARGET_SOLVERS,
    RobustSolver,
    Skeleton,
    SolveStatus,
    TargetSet,
    forward_kinematics,
)
from ikgame.kinematics.recovery import (
    HOLDS,
    JUMPED,
    OFF_STOPS,
    RESTART_BUDGET,
    SETTLED,
    SPENT,
    STILL_CALLS,
    STRAINED,
    held_nearest,
    holds_along,
)

PI = math.pi
NAMES = sorted(SOLVERS)
TOLERANCE = 0.5
r = math.radians


def _end(skeleton: Skeleton, angles: np.ndarray) -> np.ndarray:
    return forward_kinematics(skeleton, angles)[0][-1]


def _limit(rng: np.random.Generator) -> tuple[float, float] | None:
    """Free, wide, tight (a few degrees) or one-sided limits, radians."""
    kind = rng.integers(5)
    if kind == 0:
        return None
    if kind == 1:
        half = rng.uniform(r(30), r(170))
        return (-half, half)
    if kind == 2:
        half = rng.uniform(r(3), r(15))
        return (-half, half)
    near, far = rng.uniform(r(5), r(30)), rng.uniform(r(90), r(170))
    return (near, far) if kind == 3 else (-far, -near)


def _in_limits(rng: np.random.Generator, skeleton: Skeleton) -> np.ndarray:
    return rng.uniform(np.maximum(skeleton.lower, -PI), np.minimum(skeleton.upper, PI))


def _case(rng: np.random.Generator) -> tuple[Skeleton, np.ndarray, np.ndarray]:
    """A chain of 1 to 30 links, a start (straight, coiled against its limits or anywhere) and a
    reachable target."""
    n = int(rng.integers(1, 31))
    chain = Skeleton.chain(
        rng.uniform(10.0, 100.0, n),
        base=rng.uniform(-200.0, 200.0, 2),
        base_angle=rng.uniform(-PI, PI),
        limits=[_limit(rng) for _ in range(n)],
    )
    target = _end(chain, _in_limits(rng, chain))
    start = [
        chain.clamp(np.zeros(n)),
        np.maximum(chain.lower, -2.8),
        np.minimum(chain.upper, 2.8),
        _in_limits(rng, chain),
    ][rng.integers(4)]
    return chain, start, target


def _tick_by_tick(robust: RobustSolver, start: np.ndarray, target, calls: int = 60):
    """Solve as a controller does without physics: each call starts from the last answer."""
    angles = start
    for _ in range(calls):
        sol = robust.solve(angles, target, max_iterations=10, tolerance=TOLERANCE)
        assert np.all(sol.angles >= robust.skeleton.lower)
        assert np.all(sol.angles <= robust.skeleton.upper)
        assert sol.error == pytest.approx(np.hypot(*(_end(robust.skeleton, sol.angles) - target)))
        angles = sol.angles
        if sol.status is not SolveStatus.PROCESSING:
            break
    return sol


# -- reaching what is reachable -----------------------------------------------------------------


@pytest.mark.parametrize("name", NAMES)
def test_every_reachable_target_is_reached_within_the_limits(name):
    rng = np.random.default_rng(2026)
    missed = []
    for case in range(150):
        chain, start, target = _case(rng)
        sol = _tick_by_tick(RobustSolver(chain, name), start, target)
        if sol.status is not SolveStatus.SUCCESS:
            missed.append((case, chain.count, sol.status.value, sol.error))
    assert missed == []


def _elbow_arm() -> tuple[Skeleton, np.ndarray]:
    """The base limited to [-30, 120] deg, an elbow bending one way only, a wrist the other; a
    target behind the arm that needs the base at +100 deg."""
    arm = Skeleton.chain(
        [120.0, 100.0, 80.0], limits=[(r(-30), r(120)), (r(10), r(170)), (r(-170), r(-10))]
    )
    return arm, _end(arm, np.array([r(100), r(120), r(-30)]))


@pytest.mark.parametrize("name", NAMES)
def test_the_base_goes_the_long_way_round_its_stop(name):
    arm, target = _elbow_arm()
    # A trap for every raw solver: from the -30 deg stop the short way round is through it.
    raw = SOLVERS[name](arm, arm.lower, target, max_iterations=1000, tolerance=TOLERANCE)
    assert raw.status is SolveStatus.FAILURE
    robust = RobustSolver(arm, name)
    angles = arm.lower
    # Restarts far from the stall wait until the target has held still for STILL_CALLS calls.
    for _ in range(STILL_CALLS + 1):
        sol = robust.solve(angles, target, max_iterations=10, tolerance=TOLERANCE)
        assert sol.iterations <= 10 + RESTART_BUDGET
        angles = sol.angles
    assert sol.status is SolveStatus.SUCCESS
    assert sol.angles[0] > r(90)


def test_a_light_chain_coiled_into_its_limits_uncoils():
    # Eight links limited to +-160 deg, all curled onto the +160 stop: CCD alone ends short.
    chain = Skeleton.chain([30.0] * 8, base_angle=PI / 2, limits=[(r(-160), r(160))] * 8)
    rng = np.random.default_rng(7)
    start = np.full(8, r(160))
    trapped = 0
    for _ in range(20):
        target = _end(chain, _in_limits(rng, chain))
        angles = start
        for _ in range(100):
            raw = SOLVERS["ccd"](chain, angles, target, max_iterations=10, tolerance=TOLERANCE)
            angles = raw.angles
        trapped += raw.status is not SolveStatus.SUCCESS
        sol = _tick_by_tick(RobustSolver(chain, "ccd"), start, target)
        assert sol.status is SolveStatus.SUCCESS
    assert trapped >= 5


def test_a_stalled_ccd_restarts_next_to_the_chain_not_next_to_its_coil():
    # Twenty light links, slightly curled, and a target behind and below the base: CCD from the
    # chain's pose crawls, coiling the chain the long way round. The chain does not move while
    # it is asked (a chain waiting for its answer), and the answer the search settles on turns
    # the joints no more than least squares from where the chain is: once, the search restarted
    # next to CCD's coil and took an answer turning them 1,000 deg in all, not 600.
    chain = Skeleton.chain([15.0] * 20, base_angle=PI / 2, limits=[(r(-160), r(160))] * 20)
    for curl, target in (
        (-0.075, (-100.0, -200.0)),
        (0.0, (-100.0, -200.0)),
        (-0.078, (-150.0, -150.0)),
    ):
        here = np.full(20, curl)
        robust = RobustSolver(chain, "ccd")
        for _ in range(60):
            sol = robust.solve(here, np.array(target), tolerance=TOLERANCE)
            if sol.status is not SolveStatus.PROCESSING:
                break
        assert sol.status is SolveStatus.SUCCESS
        nearest = SOLVERS["dls"](
            chain, here, np.array(target), max_iterations=50, tolerance=TOLERANCE
        )
        assert nearest.status is SolveStatus.SUCCESS
        assert np.abs(sol.angles - here).sum() <= 1.05 * np.abs(nearest.angles - here).sum()


def test_a_far_seed_s_fallback_starts_from_the_seed_not_from_where_ccd_coiled():
    # Sixteen light links and a target at 96% of their reach: from the chain's pose and from
    # every far seed, CCD coils the last joints onto their -165 deg stops 28.8 px short, and
    # damped least squares run on from that coil cannot leave it. Run from the seed, it arrives.
    chain = Skeleton.chain([21.0] * 16, base_angle=PI / 2, limits=[(r(-165), r(165))] * 16)
    here = np.radians(
        [57, -3, -62, -50, -34, -23, -21, -21, -21, -21, -24, -24, -26, -16, 66, -136]
    )
    target = np.array([-320.0, 30.0])
    raw = SOLVERS["ccd"](chain, here, target, max_iterations=1000, tolerance=TOLERANCE)
    assert raw.status is not SolveStatus.SUCCESS and raw.error > 25.0
    robust = RobustSolver(chain, "ccd")
    for _ in range(100):
        sol = robust.solve(here, target, tolerance=TOLERANCE)
        if sol.status is not SolveStatus.PROCESSING:
            break
    assert sol.status is SolveStatus.SUCCESS


@pytest.mark.parametrize("name", NAMES)
def test_tight_symmetric_limits(name):
    rng = np.random.default_rng(10)
    for _ in range(20):
        n = int(rng.integers(2, 20))
        chain = Skeleton.chain(rng.uniform(20.0, 60.0, n), limits=[(r(-10), r(10))] * n)
        target = _end(chain, _in_limits(rng, chain))
        assert _tick_by_tick(RobustSolver(chain, name), np.zeros(n), target).status is (
            SolveStatus.SUCCESS
        )


# -- what cannot be reached -------------------------------------------------------------------


@pytest.mark.parametrize("name", NAMES)
def test_a_target_beyond_reach_fails_with_the_chain_stretched_toward_it(name):
    chain = Skeleton.chain([60.0, 50.0, 40.0], base=(10.0, 10.0), limits=[None, (-2, 2), None])
    robust = RobustSolver(chain, name)
    target = np.array([10.0 - 300.0, 10.0 + 400.0])
    sol = robust.solve(np.array([0.3, 1.0, -2.0]), target, tolerance=TOLERANCE)
    assert sol.status is SolveStatus.FAILURE
    np.testing.assert_allclose(sol.angles, [math.atan2(400.0, -300.0), 0.0, 0.0])
    assert sol.error == pytest.approx(500.0 - 150.0)
    again = robust.solve(sol.angles, target, tolerance=TOLERANCE)
    assert (again.status, again.iterations) == (SolveStatus.FAILURE, 0)


@pytest.mark.parametrize("name", NAMES)
def test_a_target_the_limits_keep_out_of_reach_fails_once_then_costs_nothing(name):
    # Within the reach's distance, but the base turns only in [0, 0.5] rad and the target is
    # behind it: after the search the best pose is cached with FAILURE.
    chain = Skeleton.chain([100.0, 50.0], limits=[(0.0, 0.5), (-0.2, 0.2)])
    robust = RobustSolver(chain, name)
    target = np.array([-100.0, -20.0])
    sol = _tick_by_tick(robust, np.zeros(2), target)
    assert sol.status is SolveStatus.FAILURE
    assert np.all(sol.angles >= chain.lower) and np.all(sol.angles <= chain.upper)
    best = min(
        np.hypot(*(_end(chain, np.array([a, b])) - target))
        for a in np.linspace(0.0, 0.5, 51)
        for b in np.linspace(-0.2, 0.2, 41)
    )
    assert sol.error <= best + 1e-6
    again = robust.solve(sol.angles, target, tolerance=TOLERANCE)
    assert (again.status, again.iterations, again.error) == (SolveStatus.FAILURE, 0, sol.error)


# -- the cost: the common case, the cache, the budget -------------------------------------------


@pytest.mark.parametrize("name", NAMES)
def test_a_plain_solve_that_arrives_is_returned_as_it_is(name):
    # The common case costs what the raw solver costs: no restarts, the same iterations.
    rng = np.random.default_rng(5)
    for _ in range(30):
        chain, start, target = _case(rng)
        raw = SOLVERS[name](chain, start, target, max_iterations=10, tolerance=TOLERANCE)
        if raw.status is not SolveStatus.SUCCESS:
            continue
        sol = RobustSolver(chain, name).solve(start, target, max_iterations=10, tolerance=TOLERANCE)
        assert sol.status is SolveStatus.SUCCESS
        if np.hypot(*(target - chain.base)) >= chain.reach:
            # A one-link chain's target lies at full reach: the stretched pose is the answer.
            assert sol.iterations == 0
            continue
        assert sol.iterations == raw.iterations
        np.testing.assert_allclose(sol.angles, raw.angles, atol=1e-12)


@pytest.mark.parametrize("name", NAMES)
def test_a_settled_chain_costs_no_iterations(name):
    rng = np.random.default_rng(6)
    for _ in range(20):
        chain, start, target = _case(rng)
        robust = RobustSolver(chain, name)
        sol = _tick_by_tick(robust, start, target)
        assert sol.status is SolveStatus.SUCCESS
        for _ in range(3):
            again = robust.solve(sol.angles, target, max_iterations=10, tolerance=TOLERANCE)
            assert again.iterations == 0
            np.testing.assert_array_equal(again.angles, sol.angles)


@pytest.mark.parametrize("budget", [0, 5, 40])
def test_the_budget_bounds_every_call_and_a_search_carries_on(budget):
    arm, target = _elbow_arm()
    robust = RobustSolver(arm, "ccd", budget=budget)
    angles = arm.lower
    for _ in range(100):
        sol = robust.solve(angles, target, max_iterations=10, tolerance=TOLERANCE)
        assert sol.iterations <= 10 + budget
        angles = sol.angles
    if budget:
        assert sol.status is SolveStatus.SUCCESS
    else:
        assert sol.status is not SolveStatus.SUCCESS


def test_a_bad_budget_is_refused():
    with pytest.raises(ValueError, match="budget must be an integer >= 0 iterations, got -1"):
        RobustSolver(Skeleton.chain([1.0]), "ccd", budget=-1)


def test_an_unknown_solver_is_refused():
    with pytest.raises(ValueError, match="unknown solver 'x'"):
        RobustSolver(Skeleton.chain([1.0]), "x")


# -- branches: near answers, no flipping -------------------------------------------------------


def test_an_answer_found_from_a_far_seed_is_followed_all_the_way_there():
    # Half way from the trap to such an answer, the plain solve from the measured pose could
    # fall back into the trap or take another branch, so the answer is kept.
    rng = np.random.default_rng(2026)
    followed = 0
    for _ in range(150):
        chain, start, target = _case(rng)
        robust = RobustSolver(chain, "ccd")
        answer = _tick_by_tick(robust, start, target)
        if not robust._answer.followed:
            continue
        followed += 1
        for share in np.linspace(0.0, 1.0, 5):
            measured = chain.clamp((1 - share) * start + share * answer.angles)
            sol = robust.solve(measured, target, tolerance=TOLERANCE)
            assert sol.iterations == 0
            np.testing.assert_array_equal(sol.angles, answer.angles)
    assert followed >= 3


def test_a_plain_answer_is_solved_again_until_the_chain_settles_on_it():
    # Elbow up and elbow down both reach; the answer follows the measured pose (the nearest
    # one), as the raw solver's would, until the chain has settled.
    chain = Skeleton.chain([100.0, 100.0])
    target = np.array([120.0, 60.0])
    robust = RobustSolver(chain, "dls")
    up = robust.solve(np.array([0.0, 1.0]), target, tolerance=TOLERANCE)
    assert up.status is SolveStatus.SUCCESS and up.angles[1] > 0
    down = robust.solve(np.array([1.0, -1.0]), target, tolerance=TOLERANCE)
    assert down.status is SolveStatus.SUCCESS and down.angles[1] < 0
    assert robust.solve(down.angles, target, tolerance=TOLERANCE).iterations == 0


def _coming_in(robust: RobustSolver, start: np.ndarray, target: np.ndarray, ticks: int = 30):
    """Each call's answer and the pose it was solved from, the chain brought a fifth of the way
    to the last answer between calls (as a servo brings it in)."""
    measured, calls = start, []
    for _ in range(ticks):
        sol = robust.solve(measured, target, tolerance=TOLERANCE)
        calls.append((measured, sol))
        measured = measured + 0.2 * (sol.angles - measured)
    return calls


def _gap(angles: np.ndarray, measured: np.ndarray) -> float:
    return float(np.abs(angles - measured).max())


def test_an_answer_that_jumps_to_another_shape_is_not_taken_while_the_chain_comes_in():
    # Against limits of +-7 deg, FABRIK's answer is not continuous in its start: solved afresh
    # from the poses of a chain coming in to its answer, it jumps to answers of another shape,
    # several times as far from the chain. Handed to the servo tick after tick, they threw
    # `42_eight_links_tight_limits`'s tip 70 px past its target.
    chain = Skeleton.chain([45.0] * 8, base_angle=PI / 2, limits=[(r(-7), r(7))] * 8)
    rng = np.random.default_rng(7)
    raw_jumps = 0
    for _ in range(12):
        start = _in_limits(rng, chain)
        target = _end(chain, rng.uniform(r(-6), r(6), 8))
        calls = _coming_in(RobustSolver(chain, "fabrik"), start, target)
        for (_, last), (measured, sol) in zip(calls, calls[1:], strict=False):
            if last.status is not SolveStatus.SUCCESS or _gap(last.angles, measured) <= SETTLED:
                continue
            assert _gap(sol.angles, measured) <= JUMPED * _gap(last.angles, measured)
            raw = SOLVERS["fabrik"](chain, measured, target, tolerance=TOLERANCE)
            raw_jumps += _gap(raw.angles, measured) > JUMPED * _gap(last.angles, measured)
    assert raw_jumps >= 5


@pytest.mark.parametrize("name", ["ccd", "dls"])
def test_a_continuous_solvers_fresh_answers_steer_the_chain_coming_in(name):
    # From poses on the way in, a continuous solver's answers move about as the chain does:
    # each fresh one is taken, solved from the measured pose, not the first kept.
    chain = Skeleton.chain([90.0, 80.0, 70.0, 60.0], limits=[(r(-150), r(150))] * 4)
    start = np.array([0.3, 0.4, 0.2, 0.1])
    calls = _coming_in(RobustSolver(chain, name), start, np.array([40.0, 190.0]))
    fresh = [sol for _, sol in calls[1:] if sol.iterations > 0]
    assert len(fresh) >= 10
    assert all(sol.status is SolveStatus.SUCCESS for _, sol in calls)


@pytest.mark.parametrize("name", NAMES)
def test_a_moving_target_is_followed_without_jumps(name):
    chain = Skeleton.chain([80.0, 70.0, 60.0], limits=[(r(-170), r(170))] * 3)
    robust = RobustSolver(chain, name)
    angles = robust.solve(np.full(3, 0.3), (160.0, 0.0), max_iterations=100).angles
    for tick in range(1, 480):
        phase = 2 * PI * tick / 480
        target = (130.0 + 30.0 * math.cos(phase), 30.0 * math.sin(phase))
        sol = robust.solve(angles, target, max_iterations=10, tolerance=TOLERANCE)
        assert sol.status is SolveStatus.SUCCESS
        # The target moves 0.4 px a tick; a change of branch would swing a joint by radians.
        assert np.abs(sol.angles - angles).max() < 0.3
        angles = sol.angles


# -- state, skeleton changes, determinism --------------------------------------------------------


def test_a_moved_base_is_solved_again():
    chain = Skeleton.chain([100.0, 80.0])
    robust = RobustSolver(chain, "ccd")
    target = (90.0, 90.0)
    sol = robust.solve(np.array([0.5, 0.5]), target, tolerance=TOLERANCE)
    robust.skeleton = chain.moved_to((5.0, 0.0))
    moved = robust.solve(sol.angles, target, tolerance=TOLERANCE)
    assert moved.iterations > 0
    assert moved.status is SolveStatus.SUCCESS
    assert np.hypot(*(_end(robust.skeleton, moved.angles) - target)) <= TOLERANCE


def test_switching_solver_or_reset_forgets_the_answer():
    arm, target = _elbow_arm()
    robust = RobustSolver(arm, "ccd")
    sol = _tick_by_tick(robust, arm.lower, target)
    assert robust.solve(sol.angles, target, tolerance=TOLERANCE).iterations == 0
    robust.solver_name = "fabrik"
    assert robust.solver_name == "fabrik"
    assert robust.solve(arm.lower, target, tolerance=TOLERANCE).iterations > 0
    robust.reset()
    assert robust.solve(sol.angles, target, tolerance=TOLERANCE).iterations == 0
    robust.reset()
    assert robust.solve(arm.lower, target, tolerance=TOLERANCE).iterations > 0


@pytest.mark.parametrize("name", NAMES)
def test_the_same_calls_give_the_same_answers(name):
    rng = np.random.default_rng(8)
    arm, target = _elbow_arm()
    for chain, start, goal in [_case(rng) for _ in range(10)] + [(arm, arm.lower, target)]:
        runs = []
        for _ in range(2):
            robust = RobustSolver(chain, name)
            answers = [robust.solve(start, goal, max_iterations=5, tolerance=TOLERANCE)]
            answers.append(robust.solve(answers[-1].angles, goal, max_iterations=5))
            runs.append(answers)
        for first, again in zip(*runs, strict=True):
            np.testing.assert_array_equal(first.angles, again.angles)
            assert (first.status, first.iterations, first.error) == (
                again.status,
                again.iterations,
                again.error,
            )


@pytest.mark.parametrize(
    ("call", "message"),
    [
        ({"angles": np.zeros(3)}, "angles must have shape (2,), got shape (3,)"),
        ({"angles": [0.0, math.nan]}, "angles must be finite, got [0.0, nan]"),
        ({"target": (1.0, 2.0, 3.0)}, "target must have shape (2,), got shape (3,)"),
        ({"target": (math.inf, 0.0)}, "target must be finite, got [inf, 0.0]"),
        ({"target": "up"}, "target must be a pair of numbers (x, y), got 'up'"),
        ({"max_iterations": 0}, "max_iterations must be an integer >= 1, got 0"),
        ({"tolerance": -1.0}, "tolerance must be finite and >= 0 px, got -1.0"),
    ],
    ids=repr,
)
def test_bad_input_is_named_in_the_message(call, message):
    robust = RobustSolver(Skeleton.chain([100.0, 100.0]), "ccd")
    # Also with a cached answer, which the checks must not skip.
    robust.solve(np.zeros(2), (0.0, 150.0), tolerance=TOLERANCE)
    arguments = {"angles": np.zeros(2), "target": (0.0, 150.0)} | call
    with pytest.raises(ValueError) as info:
        robust.solve(arguments.pop("angles"), arguments.pop("target"), **arguments)
    assert str(info.value) == message


def test_a_cached_answer_cannot_be_changed_in_place():
    arm, target = _elbow_arm()
    robust = RobustSolver(arm, "ccd")
    sol = _tick_by_tick(robust, arm.lower, target)
    for answer in (sol, robust.solve(arm.lower, target, tolerance=TOLERANCE)):
        with pytest.raises(ValueError):
            answer.angles[0] = 0.0


def test_another_chain_forgets_the_answer():
    robust = RobustSolver(Skeleton.chain([100.0, 80.0]), "fabrik")
    sol = robust.solve(np.array([0.5, 0.5]), (90.0, 90.0), tolerance=TOLERANCE)
    robust.skeleton = Skeleton.chain([60.0, 60.0])
    again = robust.solve(sol.angles, (90.0, 20.0), tolerance=TOLERANCE)
    assert again.status is SolveStatus.SUCCESS
    assert np.hypot(*(_end(robust.skeleton, again.angles) - (90.0, 20.0))) <= TOLERANCE
    with pytest.raises(ValueError, match="angles must have shape"):
        robust.solve(np.zeros(3), (90.0, 20.0))


@pytest.mark.parametrize("name", NAMES)
@settings(derandomize=True, deadline=None, max_examples=60)
@given(
    data=st.data(),
    target=st.one_of(
        st.tuples(st.floats(-3000.0, 3000.0), st.floats(-3000.0, 3000.0)),
        st.sampled_from([(0.0, 0.0), (1e12, -1e12), (-1e-9, 1e-9)]),
    ),
    tolerance=st.sampled_from([0.0, 0.5, 5.0]),
)
def test_any_target_from_any_start_gives_a_sound_answer(name, data, target, tolerance):
    # Reachable or not, on the base or absurdly far, from a start even past the limits.
    seed = data.draw(st.integers(0, 2**32 - 1))
    chain, _, _ = _case(np.random.default_rng(seed))
    start = np.array(
        data.draw(st.lists(st.floats(-10.0, 10.0), min_size=chain.count, max_size=chain.count))
    )
    robust = RobustSolver(chain, name, budget=40)
    angles = start
    for _ in range(3):
        sol = robust.solve(angles, target, max_iterations=5, tolerance=tolerance)
        assert np.all(np.isfinite(sol.angles))
        assert np.all(sol.angles >= chain.lower) and np.all(sol.angles <= chain.upper)
        measured = np.hypot(*(_end(chain, sol.angles) - target))
        assert sol.error == pytest.approx(measured, rel=1e-9, abs=1e-6)
        assert sol.iterations <= 5 + 40
        if sol.status is SolveStatus.SUCCESS:
            assert sol.error <= tolerance + 1e-9
        else:
            assert sol.error > tolerance - 1e-9
        angles = sol.angles


# -- several targets on a tree ------------------------------------------------------------------


def _tree_ends(skeleton: Skeleton, angles: np.ndarray, links) -> np.ndarray:
    points = forward_kinematics(skeleton, angles)[0]
    return (points[1:] if skeleton.is_chain else points[skeleton.count :])[links]


def _two_elbow_arms() -> tuple[Skeleton, TargetSet]:
    """Two copies of the elbow arm on one body, 200 px apart; one target behind each arm's
    stop (the base must go round to +100 deg), the other in easy reach."""
    arm, _ = _elbow_arm()
    limits = [(float(a), float(b)) for a, b in zip(arm.lower, arm.upper, strict=True)] * 2
    tree = Skeleton.tree(
        [120.0, 100.0, 80.0] * 2,
        [-1, 0, 1, -1, 3, 4],
        limits=limits,
        root_offsets=[(-100, 0), (0, 0), (0, 0), (100, 0), (0, 0), (0, 0)],
    )
    goal = np.array([r(100), r(120), r(-30), r(10), r(40), r(-40)])
    return tree, TargetSet([2, 5], _tree_ends(tree, goal, [2, 5]))


@pytest.mark.parametrize("name", NAMES)
def test_a_tree_gets_every_arm_out_of_its_trap(name):
    tree, targets = _two_elbow_arms()
    raw = TARGET_SOLVERS[name](tree, tree.lower, targets, max_iterations=1000, tolerance=TOLERANCE)
    assert raw.status is not SolveStatus.SUCCESS
    robust = RobustSolver(tree, name)
    angles = tree.lower
    for _ in range(STILL_CALLS + 3):
        sol = robust.solve_targets(angles, targets, max_iterations=10, tolerance=TOLERANCE)
        assert sol.iterations <= 10 + RESTART_BUDGET
        assert np.all(sol.angles >= tree.lower) and np.all(sol.angles <= tree.upper)
        reached = _tree_ends(tree, sol.angles, targets.links)
        np.testing.assert_allclose(sol.errors, np.hypot(*(reached - targets.points).T))
        angles = sol.angles
        if sol.status is SolveStatus.SUCCESS:
            break
    assert sol.status is SolveStatus.SUCCESS
    assert sol.angles[0] > r(90)


@pytest.mark.parametrize("name", NAMES)
def test_a_chain_tip_through_solve_targets_is_solve(name):
    rng = np.random.default_rng(41)
    for _ in range(20):
        chain, start, target = _case(rng)
        one, other = RobustSolver(chain, name), RobustSolver(chain, name)
        angles_one = angles_other = start
        for _ in range(8):
            a = one.solve(angles_one, target, max_iterations=10, tolerance=TOLERANCE)
            b = other.solve_targets(
                angles_other,
                TargetSet([chain.count - 1], [target]),
                max_iterations=10,
                tolerance=TOLERANCE,
            )
            np.testing.assert_array_equal(a.angles, b.angles)
            assert (a.status, a.iterations, a.error) == (b.status, b.iterations, b.error)
            assert b.errors.tolist() == [a.error]
            angles_one, angles_other = a.angles, b.angles


@pytest.mark.parametrize("name", NAMES)
def test_conflicting_targets_fail_once_then_cost_nothing(name):
    fork = Skeleton.tree([60.0, 40.0, 40.0], [-1, 0, 0])
    targets = TargetSet([1, 2], [(110.0, 70.0), (110.0, -70.0)], weights=[1.0, 3.0])
    robust = RobustSolver(fork, name, budget=400)
    angles = np.array([0.1, 0.2, -0.2])
    for _ in range(STILL_CALLS + 10):
        sol = robust.solve_targets(angles, targets, max_iterations=50, tolerance=TOLERANCE)
        angles = sol.angles
        if sol.status is SolveStatus.FAILURE:
            break
    assert sol.status is SolveStatus.FAILURE
    plain = TARGET_SOLVERS[name](
        fork, np.array([0.1, 0.2, -0.2]), targets, max_iterations=3000, tolerance=TOLERANCE
    )
    weighted = targets.weights @ sol.errors**2
    assert weighted <= targets.weights @ plain.errors**2 * (1 + 1e-6)
    again = robust.solve_targets(angles, targets, max_iterations=50, tolerance=TOLERANCE)
    assert again.iterations == 0 and again.status is SolveStatus.FAILURE
    np.testing.assert_array_equal(again.angles, sol.angles)


def test_a_tree_is_solved_by_solve_targets_only():
    tree, targets = _two_elbow_arms()
    robust = RobustSolver(tree)
    with pytest.raises(ValueError, match="use solve_targets"):
        robust.solve(tree.lower, (0.0, 100.0))
    with pytest.raises(ValueError, match="targets must be a TargetSet"):
        robust.solve_targets(tree.lower, (0.0, 100.0))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="target links must be < 6"):
        robust.solve_targets(tree.lower, TargetSet([6], [(0.0, 0.0)]))


def test_a_moved_tree_is_solved_again():
    tree, targets = _two_elbow_arms()
    robust = RobustSolver(tree, "dls")
    goal = np.array([r(10), r(40), r(-40), r(10), r(40), r(-40)])
    easy = TargetSet([2, 5], _tree_ends(tree, goal, [2, 5]))
    sol = robust.solve_targets(tree.clamp(goal + 0.05), easy, tolerance=TOLERANCE)
    assert sol.status is SolveStatus.SUCCESS
    robust.skeleton = tree.moved_to((0.0, 30.0))
    moved = robust.solve_targets(sol.angles, easy, tolerance=TOLERANCE)
    assert moved.iterations > 0 and moved.status is SolveStatus.SUCCESS
    reached = _tree_ends(robust.skeleton, moved.angles, easy.links)
    assert np.all(np.hypot(*(reached - easy.points).T) <= TOLERANCE)


@pytest.mark.parametrize("name", NAMES)
def test_an_answer_the_motors_cannot_hold_sends_the_solver_to_one_they_can(name):
    # Only poses with the elbow bent the negative way are light enough for the motors (a
    # stand-in for gravity's load against the torque limits). From an elbow bent the other
    # way, every solver's plain answer keeps that bend: the restarts find the other one.
    arm = Skeleton.chain([100.0, 100.0])
    robust = RobustSolver(arm, name)
    robust.strain = lambda angles: 2.0 if angles[1] > 0.0 else 0.5
    pose, target = np.array([0.3, 0.8]), np.array([120.0, 60.0])
    for _ in range(2 * STILL_CALLS + 10):
        sol = robust.solve(pose, target, max_iterations=10, tolerance=TOLERANCE)
    assert sol.status is SolveStatus.SUCCESS and sol.error <= TOLERANCE
    assert sol.angles[1] < 0.0


@pytest.mark.parametrize("name", NAMES)
def test_an_answer_at_the_edge_of_what_the_motors_hold_gives_way_to_one_with_margin(name):
    # The base turned below level asks 0.975 of the motors: within what they hold, past the
    # margin they rest with; the pose the target finds the arm in asks half. Every solver's
    # plain answer keeps the elbow's bend and lowers the base: the restarts find the other
    # bend, the base raised, which asks half.
    arm = Skeleton.chain([100.0, 100.0])
    robust = RobustSolver(arm, name)
    edge = (HOLDS + STRAINED) / 2.0
    robust.strain = lambda angles: edge if angles[0] < 0.0 else 0.5
    pose, target = np.array([0.3, 0.8]), np.array([120.0, 60.0])
    plain = SOLVERS[name](arm, pose, target, max_iterations=50, tolerance=TOLERANCE)
    assert plain.angles[0] < 0.0
    for _ in range(2 * STILL_CALLS + 10):
        sol = robust.solve(pose, target, max_iterations=10, tolerance=TOLERANCE)
    assert sol.status is SolveStatus.SUCCESS and sol.error <= TOLERANCE
    assert sol.angles[0] > 0.0


def test_an_answer_at_the_edge_stands_where_none_with_margin_reaches_the_target():
    # Every pose reaching out past 150 px asks 0.975 of the motors, so none with the margin
    # reaches the target at 168 px from the folded arm: the plain answer, which they hold,
    # stands (not the held pose nearest the target, short of it), and the search is not
    # begun again.
    arm = Skeleton.chain([100.0, 100.0])
    robust = RobustSolver(arm, "dls")
    edge = (HOLDS + STRAINED) / 2.0
    robust.strain = lambda angles: edge if np.hypot(*_end(arm, angles)) > 150.0 else 0.5
    pose, target = np.array([0.3, 2.0]), np.array([150.0, 75.0])
    plain = RobustSolver(arm, "dls")
    calls = [robust.solve(pose, target, max_iterations=10, tolerance=TOLERANCE) for _ in range(60)]
    alone = plain.solve(pose, target, max_iterations=10, tolerance=TOLERANCE)
    assert max(sol.iterations for sol in calls[:10]) > alone.iterations  # it searched
    assert all(sol.status is SolveStatus.SUCCESS for sol in calls)
    assert all(sol.error <= TOLERANCE for sol in calls)
    assert calls[-1].iterations == alone.iterations  # and then gave up searching


def _three_link_room(tight_everywhere: bool):
    """A three-link arm, a target, and a stand-in strain: the elbow bent the positive way (the
    plain answers' bend) asks twice what the motors have, the other bend leaves them no room to
    brake (between ``SPENT`` and ``HOLDS``) unless the base is raised past 1 rad (then half)."""
    arm = Skeleton.chain([100.0, 100.0, 100.0])
    tight = (SPENT + HOLDS) / 2.0

    def strain(angles: np.ndarray) -> float:
        if angles[1] > 0.0:
            return 2.0
        return 0.5 if angles[0] > 1.0 and not tight_everywhere else tight

    return arm, strain, tight, np.array([0.3, 0.8, 0.3]), np.array([150.0, 100.0])


@pytest.mark.parametrize("name", NAMES)
def test_a_search_prefers_an_answer_that_leaves_the_motors_room_to_brake(name):
    arm, strain, _, pose, target = _three_link_room(tight_everywhere=False)
    robust = RobustSolver(arm, name)
    robust.strain = strain
    assert strain(SOLVERS[name](arm, pose, target, max_iterations=50).angles) > STRAINED
    for _ in range(2 * STILL_CALLS + 30):
        sol = robust.solve(pose, target, max_iterations=10, tolerance=TOLERANCE)
    assert sol.status is SolveStatus.SUCCESS and sol.error <= TOLERANCE
    assert strain(sol.angles) <= SPENT


@pytest.mark.parametrize("name", NAMES)
def test_an_answer_without_room_to_brake_is_taken_where_none_has_it(name):
    arm, strain, tight, pose, target = _three_link_room(tight_everywhere=True)
    robust = RobustSolver(arm, name)
    robust.strain = strain
    calls = [
        robust.solve(pose, target, max_iterations=10, tolerance=TOLERANCE)
        for _ in range(2 * STILL_CALLS + 30)
    ]
    assert calls[-1].iterations == 0  # the search is over and its answer kept
    assert calls[-1].status is SolveStatus.SUCCESS and calls[-1].error <= TOLERANCE
    assert strain(calls[-1].angles) == tight


@pytest.mark.parametrize("name", ["ccd", "fabrik"])
def test_the_chain_waits_where_the_search_began_until_it_finds_a_pose_the_motors_hold(name):
    # Only the pose the chain starts in and poses with the base raised past 1 rad and the
    # elbow bent the negative way hold; CCD's and FABRIK's searches take calls to find one.
    arm = Skeleton.chain([100.0, 100.0, 100.0])
    pose, target = np.array([0.3, 0.8, 0.3]), np.array([150.0, 100.0])

    def strain(angles: np.ndarray) -> float:
        held = (angles[0] > 1.0 and angles[1] < 0.0) or np.allclose(angles, pose)
        return 0.5 if held else 2.0

    robust = RobustSolver(arm, name, budget=20)
    robust.strain = strain
    calls = [
        robust.solve(pose, target, max_iterations=10, tolerance=TOLERANCE)
        for _ in range(STILL_CALLS + 30)
    ]
    searching = calls[STILL_CALLS:]
    waited = [sol for sol in searching if sol.status is SolveStatus.PROCESSING]
    assert waited and all(np.array_equal(sol.angles, pose) for sol in waited)
    assert all(strain(sol.angles) <= HOLDS for sol in searching)
    assert calls[-1].status is SolveStatus.SUCCESS and calls[-1].error <= TOLERANCE


def test_when_no_pose_can_be_held_the_plain_answer_serves_without_searching_again():
    arm = Skeleton.chain([100.0, 100.0])
    robust = RobustSolver(arm, "dls")
    robust.strain = lambda angles: 2.0
    pose, target = np.array([0.3, 0.8]), np.array([120.0, 60.0])
    iterations = [
        robust.solve(pose, target, max_iterations=10, tolerance=TOLERANCE).iterations
        for _ in range(30)
    ]
    plain = RobustSolver(arm, "dls").solve(pose, target, max_iterations=10, tolerance=TOLERANCE)
    assert max(iterations[:5]) > plain.iterations  # it searched
    assert iterations[-5:] == [plain.iterations] * 5  # and then gave up searching


ELBOW_ARM = Skeleton.chain([100.0, 100.0, 100.0], limits=[(-2.6, 2.6)] * 3)


def _follow_up(robust: RobustSolver | None, moving: bool) -> list:
    """Eight answers for a target that starts at the end of ``ELBOW_ARM`` with its elbow 0.05
    rad from its stop and moves 1 px up a call (or holds still), each call from the last
    answer, by ``robust`` or (None) by the plain CCD solve; tolerance 2 px."""
    pose = np.array([0.2, 2.55, 1.0])
    start = _end(ELBOW_ARM, pose)
    answers = []
    for k in range(8):
        target = start + np.array([0.0, float(k) if moving else 0.0])
        if robust is None:
            sol = SOLVERS["ccd"](ELBOW_ARM, pose, target, max_iterations=10, tolerance=2.0)
        else:
            sol = robust.solve(pose, target, max_iterations=10, tolerance=2.0)
        assert sol.status is SolveStatus.SUCCESS
        assert np.linalg.norm(_end(ELBOW_ARM, sol.angles) - target) <= 2.0
        answers.append(sol.angles)
        pose = sol.angles
    return answers


def test_a_followed_target_gets_answers_slid_off_the_stops():
    followed = _follow_up(RobustSolver(ELBOW_ARM, "ccd"), moving=True)
    plain = _follow_up(None, moving=True)
    # CCD alone keeps the elbow against its stop; slid along the poses that keep the end on
    # the target, the answers take it out past OFF_STOPS, the end still within tolerance.
    assert 2.6 - plain[-1][1] < 0.1
    assert 2.6 - followed[-1][1] > OFF_STOPS


def test_a_target_that_holds_still_gets_the_solvers_own_answer_on_its_stops():
    held = _follow_up(RobustSolver(ELBOW_ARM, "ccd"), moving=False)
    plain = _follow_up(None, moving=False)
    assert all(np.array_equal(a, b) for a, b in zip(held, plain, strict=True))


def test_a_moving_target_starts_no_search_for_a_pose_the_motors_can_hold():
    # A target that moves every call would start a search, and pay its budget, on every call.
    arm = Skeleton.chain([100.0, 100.0])
    robust, plain = RobustSolver(arm, "dls"), RobustSolver(arm, "dls")
    robust.strain = lambda angles: 2.0
    pose = np.array([0.3, 0.8])
    for step in range(20):
        target = np.array([120.0 + 3.0 * step, 60.0])
        sol = robust.solve(pose, target, max_iterations=10, tolerance=TOLERANCE)
        assert (
            sol.iterations
            == plain.solve(pose, target, max_iterations=10, tolerance=TOLERANCE).iterations
        )
        pose = sol.angles


def _hanging_strain(arm: Skeleton, limits: np.ndarray, mass, gravity: float):
    """What holding a hanging chain still takes of its motors: each joint's static load (the
    links beyond it, each its ``mass``, one for all or one per link, at its middle) over its
    torque limit."""
    masses = np.broadcast_to(np.asarray(mass, dtype=float), (arm.count,))

    def strain(angles: np.ndarray) -> float:
        points = forward_kinematics(arm, angles)[0]
        middles = (points[:-1] + points[1:]) / 2.0
        loads = [
            gravity * float(np.sum(masses[j:] * (middles[j:, 0] - points[j, 0])))
            for j in range(arm.count)
        ]
        return float(np.max(np.abs(loads) / limits))

    return strain


def test_an_answer_the_motors_cannot_hold_slides_to_one_they_can_that_ends_on_the_target():
    # Six 60 px links hanging, the motors weaker toward the tip. FABRIK's answers, from its
    # own start and from every random restart, bend the weak far joints and ask more of some
    # motor than it has; a pose they hold exists (the target is its tip), and the slide along
    # the poses that keep the end on the target finds one.
    arm = Skeleton.chain([60.0] * 6, limits=[(-2.618, 2.618)] * 6, base_angle=-math.pi / 2)
    limits = np.array([7.0e5, 5.0e5, 3.2e5, 1.8e5, 9.0e4, 3.0e4])
    strain = _hanging_strain(arm, limits, 0.8, 1200.0)
    target = np.array([224.0, -265.5])
    pose = np.radians([-36.6, -14.0, 21.1, 3.7, -15.3, -10.2])
    robust = RobustSolver(arm, "fabrik")
    robust.strain = strain
    plain = RobustSolver(arm, "fabrik").solve(pose, target, tolerance=TOLERANCE)
    assert strain(plain.angles) > 1.0
    for _ in range(3 * STILL_CALLS):
        sol = robust.solve(pose, target, max_iterations=10, tolerance=TOLERANCE)
    assert sol.status is SolveStatus.SUCCESS and sol.error <= TOLERANCE
    assert strain(sol.angles) <= HOLDS


def test_an_answer_the_motors_can_hold_is_one_the_chain_gets_to_through_poses_they_hold():
    # The seven weakening links of 40_seven_weak_links_hanging, on their way to the third
    # target. FABRIK's first arrival the motors hold (0.93 of some torque limit) folds the
    # last two links from -111 deg on the last joint: the straight line in joint space to it
    # asks up to 1.69, and the arm, coming in each joint at its own pace, stalled on the way.
    # Later seeds arrive in poses the chain gets to through poses the motors hold.
    arm = Skeleton.chain(
        [70.0, 65.0, 60.0, 55.0, 50.0, 45.0, 40.0],
        limits=[(-r(140), r(140))] * 7,
        base_angle=-PI / 2,
    )
    limits = np.array([6.0e5, 3.5e5, 2.0e5, 1.1e5, 6.0e4, 3.0e4, 1.2e4])
    strain = _hanging_strain(arm, limits, [1.0, 0.9, 0.8, 0.7, 0.6, 0.5, 0.4], 1400.0)
    pose = np.radians([-20.0, 1.0, 1.0, 3.0, 6.0, 13.0, -111.0])
    target = np.array([30.0, -250.0])
    robust = RobustSolver(arm, "fabrik")
    robust.strain = strain
    for _ in range(3 * STILL_CALLS + 10):
        sol = robust.solve(pose, target, max_iterations=10, tolerance=TOLERANCE)
    assert sol.status is SolveStatus.SUCCESS and sol.error <= TOLERANCE
    assert strain(sol.angles) <= HOLDS
    assert holds_along(strain, pose, sol.angles - pose)
    assert sol.iterations == 0  # found, and followed


@pytest.mark.parametrize("solver", ["ccd", "fabrik"])
def test_an_answer_held_at_rest_but_not_on_the_way_gives_way_to_one_held_all_the_way(solver):
    # 46_heavy_weak_second_branch: two links hanging in strong gravity, resting where a
    # torque-bound target left them (the base at 0.95 of its limit). CCD's and FABRIK's
    # answer for the next target swings the elbow out: 0.93 at rest, but past 1 on the way.
    # The other branch of the elbow is held all the way, and is the answer.
    arm = Skeleton.chain([140.0, 130.0], limits=[(-r(150), r(150))] * 2, base_angle=-PI / 2)
    strain = _hanging_strain(arm, np.array([6.4e5, 4.2e5]), [2.2, 1.8], 1800.0)
    pose = np.radians([34.71, 79.69])
    target = np.array([151.1, -218.8])
    plain = RobustSolver(arm, solver)
    for _ in range(40):
        answer = plain.solve(pose, target, max_iterations=10, tolerance=TOLERANCE)
        pose_on = answer.angles
    assert not holds_along(strain, pose, pose_on - pose, HOLDS)
    robust = RobustSolver(arm, solver)
    robust.strain = strain
    for _ in range(3 * STILL_CALLS + 20):
        sol = robust.solve(pose, target, max_iterations=10, tolerance=TOLERANCE)
    assert sol.status is SolveStatus.SUCCESS and sol.error <= TOLERANCE
    assert strain(sol.angles) <= HOLDS
    assert holds_along(strain, pose, sol.angles - pose, HOLDS)


def _two_link_loads(base: np.ndarray, elbow: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The tip and each joint's static load of two hanging 100 px links of mass 1 in gravity
    of 1000 px/s^2, for local angles (radians, arrays of any shape)."""
    a0 = base - PI / 2
    a1 = a0 + elbow
    tip = np.stack([100.0 * (np.cos(a0) + np.cos(a1)), 100.0 * (np.sin(a0) + np.sin(a1))])
    loads = np.stack([1000.0 * (150.0 * np.cos(a0) + 50.0 * np.cos(a1)), 50000.0 * np.cos(a1)])
    return tip, loads


def _two_link_strain(limits: np.ndarray):
    """The strain of :func:`_two_link_loads` under torque ``limits``, and its slope."""

    def strain(angles: np.ndarray) -> float:
        return float(np.max(np.abs(_two_link_loads(*angles)[1]) / limits))

    def slope(angles: np.ndarray) -> np.ndarray:
        a0 = angles[0] - PI / 2
        a1 = a0 + angles[1]
        loads = _two_link_loads(*angles)[1]
        worst = int(np.argmax(np.abs(loads) / limits))
        # Each load's change as the base turns (both links with it) and as the elbow turns.
        turned = [
            [-1000.0 * (150.0 * np.sin(a0) + 50.0 * np.sin(a1)), -50000.0 * np.sin(a1)],
            [-50000.0 * np.sin(a1), -50000.0 * np.sin(a1)],
        ]
        return np.sign(loads[worst]) / limits[worst] * np.array(turned[worst])

    return strain, slope


@pytest.mark.parametrize("closed", [False, True], ids=["differences", "closed-form"])
@pytest.mark.parametrize("name", NAMES)
def test_a_target_the_motors_cannot_hold_the_end_at_gets_the_nearest_pose_they_hold(name, closed):
    # Out to the right, just below the base: held there, the arm asks 1.6 times the base's
    # torque. Every restart fails; the answer is then the pose nearest the target that the
    # motors hold, within a pixel of the best of every pose on a 0.25 deg grid, a failure
    # cached like a target out of reach; the same whether the strain's slope is known in
    # closed form or taken by differences.
    arm = Skeleton.chain([100.0, 100.0], limits=[(-2.6, 2.6)] * 2, base_angle=-PI / 2)
    limits = np.array([1.2e5, 1.0e5])
    strain, slope = _two_link_strain(limits)
    target = np.array([190.0, -30.0])
    robust = RobustSolver(arm, name)
    robust.strain = strain
    robust.strain_slope = slope if closed else None
    pose = np.zeros(2)
    answers = [robust.solve(pose, target, tolerance=TOLERANCE) for _ in range(80)]
    sol = answers[-1]
    assert sol.status is SolveStatus.FAILURE and sol.iterations == 0
    assert strain(sol.angles) <= HOLDS
    grid = np.radians(np.arange(-149.0, 149.0, 0.25))
    tips, loads = _two_link_loads(*np.meshgrid(grid, grid, indexing="ij"))
    held = np.all(np.abs(loads) <= HOLDS * limits[:, None, None], axis=0)
    best = np.hypot(*(tips - target[:, None, None]))[held].min()
    assert best > 30.0  # far from the target: its pose asks too much
    assert sol.error < best + 1.0


def test_the_slides_of_a_search_for_a_held_pose_are_spread_over_calls():
    # Thirty links whose base cannot hold them reaching out: the search slides the answer
    # along the poses that keep its end, then steps toward the nearest pose the motors hold,
    # each slide step asking the strain once per joint and more. All in the calls that came
    # to them, one call asked it 726 times (about 20 ms on this chain); spread, no call asks
    # more than a budget's worth and a step.
    arm = Skeleton.chain([10.0] * 30, limits=[(-2.6, 2.6)] * 30, base_angle=-PI / 2)
    strain = _hanging_strain(arm, np.array([3.0e5] + [1.0e9] * 29), 0.1, 1000.0)
    asked = [0]

    def counted(angles: np.ndarray) -> float:
        asked[0] += 1
        return strain(angles)

    robust = RobustSolver(arm, "dls")
    robust.strain = counted
    most = 0
    for _ in range(150):
        before = asked[0]
        sol = robust.solve(np.zeros(30), np.array([280.0, -40.0]), tolerance=TOLERANCE)
        most = max(most, asked[0] - before)
    assert sol.status is SolveStatus.FAILURE and strain(sol.angles) <= HOLDS
    assert most < 300


def test_the_strain_s_slope_in_closed_form_finds_the_pose_differences_find_asking_less():
    arm = Skeleton.chain([100.0, 100.0], limits=[(-2.6, 2.6)] * 2, base_angle=-PI / 2)
    strain, slope = _two_link_strain(np.array([1.2e5, 1.0e5]))
    asked = [0]

    def counted(angles: np.ndarray) -> float:
        asked[0] += 1
        return strain(angles)

    target, starts = np.array([190.0, -30.0]), (np.zeros(2), np.array([0.4, 1.0]))
    differenced = held_nearest(arm, starts, target, counted)
    by_differences, asked[0] = asked[0], 0
    closed = held_nearest(arm, starts, target, counted, slope)
    np.testing.assert_allclose(closed, differenced, atol=2e-3)
    assert asked[0] < by_differences


def test_the_nearest_pose_the_motors_hold_is_none_when_no_start_slides_to_one():
    arm = Skeleton.chain([100.0, 100.0])
    assert held_nearest(arm, (np.zeros(2),), np.array([0.0, 150.0]), lambda a: 2.0) is None


def test_an_answer_held_only_at_rest_is_served_at_once_and_followed_when_no_other_is_found():
    # Only a sharply negative elbow is light enough for the motors, and every way there from
    # an elbow bent the other way passes a pose they cannot hold: the first arrival they hold
    # at rest is the answer from the call the search starts on, and stays it.
    arm = Skeleton.chain([100.0, 100.0])
    robust = RobustSolver(arm, "dls")
    robust.strain = lambda angles: 2.0 if angles[1] > -0.3 else 0.5
    pose, target = np.array([0.3, 0.8]), np.array([120.0, 60.0])
    answers = [
        robust.solve(pose, target, max_iterations=10, tolerance=TOLERANCE) for _ in range(40)
    ]
    first = answers[STILL_CALLS]
    assert first.status is SolveStatus.SUCCESS and first.error <= TOLERANCE
    assert first.angles[1] < -0.3
    assert all(np.array_equal(sol.angles, first.angles) for sol in answers[STILL_CALLS:])
    assert answers[STILL_CALLS + 1].iterations > 0  # served while the search went on
    assert answers[-1].iterations == 0  # the search has ended, and the answer is followed


def test_a_restarts_answer_is_kept_while_the_chain_comes_in_to_it(stress_simulation):
    # Thirty-five light links without gravity, CCD, third target: the plain solve from the
    # chain's pose crawls, and the answer the restarts find near the chain is followed. When
    # the plain solve arrived from a pose on the way in, 34 px from the target, its answer had
    # a joint 210 deg from the chain's and was taken (a restart's answer was not one the chain
    # was known to be coming in to): the chain turned that joint round at its speed limit and
    # reached the target in 0.77 s. Kept as the plain solver's own last answer would be, the
    # answer changes by a few degrees a tick, and the chain is there in 0.43 s.
    sim = stress_simulation("33_zero_g_thirty_five_links", "ccd")
    while sim.script.step_index < 2:
        sim.step()
    solve, answers = sim.controller.solver.solve, []

    def answered(*args, **kwargs):
        answer = solve(*args, **kwargs)
        answers.append((sim.world.effector_positions()[0].copy(), answer.angles))
        return answer

    sim.controller.solver.solve = answered
    while sim.script.step_index == 2:
        sim.step()
    target = np.array([-98.6, 198.2])  # the level's third target
    near = [angles for tip, angles in answers if np.hypot(*(tip - target)) < 100.0]
    assert np.abs(np.diff(near, axis=0)).max() < r(30.0)
    assert sim.script.outcomes[2].reached and sim.script.outcomes[2].time_to_reach < 0.6


def test_the_chain_waits_for_an_answer_held_on_the_way_rather_than_take_one_that_is_not():
    # 80_heavy_weak_three_swing_over: three links standing up in gravity of 2300 px/s^2, the
    # motors unable to hold the arm out level. CCD's answer for (115, 150) asks 0.97 of a motor
    # at rest but up to 1.19 on the straight way to it: set off toward it, the arm fell past
    # the target onto the floor. While the search for an answer held on the way runs, the
    # chain is told to stay where it is; then it gets that answer.
    arm = Skeleton.chain([108.0, 96.0, 70.0], limits=[(-r(150), r(150))] * 3, base_angle=PI / 2)
    strain = _hanging_strain(arm, np.array([7.6e5, 2.6e5, 4.4e4]), [1.5, 1.2, 0.65], 2300.0)
    pose = np.zeros(3)
    target = np.array([115.0, 150.0])
    plain = RobustSolver(arm, "ccd").solve(pose, target, max_iterations=10, tolerance=TOLERANCE)
    assert strain(plain.angles) <= STRAINED
    assert not holds_along(strain, pose, plain.angles - pose, STRAINED)
    robust = RobustSolver(arm, "ccd", budget=20)
    robust.strain = strain
    for _ in range(STILL_CALLS):
        robust.solve(pose, target, max_iterations=10, tolerance=TOLERANCE)  # still moving?
    waited = 0
    for _ in range(60):
        sol = robust.solve(pose, target, max_iterations=10, tolerance=TOLERANCE)
        if sol.status is SolveStatus.PROCESSING:
            assert np.array_equal(sol.angles, pose)
            waited += 1
        else:
            assert holds_along(strain, pose, sol.angles - pose, STRAINED)
    assert waited > 0
    assert sol.status is SolveStatus.SUCCESS and sol.error <= TOLERANCE
    assert strain(sol.angles) <= HOLDS
    assert holds_along(strain, pose, sol.angles - pose, HOLDS)
