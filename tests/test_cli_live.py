"""``ikgame play`` and ``ikgame watch`` on the command line: help, bad input, missing extras."""

from __future__ import annotations

import subprocess
import sys

import pytest

from ikgame.app.state import PlayState
from ikgame.cli import main


@pytest.mark.parametrize("command", ["play", "watch"])
def test_help_teaches_with_examples(command, capsys):
    with pytest.raises(SystemExit) as exc:
        main([command, "--help"])
    assert exc.value.code == 0
    out = capsys.readouterr().out
    assert "examples:" in out and f"ikgame {command} " in out
    assert f"python -m pip install 'ikgame[{command}]'" in out


@pytest.mark.parametrize(
    ("argv", "module", "extra"),
    [
        (["play"], "pygame", "play"),
        (["play", "--watch"], "watchfiles", "watch"),
        (["watch", "01_first_reach"], "watchfiles", "watch"),
    ],
)
def test_a_missing_extra_exits_2_with_the_install_command(argv, module, extra, monkeypatch, capsys):
    if argv[0] == "play" and module != "pygame":
        pytest.importorskip("pygame", reason="the play extra (pygame-ce) is not installed")
    monkeypatch.setitem(sys.modules, module, None)  # makes `import module` fail
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"python -m pip install 'ikgame[{extra}]'" in err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_play_rejects_bad_input_before_opening_a_window(tmp_path, capsys):
    pytest.importorskip("pygame", reason="the play extra (pygame-ce) is not installed")
    assert main(["play", str(tmp_path / "nope.toml")]) == 2
    assert "no such level file" in capsys.readouterr().err
    assert main(["play", "--size", "10x10"]) == 2
    assert "--size" in capsys.readouterr().err


def test_play_opens_a_window_and_saves_screenshots_into_out(tmp_path, monkeypatch):
    pytest.importorskip("pygame", reason="the play extra (pygame-ce) is not installed")
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    advance = PlayState.advance

    def advance_then_quit(self: PlayState, seconds: float) -> int:
        ticks = advance(self, seconds)
        if self.sim.time >= 0.1:
            self.screenshot()
            self.quit = True
        return ticks

    monkeypatch.setattr(PlayState, "advance", advance_then_quit)
    assert main(["play", "02_tentacle", "--size", "320x180", "--out", str(tmp_path)]) == 0
    assert [p.name for p in tmp_path.iterdir()] == ["screenshot-001.png"]


def test_the_extras_are_imported_only_when_a_command_needs_them():
    code = (
        "import sys, ikgame.cli, ikgame.app.window, ikgame.app.watch; "
        "print(sorted({'pygame', 'watchfiles'} & set(sys.modules)))"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert proc.stdout.strip() == "[]"


def test_play_without_a_display_says_so_instead_of_running_unseen(monkeypatch, capsys):
    pygame = pytest.importorskip("pygame", reason="the play extra (pygame-ce) is not installed")
    monkeypatch.delenv("SDL_VIDEODRIVER", raising=False)
    monkeypatch.setattr(pygame.display, "init", lambda: None)
    monkeypatch.setattr(pygame.display, "get_driver", lambda: "offscreen")
    assert main(["play", "--size", "320x180"]) == 2
    err = capsys.readouterr().err
    assert "cannot open a window" in err and "'offscreen'" in err and "Traceback" not in err

    def no_video() -> None:
        raise pygame.error("x11 not available")

    monkeypatch.setattr(pygame.display, "init", no_video)
    assert main(["play", "--size", "320x180"]) == 2
    assert "cannot open a window: x11 not available" in capsys.readouterr().err
