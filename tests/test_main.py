"""The ``ikgame`` command's entry point: a Ctrl-C while the command line loads is one line."""

import importlib.abc
import sys
import tomllib
from pathlib import Path

from ikgame.__main__ import run


class _CtrlC(importlib.abc.MetaPathFinder):
    """Raises KeyboardInterrupt when ``ikgame.cli`` is imported, as a Ctrl-C would while it loads."""

    def find_spec(self, name, path=None, target=None):
        if name == "ikgame.cli":
            raise KeyboardInterrupt
        return None


def test_a_ctrl_c_while_loading_exits_130_with_one_line(monkeypatch, capsys):
    monkeypatch.delitem(sys.modules, "ikgame.cli", raising=False)
    monkeypatch.setattr(sys, "meta_path", [_CtrlC(), *sys.meta_path])
    assert run() == 130
    assert capsys.readouterr().err == "interrupted: nothing was written\n"


def test_the_installed_command_goes_through_it():
    project = tomllib.loads((Path(__file__).resolve().parents[1] / "pyproject.toml").read_text())
    assert project["project"]["scripts"]["ikgame"] == "ikgame.__main__:run"
