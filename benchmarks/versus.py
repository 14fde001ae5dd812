"""The tick of this tree against another version's, side by side: ``python benchmarks/versus.py
OTHER_TREE`` (a checkout, e.g. ``git worktree add /tmp/old 415f3fc``).

Both trees run the benchmarks' 10-link chain (:func:`chains.chain_level`, built by each tree's own
level model) with a reach and a circle target, at the same time, one process on each core, so
that a shared machine's other jobs weigh on both alike. Each process warms up for ``--warm-up``
ticks, then times ``--ticks`` more in batches and prints their mean CPU time per tick: the mean
over many ticks, not the fastest batch, since a loop whose cost swings with the target's phase
(a solve taking more iterations or fewer) has its fastest batch far below its mean. Each round
prints both means and their ratio; ``--rounds`` repeats it. ``--callgrind`` counts instructions
instead (valgrind, one run per tree and target: slow, but the same count on every run).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LINKS = 10

# Runs in each tree's own interpreter process, with that tree first on the path: the chain is
# validated by that tree's level model. Prints one JSON line: the mean CPU us per tick.
_CHILD = """
import json, sys, time
sys.path[:0] = [sys.argv[1], sys.argv[2]]
from chains import chain_level
from ikgame.sim import Simulation
target, warm_up, ticks = sys.argv[3], int(sys.argv[4]), int(sys.argv[5])
batch = min(400, ticks)
sim = Simulation(chain_level(int(sys.argv[7]), target), record=False)
for _ in range(warm_up):
    sim.step()
if sys.argv[6] == "count":
    for _ in range(ticks):
        sim.step()
    sys.exit()
times = []
for _ in range(ticks // batch):
    start = time.process_time()
    for _ in range(batch):
        sim.step()
    times.append((time.process_time() - start) / batch)
print(json.dumps({"mean_us": sum(times) / len(times) * 1e6}))
"""


def _command(tree: Path, target: str, warm_up: int, ticks: int, mode: str) -> list[str]:
    # The chain comes from this tree's benchmarks; the code it runs from ``tree``.
    return [
        sys.executable,
        "-c",
        _CHILD,
        str(tree),
        str(ROOT / "benchmarks"),
        target,
        str(warm_up),
        str(ticks),
        mode,
        str(LINKS),
    ]


def _environment() -> dict[str, str]:
    env = dict(os.environ)
    # The same hashing in every process, so that callgrind repeats its count.
    env["PYTHONHASHSEED"] = "0"
    env.pop("PYTHONPATH", None)
    return env


def _side_by_side(trees: list[Path], target: str, warm_up: int, ticks: int) -> list[float]:
    """Both trees at once; each one's mean CPU us per tick."""
    env = _environment()
    procs = [
        subprocess.Popen(
            _command(tree, target, warm_up, ticks, "time"),
            stdout=subprocess.PIPE,
            text=True,
            env=env,
        )
        for tree in trees
    ]
    means = []
    for proc, tree in zip(procs, trees, strict=True):
        out, _ = proc.communicate()
        if proc.returncode != 0:
            raise SystemExit(f"the tick in {tree} failed (exit code {proc.returncode})")
        means.append(json.loads(out.strip().splitlines()[-1])["mean_us"])
    return means


def _instructions(tree: Path, target: str, warm_up: int, ticks: int) -> float:
    """Instructions per tick of ``ticks`` ticks after ``warm_up``: a run that ticks them less
    the same run that stops after the warm-up (start-up and warm-up cancel)."""
    counts = []
    with tempfile.TemporaryDirectory() as folder:
        for n in (ticks, 0):
            out = Path(folder) / f"callgrind.{n}"
            subprocess.run(
                [
                    "valgrind",
                    "--tool=callgrind",
                    f"--callgrind-out-file={out}",
                    *_command(tree, target, warm_up, n, "count"),
                ],
                check=True,
                capture_output=True,
                env=_environment(),
            )
            totals = [line for line in out.read_text().splitlines() if line.startswith("totals:")]
            counts.append(int(totals[0].split()[1]))
    return (counts[0] - counts[1]) / ticks


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.RawTextHelpFormatter
    )
    parser.add_argument("other", type=Path, help="the other version's source tree")
    parser.add_argument("--ticks", type=int, default=8000, help="ticks measured (default 8000)")
    parser.add_argument("--warm-up", type=int, default=300, help="ticks first (default 300)")
    parser.add_argument("--rounds", type=int, default=3, help="side-by-side rounds (default 3)")
    parser.add_argument(
        "--callgrind", action="store_true", help="count instructions instead (valgrind)"
    )
    args = parser.parse_args(argv)
    other = args.other.resolve()
    if not (other / "ikgame" / "__init__.py").is_file():
        print(f"error: {other} holds no ikgame package (ikgame/__init__.py)", file=sys.stderr)
        return 2
    if args.ticks < 1 or args.warm_up < 0 or args.rounds < 1:
        print(
            "error: --ticks and --rounds must be at least 1, --warm-up at least 0", file=sys.stderr
        )
        return 2
    if args.callgrind and shutil.which("valgrind") is None:
        print("error: --callgrind needs valgrind (apt install valgrind)", file=sys.stderr)
        return 2
    trees = [ROOT, other]
    print(f"{LINKS}-link tick: this tree ({ROOT}) against {other}")
    print(f"   {args.ticks} ticks after {args.warm_up} of warm-up")
    for target in ("reach", "circle"):
        if args.callgrind:
            here, there = (_instructions(t, target, args.warm_up, args.ticks) for t in trees)
            print(
                f"   {target:<7} {here:>12,.0f} instr  {there:>12,.0f} instr  {here / there:.2f}x"
            )
            continue
        ratios = []
        for _ in range(args.rounds):
            here, there = _side_by_side(trees, target, args.warm_up, args.ticks)
            ratios.append(here / there)
            print(f"   {target:<7} {here:>8.0f} us  {there:>8.0f} us  {here / there:.2f}x")
        print(f"   {target:<7} median ratio {statistics.median(ratios):.2f}x")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
