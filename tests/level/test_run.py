"""A level's script acting on the world: set steps, the moving base, props, goals and scores."""

import json

import numpy as np
import pytest

from ikgame.level.model import Level
from ikgame.level.scoring import follow_score, level_score, reach_score
from ikgame.sim import Simulation

ARM = {"links": [{"length": 100.0, "mass": 1.0, "max_torque": 4.0e6, "repeat": 3}]}


def _level(script, **extra) -> Level:
    data = {
        "level": {"name": "t", "duration": extra.pop("duration", 6.0)},
        "world": extra.pop("world", {"gravity": [0.0, -900.0]}),
        "chain": {**ARM, **extra.pop("chain", {})},
        "script": script,
        **extra,
    }
    return Level.model_validate(data)


def test_set_gravity_gain_and_solver_act_from_that_tick_on():
    level = _level(
        [
            {"wait": 0.1},
            {"set": {"gravity": [0.0, -100.0], "gain": 5.0, "solver": "dls"}},
            {"wait": 0.1},
        ]
    )
    sim = Simulation(level, record=False)
    while sim.script.step_index < 1:
        sim.step()
    assert tuple(sim.world.space.gravity) == (0.0, -900.0)
    sim.step()
    assert tuple(sim.world.space.gravity) == (0.0, -100.0)
    assert sim.controller.gain == 5.0 and sim.controller.solver_name == "dls"
    assert sim.run().solver == "ccd"


def test_a_solver_chosen_for_the_run_is_not_changed_by_the_script():
    level = _level([{"set": {"solver": "dls"}}, {"wait": 0.1}])
    sim = Simulation(level, solver="fabrik", record=False)
    sim.run()
    assert sim.controller.solver_name == "fabrik"


def test_the_base_moves_smoothly_lands_exactly_and_the_solver_follows_it():
    level = _level(
        [
            {"set": {"base": [120.0, 30.0], "over": 1.0}},
            {"reach": [150.0, 200.0], "hold": 1.5, "timeout": 4.0},
        ],
        world={"gravity": [0.0, 0.0]},
    )
    sim = Simulation(level, record=False)
    xs = []
    for _ in range(240):
        sim.step()
        xs.append(sim.world.base_body.position.x)
    assert np.all(np.diff(xs) >= 0)
    assert np.diff(xs)[:5].max() < 0.1  # starts from rest (0.5 px a tick on average)
    assert xs[119] == pytest.approx(60.0, abs=0.5)  # half way at half time
    assert tuple(sim.world.base_body.position) == (120.0, 30.0)
    assert tuple(sim.world.base_body.velocity) == (0.0, 0.0)
    assert sim.controller.skeleton.base.tolist() == [120.0, 30.0]
    assert sim.joint_positions()[0] == pytest.approx((120.0, 30.0), abs=0.5)
    assert sim.run().status == "passed"


def test_the_base_move_takes_the_same_time_at_any_tick_rate():
    positions = {}
    for rate in (120, 480):
        level = _level(
            [{"set": {"base": [100.0, 0.0], "over": 0.5}}, {"wait": 1.0}],
            world={"gravity": [0.0, 0.0], "tick_rate": rate},
        )
        sim = Simulation(level, record=False)
        for _ in range(rate // 4):
            sim.step()
        positions[rate] = sim.world.base_body.position.x
    assert positions[120] == pytest.approx(positions[480], abs=0.5)


PROPS = [
    {"kind": "ball", "name": "ball", "position": [200.0, 0.0], "radius": 15.0},
    {"kind": "box", "name": "crate", "position": [-150.0, 0.0], "size": [30.0, 20.0]},
]
FLOOR = [{"kind": "segment", "a": [-400.0, -20.0], "b": [400.0, -20.0]}]


def test_props_fall_onto_obstacles_and_reach_the_snapshots_and_the_scene():
    level = _level([{"wait": 1.0}], props=PROPS, obstacles=FLOOR)
    sim = Simulation(level)
    sim.run()
    assert [(p.kind, p.size) for p in sim.scene.props] == [
        ("ball", (15.0, 15.0)),
        ("box", (30.0, 20.0)),
    ]
    final = sim.snapshots[-1].props
    assert final.shape == (2, 3)
    assert final[0, 1] == pytest.approx(-16.0 + 15.0, abs=0.5)  # resting on the floor
    assert final[1, 1] == pytest.approx(-16.0 + 10.0, abs=0.5)


def test_the_chain_pushes_a_prop_goes_clear_of_the_floor_and_says_when_a_wall_jams_it():
    def sweep(base_height, obstacles=FLOOR):
        level = _level(
            [
                {"sequence": [[80.0, 120.0], [90.0, 15.0]], "tolerance": 10.0, "hold": 0.2},
                {"reach": [280.0, 15.0], "timeout": 2.0},
            ],
            props=[{"kind": "ball", "name": "ball", "position": [150.0, 0.0], "radius": 15.0}],
            obstacles=obstacles,
            world={"gravity": [0.0, -900.0]},
            chain={"base": [0.0, base_height]},
        )
        sim = Simulation(level, record=False)
        sim.run()
        return sim

    # Mounted 50 px up, the arm sweeps along the floor and knocks the ball on.
    assert sweep(50.0).world.prop_states()[0, 0] > 200.0
    # Mounted on the floor, the arm unfolds toward the far target on a way clear of the floor
    # (the straight unfolding pressed its tip into the floor, where friction held it).
    clear = sweep(0.0).result.steps[-1]
    assert clear.passed and "blocked" not in clear.note
    # A wall taller than the arm leaves no clear pose: the chain presses on it, and says so.
    wall = [*FLOOR, {"kind": "segment", "a": [200.0, -20.0], "b": [200.0, 400.0]}]
    jammed = sweep(0.0, wall).result.steps[-1]
    assert not jammed.passed and "blocked" in jammed.note


def test_goals_are_judged_at_the_end_with_their_hold_and_scored():
    goals = [
        {"prop": "ball", "region": [150.0, -30.0, 250.0, 50.0], "hold": 0.5},
        {"prop": "crate", "region": [0.0, -30.0, 100.0, 50.0], "name": "far"},
        {"prop": "ball", "region": [150.0, -30.0, 250.0, 50.0], "hold": 5.0},
    ]
    level = _level([{"wait": 1.0}], props=PROPS, obstacles=FLOOR, goals=goals)
    result = Simulation(level, record=False).run()
    assert [(g.name, g.prop, g.passed) for g in result.goals] == [
        ("goal 1", "ball", True),
        ("far", "crate", False),
        ("goal 3", "ball", False),
    ]
    assert result.goals[0].time_inside == pytest.approx(1.0)
    assert result.status == "failed"
    assert result.score == pytest.approx(100.0 / 3, abs=0.05)  # the wait is not scored


def test_results_carry_score_goals_and_expect_in_a_stable_order_and_repeat_exactly():
    level = _level(
        [{"reach": [150.0, 150.0]}],
        props=PROPS[:1],
        obstacles=FLOOR,
        goals=[{"prop": "ball", "region": [150.0, -30.0, 250.0, 50.0]}],
    )
    first = Simulation(level, record=False).run().as_dict()
    second = Simulation(level, record=False).run().as_dict()
    assert json.dumps(first) == json.dumps(second)
    assert list(first) == [
        "level",
        "solver",
        "status",
        "expect",
        "score",
        "steps_passed",
        "steps_total",
        "goals_passed",
        "goals_total",
        "ticks",
        "sim_time",
        "steps",
        "goals",
        "options",
    ]
    assert list(first["goals"][0]) == [
        "index",
        "name",
        "prop",
        "passed",
        "score",
        "final_position",
        "time_inside",
    ]
    assert first["expect"] == "passed" and first["status"] == "passed"


def test_a_diverged_run_scores_zero():
    sim = Simulation(_level([{"reach": [150.0, 150.0]}]), record=False)
    sim.step()
    sim.world.bodies[1].velocity = (1e12, 0.0)
    result = sim.run()
    assert result.status == "diverged" and result.score == 0.0


def test_score_formulas():
    assert reach_score(0.0, 4.0) == 100.0
    assert reach_score(4.0, 4.0) == 50.0
    assert reach_score(None, 4.0) == 0.0
    assert follow_score(0.0, 10.0) == 100.0
    assert follow_score(10.0, 10.0) == 50.0
    assert level_score([None, None], [], passed=True, diverged=False) == 100.0
    assert level_score([None], [], passed=False, diverged=False) == 0.0
    assert level_score([80.0, 90.0], [100.0], passed=True, diverged=True) == 0.0
    assert level_score([80.0, 90.0], [100.0], passed=True, diverged=False) == 90.0
