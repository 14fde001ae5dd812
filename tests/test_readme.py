"""The README's promises: the two quick-start commands, and examples that really run."""

import re
import subprocess
import sys
from pathlib import Path

from ikgame.level.loader import parse_level
from ikgame.sim import Simulation

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def _block(after: str, language: str) -> str:
    section = README.split(after, 1)[1]
    return re.search(rf"```{language}\n(.*?)```", section, re.S).group(1)


def test_quick_start_is_two_commands_and_ci_runs_the_second():
    lines = [line for line in _block("## Quick start", "bash").splitlines() if line.strip()]
    assert len(lines) == 2
    assert "ikgame run" in lines[0]
    assert "pytest" in lines[1]
    # .ci/run reads the command from the README itself, so the two cannot drift apart.
    proc = subprocess.run(
        [sys.executable, "-c", _ci_extractor()], capture_output=True, text=True, cwd=ROOT
    )
    assert proc.stdout.strip() == lines[1]


def _ci_extractor() -> str:
    script = (ROOT / ".ci" / "run").read_text()
    return re.search(r"<<'PY'\n(.*?)\nPY\n", script, re.S).group(1)


def test_game_loop_example_runs():
    exec(compile(_block("## Use it from your game loop", "python"), "README.md", "exec"), {})


def test_tree_example_runs():
    code = _block("A tree of bones has one target per effector", "python")
    exec(compile("import ikgame\n" + code, "README.md", "exec"), {})


def test_level_example_is_a_valid_level_that_runs():
    level = parse_level(_block("A level in brief", "toml"), "README.md")
    assert Simulation(level, record=False).run().status in ("passed", "failed")
