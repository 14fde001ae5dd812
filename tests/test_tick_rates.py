"""The tick-rate measure's own judgement (benchmarks/tick_rates.py), without running levels: which
levels it measures, and how it reads a target's times at each rate."""

import importlib
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
quality = importlib.import_module("quality")
tick_rates = importlib.import_module("tick_rates")


def _run(rate_times: list[float | None], expects: list[str]) -> object:
    """What :func:`tick_rates.target_times` reads of a run report: one level and solver whose
    steps took ``rate_times`` to reach."""
    steps = [
        quality.StepReport(
            index=i,
            kind="reach",
            expect=expect,
            passed=t is not None,
            time_to_reach=t,
            final_state="success",
        )
        for i, (t, expect) in enumerate(zip(rate_times, expects, strict=True))
    ]
    return SimpleNamespace(level="23_chain20_low.toml", solver="ccd", steps=steps)


def test_each_reachable_target_is_compared_with_its_time_at_the_reference_rate():
    expects = [quality.REACHABLE, quality.OUT_OF_REACH, quality.REACHABLE]
    runs = {
        120: _run([0.55, None, 0.30], expects),
        240: _run([0.50, None, 0.50], expects),
        480: _run([0.44, None, None], expects),
    }
    first, third = tick_rates.target_times(runs)  # the target out of reach is not timed
    assert (first.step, third.step) == (0, 2)
    assert first.shares == pytest.approx((1.1, 1.0, 0.88))
    assert first.passed
    # 40% sooner at 120 ticks/s, and not reached at 480: either fails.
    assert third.shares[0] == pytest.approx(0.6) and third.shares[2] is None
    assert not third.passed
    assert not tick_rates.TargetTimes("l", "ccd", 0, (0.5, 0.5, 0.58)).passed
    assert tick_rates.TargetTimes("l", "ccd", 0, (0.5, 0.5, 0.575)).passed


def test_the_long_chains_are_the_stress_levels_of_twenty_links_or_more():
    every = tick_rates.long_levels(quick=False)
    quick = tick_rates.long_levels(quick=True)
    names = {path.name for path in every}
    assert {"23_chain20_low.toml", "48_chain30_gravity.toml", "03_chain200_gravity.toml"} <= names
    assert "01_one_link.toml" not in names
    assert set(quick) < set(every)
    assert all(
        len(quality.load(path).chain.expanded_links) <= tick_rates.QUICK_LINKS for path in quick
    )
    assert "03_chain200_gravity.toml" not in {path.name for path in quick}
