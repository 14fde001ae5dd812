"""Tick-rate independence of long chains: ``python benchmarks/tick_rates.py [--quick]``.

Gains are in 1/s and speeds per second, so a level should behave the same at any tick rate
(docs/levels.md). This runs the motion-quality suite's long chains (``LONG_LINKS`` links or more)
with every solver at each of ``RATES`` ticks a second, and prints, for each target the level
expects reached, its time to reach at each rate as a share of the time at ``REFERENCE``: within
``TOLERANCE`` of it at every rate passes; a target missed at some rate fails. ``--quick`` keeps
the chains of up to ``QUICK_LINKS`` links (the chains of 150 to 200 links take most of a whole
run's minutes at 480 ticks a second).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Final

import _checkout  # noqa: F401  (first: this checkout's ikgame)
from quality import REACHABLE, SOLVER_NAMES, RunReport, load, run_job, stress_levels
from rich.console import Console
from rich.table import Table

RATES: Final = (120, 240, 480)
"""Ticks a simulated second each run is made at."""

REFERENCE: Final = 240
"""The rate the others are compared with: the stress levels' own."""

TOLERANCE: Final = 0.15
"""Largest share by which a time to reach may differ from the reference's."""

LONG_LINKS: Final = 20
"""Chains of this many links or more are measured."""

QUICK_LINKS: Final = 60
"""With ``--quick``, chains of more links than this are left out."""


@dataclass(frozen=True)
class TargetTimes:
    """One reachable target of one run, at every rate.

    Attributes:
        level: the stress level's file name.
        solver: the solver's name.
        step: the script step's index.
        seconds: time to reach at each of ``RATES`` (simulated s; None where it was not
            reached).
    """

    level: str
    solver: str
    step: int
    seconds: tuple[float | None, ...]

    @property
    def shares(self) -> tuple[float | None, ...]:
        """Each rate's time to reach over the reference's (None where either is missing)."""
        reference = self.seconds[RATES.index(REFERENCE)]
        return tuple(
            None if t is None or reference is None or reference == 0.0 else t / reference
            for t in self.seconds
        )

    @property
    def passed(self) -> bool:
        """Reached at every rate, each time within ``TOLERANCE`` of the reference's.

        >>> TargetTimes("23_chain20_low.toml", "ccd", 0, (0.52, 0.5, 0.48)).passed
        True
        >>> TargetTimes("23_chain20_low.toml", "ccd", 0, (0.3, 0.5, 0.48)).passed
        False
        >>> TargetTimes("23_chain20_low.toml", "ccd", 0, (None, 0.5, 0.5)).passed
        False
        """
        shares = self.shares
        return all(s is not None and abs(s - 1.0) <= TOLERANCE + 1e-9 for s in shares)


def long_levels(quick: bool) -> list[Path]:
    """The stress levels whose chain has ``LONG_LINKS`` links or more (with ``quick``, at most
    ``QUICK_LINKS``)."""
    most = QUICK_LINKS if quick else float("inf")
    return [
        path
        for path in stress_levels()
        if LONG_LINKS <= len(load(path).chain.expanded_links) <= most
    ]


def target_times(runs: dict[int, RunReport]) -> list[TargetTimes]:
    """The reachable targets of one level and solver, from its run at each of ``RATES``."""
    reference = runs[REFERENCE]
    times = []
    for i, step in enumerate(reference.steps):
        if step.expect != REACHABLE:
            continue
        seconds = tuple(runs[rate].steps[i].time_to_reach for rate in RATES)
        times.append(TargetTimes(reference.level, reference.solver, step.index, seconds))
    return times


def render(rows: list[TargetTimes], console: Console) -> None:
    """The table of every target's times, and the count of those that pass."""
    table = Table(title=f"Time to reach at {', '.join(map(str, RATES))} ticks/s")
    for name, justify in (("level", "left"), ("solver", "left"), ("step", "right")):
        table.add_column(name, justify=justify)
    for rate in RATES:
        table.add_column(f"{rate}/s", justify="right")
    table.add_column("shares", justify="right")
    table.add_column("", justify="left")
    for row in rows:
        seconds = ["-" if t is None else f"{t:.2f} s" for t in row.seconds]
        shares = " / ".join("-" if s is None else f"{s:.2f}" for s in row.shares)
        table.add_row(
            row.level.removesuffix(".toml"),
            row.solver,
            str(row.step),
            *seconds,
            shares,
            "pass" if row.passed else "FAIL",
        )
    console.print(table)
    passed = sum(row.passed for row in rows)
    console.print(
        f"{passed} of {len(rows)} targets reached at every rate within "
        f"{TOLERANCE:.0%} of the time at {REFERENCE} ticks/s"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--solvers", nargs="+", choices=SOLVER_NAMES, default=list(SOLVER_NAMES))
    parser.add_argument(
        "--quick", action="store_true", help=f"chains of at most {QUICK_LINKS} links"
    )
    parser.add_argument("--jobs", type=int, default=1, help="runs in parallel (processes)")
    parser.add_argument("--json", type=Path, metavar="OUT", help="write every time here")
    args = parser.parse_args(argv)
    jobs = [
        (str(path), solver, rate)
        for path in long_levels(args.quick)
        for solver in args.solvers
        for rate in RATES
    ]
    started = time.perf_counter()
    err = Console(stderr=True)
    runs: dict[tuple[str, str], dict[int, RunReport]] = {}
    with ProcessPoolExecutor(max(args.jobs, 1)) as pool:
        reports = pool.map(run_job, jobs)
        for i, ((path, solver, rate), report) in enumerate(zip(jobs, reports, strict=True), 1):
            runs.setdefault((path, solver), {})[rate] = report
            err.print(f"[{i}/{len(jobs)}] {Path(path).stem} {solver} at {rate}/s")
    rows = [row for by_rate in runs.values() for row in target_times(by_rate)]
    console = Console(width=150, highlight=False)
    render(rows, console)
    console.print(f"wall time: {time.perf_counter() - started:.0f} s for {len(jobs)} runs")
    if args.json is not None:
        data = [asdict(row) | {"passed": row.passed} for row in rows]
        args.json.write_text(json.dumps(data, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
