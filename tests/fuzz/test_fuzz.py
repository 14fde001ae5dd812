"""Fuzzing ``ikgame run`` with generated and broken level files.

Every case ends one of two ways: exit 2 with a message on every line that names the file (and
the line, unless the problem is the file as a whole) and nothing written; or exit 0 with a
results.json whose status is passed, failed or diverged (a diverged run naming the body and the
tick). Never exit 1, never a traceback. The same case run twice writes the same bytes. The cases
are chains and trees of bones, creatures with a gait among them (see fuzzgen).

The default profile is small and seeded (derandomized), so CI runs the same cases every time.
``IKGAME_FUZZ_EXAMPLES=10000`` runs a larger, random profile; ``benchmarks/fuzz.py`` counts the
outcomes of a large run instead of stopping at the first failure.
"""

from __future__ import annotations

import os
import random
import tempfile
from pathlib import Path

from fuzzgen import case_text, generated_level, level_toml, run_case, unlocated
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from ikgame.level.loader import LevelError, parse_level

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
            assert (outcome.status == "diverged") == bool(outcome.divergence), outcome


@PROFILE
@given(SEEDS)
def test_every_case_exits_0_with_a_status_or_2_with_a_located_message(seed):
    _check(case_text(seed)[1], frames=False)


@settings(PROFILE, max_examples=max(10, EXAMPLES // 20))
@given(SEEDS)
def test_valid_cases_draw_their_frames(seed):
    kind, data = case_text(seed)
    _check(data, frames=kind == "generated")


@settings(PROFILE, max_examples=max(8, EXAMPLES // 50))
@given(SEEDS)
def test_a_case_run_twice_writes_the_same_bytes(seed):
    kind, data = case_text(seed)
    with tempfile.TemporaryDirectory() as folder:
        outputs = []
        for name in ("first", "second"):
            outcome = run_case(data, Path(folder), frames=kind == "generated")
            out = (Path(folder) / "out").rename(Path(folder) / name) if outcome.wrote else None
            files = sorted(p for p in out.rglob("*") if p.is_file()) if out else []
            outputs.append(
                (outcome.code, outcome.errors, {p.relative_to(out): p.read_bytes() for p in files})
            )
    assert outputs[0] == outputs[1]


def test_generated_levels_are_chains_trees_and_creatures_that_mostly_load():
    kinds: dict[str, int] = {}
    for seed in range(300):
        text = level_toml(generated_level(random.Random(seed)))
        try:
            level = parse_level(text, "case.toml")
        except LevelError:
            continue
        chain, script = level.chain, level.script
        features = {
            "tree": chain.bones is not None,
            "several roots": sum(k.parent_index < 0 for k in chain.expanded_links) > 1,
            "inner effector": any(
                k.effector and any(c.parent_index == i for c in chain.expanded_links)
                for i, k in enumerate(chain.expanded_links)
            ),
            "repeated bone": chain.bones is not None and any(b.repeat > 1 for b in chain.bones),
            "reach table": any(isinstance(getattr(s, "reach", None), dict) for s in script),
            "several at once": any(
                isinstance(getattr(s, "reach", None), dict) and len(s.reach) > 1 for s in script
            ),
            "named effector": any(getattr(s, "effector", None) for s in script),
            "base turn": any(getattr(getattr(s, "set", None), "angle", None) for s in script),
            "gait": level.gait is not None,
            "gait groups": level.gait is not None and level.gait.groups is not None,
        }
        for name, present in features.items():
            kinds[name] = kinds.get(name, 0) + present
        kinds["valid"] = kinds.get("valid", 0) + 1
    assert kinds["valid"] >= 100, kinds
    assert min(kinds.values()) >= 5, sorted(kinds.items())
