"""The window's state without a window: pacing, the mouse, reloads, and no physics of its own."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ikgame.app.state import (
    MAX_CATCH_UP,
    KeyPress,
    MouseDown,
    MouseMove,
    MouseUp,
    PlayState,
    help_lines,
)
from ikgame.level.loader import load_level
from ikgame.sim import run_level


def _state(path, **options) -> PlayState:
    return PlayState(path, size=(320, 180), out_dir=path.parent / "out", **options)


def _run_out(state: PlayState, frame_seconds) -> None:
    frames = iter(frame_seconds)
    while not state.sim.done:
        state.advance(next(frames))


def test_a_run_without_input_ends_exactly_as_a_headless_run(level_file):
    headless = run_level(load_level(level_file), record=False).result.as_dict()
    state = _state(level_file)
    _run_out(state, iter(lambda: 1 / 60, None))
    assert state.sim.result.as_dict() == headless


def test_the_physics_does_not_depend_on_the_frame_rate(level_file):
    steady, ragged = _state(level_file), _state(level_file)
    for _ in range(60):
        steady.advance(1 / 60)
    # The same second of real time cut into uneven frames, one of them a stall past the cap.
    for seconds in [0.013, 0.031, 0.002, 0.2, 0.0, 0.11, 0.3, 0.06, 0.1, 0.184]:
        ragged.advance(seconds)
    # The stall lost its time past the cap (and the fraction of a tick it held), nothing more.
    lost = round((0.3 - MAX_CATCH_UP) * 240)
    assert steady.sim.tick - lost - 1 <= ragged.sim.tick <= steady.sim.tick - lost
    # Stepped on to the same tick, both are in exactly the same state.
    while ragged.sim.tick < steady.sim.tick:
        ragged.sim.step()
    assert np.array_equal(ragged.sim.joint_positions(), steady.sim.joint_positions())


def test_a_stalled_frame_catches_up_at_most_the_cap(level_file):
    state = _state(level_file)
    assert state.advance(5.0) == round(MAX_CATCH_UP * 240)
    # The stall's remainder is dropped, not carried over.
    assert state.advance(0.0) == 0


def test_holding_the_mouse_drives_the_target_and_releasing_hands_it_back(level_file):
    state = _state(level_file)
    pixel = tuple(int(v) for v in state.camera.world_to_pixel([[-60.0, 120.0]])[0])
    state.handle(MouseDown(pixel))
    state.handle(MouseMove((pixel[0] + 1, pixel[1])))
    held = state.pixel_to_world((pixel[0] + 1, pixel[1]))
    assert np.array_equal(state.sim.target, held)
    for _ in range(120):
        state.advance(1 / 60)
    assert np.hypot(*(state.sim.joint_positions()[-1] - held)) < 3.0
    state.handle(MouseUp())
    assert state.held is None
    assert np.array_equal(state.sim.target, state.sim.script.target)


def test_after_the_run_the_chain_still_follows_the_mouse_and_the_result_stays(level_file):
    state = _state(level_file)
    _run_out(state, iter(lambda: 1 / 30, None))
    result = state.sim.result.as_dict()
    pixel = tuple(int(v) for v in state.camera.world_to_pixel([[110.0, 90.0]])[0])
    state.handle(MouseDown(pixel))
    assert state.advance(0.25) == 60
    for _ in range(60):
        state.advance(1 / 30)
    assert np.hypot(*(state.sim.joint_positions()[-1] - state.held)) < 3.0
    assert state.sim.result.as_dict() == result == state.result.as_dict()
    assert state.frame().size == (320, 180)


def test_moving_the_mouse_without_the_button_moves_nothing(level_file):
    state = _state(level_file)
    state.handle(MouseMove((10, 10)))
    assert state.held is None and np.array_equal(state.sim.target, state.sim.script.target)


def test_a_restart_keeps_the_held_target(level_file):
    state = _state(level_file)
    state.handle(MouseDown((100, 50)))
    state.advance(0.1)
    state.handle(KeyPress("r"))
    assert state.sim.tick == 0
    assert np.array_equal(state.sim.target, state.pixel_to_world((100, 50)))


def test_reload_reads_the_file_again(level_file, level_text):
    state = _state(level_file)
    state.advance(0.2)
    level_file.write_text(level_text("Edited"))
    assert state.reload()
    assert state.level.level.name == "Edited" and state.sim.tick == 0
    assert "reloaded" in state.message


def test_a_broken_reload_keeps_the_running_level_and_says_why(level_file, level_text):
    state = _state(level_file)
    state.advance(0.2)
    level_file.write_text(level_text().replace("length = 100.0", "length = -1.0"))
    assert not state.reload()
    assert state.level.level.name == "Live" and state.sim.tick == 48
    assert f"{level_file}:" in state.message and "chain.links[0].length" in state.message
    state.advance(10.0)
    assert state.message == ""  # notices fade


def test_gravity_switched_off_stays_off_through_a_set_step(level_file, level_text):
    level_file.write_text(
        level_text() + "\n[[script]]\nset = { gravity = [0.0, -500.0] }\n\n[[script]]\nwait = 0.2\n"
    )
    state = _state(level_file)
    state.handle(KeyPress("g"))
    _run_out(state, iter(lambda: 1 / 30, None))
    assert tuple(state.sim.world.space.gravity) == (0.0, 0.0)
    state.handle(KeyPress("g"))
    assert tuple(state.sim.world.space.gravity) == (0.0, -500.0)


def test_the_status_line_tells_the_run_is_over(level_file):
    state = _state(level_file)
    _run_out(state, iter(lambda: 1 / 30, None))
    result = state.sim.result
    assert f"run over: {result.status}, score {result.score:.0f}/100" in state.status_line()


def test_a_blown_up_world_shows_its_last_drawable_state(level_file):
    state = _state(level_file)
    state.advance(0.1)
    before = state.frame()
    state.sim.world.bodies[1].velocity = (math.inf, 0.0)
    assert state.advance(0.1) == 1 and state.sim.diverged
    assert state.advance(0.1) == 0  # nothing more to simulate
    assert not np.all(np.isfinite(state.sim.joint_positions()))
    assert state.frame().tobytes() == before.tobytes()
    assert "run over: diverged" in state.status_line()


def test_the_help_lists_every_key():
    keys = " ".join(keys for keys, _ in help_lines())
    for name in ("space", ".", "s", "r", "tab", "n", "g", "p", "h", "F1", "esc", "q", "mouse"):
        assert name in keys.split() or name == "mouse" and "mouse" in keys


def test_advance_refuses_negative_time(level_file):
    with pytest.raises(ValueError, match="seconds"):
        _state(level_file).advance(-1.0)


def test_the_mouse_drags_the_effector_nearest_to_where_it_pressed():
    from ikgame.level.library import LEVELS_DIR

    state = PlayState(LEVELS_DIR / "15_two_hands.toml", size=(320, 180))
    hands = dict(zip(state.sim.effector_names, state.sim.world.effector_positions(), strict=True))
    pixel = state.camera.world_to_pixel([hands["right_hand"] + (5.0, 5.0)])[0]
    state.handle(MouseDown(tuple(pixel)))
    assert set(state.sim.targets) >= {"right_hand"}
    # One window pixel is a few world px at this size.
    assert state.sim.targets["right_hand"] == pytest.approx(hands["right_hand"] + 5.0, abs=4.0)
    state.handle(MouseUp())
    scripted = state.sim.script.targets.get("right_hand")
    assert (
        "right_hand" not in state.sim.targets
        if scripted is None
        else state.sim.targets["right_hand"] == pytest.approx(scripted)
    )
