"""The pygame window without a display: SDL's dummy video driver and posted events."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from ikgame.app.state import BINDINGS, PlayState
from ikgame.level.model import SOLVER_NAMES
from ikgame.sim import run_level

pygame = pytest.importorskip("pygame", reason="the play extra (pygame-ce) is not installed")

from ikgame.app.window import Window, play  # noqa: E402  (needs pygame)

FRAME = 1 / 60  # s of fake real time per frame


@pytest.fixture
def headless(monkeypatch):
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")


@pytest.fixture
def window(headless, level_file):
    state = PlayState(level_file, size=(320, 180), out_dir=level_file.parent / "out")
    with Window(state) as win:
        yield win
    assert not pygame.display.get_init()


def _key(name: str) -> None:
    pygame.event.post(pygame.event.Event(pygame.KEYDOWN, key=pygame.key.key_code(name), mod=0))


def _frames(window: Window, count: int) -> int:
    return sum(window.frame(FRAME) for _ in range(count))


def test_dragging_moves_the_effector_to_the_mouse(window):
    state = window.state
    pixel = tuple(int(v) for v in state.camera.world_to_pixel([[-70.0, 110.0]])[0])
    pygame.event.post(pygame.event.Event(pygame.MOUSEBUTTONDOWN, pos=pixel, button=1))
    moved = (pixel[0] + 3, pixel[1] - 2)
    pygame.event.post(
        pygame.event.Event(pygame.MOUSEMOTION, pos=moved, rel=(3, -2), buttons=(1, 0, 0))
    )
    assert _frames(window, 120) == 480  # 2 s at 240 ticks/s
    # The world point under the pixel's centre, through the camera's inverse transform.
    under = state.camera.pixel_to_world([[moved[0] + 0.5, moved[1] + 0.5]])[0]
    assert np.hypot(*(state.sim.joint_positions()[-1] - under)) < 3.0
    pygame.event.post(pygame.event.Event(pygame.MOUSEBUTTONUP, pos=moved, button=1))
    window.frame(FRAME)
    assert state.held is None and np.array_equal(state.sim.target, state.sim.script.target)


def test_other_buttons_do_not_grab_the_target(window):
    pygame.event.post(pygame.event.Event(pygame.MOUSEBUTTONDOWN, pos=(5, 5), button=3))
    window.frame(FRAME)
    assert window.state.held is None


def _check_pause(win: Window, key: str) -> None:
    _key(key)
    assert _frames(win, 10) == 0 and win.state.paused
    _key(key)
    assert _frames(win, 10) == 40 and not win.state.paused


def _check_step(win: Window, key: str) -> None:
    ticks = _frames(win, 1)
    assert ticks == 4  # running: the key changes nothing
    _key("space")
    win.frame(FRAME)
    before = win.state.sim.tick
    _key(key)
    _key(key)
    assert win.frame(FRAME) == 2 and win.state.sim.tick == before + 2
    assert _frames(win, 5) == 0


def _check_restart(win: Window, key: str) -> None:
    _frames(win, 10)
    _key(key)
    win.frame(0.0)
    assert win.state.sim.tick == 0


def _check_solver(win: Window, key: str) -> None:
    first = win.state.sim.controller.solver_name
    _key(key)
    win.frame(FRAME)
    expected = SOLVER_NAMES[(SOLVER_NAMES.index(first) + 1) % len(SOLVER_NAMES)]
    assert win.state.sim.controller.solver_name == expected
    assert expected in win.state.status_line()


def _check_gravity(win: Window, key: str) -> None:
    _key(key)
    win.frame(FRAME)
    assert tuple(win.state.sim.world.space.gravity) == (0.0, 0.0)
    _key(key)
    win.frame(FRAME)
    assert tuple(win.state.sim.world.space.gravity) == (0.0, -900.0)


def _check_screenshot(win: Window, key: str) -> None:
    _key(key)
    win.frame(0.0)
    shots = sorted((win.state.out_dir).glob("screenshot-*.png"))
    assert [p.name for p in shots][-1].startswith("screenshot-")
    from PIL import Image

    with Image.open(shots[-1]) as shot:
        assert shot.tobytes() == win.state.frame().tobytes()  # the export frame, no overlays
    assert not list(win.state.out_dir.glob(".*.tmp"))


def _check_help(win: Window, key: str) -> None:
    _key(key)
    win.frame(0.0)
    assert win.state.help
    _key(key)
    win.frame(0.0)
    assert not win.state.help


def _check_quit(win: Window, key: str) -> None:
    _key(key)
    win.frame(0.0)
    assert win.state.quit


CHECKS = {
    "pause": _check_pause,
    "step": _check_step,
    "restart": _check_restart,
    "solver": _check_solver,
    "gravity": _check_gravity,
    "screenshot": _check_screenshot,
    "help": _check_help,
    "quit": _check_quit,
}


@pytest.mark.parametrize(("action", "key"), [(b.action, key) for b in BINDINGS for key in b.keys])
def test_each_key_does_what_the_help_says(window, action, key):
    CHECKS[action](window, key)


def test_every_binding_is_checked():
    assert {b.action for b in BINDINGS} == set(CHECKS)


def test_the_window_shows_what_the_renderer_draws(window):
    _key("h")
    _frames(window, 3)
    shown = pygame.image.tobytes(window.surface, "RGB")
    assert shown == window.state.image().tobytes()
    assert shown != window.state.frame().tobytes()  # the help overlay is on it


def test_closing_the_window_quits(window):
    pygame.event.post(pygame.event.Event(pygame.QUIT))
    window.frame(FRAME)
    assert window.state.quit


def test_a_window_run_without_input_gives_the_headless_results(window):
    headless = run_level(window.state.level, record=False).result.as_dict()
    frames = 0
    while not window.state.sim.done:
        window.frame(FRAME)
        frames += 1
    assert window.state.sim.result.as_dict() == headless
    assert frames <= round(3.0 / FRAME) + 1


def test_a_set_reload_event_reloads_the_level_in_the_open_window(headless, level_file, level_text):
    reload = threading.Event()
    state = PlayState(level_file, size=(320, 180))
    with Window(state, reload=reload) as win:
        _frames(win, 5)
        level_file.write_text(level_text("Renamed"))
        reload.set()
        win.frame(FRAME)
        assert state.level.level.name == "Renamed" and not reload.is_set()
        assert pygame.display.get_caption()[0] == "ikgame: Renamed"


def test_play_runs_until_quit_and_closes_the_window(headless, level_file):
    state = PlayState(level_file, size=(320, 180))
    calls = []

    def clock() -> float:
        calls.append(None)
        if len(calls) == 30:
            _key("escape")
        return len(calls) * FRAME

    play(state, clock=clock)
    assert state.quit and not pygame.display.get_init()
    assert state.sim.tick == 4 * 29  # 29 frames of 1/60 s at 240 ticks/s


def test_a_paused_window_draws_only_when_something_changes(window, monkeypatch):
    drawn = []
    image = window.state.image
    monkeypatch.setattr(window.state, "image", lambda: drawn.append(1) or image())
    _frames(window, 3)
    assert len(drawn) == 3
    _key("space")
    _frames(window, 10)
    assert len(drawn) == 4  # the pause itself, then nothing
    _key("h")
    _frames(window, 2)
    assert len(drawn) == 5
