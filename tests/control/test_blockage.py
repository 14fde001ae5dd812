"""The block watch on made-up error traces, and a jammed arm in the physics world."""

import numpy as np

from ikgame.control.blockage import BlockWatch
from ikgame.level.model import Level
from ikgame.sim import Simulation


def _run(watch, errors, *, reachable=True, pushing=True, touching=True):
    return [
        watch.observe(
            error=e, reachable=reachable, pushing=lambda: pushing, touching=lambda: touching
        )
        for e in errors
    ]


def test_no_progress_while_pushing_is_blocked_after_the_window():
    flags = _run(BlockWatch(dt=0.01, arrival=0.5), [50.0] * 60)
    assert not any(flags[:50]) and all(flags[51:])


def test_progress_a_free_chain_a_given_up_target_or_arrival_are_not_blocked():
    assert not any(_run(BlockWatch(dt=0.01, arrival=0.5), np.linspace(200, 30, 120)))
    assert not any(_run(BlockWatch(dt=0.01, arrival=0.5), [50.0] * 120, pushing=False))
    assert not any(_run(BlockWatch(dt=0.01, arrival=0.5), [50.0] * 120, reachable=False))
    assert not any(_run(BlockWatch(dt=0.01, arrival=0.5), [0.8] * 120))


def test_a_target_that_jumps_away_is_not_lost_ground():
    errors = [0.5] * 30 + list(np.linspace(300, 200, 60))
    assert not any(_run(BlockWatch(dt=0.01, arrival=0.5), errors))


def test_a_slide_that_dies_out_short_of_the_target_is_blocked_before_it_stops():
    # A chain pressing on an obstacle slides along it, slower and slower, toward a rest 100 px
    # short; its error still falls by more than the band within every window.
    t = np.arange(0, 4, 0.01)
    flags = _run(BlockWatch(dt=0.01, arrival=0.5), 100 + 150 * np.exp(-t / 0.8))
    first = flags.index(True)
    assert 1.5 < t[first] < 3.0
    slide = 150 * np.exp(-t[first] / 0.8)
    assert slide > 2.0  # still falling more than the band over the window


def test_a_weak_arm_slowing_at_its_torque_limit_is_not_judged_by_its_fading_fall():
    # Lifting itself, a weak arm slows down and may speed up again as the load on it changes:
    # only a chain touching something is judged blocked while its error still falls.
    t = np.arange(0, 4, 0.01)
    creep = 100 + 150 * np.exp(-t / 0.8)
    flags = _run(BlockWatch(dt=0.01, arrival=0.5), creep, touching=False)
    assert t[flags.index(True)] > 3.3  # blocked only once its error stays within the band


def test_braking_onto_the_target_and_a_steady_slide_are_not_blocked():
    t = np.arange(0, 4, 0.01)
    assert not any(_run(BlockWatch(dt=0.01, arrival=0.5), 250 * np.exp(-t / 0.8)))
    braking = np.maximum(0.0, 4.0 - t) ** 2 * 20  # constant deceleration, stopping on it at 4 s
    assert not any(_run(BlockWatch(dt=0.01, arrival=0.5), braking))
    # Swung in fast, hit a rock at 1 s, then slides along it at a steady 20 px/s.
    hit = np.where(t < 1.0, 400 - 300 * t, 100 - 20 * (t - 1.0))
    assert not any(_run(BlockWatch(dt=0.01, arrival=0.5), hit))


def test_a_slow_crawl_that_barely_slows_is_not_blocked():
    # Sliding along something at 15 px/s, slowing by 0.5 px/s each second: a tenth of its way
    # in half a second is out of its reach, but the way it still makes adds up to the target.
    t = np.arange(0, 4, 0.01)
    crawl = 200 - 15 * t + 0.25 * t**2
    assert not any(_run(BlockWatch(dt=0.01, arrival=0.5), crawl))


def test_a_fading_swing_is_not_a_slide_coming_to_rest():
    t = np.arange(0, 4, 0.01)
    swing = 100 + 150 * np.exp(-t / 0.8) + 3.0 * np.sin(2 * np.pi * t / 0.3)
    assert not any(_run(BlockWatch(dt=0.01, arrival=0.5), swing))


def test_a_jammed_arm_reports_blocked_holds_and_tries_again_when_the_target_moves():
    level = Level.model_validate(
        {
            "level": {"name": "jam", "duration": 8.0},
            "world": {"gravity": [0.0, 0.0]},
            "chain": {"angle": 0.0, "links": [{"length": 100.0, "repeat": 2}]},
            # A target within the arm's reach but inside a post: no clear pose reaches it.
            "obstacles": [{"kind": "circle", "center": [150.0, 100.0], "radius": 25.0}],
            "script": [
                {"reach": [150.0, 100.0], "timeout": 3.0},
                {"reach": [0.0, -150.0], "timeout": 3.0},
            ],
        }
    )
    sim = Simulation(level, record=False)
    states = []
    while not sim.done:
        states.append((sim.script.step_index, sim.step().solver_status))
    first = [s for i, s in states if i == 0]
    assert "blocked" in first and first[-1] == "blocked"
    assert [s for i, s in states if i == 1][-1] == "success"
    steps = sim.result.steps
    assert not steps[0].passed and "blocked" in steps[0].note
    assert steps[1].passed and steps[1].note == ""


def test_a_moving_base_releases_a_blocked_arm_and_blocks_nothing_while_it_carries_it():
    # The jammed arm above; then its base slides away with the target left where it was.
    level = Level.model_validate(
        {
            "level": {"name": "carried", "duration": 6.0},
            "world": {"gravity": [0.0, 0.0]},
            "chain": {"angle": 0.0, "links": [{"length": 100.0, "repeat": 2}]},
            "obstacles": [{"kind": "circle", "center": [150.0, 100.0], "radius": 25.0}],
            "script": [
                {"reach": [150.0, 100.0], "timeout": 3.0},
                {"set": {"base": [-80.0, 0.0], "over": 1.0}},
                {"wait": 2.0},
            ],
        }
    )
    sim = Simulation(level, record=False)
    ticks = []
    while not sim.done:
        carried = sim.world.base_motion() is not None
        ticks.append((carried, sim.step().solver_status))
    assert ticks[int(2.9 * 240)][1] == "blocked"
    moving = [status for carried, status in ticks if carried]
    assert moving and "blocked" not in moving
