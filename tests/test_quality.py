"""The motion-quality suite's own judgement (benchmarks/quality.py), without running levels:
the weighted optimum a conflict is held to, and the table a set of runs makes."""

import importlib
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from ikgame.kinematics import Skeleton, TargetSet

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
quality = importlib.import_module("quality")


def test_the_kinematic_optimum_of_a_conflict_splits_the_gap_by_weight():
    # Two arms of 100 px aimed 250 px apart: 50 px too far between them.
    targets = TargetSet([0, 1], [(-125.0, 0.0), (125.0, 0.0)], weights=[2.0, 1.0])
    # On a base that cannot move, each arm stretches toward its own target, whatever the weights.
    fixed = Skeleton.tree([100.0, 100.0], [-1, -1])
    errors = quality.kinematic_optimum(fixed, np.array([2.0, 1.0]), targets)
    assert errors == pytest.approx([25.0, 25.0], abs=0.01)
    # On the tip of a long trunk that can swing them sideways, the least squares leave the
    # heavier hand (weight 2) about a third of the gap short and the other two thirds.
    trunk = Skeleton.tree(
        [300.0, 100.0, 100.0], [-1, 0, 0], base=(0.0, -300.0), base_angle=np.pi / 2
    )
    errors = quality.kinematic_optimum(
        trunk, np.array([0.0, 2.5, -2.5]), TargetSet([1, 2], targets.points, targets.weights)
    )
    assert errors[0] / errors[1] == pytest.approx(0.5, abs=0.05)
    assert errors.sum() == pytest.approx(50.0, abs=1.0)


def _report(level: str, *, footing: dict | None = None) -> object:
    checks = dict.fromkeys(("reached", "overshoot", "jitter", "limits", "spins", "expect"), True)
    checks["states"] = True
    if footing:
        checks["footing"] = False
    return quality.RunReport(
        level=level,
        solver="dls",
        status="passed",
        reached=1,
        reachable=1,
        mean_time_to_reach=0.5,
        overshoot_pct=0.0,
        jitter_px=0.01,
        limit_excursion_deg=0.0,
        spins=0,
        saturated_share=0.1,
        states={"success": 1},
        special_met=0,
        special_total=0,
        false_success=0,
        checks=checks,
        wall_s=1.0,
        footing=footing or {},
    )


def test_a_success_counts_as_false_only_off_the_target():
    def step(passed: bool, state: str, on_target: bool) -> quality.StepReport:
        return quality.StepReport(
            index=0,
            kind="reach",
            expect="reachable",
            passed=passed,
            time_to_reach=None,
            final_state=state,
            jitter_px=0.0,
            jitter_limit_px=0.5,
            on_target=on_target,
        )

    stopped_short = step(False, "success", False)
    late_on_target = step(False, "success", True)  # its hold cut short by the timeout
    said_blocked = step(False, "blocked", False)
    arrived = step(True, "success", True)
    assert quality.false_successes([stopped_short]) == 1
    assert quality.false_successes([late_on_target, said_blocked, arrived]) == 0


def test_the_footing_column_shows_only_with_a_creature_in_the_table():
    chain = _report("02_chain.toml")
    table = quality.markdown([chain])
    assert "slip/sink" not in table and table.count("| pass |") == 1
    assert "foot" not in quality.legend([chain])
    walker = _report(
        "18_walker.toml",
        footing={
            "a": {"steps": 4, "landing": 1.0, "slip": 0.5, "sink": 0.25},
            "b": {"steps": 0, "landing": 0.0, "slip": 2.5, "sink": 1.0},
        },
    )
    lines = quality.markdown([chain, walker]).splitlines()
    assert lines[0].endswith("| slip/sink px | run |")
    assert lines[2].endswith("| - | pass |")
    assert lines[3].endswith("| 2.50/1.00 x | FAIL x |")
    assert "every foot steps" in quality.legend([chain, walker])
    assert quality.summary([chain, walker]).startswith("runs passing: 1/2   checks passing: 14/15")


def test_the_benchmarks_measure_the_checkout_they_live_in(tmp_path):
    # Another ikgame first on the path (as an editable install of another worktree would be):
    # a benchmark script run from this checkout still imports this checkout's.
    other = tmp_path / "ikgame"
    other.mkdir()
    (other / "__init__.py").write_text("")
    root = Path(__file__).resolve().parents[1]
    probe = "import _checkout, ikgame; print(ikgame.__file__)"
    done = subprocess.run(
        [sys.executable, "-c", f"import sys; sys.path[0] = {str(root / 'benchmarks')!r}; {probe}"],
        env={**os.environ, "PYTHONPATH": str(tmp_path)},
        cwd=tmp_path,
        capture_output=True,
        text=True,
        check=True,
    )
    assert Path(done.stdout.strip()) == root / "ikgame" / "__init__.py"
