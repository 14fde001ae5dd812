"""The solver registry, and properties every solver must have (fuzzed over all four).

Each property draws its chains, poses and targets with hypothesis, derandomised so a run is
repeatable. Reachable targets are made by forward kinematics of drawn angles.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import ikgame.kinematics as kinematics
from ikgame.kinematics import (
    SOLVERS,
    Skeleton,
    SolveStatus,
    forward_kinematics,
    get_solver,
    solve_ccd,
    solve_dls,
    solve_fabrik,
    solve_jacobian_transpose,
)

PI = math.pi
NAMES = sorted(SOLVERS)
OURS = ["dls", "fabrik", "jacobian_transpose"]
FUZZ = settings(derandomize=True, deadline=None, max_examples=100)


def _end(skeleton: Skeleton, angles: np.ndarray) -> np.ndarray:
    return forward_kinematics(skeleton, angles)[0][-1]


def _assert_sound(skeleton: Skeleton, sol, target, max_iterations: int, tolerance: float) -> None:
    """What holds for every solution: finite, within limits, honest error and status."""
    assert sol.angles.shape == (skeleton.count,)
    assert np.all(np.isfinite(sol.angles))
    assert np.all(sol.angles >= skeleton.lower) and np.all(sol.angles <= skeleton.upper)
    assert math.isfinite(sol.error)
    measured = np.hypot(*(_end(skeleton, sol.angles) - target))
    assert sol.error == pytest.approx(measured, rel=1e-9, abs=1e-6)
    assert 0 <= sol.iterations <= max_iterations
    # Solvers track the error their own way; allow for rounding at the tolerance itself.
    if sol.status is SolveStatus.SUCCESS:
        assert sol.error <= tolerance + 1e-9
    else:
        assert sol.error > tolerance - 1e-9


# -- the registry -------------------------------------------------------------------------------


def test_every_solver_is_registered_by_its_level_file_name():
    assert dict(SOLVERS) == {
        "ccd": solve_ccd,
        "dls": solve_dls,
        "fabrik": solve_fabrik,
        "jacobian_transpose": solve_jacobian_transpose,
    }
    for name in NAMES:
        assert get_solver(name) is SOLVERS[name]


def test_the_registry_is_read_only():
    with pytest.raises(TypeError):
        SOLVERS["mine"] = solve_ccd  # type: ignore[index]


@pytest.mark.parametrize("name", ["x", "CCD", "", None])
def test_an_unknown_solver_names_the_choices(name):
    expected = f"unknown solver {name!r}; choose one of: ccd, dls, fabrik, jacobian_transpose"
    with pytest.raises(ValueError) as info:
        get_solver(name)  # type: ignore[arg-type]
    assert str(info.value) == expected


def test_the_package_exports_the_solvers_and_the_registry():
    for name in ["SOLVERS", "get_solver", "solve_dls", "solve_fabrik", "solve_jacobian_transpose"]:
        assert name in kinematics.__all__
    # The submodule stays reachable under its own name.
    assert kinematics.jacobian.__name__ == "ikgame.kinematics.jacobian"


# -- input checks -------------------------------------------------------------------------------

CHAIN = Skeleton.chain([100.0, 100.0])


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize(
    "kwargs",
    [
        {"target": (1.0, 2.0, 3.0)},
        {"target": (math.nan, 0.0)},
        {"target": "up"},
        {"max_iterations": 0},
        {"tolerance": -1.0},
        {"tolerance": math.inf},
        {"angles": np.zeros(3)},
    ],
    ids=repr,
)
def test_bad_input_raises_value_error(name, kwargs):
    call = {"angles": np.zeros(2), "target": (0.0, 150.0)} | kwargs
    angles = call.pop("angles")
    target = call.pop("target")
    with pytest.raises(ValueError):
        SOLVERS[name](CHAIN, angles, target, **call)


@pytest.mark.parametrize("name", OURS)
@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"max_iterations": 0}, "max_iterations must be an integer >= 1, got 0"),
        ({"max_iterations": 2.5}, "max_iterations must be an integer >= 1, got 2.5"),
        ({"max_iterations": True}, "max_iterations must be an integer >= 1, got True"),
        ({"tolerance": -1.0}, "tolerance must be finite and >= 0 px, got -1.0"),
        ({"tolerance": math.nan}, "tolerance must be finite and >= 0 px, got nan"),
        ({"tolerance": "1"}, "tolerance must be a number of px, got '1'"),
        ({"tolerance": None}, "tolerance must be a number of px, got None"),
    ],
    ids=repr,
)
def test_bad_settings_are_named_in_the_message(name, kwargs, message):
    with pytest.raises(ValueError) as info:
        SOLVERS[name](CHAIN, np.zeros(2), (0.0, 150.0), **kwargs)
    assert str(info.value) == message


@pytest.mark.parametrize("name", OURS)
def test_a_tree_is_refused(name):
    tree = Skeleton(
        lengths=np.ones(3), parents=np.array([-1, 0, 0]), lower=-np.inf, upper=np.inf, base=(0, 0)
    )
    with pytest.raises(ValueError, match="serial chain"):
        SOLVERS[name](tree, np.zeros(3), (1.0, 1.0))


# -- properties ---------------------------------------------------------------------------------


@st.composite
def _chains(draw, *, limited: bool, max_links: int = 30):
    n = draw(st.integers(2, max_links))
    lengths = draw(st.lists(st.floats(5.0, 100.0), min_size=n, max_size=n))
    base = draw(st.tuples(st.floats(-300.0, 300.0), st.floats(-300.0, 300.0)))
    base_angle = draw(st.floats(-PI, PI))
    limits = None
    if limited:
        lows = draw(st.lists(st.floats(-PI, -0.3), min_size=n, max_size=n))
        highs = draw(st.lists(st.floats(0.3, PI), min_size=n, max_size=n))
        limits = list(zip(lows, highs, strict=True))
    return Skeleton.chain(lengths, base=base, base_angle=base_angle, limits=limits)


def _angles(draw, skeleton: Skeleton) -> np.ndarray:
    """Angles drawn within the limits (anywhere in [-pi, pi] for a free joint)."""
    fractions = draw(
        st.lists(st.floats(0.0, 1.0), min_size=skeleton.count, max_size=skeleton.count)
    )
    low = np.maximum(skeleton.lower, -PI)
    high = np.minimum(skeleton.upper, PI)
    return low + np.array(fractions) * (high - low)


@pytest.mark.parametrize("name", NAMES)
@FUZZ
@given(data=st.data())
def test_converges_on_reachable_targets_of_free_chains(name, data):
    chain = data.draw(_chains(limited=False))
    target = _end(chain, _angles(data.draw, chain))
    tolerance = 0.01 * chain.reach
    start = np.zeros(chain.count)
    # A target on the straight chain's own line is a saddle where CCD stalls (its rotations are
    # all zero); test_jacobian and test_fabrik cover the saddle on purpose.
    line = np.array([math.cos(chain.base_angle), math.sin(chain.base_angle)])
    offset = target - chain.base
    assume(abs(line[0] * offset[1] - line[1] * offset[0]) > 1e-3 * chain.reach)
    # Converging is what is asserted, not how fast: CCD crawls toward a target near full reach
    # behind a short first link (lengths 5 and 45, a target 48.7 px out: 306 iterations; 5 and
    # 81, a target 85.6 px out: 1011).
    sol = SOLVERS[name](chain, start, target, max_iterations=5000, tolerance=tolerance)
    _assert_sound(chain, sol, target, 5000, tolerance)
    assert sol.status is SolveStatus.SUCCESS


@pytest.mark.parametrize("name", NAMES)
@FUZZ
@given(data=st.data())
def test_converges_on_reachable_targets_of_limited_chains_from_near_by(name, data):
    # With limits the reachable set is not convex: from far away any local method can end at a
    # limit short of the target. Starting near a solution, as a warm start tick to tick does,
    # a solver must get there.
    chain = data.draw(_chains(limited=True))
    solution = _angles(data.draw, chain)
    target = _end(chain, solution)
    nudge = data.draw(st.lists(st.floats(-0.1, 0.1), min_size=chain.count, max_size=chain.count))
    start = chain.clamp(solution + np.array(nudge))
    tolerance = 0.01 * chain.reach
    sol = SOLVERS[name](chain, start, target, max_iterations=300, tolerance=tolerance)
    _assert_sound(chain, sol, target, 300, tolerance)
    assert sol.status is SolveStatus.SUCCESS


_targets = st.one_of(
    st.tuples(st.floats(-3000.0, 3000.0), st.floats(-3000.0, 3000.0)),
    st.sampled_from([(0.0, 0.0), (1e12, -1e12), (-1e-9, 1e-9)]),
)


@pytest.mark.parametrize("name", NAMES)
@FUZZ
@given(
    data=st.data(),
    limited=st.booleans(),
    target=_targets,
    max_iterations=st.integers(1, 20),
    tolerance=st.sampled_from([0.0, 0.5, 5.0]),
)
def test_never_breaks_a_limit_never_nan_never_worse(
    name, data, limited, target, max_iterations, tolerance
):
    chain = data.draw(_chains(limited=limited, max_links=12))
    # Any target (reachable or not, on the base, absurdly far) from any start (even past a limit).
    start = np.array(
        data.draw(st.lists(st.floats(-10.0, 10.0), min_size=chain.count, max_size=chain.count))
    )
    target = np.asarray(target) + chain.base
    given_start = start.copy()
    sol = SOLVERS[name](chain, start, target, max_iterations=max_iterations, tolerance=tolerance)
    np.testing.assert_array_equal(start, given_start)
    _assert_sound(chain, sol, target, max_iterations, tolerance)
    if name in OURS:
        # CCD wraps only the joints it turns: a free joint it never reached keeps its start.
        assert np.all(np.abs(sol.angles[~chain.limited]) <= PI)
    start_error = np.hypot(*(_end(chain, chain.clamp(start)) - target))
    assert sol.error <= start_error * (1 + 1e-12) + 1e-9


@pytest.mark.parametrize("name", NAMES)
@FUZZ
@given(data=st.data(), distance=st.floats(1.1, 3.0), direction=st.floats(-PI, PI))
def test_an_unreachable_target_fails_gracefully_stretched_toward_it(
    name, data, distance, direction
):
    chain = data.draw(_chains(limited=False))
    heading = np.array([math.cos(direction), math.sin(direction)])
    target = chain.base + distance * chain.reach * heading
    tolerance = 0.001 * chain.reach
    sol = SOLVERS[name](
        chain, np.zeros(chain.count), target, max_iterations=500, tolerance=tolerance
    )
    _assert_sound(chain, sol, target, 500, tolerance)
    assert sol.status in (SolveStatus.FAILURE, SolveStatus.PROCESSING)
    arm = _end(chain, sol.angles) - chain.base
    off = math.atan2(heading[0] * arm[1] - heading[1] * arm[0], heading @ arm)
    assert abs(off) < math.radians(3.0)
    assert np.hypot(*arm) > 0.9 * chain.reach


@pytest.mark.parametrize("name", NAMES)
def test_a_pose_already_within_tolerance_is_left_alone(name):
    chain = Skeleton.chain([50.0] * 4, limits=[(-1.0, 1.0)] * 4)
    start = np.array([0.1, -0.2, 0.3, 0.4])
    target = _end(chain, start) + (0.3, 0.0)
    sol = SOLVERS[name](chain, start, target, max_iterations=10, tolerance=0.5)
    assert sol.status is SolveStatus.SUCCESS
    assert sol.iterations == 0
    np.testing.assert_array_equal(sol.angles, start)


@pytest.mark.parametrize("name", NAMES)
def test_a_read_only_start_is_fine(name):
    start = np.zeros(3)
    start.setflags(write=False)
    sol = SOLVERS[name](Skeleton.chain([1.0, 1.0, 1.0]), start, (1.0, 1.0))
    assert sol.error <= 1.0


@pytest.mark.parametrize("name", NAMES)
def test_solving_twice_gives_the_same_answer(name):
    chain = Skeleton.chain([40.0, 30.0, 20.0, 10.0], limits=[None, (-2.0, 2.0), None, (-1.0, 0.0)])
    first = SOLVERS[name](chain, np.ones(4), (-20.0, 50.0), max_iterations=7, tolerance=0.1)
    again = SOLVERS[name](chain, np.ones(4), (-20.0, 50.0), max_iterations=7, tolerance=0.1)
    np.testing.assert_array_equal(first.angles, again.angles)
    assert (first.status, first.iterations, first.error) == (
        again.status,
        again.iterations,
        again.error,
    )
