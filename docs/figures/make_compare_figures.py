"""Draw docs/figures/compare_<level>.png and print the tables of docs/solvers.md.

Each shipped level in ``LEVELS`` is run once per solver in the physics world with
:func:`ikgame.compare.compare_level`; the figure is :func:`ikgame.render.plot.render_comparison`.
The printed Markdown has, per level, the comparison table, the jerk near target switches and
away from them, each reach step's convergence (time to reach the tolerance, time from which the
error stays within ``FINE`` px), the hold analysis of every step some solver failed, and the
solvers alone without physics (the seed article's setting): the error after one iteration and
the iterations needed to arrive, from the level's start pose. Levels in ``VARIANTS`` are run
again with their settings changed, with a hold analysis of each variant some solver failed.

Run from the repository root::

    python docs/figures/make_compare_figures.py

Everything but the solver's wall-clock time per tick is deterministic; that one is the best of
``REPEATS`` runs, since other work on the machine only ever adds to it.
"""

from __future__ import annotations

import io
import math
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

from ikgame._files import write_atomic
from ikgame.compare import DEFAULT_SOLVERS, Comparison, SolverRun, compare_level, squared_jerk
from ikgame.kinematics import SOLVERS
from ikgame.level.library import LEVELS_DIR
from ikgame.level.loader import load_level
from ikgame.level.model import Level
from ikgame.physics.world import build_skeleton
from ikgame.render.plot import render_comparison

LEVELS = ("01_first_reach", "02_tentacle", "03_elbow_limits", "06_circle")
FIGURES = Path(__file__).resolve().parent
SWITCH = 0.05  # s after a target switch whose jerk the split table sets apart
FINE = 1.0  # px: "converged" in the physics world (the solvers' arrival distance is 0.5 px)
ARRIVAL = 0.5  # px, the levels' solver arrival distance, for the solver-only table
MAX_ITERATIONS = 1000  # solver-only table: iterations allowed to arrive
REPEATS = 3  # runs per level; the solver time kept is the smallest


def _no_gravity(data: dict) -> None:
    data["world"]["gravity"] = (0.0, 0.0)


def _torque_x10(data: dict) -> None:
    for link in data["chain"]["links"]:
        link["max_torque"] *= 10


# Levels run again with one thing changed, to show how the control loop copes beyond the level as
# shipped: the Tentacle without gravity, and with ten times the torque (a stiffer, faster arm).
# Each change edits the level's data (file units).
VARIANTS = {
    "02_tentacle": {
        "gravity off": [_no_gravity],
        "torque x10": [_torque_x10],
    },
}


def main() -> int:
    """Write the figures and print the Markdown tables; returns the exit code."""
    for stem in LEVELS:
        level = load_level(LEVELS_DIR / f"{stem}.toml")
        comparison = best_of(level, REPEATS)
        buffer = io.BytesIO()
        render_comparison(comparison.plot_data()).save(buffer, format="PNG", optimize=True)
        path = write_atomic(FIGURES / f"compare_{stem}.png", buffer.getvalue())
        print(f"\n## {comparison.level} ({stem}.toml) -> {path.name}, {path.stat().st_size} B\n")
        print(summary_table(comparison))
        print()
        print(jerk_split_table(comparison))
        if _reach_steps(comparison.runs[0]):
            print()
            print(convergence_table(comparison))
            failures = hold_analysis(comparison)
            if failures:
                print()
                print(failures)
            print()
            print(solver_only_table(level))
        if stem in VARIANTS:
            variants = {
                label: compare_level(changed(level, changes))
                for label, changes in VARIANTS[stem].items()
            }
            print()
            print(variant_table(variants))
            for label, variant in variants.items():
                failures = hold_analysis(variant)
                if failures:
                    print(f"\n{label}:\n\n{failures}")
    return 0


def best_of(level: Level, repeats: int) -> Comparison:
    """The comparison with each solver's smallest wall-clock time per tick over ``repeats`` runs
    (the rest of a comparison is the same in every run)."""
    comparisons = [compare_level(level) for _ in range(repeats)]
    runs = []
    for i, run in enumerate(comparisons[0].runs):
        fastest = min(c.runs[i].solver_us_per_tick or math.inf for c in comparisons)
        runs.append(replace(run, solver_us_per_tick=fastest if math.isfinite(fastest) else None))
    return replace(comparisons[0], runs=tuple(runs))


def _md(header: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return "\n".join(lines)


def _f(value: float | None, spec: str, missing: str = "-") -> str:
    return missing if value is None or not math.isfinite(value) else format(value, spec)


def _reach_steps(run: SolverRun) -> list:
    return [s for s in run.steps if s.kind == "reach"]


def _follow_steps(run: SolverRun) -> list:
    return [s for s in run.steps if s.kind == "follow"]


def summary_table(comparison: Comparison) -> str:
    """The ``ikgame compare`` table as Markdown, with each follow step's mean and peak error,
    iterations per tick and torque saturation."""
    first = comparison.runs[0]
    reaches = len(_reach_steps(first))
    follows = len(_follow_steps(first))
    header = ["solver", "status", *[f"reach {i + 1} (s)" for i in range(reaches)]]
    header += ["final error, mean (px)"] if reaches else []
    header += [f"follow {i + 1}: mean, peak error (px)" for i in range(follows)]
    header += ["path (px)", "jerk (rad²/s⁶)", "solver (µs/tick)"]
    header += ["iterations/tick", "torque-limited", "sim time (s)"]
    rows = []
    for run in comparison.runs:
        steps = _reach_steps(run)
        finals = [s.final_error for s in steps if s.final_error is not None]
        row = [run.solver, run.status, *[_f(s.time_to_reach, ".2f", "failed") for s in steps]]
        row += [_f(float(np.mean(finals)) if finals else None, ".2f")] if reaches else []
        row += [f"{_f(s.mean_error, '.1f')}, {_f(s.max_error, '.1f')}" for s in _follow_steps(run)]
        row += [
            f"{run.path_length:.0f}",
            f"{run.mean_squared_jerk:.3g}",
            _f(run.solver_us_per_tick, ".0f"),
            f"{run.iterations_per_tick:.1f}",
            f"{run.torque_limited:.1%}",
            f"{run.sim_time:.2f}",
        ]
        rows.append(row)
    return _md(header, rows)


def _settled(run: SolverRun, start: float, end: float, limit: float) -> float | None:
    """Time from ``start`` after which the error stays within ``limit`` to ``end`` (None: never)."""
    window = (run.times > start) & (run.times <= end + 1e-9)
    times, outside = run.times[window], ~(run.errors[window] <= limit)
    if not times.size or outside[-1]:
        return None
    last_out = np.flatnonzero(outside)
    return float(times[last_out[-1] + 1] - start) if last_out.size else float(times[0] - start)


def convergence_table(comparison: Comparison) -> str:
    """Per reach step and solver: time to reach (tolerance held), time settled within FINE."""
    header = ["solver"]
    for i, _ in enumerate(_reach_steps(comparison.runs[0])):
        header += [f"{i + 1}: reach (s)", f"{i + 1}: settled ≤ {FINE:g} px (s)"]
    rows = []
    for run in comparison.runs:
        row = [run.solver]
        for step in _reach_steps(run):
            fine = _settled(run, step.started, step.ended or run.sim_time, FINE)
            row += [_f(step.time_to_reach, ".2f", "failed"), _f(fine, ".2f", "never")]
        rows.append(row)
    return _md(header, rows)


def jerk_split_table(comparison: Comparison) -> str:
    """Mean squared jerk split into the first SWITCH s of each step (the motors' answer to a new
    target, mostly the speed clamp's step in commanded rate) and the rest of the run."""
    header = [
        "solver",
        "jerk, all (rad²/s⁶)",
        f"share in the {SWITCH * 1000:.0f} ms after a switch",
    ]
    header += ["ticks there", "jerk elsewhere (rad²/s⁶)"]
    rows = []
    dt = 1.0 / comparison.tick_rate
    for run in comparison.runs:
        jerk = squared_jerk(run.angles, dt)
        # Sample i spans poses i..i+3, that is t in [i dt, (i + 3) dt].
        begins = np.arange(len(jerk)) * dt
        near = np.zeros(len(jerk), dtype=bool)
        for start in {0.0, *(s.started for s in run.steps)}:
            near |= (begins + 3 * dt >= start - 1e-9) & (begins <= start + SWITCH + 1e-9)
        rows.append(
            [
                run.solver,
                f"{jerk.mean():.3g}",
                f"{jerk[near].sum() / jerk.sum():.0%}",
                f"{near.mean():.0%}",
                f"{jerk[~near].mean():.3g}",
            ]
        )
    return _md(header, rows)


def hold_analysis(comparison: Comparison) -> str:
    """Each reach step some solver failed, for every solver: how the error behaved after it first
    got within tolerance (a step passes after a stay of ``hold`` s within it)."""
    tolerance = comparison.tolerance or 0.0
    failed = {s.index for run in comparison.runs for s in _reach_steps(run) if not s.passed}
    header = ["solver", "step", "passed", "first within tolerance (s)", "share within after that"]
    header += ["exits", "longest stay within (s)", "peak error after that (px)"]
    header += ["final error (px)"]
    rows = []
    for run in comparison.runs:
        for step in _reach_steps(run):
            if step.index not in failed:
                continue
            window = (run.times > step.started) & (run.times <= (step.ended or run.sim_time))
            times, errors = run.times[window], run.errors[window]
            inside = errors <= tolerance
            if not inside.any():
                rows.append([run.solver, str(step.index + 1), "no", "never", "-", "-", "-", "-"])
                rows[-1].append(_f(step.final_error, ".1f"))
                continue
            first = int(np.argmax(inside))
            longest = current = 0
            for value in inside[first:]:
                current = current + 1 if value else 0
                longest = max(longest, current)
            rows.append(
                [
                    run.solver,
                    str(step.index + 1),
                    "yes" if step.passed else "no",
                    f"{times[first] - step.started:.2f}",
                    f"{inside[first:].mean():.0%}",
                    str(int(np.count_nonzero(inside[first:-1] & ~inside[first + 1 :]))),
                    f"{longest / comparison.tick_rate:.2f}",
                    f"{errors[first:].max():.1f}",
                    _f(step.final_error, ".1f"),
                ]
            )
    return _md(header, rows) if rows else ""


def solver_only_table(level) -> str:
    """The solvers alone, without physics, from the level's start pose through its reach targets.

    Each solver warm-starts each target from its own previous answer, as the seed's animation does.
    """
    skeleton = build_skeleton(level)
    targets = [np.array(step.reach, dtype=float) for step in level.script if hasattr(step, "reach")]
    header = ["solver"]
    for i, _ in enumerate(targets):
        header += [f"{i + 1}: error after 1 iteration (px)", f"{i + 1}: iterations to arrive"]
    rows = []
    for name in DEFAULT_SOLVERS:
        solve = SOLVERS[name]
        angles = skeleton.clamp(np.zeros(skeleton.count))
        row = [name]
        for target in targets:
            first = solve(skeleton, angles, target, max_iterations=1, tolerance=ARRIVAL)
            full = solve(skeleton, angles, target, max_iterations=MAX_ITERATIONS, tolerance=ARRIVAL)
            arrived = full.error <= ARRIVAL
            row += [
                f"{first.error:.1f}",
                f"{full.iterations}" if arrived else f"{full.status.value} at {full.error:.1f} px",
            ]
            angles = full.angles
        rows.append(row)
    return _md(header, rows)


def changed(level: Level, changes: list) -> Level:
    """``level`` with each of ``changes`` applied, in order, to its data."""
    data = level.model_dump(by_alias=True, exclude_unset=True)
    for change in changes:
        change(data)
    return Level.model_validate(data)


def variant_table(variants: dict[str, Comparison]) -> str:
    """Status and reach times of every solver on each variant of a level."""
    header = ["variant", *DEFAULT_SOLVERS]
    rows = []
    for label, comparison in variants.items():
        cells = []
        for run in comparison.runs:
            times = ", ".join(_f(s.time_to_reach, ".2f", "x") for s in _reach_steps(run))
            cells.append(f"{run.status} ({times})")
        rows.append([label, *cells])
    return _md(header, rows)


if __name__ == "__main__":
    sys.exit(main())
