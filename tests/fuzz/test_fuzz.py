"""Fuzzing ``ikgame run`` with generated and broken level files.

Every case ends one of two ways: exit 2 with a message on every line that names the file (and
the line, unless the problem is the file as a whole) and nothing written; or exit 0 with a
results.json whose status is passed, failed or diverged. Never exit 1, never a traceback.

The default profile is small and seeded (derandomized), so CI runs the same cases every time.
``IKGAME_FUZZ_EXAMPLES=10000`` runs a larger, random profile; ``benchmarks/fuzz.py`` counts the
outcomes of a large run instead of stopping at the first failure.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from fuzzgen import case_text, run_case, unlocated
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

EXAMPLES = int(os.environ.get("IKGAME_FUZZ_EXAMPLES", "0"))
PROFILE = settings(
    max_examples=EXAMPLES or 150,
    derandomize=not EXAMPLES,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow],
)
SEEDS = st.integers(min_value=0, max_value=2**32 - 1)


def _check(data: str | bytes, frames: bool) -> None:
    with tempfile.TemporaryDirectory() as folder:
        outcome = run_case(data, Path(folder), frames=frames)
        file = str(Path(folder) / "case.toml")
        assert outcome.code in (0, 2), outcome.errors
        if outcome.code == 2:
            assert outcome.errors, "exit 2 without a message"
            assert all(line.startswith(f"error: {file}") for line in outcome.errors), outcome
            assert not unlocated(outcome, file), outcome.errors
            assert not outcome.wrote, "a refused level wrote files"
        else:
            assert outcome.status in ("passed", "failed", "diverged"), outcome


@PROFILE
@given(SEEDS)
def test_every_case_exits_0_with_a_status_or_2_with_a_located_message(seed):
    _check(case_text(seed)[1], frames=False)


@settings(PROFILE, max_examples=max(10, EXAMPLES // 20))
@given(SEEDS)
def test_valid_cases_draw_their_frames(seed):
    kind, data = case_text(seed)
    _check(data, frames=kind == "generated")
