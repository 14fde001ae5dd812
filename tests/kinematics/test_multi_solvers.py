"""The multi-target solvers (all four, by name): reaching every effector of random trees,
settling at the weighted least-squares optimum when the targets conflict, the root fixed, the
limits kept, untargeted branches held, and a chain's one target solved as the chain solvers do.

Trees are drawn by a seeded numpy generator; reachable targets are forward kinematics of a pose
within the limits. The optimum of conflicting targets is checked against a reference of its own:
a grid over the joint angles, refined by projected gradient descent with finite-difference
gradients, on forward kinematics written out here link by link.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from ikgame.kinematics import (
    SOLVERS,
    TARGET_SOLVERS,
    Skeleton,
    SolveStatus,
    TargetSet,
    forward_kinematics,
    get_target_solver,
    solve_ccd,
    solve_ccd_targets,
    solve_dls_targets,
    solve_fabrik_targets,
    solve_jacobian_transpose_targets,
)

PI = math.pi
NAMES = sorted(TARGET_SOLVERS)


def _random_tree(rng: np.random.Generator, *, limited: bool, offsets: bool = False) -> Skeleton:
    n = int(rng.integers(2, 9))
    parents = [-1] + [int(rng.integers(-1 if offsets else 0, i)) for i in range(1, n)]
    limits = None
    if limited:
        lows = rng.uniform(-2.5, -0.3, n)
        highs = rng.uniform(0.3, 2.5, n)
        limits = list(zip(lows.tolist(), highs.tolist(), strict=True))
    root_offsets = None
    if offsets:
        root_offsets = rng.normal(0.0, 40.0, (n, 2)) * (np.array(parents) < 0)[:, None]
    return Skeleton.tree(
        rng.uniform(20.0, 80.0, n),
        parents,
        base=rng.normal(0.0, 50.0, 2),
        base_angle=float(rng.uniform(-PI, PI)),
        limits=limits,
        root_offsets=root_offsets,
    )


def _pose_within_limits(rng: np.random.Generator, skeleton: Skeleton) -> np.ndarray:
    return rng.uniform(np.maximum(skeleton.lower, -PI), np.minimum(skeleton.upper, PI))


def _ends(skeleton: Skeleton, angles: np.ndarray) -> np.ndarray:
    """Every link's end, px, by the package's forward kinematics (tree or chain layout)."""
    points = forward_kinematics(skeleton, angles)[0]
    return points[1:] if skeleton.is_chain else points[skeleton.count :]


def _assert_sound(skeleton: Skeleton, sol, targets: TargetSet, start: np.ndarray) -> None:
    """What holds for every answer: within limits, honest errors, untargeted joints unmoved."""
    assert np.all(np.isfinite(sol.angles))
    assert np.all(sol.angles >= skeleton.lower) and np.all(sol.angles <= skeleton.upper)
    reached = _ends(skeleton, sol.angles)[targets.links]
    distances = np.hypot(*(reached - targets.points).T)
    np.testing.assert_allclose(sol.errors, distances, rtol=1e-9, atol=1e-6)
    assert sol.error == pytest.approx(distances.max(), rel=1e-9, abs=1e-6)
    idle = ~skeleton.ancestors[targets.links].any(axis=0)
    # Idle joints keep their angle (a free one may come back wrapped).
    turn = np.angle(np.exp(1j * (sol.angles[idle] - start[idle])))
    np.testing.assert_allclose(turn, 0.0, atol=1e-12)


# -- the registry -------------------------------------------------------------------------------


def test_every_multi_target_solver_goes_by_the_chain_solvers_names():
    assert dict(TARGET_SOLVERS) == {
        "ccd": solve_ccd_targets,
        "dls": solve_dls_targets,
        "fabrik": solve_fabrik_targets,
        "jacobian_transpose": solve_jacobian_transpose_targets,
    }
    assert set(TARGET_SOLVERS) == set(SOLVERS)
    for name in NAMES:
        assert get_target_solver(name) is TARGET_SOLVERS[name]
    with pytest.raises(ValueError, match="unknown solver 'x'; choose one of: ccd, dls, fabrik"):
        get_target_solver("x")


@pytest.mark.parametrize("name", NAMES)
def test_bad_input_raises_value_error(name):
    tree = Skeleton.tree([1.0, 1.0, 1.0], [-1, 0, 0])
    solve = TARGET_SOLVERS[name]
    good = TargetSet([1, 2], [(1.0, 1.0), (1.0, -1.0)])
    with pytest.raises(ValueError, match="targets must be a TargetSet"):
        solve(tree, np.zeros(3), (1.0, 1.0))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"target links must be < 3"):
        solve(tree, np.zeros(3), TargetSet([3], [(1.0, 1.0)]))
    with pytest.raises(ValueError, match=r"angles must have shape \(3,\)"):
        solve(tree, np.zeros(2), good)
    with pytest.raises(ValueError, match="max_iterations must be an integer >= 1, got 0"):
        solve(tree, np.zeros(3), good, max_iterations=0)
    with pytest.raises(ValueError, match="tolerance must be finite and >= 0 px"):
        solve(tree, np.zeros(3), good, tolerance=-1.0)


@pytest.mark.parametrize("name", NAMES)
def test_set_up_kept_per_skeleton_changes_no_answer(name):
    # A skeleton keeps each target set's set-up, and its moved copies share it: the answers
    # must be those of a fresh skeleton, to the bit, whatever was solved on it before.
    rng = np.random.default_rng(3)
    solve = TARGET_SOLVERS[name]
    tree = _random_tree(rng, limited=True, offsets=True)
    links = tree.effectors
    points = rng.normal(0.0, 60.0, (len(links), 2)) + tree.base
    start = _pose_within_limits(rng, tree)
    for weights in (np.ones(len(links)), rng.uniform(0.5, 3.0, len(links))):
        targets = TargetSet(links, points, weights)
        solve(tree, start, targets)
        for base, angle in ((tree.base, tree.base_angle), ((10.0, -20.0), 0.7)):
            moved = tree.moved_to(base, angle)
            fresh = Skeleton.tree(
                tree.lengths,
                tree.parents,
                base=base,
                base_angle=angle,
                limits=list(zip(tree.lower.tolist(), tree.upper.tolist(), strict=True)),
                root_offsets=tree.root_offsets,
            )
            kept, anew = solve(moved, start, targets), solve(fresh, start, targets)
            assert np.array_equal(kept.angles, anew.angles)
            assert np.array_equal(kept.errors, anew.errors)
            assert (kept.status, kept.iterations) == (anew.status, anew.iterations)
    with pytest.raises(ValueError, match=rf"target links must be < {tree.count}"):
        solve(tree, start, TargetSet([tree.count], [(1.0, 1.0)]))


# -- reachable targets --------------------------------------------------------------------------


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize(("limited", "spread"), [(False, 0.3), (True, 0.1)])
def test_every_effector_of_random_trees_reaches_its_target(name, limited, spread):
    # Trees are not convex even without limits (effectors share joints), so a local solver
    # starts near a solution, as the warm start of one tick from the last gives it.
    rng = np.random.default_rng(2026 + limited)
    for _ in range(40):
        tree = _random_tree(rng, limited=limited, offsets=not limited)
        goal = _pose_within_limits(rng, tree)
        targets = TargetSet(tree.effectors, _ends(tree, goal)[tree.effectors])
        start = tree.clamp(goal + rng.uniform(-spread, spread, tree.count))
        tolerance = 0.01 * tree.reach
        sol = TARGET_SOLVERS[name](tree, start, targets, max_iterations=500, tolerance=tolerance)
        _assert_sound(tree, sol, targets, start)
        assert sol.status is SolveStatus.SUCCESS
        assert np.all(sol.errors <= tolerance)


@pytest.mark.parametrize("name", NAMES)
def test_an_effector_without_a_target_holds_its_pose(name):
    rng = np.random.default_rng(7)
    for _ in range(20):
        tree = _random_tree(rng, limited=False)
        if len(tree.effectors) < 2:
            continue
        goal = _pose_within_limits(rng, tree)
        start = goal + rng.uniform(-0.3, 0.3, tree.count)
        chosen = tree.effectors[:1]
        targets = TargetSet(chosen, _ends(tree, goal)[chosen])
        sol = TARGET_SOLVERS[name](tree, start, targets, max_iterations=500, tolerance=0.5)
        _assert_sound(tree, sol, targets, start)
        assert sol.status is SolveStatus.SUCCESS


@pytest.mark.parametrize("name", NAMES)
def test_the_roots_never_move(name):
    rng = np.random.default_rng(11)
    for _ in range(20):
        tree = _random_tree(rng, limited=bool(rng.integers(2)), offsets=True)
        targets = TargetSet(tree.effectors, rng.normal(0.0, 150.0, (len(tree.effectors), 2)))
        start = _pose_within_limits(rng, tree)
        sol = TARGET_SOLVERS[name](tree, start, targets, max_iterations=50, tolerance=0.5)
        _assert_sound(tree, sol, targets, start)
        before = forward_kinematics(tree, start)[0][: tree.count]
        after = forward_kinematics(tree, sol.angles)[0][: tree.count]
        roots = tree.parents < 0
        np.testing.assert_array_equal(after[roots], before[roots])


@pytest.mark.parametrize("name", NAMES)
def test_a_pose_already_there_is_left_alone(name):
    tree = Skeleton.tree([50.0, 30.0, 30.0], [-1, 0, 0])
    start = np.array([0.3, 0.4, -0.5])
    targets = TargetSet([1, 2], _ends(tree, start)[[1, 2]] + 0.1)
    sol = TARGET_SOLVERS[name](tree, start, targets, max_iterations=10, tolerance=0.5)
    assert sol.status is SolveStatus.SUCCESS and sol.iterations == 0
    np.testing.assert_array_equal(sol.angles, start)


# -- one target on a chain ----------------------------------------------------------------------


@pytest.mark.parametrize("name", NAMES)
def test_a_chain_with_one_target_at_its_tip_is_solved_as_the_chain_solver_does(name):
    rng = np.random.default_rng(3)
    for _ in range(50):
        n = int(rng.integers(1, 12))
        limits = None
        if rng.random() < 0.5:
            limits = [(-a, b) for a, b in rng.uniform(0.2, 3.0, (n, 2)).tolist()]
        chain = Skeleton.chain(
            rng.uniform(5.0, 90.0, n),
            base=rng.normal(0.0, 80.0, 2),
            base_angle=float(rng.uniform(-PI, PI)),
            limits=limits,
        )
        start = chain.clamp(rng.uniform(-PI, PI, n))
        target = rng.normal(0.0, chain.reach, 2)
        iterations = int(rng.integers(1, 40))
        weight = float(rng.uniform(0.1, 5.0))
        multi = TARGET_SOLVERS[name](
            chain,
            start,
            TargetSet([n - 1], [target], weights=[weight]),
            max_iterations=iterations,
            tolerance=0.5,
        )
        single = SOLVERS[name](chain, start, target, max_iterations=iterations, tolerance=0.5)
        np.testing.assert_array_equal(multi.angles, single.angles)
        assert (multi.status, multi.iterations, multi.error) == (
            single.status,
            single.iterations,
            single.error,
        )
        assert multi.errors.tolist() == [single.error]


def test_a_chain_solver_refuses_a_root_offset():
    chain = Skeleton.tree([1.0, 1.0], [-1, 0], root_offsets=[(1.0, 0.0), (0.0, 0.0)])
    with pytest.raises(ValueError, match="zero root_offsets"):
        solve_ccd(chain, np.zeros(2), (1.0, 1.0))
    sol = solve_ccd_targets(chain, np.zeros(2), TargetSet([1], [(1.0, 1.5)]), max_iterations=50)
    assert sol.status is SolveStatus.SUCCESS


# -- conflicting targets: the weighted least-squares optimum -------------------------------------


def _batch_ends(skeleton: Skeleton, poses: np.ndarray) -> np.ndarray:
    """(m, n, 2) link ends of m poses, walked link by link from the roots (reference FK)."""
    m, n = poses.shape
    world = np.zeros((m, n))
    ends = np.zeros((m, n, 2))
    c, s = math.cos(skeleton.base_angle), math.sin(skeleton.base_angle)
    for i in range(n):
        p = int(skeleton.parents[i])
        if p < 0:
            ox, oy = skeleton.root_offsets[i]
            start = skeleton.base + np.array((c * ox - s * oy, s * ox + c * oy))
            world[:, i] = skeleton.base_angle + poses[:, i]
        else:
            start = ends[:, p]
            world[:, i] = world[:, p] + poses[:, i]
        heading = np.stack((np.cos(world[:, i]), np.sin(world[:, i])), axis=1)
        ends[:, i] = start + skeleton.lengths[i] * heading
    return ends


def _objective(skeleton: Skeleton, poses: np.ndarray, targets: TargetSet) -> np.ndarray:
    gaps = _batch_ends(skeleton, poses)[:, targets.links] - targets.points
    return 0.5 * (targets.weights * (gaps**2).sum(axis=2)).sum(axis=1)


def _reference_optimum(skeleton: Skeleton, targets: TargetSet) -> np.ndarray:
    """The best pose of a 24-per-joint grid, refined by projected gradient descent (central
    differences, step halved when it does not help) from its 4 best points."""
    low = np.maximum(skeleton.lower, -PI)
    high = np.minimum(skeleton.upper, PI)
    axes = [np.linspace(a, b, 24) for a, b in zip(low, high, strict=True)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, skeleton.count)
    poses = grid[np.argsort(_objective(skeleton, grid, targets))[:4]]
    steps = np.full(len(poses), 1e-4)
    h = 1e-6
    for _ in range(1500):
        values = _objective(skeleton, poses, targets)
        gradient = np.empty_like(poses)
        for i in range(skeleton.count):
            bump = np.zeros(skeleton.count)
            bump[i] = h
            gradient[:, i] = (
                _objective(skeleton, poses + bump, targets)
                - _objective(skeleton, poses - bump, targets)
            ) / (2 * h)
        trial = np.clip(poses - steps[:, None] * gradient, low, high)
        better = _objective(skeleton, trial, targets) < values
        poses[better] = trial[better]
        steps = np.where(better, steps * 1.5, steps * 0.5)
    return poses[np.argmin(_objective(skeleton, poses, targets))]


CONFLICTS = {
    # Two branches off one link, their targets too far apart for both.
    "fork": (
        Skeleton.tree([60.0, 40.0, 40.0], [-1, 0, 0]),
        TargetSet([1, 2], [(110.0, 70.0), (110.0, -70.0)], weights=[1.0, 3.0]),
    ),
    # A chain with targets on the middle and the last link, pulling opposite ways.
    "chain": (
        Skeleton.chain([50.0, 50.0, 50.0]),
        TargetSet([1, 2], [(0.0, 100.0), (150.0, -20.0)], weights=[2.0, 1.0]),
    ),
    # The fork with limits that hold the compromise back.
    "limited fork": (
        Skeleton.tree(
            [60.0, 40.0, 40.0], [-1, 0, 0], limits=[(-0.4, 0.4), (-1.0, 0.2), (-0.2, 1.0)]
        ),
        TargetSet([1, 2], [(60.0, 90.0), (60.0, -90.0)], weights=[1.0, 1.0]),
    ),
}


@pytest.fixture(scope="module")
def references() -> dict[str, np.ndarray]:
    return {key: _reference_optimum(*CONFLICTS[key]) for key in CONFLICTS}


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("case", sorted(CONFLICTS))
def test_conflicting_targets_settle_at_the_weighted_least_squares_optimum(name, case, references):
    skeleton, targets = CONFLICTS[case]
    best = references[case]
    best_value = float(_objective(skeleton, best[None], targets)[0])
    assert best_value > 100.0  # the targets really conflict
    rng = np.random.default_rng(5)
    for _ in range(3):
        start = skeleton.clamp(best + rng.uniform(-0.3, 0.3, skeleton.count))
        sol = TARGET_SOLVERS[name](skeleton, start, targets, max_iterations=3000, tolerance=0.5)
        _assert_sound(skeleton, sol, targets, start)
        assert sol.status is SolveStatus.FAILURE
        value = float(_objective(skeleton, sol.angles[None], targets)[0])
        assert value == pytest.approx(best_value, rel=1e-6)
        np.testing.assert_allclose(np.angle(np.exp(1j * (sol.angles - best))), 0.0, atol=2e-4)


@pytest.mark.parametrize("name", NAMES)
def test_a_target_on_a_middle_link_leaves_the_links_beyond_it_alone(name):
    chain = Skeleton.chain([40.0, 30.0, 20.0, 10.0], limits=[None, (-2.0, 2.0), None, None])
    start = np.array([0.2, 0.5, -0.7, 1.1])
    targets = TargetSet([1], _ends(chain, np.array([1.0, -0.8, 0.0, 0.0]))[[1]])
    sol = TARGET_SOLVERS[name](chain, start, targets, max_iterations=200, tolerance=0.1)
    _assert_sound(chain, sol, targets, start)
    assert sol.status is SolveStatus.SUCCESS
    np.testing.assert_array_equal(sol.angles[2:], start[2:])
