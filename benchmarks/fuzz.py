"""Count what ``ikgame run`` does with many fuzzed level files: ``python benchmarks/fuzz.py -n 10000``.

The cases are those of ``tests/fuzz`` (a seed is a case), but instead of stopping at the first
failure this counts every outcome: exit codes per kind of case, run statuses, diverged runs with
the body and tick that blew up, error lines without a line number, and any exit other than 0
or 2. Add ``--frames`` to also draw tiny frames for every valid case.
"""

from __future__ import annotations

import argparse
import collections
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "fuzz"))

from fuzzgen import case_text, run_case, unlocated  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-n", type=int, default=1000, help="cases (default: 1000)")
    parser.add_argument("--seed", type=int, default=0, help="first seed (default: 0)")
    parser.add_argument("--frames", action="store_true", help="draw frames of valid cases")
    args = parser.parse_args()
    codes: collections.Counter[tuple[str, int]] = collections.Counter()
    statuses: collections.Counter[tuple[str, str]] = collections.Counter()
    diverged, no_line, wrong = [], [], []
    error_lines = 0
    start = time.perf_counter()
    for seed in range(args.seed, args.seed + args.n):
        kind, data = case_text(seed)
        with tempfile.TemporaryDirectory() as folder:
            outcome = run_case(data, Path(folder), frames=args.frames and kind == "generated")
            file = str(Path(folder) / "case.toml")
            codes[(kind, outcome.code)] += 1
            if outcome.status is not None:
                statuses[(kind, outcome.status)] += 1
            if outcome.status == "diverged":
                diverged.append((seed, outcome.divergence))
            if outcome.code == 2:
                error_lines += len(outcome.errors)
                no_line += [(seed, line.replace(file, "CASE")) for line in unlocated(outcome, file)]
            if outcome.code not in (0, 2) or (outcome.code == 2 and outcome.wrote):
                wrong.append((seed, outcome.code, outcome.errors[:3]))
    valid = sum(n for (kind, code), n in codes.items() if code == 0)
    print(f"{args.n} cases from seed {args.seed} in {time.perf_counter() - start:.0f} s")
    for (kind, code), n in sorted(codes.items()):
        print(f"  {kind:9} exit {code}: {n}")
    for (kind, status), n in sorted(statuses.items()):
        print(f"  {kind:9} {status}: {n}")
    rate = len(diverged) / valid if valid else 0.0
    print(f"diverged: {len(diverged)} of {valid} valid runs ({100 * rate:.2f}%)")
    for seed, where in diverged:
        print(f"  seed {seed}: {where}")
    print(f"error lines: {error_lines}, without a line number (and not file-level): {len(no_line)}")
    for seed, line in no_line[:20]:
        print(f"  seed {seed}: {line}")
    print(f"exits other than 0 or 2, or output written on exit 2: {len(wrong)}")
    for seed, code, errors in wrong[:20]:
        print(f"  seed {seed}: exit {code}: {errors}")


if __name__ == "__main__":
    main()
