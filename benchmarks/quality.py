"""Motion-quality suite: ``python benchmarks/quality.py [--quick] [--levels ...] [--solvers ...]``.

Runs every stress level (``benchmarks/stress_levels/``) with each IK solver in the physics world
and prints one table of level x solver: targets reached, time to reach, overshoot, rest jitter,
joint-limit excursion, spins, torque-saturated frames and the solver states the steps ended in,
each cell marked against the thresholds below; a creature's footing too. A tree's reach step
is measured on all of its effectors: the worst of them counts. docs/quality.md defines every
measure.

Only the public simulation API is used: ``ikgame.Simulation(level, solver=..., record=False)``,
``step()``, ``done``, ``diverged``, ``joint_positions()``, ``joint_angles()``, ``last_tick``
(``solver_status``, ``torque_limited``), ``targets``, ``effector_names``, ``world``
(``effector_positions()``, ``skeleton``), ``script.step_index``, ``script.steps`` and
``result``; the kinematic optimum of a conflict comes from ``ikgame.kinematics.RobustSolver``.
The output is the same on every run apart from the wall times.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Final

import _checkout  # noqa: F401  (first: this checkout's ikgame)
import numpy as np
from _quality_metrics import (
    ChainSpec,
    approach_overshoot,
    limit_excursion_deg,
    rest_jitter,
    spin_joints,
    stretched_toward,
)
from pydantic import ValidationError
from rich.console import Console
from rich.table import Table

import ikgame
from ikgame.kinematics import RobustSolver, Skeleton, TargetSet
from ikgame.level.model import CircleObstacle, Level, ReachStep, SegmentObstacle

STRESS_DIR: Final = Path(__file__).resolve().parent / "stress_levels"
SOLVER_NAMES: Final = ("ccd", "jacobian_transpose", "dls", "fabrik")

# What a reach step should end as, when not "reached"; the level format has no field for it.
REACHABLE: Final = "reachable"
OUT_OF_REACH: Final = "out_of_reach"
"""Farther than the chain is long: fail with ``failure``, at rest, stretched toward it."""
TORQUE_BOUND: Final = "torque_bound"
"""Within length, beyond the torque budget: come to rest where the torque runs out."""
JAMMED: Final = "jammed"
"""Within length, but an obstacle is in the way: come to rest and report ``blocked``."""
CONFLICT: Final = "conflict"
"""Targets of one tree that no pose meets together: come to rest at the weighted least-squares
optimum (each effector's error within ``CONFLICT_PX`` of the kinematic optimum's)."""

CONFLICT_STEP: Final = 6
"""The step of ``17_two_arms`` that pulls the hands apart."""

EXPECTATIONS: Final[dict[str, dict[int, str]]] = {
    "09_just_out_of_reach.toml": {1: OUT_OF_REACH, 3: OUT_OF_REACH},
    "13_heavy_weak.toml": {0: TORQUE_BOUND},
    "16_jammed.toml": {1: JAMMED},
    "17_two_arms.toml": {CONFLICT_STEP: CONFLICT},
    "21_three_weak_links.toml": {0: TORQUE_BOUND},
    "29_five_weak_links.toml": {0: TORQUE_BOUND},
    "34_chain40_pressed_to_floor.toml": {0: JAMMED, 1: JAMMED, 2: JAMMED},
    "43_five_weak_links_reaching_left.toml": {0: TORQUE_BOUND},
    "46_heavy_weak_second_branch.toml": {0: TORQUE_BOUND},
    "57_heavy_weak_four.toml": {1: TORQUE_BOUND},
}
"""Stress level file -> {step index as the run counts them: the kind of an unreachable step}.
Every other reach step is reachable (tests/test_stress_levels.py proves it with a pose)."""

QUICK: Final = (
    "01_one_link.toml",
    "02_chain30_gravity.toml",
    "06_one_sided_limits.toml",
    "08_full_reach.toml",
    "09_just_out_of_reach.toml",
    "13_heavy_weak.toml",
)
"""The levels of ``--quick``: one of each failure the suite was built to show."""

OVERSHOOT_PCT: Final = 5.0
"""Largest overshoot that passes, % of the approach distance."""
JITTER_PX: Final = 0.5
"""Largest rest jitter that passes, px."""
SATURATED_JITTER_PX: Final = 1.0
"""Largest rest jitter of an arm held by its torque limit (torque-bound or jammed), px."""
LIMIT_DEG: Final = 2.0
"""Largest joint-limit excursion that passes, degrees."""
REST_WINDOW_S: Final = 0.5
"""The rest jitter is measured over this last part of a step, s."""
ON_TARGET_S: Final = 0.1
"""A reach step whose effectors stay within its tolerance over this last part ended on its
target, s."""
SPIN_DEG: Final = 180.0
"""A joint turning through more than this within a hold spins, degrees."""
CONFLICT_PX: Final = 1.0
"""Largest difference between an effector's error at rest and at the kinematic optimum, px."""
SLIP_PX: Final = 2.0
"""Largest distance a planted foot may slide, px."""
SINK_PX: Final = 2.0
"""Largest depth a foot may sink into the ground, px."""

_STATE_LETTERS: Final = {"success": "s", "processing": "p", "failure": "f", "blocked": "b"}
_EPS: Final = 1e-9


@dataclass
class StepReport:
    """How one scored step of a run went, measured from its ticks (a measure that does not
    apply to the step keeps its default)."""

    index: int
    kind: str
    expect: str
    passed: bool
    time_to_reach: float | None
    final_state: str
    overshoot_pct: float | None = None
    jitter_px: float | None = None
    jitter_limit_px: float | None = None
    spins: int = 0
    expectation_met: bool | None = None
    optimum_gap_px: float | None = None
    """For a conflict: the largest difference between an effector's error at rest and its
    error at the kinematic optimum, px."""
    on_target: bool = False
    """A reach step whose effectors stayed within its tolerance over its last ``ON_TARGET_S``:
    unpassed, a chain on its target whose hold the timeout cut short (late, not misreported),
    not one swinging through it."""


@dataclass
class RunReport:
    """One stress level run with one solver: the measures, and whether each passes."""

    level: str
    solver: str
    status: str
    reached: int
    reachable: int
    mean_time_to_reach: float | None
    overshoot_pct: float | None
    jitter_px: float | None
    limit_excursion_deg: float
    spins: int
    saturated_share: float
    states: dict[str, int]
    special_met: int
    special_total: int
    false_success: int
    checks: dict[str, bool]
    wall_s: float
    steps: list[StepReport] = field(default_factory=list)
    footing: dict[str, dict[str, float | int]] = field(default_factory=dict)
    """A creature's footing from ``results.json``: per leg steps, landing, slip, sink (px)."""

    @property
    def slip_px(self) -> float | None:
        """The farthest a planted foot slid, px (None without a gait)."""
        return max((leg["slip"] for leg in self.footing.values()), default=None)

    @property
    def sink_px(self) -> float | None:
        """The deepest a foot sank into the ground, px (None without a gait)."""
        return max((leg["sink"] for leg in self.footing.values()), default=None)

    @property
    def passed(self) -> bool:
        """True when every check passes."""
        return all(self.checks.values())


@dataclass
class _Trace:
    """Per-tick records of a run: the step each tick belonged to and what it ended in."""

    step: list[int] = field(default_factory=list)
    time: list[float] = field(default_factory=list)
    effectors: list[np.ndarray] = field(default_factory=list)
    targets: list[dict[str, np.ndarray]] = field(default_factory=list)
    skeleton: list[Skeleton] = field(default_factory=list)
    base: list[np.ndarray] = field(default_factory=list)
    angles: list[np.ndarray] = field(default_factory=list)
    saturated: list[bool] = field(default_factory=list)
    state: list[str] = field(default_factory=list)


def chain_spec(level: Level) -> ChainSpec:
    """The level's chain or tree and obstacles for the kinematic checks (radians, px)."""
    links = level.chain.expanded_links
    tree = level.chain.bones is not None
    limits = [link.limits_rad or (-math.inf, math.inf) for link in links]
    segments = [(*o.a, *o.b, o.radius) for o in level.obstacles if isinstance(o, SegmentObstacle)]
    circles = [(*o.center, o.radius) for o in level.obstacles if isinstance(o, CircleObstacle)]
    return ChainSpec(
        lengths=np.array([link.length for link in links]),
        masses=np.array([link.mass for link in links]),
        widths=np.array([link.width for link in links]),
        max_torque=np.array([link.max_torque for link in links]),
        lower=np.array([lo for lo, _ in limits]),
        upper=np.array([hi for _, hi in limits]),
        base=np.array(level.chain.base, dtype=float),
        base_angle=math.radians(level.chain.angle),
        gravity=np.array(level.world.gravity, dtype=float),
        segments=np.array(segments, dtype=float).reshape(-1, 5),
        circles=np.array(circles, dtype=float).reshape(-1, 3),
        parents=np.array([link.parent_index for link in links]) if tree else None,
        offsets=np.array([link.at for link in links], dtype=float) if tree else None,
    )


def step_targets(level: Level, step: ReachStep) -> dict[str, tuple[float, float]]:
    """The points a reach step aims at, by effector name (a bare point aims the only effector
    the script moves: a chain's ``tip``)."""
    if isinstance(step.reach, dict):
        return dict(step.reach)
    return {level.script_effectors[0]: step.reach}


def stress_levels() -> list[Path]:
    """Every stress level file, in name order."""
    return sorted(STRESS_DIR.glob("*.toml"))


def load(path: Path, tick_rate: int | None = None) -> Level:
    """A stress level, at another tick rate if asked (validated again)."""
    level = ikgame.load_level(path)
    if tick_rate is None:
        return level
    data = level.model_dump(by_alias=True, exclude_none=True, exclude_unset=True)
    data.setdefault("world", {})["tick_rate"] = tick_rate
    return Level.model_validate(data)


def _record(sim: ikgame.Simulation) -> _Trace:
    trace = _Trace()
    while not sim.done:
        step = sim.script.step_index
        info = sim.step()
        if sim.diverged:
            break
        trace.step.append(step)
        trace.time.append(info.time)
        trace.effectors.append(sim.world.effector_positions())
        trace.targets.append(sim.targets)
        trace.skeleton.append(sim.world.skeleton)
        trace.base.append(sim.joint_positions()[0])
        trace.angles.append(sim.joint_angles())
        trace.saturated.append(bool(np.any(info.torque_limited)))
        trace.state.append(info.solver_status)
    return trace


def run_one(path: Path, solver: str, tick_rate: int | None = None) -> RunReport:
    """Run one stress level with one solver and measure it."""
    level = load(path, tick_rate)
    spec = chain_spec(level)
    sim = ikgame.Simulation(level, solver=solver, record=False)
    names = list(sim.effector_names)
    start = sim.world.effector_positions()
    wall = time.perf_counter()
    trace = _record(sim)
    wall = time.perf_counter() - wall
    result = sim.result
    steps = [step for _, step in sim.script.steps]
    expectations = EXPECTATIONS.get(path.name, {})

    step_of = np.array(trace.step, dtype=int)
    times = np.array(trace.time)
    effectors = np.array(trace.effectors).reshape(len(trace.effectors), len(names), 2)
    angles = np.array(trace.angles).reshape(len(trace.angles), -1)
    reports: list[StepReport] = []
    for outcome in result.steps:
        if outcome.kind == "set":
            continue
        ticks = np.flatnonzero(step_of == outcome.index)
        expect = expectations.get(outcome.index, REACHABLE if outcome.kind == "reach" else "")
        final_state = trace.state[ticks[-1]] if ticks.size else ""
        report = StepReport(
            index=outcome.index,
            kind=outcome.kind,
            expect=expect,
            passed=outcome.passed,
            time_to_reach=outcome.time_to_reach,
            final_state=final_state,
        )
        reports.append(report)
        if ticks.size == 0 or outcome.kind == "follow":
            continue
        step = steps[outcome.index]
        aims = step_targets(level, step) if isinstance(step, ReachStep) else {}
        # A reach step is measured on its effectors; a wait on every effector aimed at its end.
        moved = [names.index(name) for name in aims] or [
            j for j, name in enumerate(names) if name in trace.targets[ticks[-1]]
        ]
        moved = moved or list(range(len(names)))
        end = times[ticks[-1]]
        rest = ticks[times[ticks] >= end - REST_WINDOW_S - _EPS]
        report.jitter_px = max(rest_jitter(effectors[rest, j]) for j in moved)
        report.jitter_limit_px = (
            SATURATED_JITTER_PX if expect in (TORQUE_BOUND, JAMMED) else JITTER_PX
        )
        if outcome.kind == "wait":
            report.spins = spin_joints(angles[ticks], SPIN_DEG)
            continue
        if not isinstance(step, ReachStep):
            continue
        settled = ticks[times[ticks] >= end - ON_TARGET_S - _EPS]
        report.on_target = all(
            float(np.hypot(*(effectors[settled, j] - aims[names[j]]).T).max()) <= step.tolerance
            for j in moved
        )
        before = effectors[ticks[0] - 1] if ticks[0] > 0 else start
        if outcome.time_to_reach is not None:
            held_from = outcome.started + outcome.time_to_reach
        else:
            held_from = (outcome.started + end) / 2.0
        report.spins = spin_joints(angles[ticks[times[ticks] >= held_from - _EPS]], SPIN_DEG)
        last = effectors[ticks[-1]]
        if expect == REACHABLE:
            overshoots = [
                approach_overshoot(
                    effectors[ticks, j], before[j], np.array(aims[names[j]]), step.tolerance
                )
                for j in moved
            ]
            measured = [o for o in overshoots if o is not None]
            report.overshoot_pct = max(measured) if measured else None
        elif expect == OUT_OF_REACH:
            base = trace.base[ticks[-1]]
            report.expectation_met = (
                not outcome.reached
                and final_state == "failure"
                and stretched_toward(
                    base, last[0], np.array(step.reach), spec.reach, step.tolerance
                )
            )
        elif expect == JAMMED:
            report.expectation_met = final_state == "blocked"
        elif expect == TORQUE_BOUND:
            report.expectation_met = report.jitter_px < SATURATED_JITTER_PX
        elif expect == CONFLICT:
            goal = _target_set(level, names, trace.targets[ticks[-1]])
            at_rest = np.hypot(*(last[goal.links_order] - goal.targets.points).T)
            optimum = kinematic_optimum(trace.skeleton[ticks[-1]], angles[ticks[-1]], goal.targets)
            report.optimum_gap_px = float(np.abs(at_rest - optimum).max())
            report.expectation_met = (
                not outcome.reached
                and report.jitter_px <= JITTER_PX
                and report.optimum_gap_px <= CONFLICT_PX
            )
    return _summarise(path, solver, result, reports, trace, angles, spec, wall)


@dataclass(frozen=True)
class _Aimed:
    """The targets of a tree at one tick, and where its effectors are among them."""

    targets: TargetSet
    links_order: np.ndarray
    """Each target's effector, as an index into the level's effectors."""


def _target_set(level: Level, names: list[str], targets: dict[str, np.ndarray]) -> _Aimed:
    """Every aimed effector's target, weighted as the level weights it, in effector order."""
    chain = level.chain
    order = np.array([j for j, name in enumerate(names) if name in targets])
    links = np.array(chain.effector_links)[order]
    return _Aimed(
        TargetSet(
            links,
            [targets[names[j]] for j in order],
            [chain.expanded_links[link].weight for link in links],
        ),
        order,
    )


def kinematic_optimum(
    skeleton: Skeleton, angles: np.ndarray, targets: TargetSet, rounds: int = 20
) -> np.ndarray:
    """(k,) each target's error, px, at the weighted least-squares optimum nearest ``angles``:
    the multi-target damped least squares (with restarts), solved again from its own answer."""
    robust = RobustSolver(skeleton, "dls")
    for _ in range(rounds):
        angles = robust.solve_targets(angles, targets, max_iterations=50, tolerance=0.5).angles
    errors = robust.solve_targets(angles, targets, max_iterations=50, tolerance=0.5).errors
    return np.asarray(errors, dtype=float)


def false_successes(reports: list[StepReport]) -> int:
    """Reach steps that ended unpassed and off their target while the solver said ``success``:
    a chain stopped short (or still on its way) that its solver reports as arrived. One at rest
    on its target when the timeout cut its hold short is late, and the reached check says so.
    """
    return sum(
        1
        for r in reports
        if r.kind == "reach" and not r.passed and not r.on_target and r.final_state == "success"
    )


def _summarise(
    path: Path,
    solver: str,
    result: ikgame.RunResult,
    reports: list[StepReport],
    trace: _Trace,
    angles: np.ndarray,
    spec: ChainSpec,
    wall: float,
) -> RunReport:
    status = result.status
    scored = [r for r in reports if r.expect == REACHABLE or r.kind == "follow"]
    reached = sum(r.passed for r in scored)
    times = [r.time_to_reach for r in reports if r.expect == REACHABLE and r.passed]
    overshoots = [r.overshoot_pct for r in reports if r.overshoot_pct is not None]
    rested = [r for r in reports if r.jitter_px is not None]
    special = [r for r in reports if r.expectation_met is not None]
    false_success = false_successes(reports)
    excursion = limit_excursion_deg(angles, spec.lower, spec.upper)
    spins = sum(r.spins for r in reports)
    overshoot = max(overshoots) if overshoots else None
    checks = {
        "reached": reached == len(scored) and status != "diverged",
        "overshoot": overshoot is None or overshoot <= OVERSHOOT_PCT,
        "jitter": all(r.jitter_px <= r.jitter_limit_px for r in rested),
        "limits": excursion <= LIMIT_DEG,
        "spins": spins == 0,
        "expect": all(r.expectation_met for r in special),
        "states": false_success == 0,
    }
    footing = result.footing
    if footing:
        checks["footing"] = all(
            leg["steps"] > 0 and leg["slip"] <= SLIP_PX and leg["sink"] <= SINK_PX
            for leg in footing.values()
        )
    return RunReport(
        level=path.name,
        solver=solver,
        status=status,
        reached=reached,
        reachable=len(scored),
        mean_time_to_reach=float(np.mean(times)) if times else None,
        overshoot_pct=overshoot,
        jitter_px=max(r.jitter_px for r in rested) if rested else None,
        limit_excursion_deg=excursion,
        spins=spins,
        saturated_share=float(np.mean(trace.saturated)) if trace.saturated else 0.0,
        states=dict(sorted(Counter(r.final_state for r in reports).items())),
        special_met=sum(bool(r.expectation_met) for r in special),
        special_total=len(special),
        false_success=false_success,
        checks=checks,
        wall_s=wall,
        steps=reports,
        footing=footing,
    )


_COLUMNS: Final = (
    ("level", "left"),
    ("solver", "left"),
    ("reached", "right"),
    ("t reach s", "right"),
    ("overshoot %", "right"),
    ("jitter px", "right"),
    ("limit deg", "right"),
    ("spins", "right"),
    ("sat %", "right"),
    ("states", "left"),
    ("fail/jam", "right"),
    ("run", "left"),
)
_FOOTING_COLUMN: Final = ("slip/sink px", "right")
"""Shown before ``run`` when a creature is in the table."""


def _columns(reports: list[RunReport]) -> tuple[tuple[str, str], ...]:
    if not any(r.footing for r in reports):
        return _COLUMNS
    return (*_COLUMNS[:-1], _FOOTING_COLUMN, _COLUMNS[-1])


def _number(value: float | None, fmt: str) -> str:
    return "-" if value is None else format(value, fmt)


def _states(states: dict[str, int]) -> str:
    return " ".join(f"{n}{_STATE_LETTERS.get(name, name)}" for name, n in states.items())


def table_rows(reports: list[RunReport]) -> list[list[tuple[str, bool | None]]]:
    """Each run as the cells of the table: (text, passes its threshold or None if not judged)."""
    rows = []
    previous = None
    creatures = any(r.footing for r in reports)
    for r in reports:
        c = r.checks
        special = (f"{r.special_met}/{r.special_total}", c["expect"]) if r.special_total else None
        row = [
            ("" if r.level == previous else Path(r.level).stem, None),
            (r.solver, None),
            (f"{r.reached}/{r.reachable}", c["reached"]),
            (_number(r.mean_time_to_reach, ".2f"), None),
            (_number(r.overshoot_pct, ".1f"), c["overshoot"]),
            (_number(r.jitter_px, ".2f"), c["jitter"]),
            (f"{r.limit_excursion_deg:.1f}", c["limits"]),
            (str(r.spins), c["spins"]),
            (f"{100.0 * r.saturated_share:.0f}", None),
            (_states(r.states), c["states"]),
            special or ("-", None),
        ]
        if creatures:
            row.append(
                (f"{r.slip_px:.2f}/{r.sink_px:.2f}", c["footing"]) if r.footing else ("-", None)
            )
        row.append(("pass" if r.passed else "FAIL", r.passed))
        rows.append(row)
        previous = r.level
    return rows


def summary(reports: list[RunReport]) -> str:
    """The pass counts of a set of runs."""
    runs = sum(r.passed for r in reports)
    checks = sum(sum(r.checks.values()) for r in reports)
    total = sum(len(r.checks) for r in reports)
    reached = sum(r.reached for r in reports)
    return (
        f"runs passing: {runs}/{len(reports)}   checks passing: {checks}/{total}   "
        f"targets reached: {reached}/{sum(r.reachable for r in reports)}"
    )


def legend(reports: list[RunReport]) -> str:
    """What the letters, the fail/jam column and the marks mean (and the footing, with a
    creature in the table)."""
    conflicts = any(s.expect == CONFLICT for r in reports for s in r.steps)
    special = (
        "unreachable, jammed or conflicting steps" if conflicts else "unreachable or jammed steps"
    )
    text = (
        "states: the solver state each step ended in (s success, p processing, f failure, "
        f"b blocked); fail/jam: {special} that ended as they should; x: fails "
        f"its threshold (overshoot <= {OVERSHOOT_PCT:g}%, jitter <= {JITTER_PX:g} px, "
        f"< {SATURATED_JITTER_PX:g} px torque-bound or jammed, limit <= {LIMIT_DEG:g} deg, "
        "no spin, no step ending off its target in success"
    )
    if conflicts:
        text += f", conflict at rest within {CONFLICT_PX:g} px of the optimum's errors"
    if any(r.footing for r in reports):
        text += (
            f", every foot steps and slips <= {SLIP_PX:g} px and sinks <= {SINK_PX:g} px; "
            "slip/sink: the farthest a planted foot slid and the deepest a foot sank"
        )
    return text + ")"


def render(reports: list[RunReport], console: Console, *, tick_rate: int | None) -> None:
    """Print the table of stress level x solver, with each run's wall time, and the counts."""
    rate = "the levels' own tick rate" if tick_rate is None else f"{tick_rate} ticks/s"
    table = Table(title=f"Motion quality in the physics world ({rate})", title_justify="left")
    for name, justify in (*_columns(reports), ("wall s", "right")):
        table.add_column(name, justify=justify, no_wrap=True)
    for report, row in zip(reports, table_rows(reports), strict=True):
        cells = [
            text if ok is None else f"[green]{text}[/]" if ok else f"[red]{text} x[/]"
            for text, ok in row
        ]
        table.add_row(*cells, f"{report.wall_s:.1f}")
    console.print(table)
    console.print(summary(reports))
    console.print(legend(reports))


def markdown(reports: list[RunReport]) -> str:
    """The table as Markdown, without wall times, so it is the same on every run."""
    align = {"left": ":---", "right": "---:"}
    columns = _columns(reports)
    lines = [
        "| " + " | ".join(name for name, _ in columns) + " |",
        "|" + "|".join(align[justify] for _, justify in columns) + "|",
    ]
    for row in table_rows(reports):
        cells = [text if ok is not False else f"{text} x" for text, ok in row]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n\n" + summary(reports) + "\n\n" + legend(reports) + "\n"


def run_job(args: tuple[str, str, int | None]) -> RunReport:
    """:func:`run_one` of a (level path, solver, tick rate) job, as a process pool maps it."""
    path, solver, tick_rate = args
    return run_one(Path(path), solver, tick_rate)


def _pick_levels(names: list[str] | None, quick: bool) -> tuple[list[Path], list[str]]:
    """The stress levels asked for (each name a part of a file name), and names matching none."""
    paths = stress_levels()
    if quick:
        paths = [p for p in paths if p.name in QUICK]
    if not names:
        return paths, []
    missing = [n for n in names if not any(n in p.name for p in paths)]
    return [p for p in paths if any(n in p.name for n in names)], missing


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--levels", nargs="+", metavar="NAME", help="stress levels (name parts)")
    parser.add_argument("--solvers", nargs="+", choices=SOLVER_NAMES, default=list(SOLVER_NAMES))
    parser.add_argument("--tick-rate", type=int, help="override every level's tick rate")
    parser.add_argument("--quick", action="store_true", help="a subset of six levels")
    parser.add_argument("--jobs", type=int, default=1, help="runs in parallel (processes)")
    parser.add_argument("--json", type=Path, metavar="OUT", help="write every measure here")
    parser.add_argument("--markdown", type=Path, metavar="OUT", help="write the table as Markdown")
    args = parser.parse_args(argv)
    paths, missing = _pick_levels(args.levels, args.quick)
    if missing:
        parser.error(f"no stress level matches {', '.join(missing)} (see {STRESS_DIR})")
    for path in paths:
        try:
            load(path, args.tick_rate)
        except ValidationError as exc:
            parser.error(f"{path.name} at --tick-rate {args.tick_rate}: {exc.errors()[0]['msg']}")
    jobs = [(str(p), s, args.tick_rate) for p in paths for s in args.solvers]
    started = time.perf_counter()
    err = Console(stderr=True)
    if args.jobs > 1:
        with ProcessPoolExecutor(args.jobs) as pool:
            reports = list(pool.map(run_job, jobs))
    else:
        reports = []
        for i, job in enumerate(jobs, 1):
            reports.append(run_job(job))
            err.print(f"[{i}/{len(jobs)}] {Path(job[0]).stem} {job[1]}: {reports[-1].wall_s:.1f} s")
    total = time.perf_counter() - started
    console = Console(width=170, highlight=False)
    render(reports, console, tick_rate=args.tick_rate)
    console.print(f"wall time: {total:.0f} s for {len(reports)} runs")
    if args.json is not None:
        data = {
            "tick_rate": args.tick_rate,
            "runs": [asdict(r) | {"passed": r.passed} for r in reports],
        }
        args.json.write_text(json.dumps(data, indent=1) + "\n")
    if args.markdown is not None:
        args.markdown.write_text(markdown(reports))
    return 0


if __name__ == "__main__":
    sys.exit(main())
