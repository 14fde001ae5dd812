"""Watching a level: re-runs on edits, broken edits reported, a clean stop, files whole."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
from pathlib import Path

import pytest

import ikgame.cli as cli
from ikgame.app.watch import level_files, watch_level

pytest.importorskip("watchfiles", reason="the watch extra (watchfiles) is not installed")

NOTICE = 1.0  # s: an edit is noticed and its re-run starts within this
SETTLE = 30.0  # s: bound on anything else (a run to finish, a thread to end)


class _Runs:
    """Counts the run commands the watch makes, by wrapping ``ikgame.cli.main``."""

    def __init__(self, monkeypatch) -> None:
        self.started = threading.Semaphore(0)
        self.finished = threading.Semaphore(0)
        self.codes: list[int] = []
        original = cli.main

        def main(argv):
            self.started.release()
            code = original(argv)
            self.codes.append(code)
            self.finished.release()
            return code

        monkeypatch.setattr(cli, "main", main)

    def next(self) -> int:
        assert self.started.acquire(timeout=NOTICE), "the edit was not re-run within a second"
        assert self.finished.acquire(timeout=SETTLE)
        return self.codes[-1]


class _Watch:
    """``ikgame watch ARGS`` in a thread, stopped by an event."""

    def __init__(self, *args: str) -> None:
        self.stop, self.ready = threading.Event(), threading.Event()
        self.code: int | None = None
        parsed = cli._parser().parse_args(["watch", *args])

        def target() -> None:
            self.code = cli._cmd_watch(parsed, stop=self.stop, ready=self.ready.set)

        self.thread = threading.Thread(target=target, daemon=True)

    def __enter__(self) -> _Watch:
        self.thread.start()
        assert self.ready.wait(SETTLE)
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop.set()
        self.thread.join(SETTLE)
        assert not self.thread.is_alive()


def _results(out: Path) -> dict:
    return json.loads((out / "results.json").read_text())


def test_an_edit_reruns_and_a_broken_edit_is_reported_while_watching(
    monkeypatch, level_file, level_text, tmp_path, capsys
):
    out = tmp_path / "out"
    runs = _Runs(monkeypatch)
    with _Watch(str(level_file), "--out", str(out), "--no-frames") as watch:
        assert runs.next() == 0  # the first run, before watching
        assert _results(out)["level"] == "Live"
        level_file.write_text(level_text("Edited"))
        assert runs.next() == 0
        assert _results(out)["level"] == "Edited"
        level_file.write_text(level_text("Broken").replace("length = 100.0", "length = -1.0"))
        assert runs.next() == 2
        err = capsys.readouterr().err
        assert f"{level_file}:" in err and "chain.links[0].length" in err
        assert "Traceback" not in err
        assert _results(out)["level"] == "Edited"  # the last good outputs stay
        level_file.write_text(level_text("Fixed"))
        assert runs.next() == 0
    assert watch.code == 0
    # Stopped: the last outputs are whole, and no temporary file is left behind.
    assert _results(out)["level"] == "Fixed"
    assert not [p for p in out.rglob("*") if p.name.endswith(".tmp")]
    assert "running it again" in capsys.readouterr().out


def test_a_save_by_rename_is_seen(monkeypatch, level_file, level_text, tmp_path):
    out = tmp_path / "out"
    runs = _Runs(monkeypatch)
    with _Watch(str(level_file), "--out", str(out), "--no-frames"):
        assert runs.next() == 0
        # Editors often write a new file and rename it over the old one.
        fresh = level_file.with_name(".live.toml.swp")
        fresh.write_text(level_text("Renamed"))
        os.replace(fresh, level_file)
        assert runs.next() == 0
    assert _results(out)["level"] == "Renamed"


def test_editing_the_theme_a_level_names_reruns_it(monkeypatch, level_file, level_text, tmp_path):
    theme = level_file.with_name("mine.json")
    theme.write_text((Path(cli.__file__).parents[1] / "assets/themes/dark.json").read_text())
    level_file.write_text(level_text().replace("[level]\n", '[level]\ntheme = "mine.json"\n'))
    assert level_files(level_file) == {level_file.resolve(), theme.resolve()}
    runs = _Runs(monkeypatch)
    with _Watch(str(level_file), "--out", str(tmp_path / "out"), "--no-frames"):
        assert runs.next() == 0
        theme.write_text(theme.read_text().replace('"name"', '"description": "edited", "name"'))
        assert runs.next() == 0


def test_unrelated_files_beside_the_level_do_not_rerun_it(level_file):
    seen, stop, ready = [], threading.Event(), threading.Event()

    def on_change() -> None:
        seen.append(level_file.read_text())
        stop.set()

    thread = threading.Thread(
        target=watch_level, args=(level_file, on_change), kwargs={"stop": stop, "ready": ready.set}
    )
    thread.start()
    assert ready.wait(SETTLE)
    level_file.with_name("notes.txt").write_text("not a level")
    level_file.write_text(level_file.read_text() + "\n# the only change that counts\n")
    thread.join(SETTLE)
    assert len(seen) == 1 and seen[0].endswith("counts\n")


def test_watch_refuses_a_non_empty_out_folder_at_once(tmp_path, level_file, capsys):
    out = tmp_path / "out"
    out.mkdir()
    (out / "keep.txt").write_text("mine")
    assert cli.main(["watch", str(level_file), "--out", str(out)]) == 2
    assert "--force" in capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == ["keep.txt"]


def test_ctrl_c_stops_watching_with_exit_code_zero(tmp_path, level_file, interruptible):
    out = tmp_path / "out"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "ikgame",
            "watch",
            str(level_file),
            "--out",
            str(out),
            "--no-frames",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        lines: list[str] = []
        watching = threading.Event()

        def read() -> None:
            for line in proc.stdout:
                lines.append(line)
                if line.startswith("watching"):
                    watching.set()

        threading.Thread(target=read, daemon=True).start()
        assert watching.wait(SETTLE), lines
        proc.send_signal(signal.SIGINT)
        assert proc.wait(SETTLE) == 0
    finally:
        proc.kill()
    assert "Traceback" not in proc.stderr.read()
    assert _results(out)["status"] == "passed"


def test_the_files_of_a_skinned_level_include_its_sprites():
    from ikgame.app.watch import level_files
    from ikgame.level.library import LEVELS_DIR

    names = {p.name for p in level_files(LEVELS_DIR / "14_skinned_arm.toml")}
    assert "14_skinned_arm.toml" in names
    assert {"upper_arm.png", "ball.png"} <= names
