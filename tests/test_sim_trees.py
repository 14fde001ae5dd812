"""Trees of bones and creatures in the physics world, with every solver: several effectors
aimed at once, weights settling what cannot all be reached, a gait whose feet hold."""

from pathlib import Path

import numpy as np
import pytest

from ikgame.kinematics import RobustSolver, TargetSet
from ikgame.level.library import LEVELS_DIR
from ikgame.level.loader import load_level
from ikgame.physics.world import build_skeleton
from ikgame.sim import Simulation

SOLVERS = ["ccd", "jacobian_transpose", "dls", "fabrik"]
STRESS_LEVELS = Path(__file__).resolve().parents[1] / "benchmarks" / "stress_levels"


@pytest.mark.parametrize("solver", SOLVERS)
def test_two_hands_reach_together_and_settle_at_the_weighted_optimum(solver):
    level = load_level(LEVELS_DIR / "15_two_hands.toml")
    sim = Simulation(level, solver=solver, record=False)
    result = sim.run()
    assert result.status == "passed"
    # The last step leaves the right hand aiming at a point it cannot reach while the left
    # leans away: the pose the chain rests in is the kinematic weighted least-squares optimum.
    targets = TargetSet(
        sim.world.effector_links,
        [sim.targets[name] for name in sim.effector_names],
        [3.0, 1.0],
    )
    skeleton = build_skeleton(level)
    robust = RobustSolver(skeleton, "dls")
    angles = sim.joint_angles()
    for _ in range(20):
        angles = robust.solve_targets(angles, targets, max_iterations=50, tolerance=0.5).angles
    optimum = np.hypot(*(sim.world.link_ends(targets.links) - targets.points).T)
    expected = robust.solve_targets(angles, targets, max_iterations=50, tolerance=0.5).errors
    assert optimum == pytest.approx(expected, abs=1.0)
    assert optimum[0] < optimum[1]  # the heavier hand gets closer


@pytest.mark.parametrize("solver", ["dls", "fabrik"])
def test_a_hand_sent_low_from_crossed_arms_goes_round_the_floor(solver):
    # Two steps of the two-armed stress level: the arms cross, then the left hand goes low on
    # the left while the right reaches high. The straight way between those poses in joint
    # space swings the left hand through the floor, where it used to stay.
    level = load_level(STRESS_LEVELS / "17_two_arms.toml")
    level = level.model_copy(update={"script": level.script[1:3], "duration": 12.0})
    sim = Simulation(level, solver=solver, record=False)
    room = sim.controller.avoider.clearance
    closest = np.inf
    while not sim.done:
        sim.step()
        closest = min(closest, float(room.gaps(sim.joint_angles()).min()))
    result = sim.result
    assert result.status == "passed"
    assert all(step.reached for step in result.steps)
    assert closest > 0.0  # px: no link touched the floor on the way


@pytest.mark.parametrize("solver", SOLVERS)
def test_head_and_tail_reach_their_targets_while_the_body_moves(solver):
    sim = Simulation(load_level(LEVELS_DIR / "17_head_and_tail.toml"), solver=solver, record=False)
    result = sim.run()
    assert result.status == "passed"
    assert sim.world.skeleton.base == pytest.approx([250.0, 170.0])


@pytest.mark.parametrize("solver", SOLVERS)
def test_the_walker_crosses_1000_px_and_its_planted_feet_hold(solver):
    level = load_level(LEVELS_DIR / "16_walker.toml")
    sim = Simulation(level, solver=solver, record=False)
    result = sim.run()
    assert result.status == "passed"
    assert sim.world.skeleton.base[0] - level.chain.base[0] == pytest.approx(1000.0)
    footing = result.as_dict()["footing"]
    assert set(footing) == set(level.gait.legs)
    for leg in footing.values():
        assert leg["steps"] >= 10  # every foot walked
        assert leg["slip"] <= 2.0  # px, while planted
        assert leg["sink"] <= 2.0  # px into the ground: resting on it, not through it


def _fork_level():
    return load_level(LEVELS_DIR / "15_two_hands.toml")


def test_code_aims_each_effector_by_name_and_hands_it_back():
    sim = Simulation(_fork_level(), record=False)
    for _ in range(5):
        sim.step()
    scripted = sim.targets["right_hand"].copy()
    sim.set_target("right_hand", (150.0, 150.0))
    assert sim.targets["right_hand"].tolist() == [150.0, 150.0]
    for _ in range(240):
        sim.step()
    reached = sim.world.effector_positions()[sim.effector_names.index("right_hand")]
    assert np.hypot(*(reached - (150.0, 150.0))) < 2.0
    sim.set_target("right_hand", None)
    assert sim.targets["right_hand"] == pytest.approx(scripted)


def test_a_tree_of_several_effectors_refuses_a_nameless_target():
    sim = Simulation(_fork_level(), record=False)
    with pytest.raises(ValueError, match="set_target"):
        sim.target = (0.0, 100.0)
    with pytest.raises(ValueError, match="no effector is named 'foot'"):
        sim.set_target("foot", (0.0, 100.0))


def test_tick_info_and_snapshots_carry_every_effector():
    sim = Simulation(_fork_level())
    for _ in range(20):
        info = sim.step()
    assert info.errors.shape == (2,)
    assert info.error == pytest.approx(float(info.errors.max()))
    snap = sim.snapshots[-1]
    assert snap.targets.shape == (2, 2) and snap.target is None
    assert sim.scene.effector_names == ("left_hand", "right_hand")
    assert [len(t) for t in sim.scene.effector_targets] == [4, 3]
    assert np.all(np.isfinite(snap.errors))


def test_a_single_bone_named_tip_off_the_base_is_still_a_tree():
    from ikgame.level.model import Level

    level = Level.model_validate(
        {
            "level": {"name": "one bone", "duration": 3.0},
            "world": {"gravity": [0.0, 0.0]},
            "chain": {
                "angle": 0.0,
                "bones": [{"name": "tip", "at": [20.0, 0.0], "angle": 90.0, "length": 60.0}],
            },
            "script": [{"reach": [50.0, 51.96]}],
        }
    )
    assert Simulation(level, record=False).run().status == "passed"
