"""The command line end to end: exit codes, messages, files written (or not)."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from ikgame.cli import main

ROOT = Path(__file__).resolve().parents[1]


def test_version_and_help(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert "ikgame 0.1.0" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        main(["run", "--help"])
    assert "exit codes" in capsys.readouterr().out


def test_run_writes_results_and_exits_zero(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["run", "--no-frames", "--out", str(out)]) == 0
    data = json.loads((out / "results.json").read_text())
    assert data["level"] == "First reach"
    assert data["status"] == "passed"
    assert all(step["final_error"] <= 6.0 for step in data["steps"])
    assert "passed" in capsys.readouterr().out


def test_two_runs_write_byte_identical_results(tmp_path):
    assert main(["run", "--no-frames", "--quiet", "--out", str(tmp_path / "a")]) == 0
    assert main(["run", "--no-frames", "--quiet", "--out", str(tmp_path / "b")]) == 0
    assert (tmp_path / "a/results.json").read_bytes() == (tmp_path / "b/results.json").read_bytes()


def test_bad_level_exits_2_with_file_line_and_field(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text(
        '[level]\nname = "x"\nduration = 5\n[chain]\n[[chain.links]]\nlength = -3\n'
        '[[script]]\nreach = [1, 2]\n'
    )
    out = tmp_path / "out"
    assert main(["run", str(bad), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"{bad}:6: chain.links[0].length: Input should be greater than 0 (got -3)" in err
    assert "Traceback" not in err
    assert not out.exists()


def test_missing_level_file_exits_2(tmp_path, capsys):
    assert main(["run", str(tmp_path / "nope.toml")]) == 2
    assert "no such level file" in capsys.readouterr().err


def test_refuses_a_non_empty_out_dir_unless_forced(tmp_path, capsys):
    (tmp_path / "keep.txt").write_text("mine")
    assert main(["run", "--no-frames", "--out", str(tmp_path)]) == 2
    assert "not empty" in capsys.readouterr().err
    assert not (tmp_path / "results.json").exists()
    assert main(["run", "--no-frames", "--quiet", "--force", "--out", str(tmp_path)]) == 0
    assert (tmp_path / "keep.txt").read_text() == "mine"


def test_console_script_runs_as_a_module(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "ikgame", "run", "/nonexistent/level.toml"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
