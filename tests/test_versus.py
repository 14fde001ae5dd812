"""benchmarks/versus.py: the tick of this tree against another's, side by side."""

import importlib
import re
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
versus = importlib.import_module("versus")


def test_this_tree_against_itself_gives_a_ratio_per_target(capsys):
    assert versus.main([str(versus.ROOT), "--ticks", "400", "--warm-up", "0", "--rounds", "1"]) == 0
    out = capsys.readouterr().out
    ratios = re.findall(r"^\s+(reach|circle)\s+median ratio (\d+\.\d+)x$", out, re.M)
    assert [target for target, _ in ratios] == ["reach", "circle"]
    # The same code on both cores: a ratio of 1, within what a shared machine's noise allows.
    assert all(0.2 < float(ratio) < 5.0 for _, ratio in ratios)


def test_a_folder_without_ikgame_is_refused_with_exit_code_2(tmp_path, capsys):
    assert versus.main([str(tmp_path)]) == 2
    assert "holds no ikgame package" in capsys.readouterr().err
