"""The ``ikgame`` command's entry point: a Ctrl-C while the command line loads is one line."""

import gc
import importlib.abc
import os
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


def test_the_command_runs_blas_on_one_thread_unless_told_otherwise(monkeypatch):
    # OpenBLAS starting a thread per core costs a short run more than its matrices need.
    import ikgame.cli

    seen = []
    monkeypatch.setattr(ikgame.cli, "main", lambda: seen.append(os.environ["OPENBLAS_NUM_THREADS"]))
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "4")  # restored after the test, set or not
    try:
        run()
        monkeypatch.delenv("OPENBLAS_NUM_THREADS")
        run()
    finally:
        gc.unfreeze()  # run() freezes the heap for the interpreter's exit
    assert seen == ["4", "1"]
