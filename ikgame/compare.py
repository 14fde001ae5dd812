"""Compare IK solvers on one level, in the physics world: who gets there first, how precisely,
by how direct a path, how smoothly, and at what cost per tick.

Solvers differ in more than their kinematic answer: the chain has mass, motors have torque and
speed limits, and the controller re-solves from the measured pose every tick. So the fair
comparison runs the whole level once per solver, in the same world, and measures the motion
the chain actually makes. :func:`compare_level` does that and returns a :class:`Comparison`;
:func:`write_comparison` writes ``compare.json`` and ``compare.png``; :func:`comparison_table`
is the table the ``ikgame compare`` command prints. The picture is drawn by
:func:`ikgame.render.plot.render_comparison` from :meth:`Comparison.plot_data`, plain data, so
drawing stays out of the simulation's layer.

Everything in a comparison is deterministic for a given level except the wall-clock timing of
the solver calls, which ``compare.json`` keeps apart under ``wall_clock``.

A tree of bones is measured over all of its effectors: the path length adds up every effector's
travel (``compare.json`` also lists each one's), the reach points are every effector's targets,
and a creature's runs report their footing, as ``results.json`` does. A chain's comparison is
what it always was.

Units: time s, lengths and errors px, angles rad.
"""

from __future__ import annotations

import io
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Final

import numpy as np
from rich.markup import escape
from rich.table import Table

from ikgame._files import write_atomic, write_json
from ikgame.kinematics import SOLVERS, Solution, TargetSet
from ikgame.level.model import CHAIN_EFFECTOR, Level
from ikgame.level.script import StepOutcome
from ikgame.physics.world import World
from ikgame.render.plot import ComparisonPlot, SolverTrace, render_comparison
from ikgame.sim import Simulation

__all__ = [
    "DEFAULT_SOLVERS",
    "Comparison",
    "SolverRun",
    "compare_level",
    "comparison_table",
    "squared_jerk",
    "write_comparison",
]

_SEED_ORDER: Final = ("ccd", "jacobian_transpose", "dls", "fabrik")

DEFAULT_SOLVERS: Final = tuple(n for n in _SEED_ORDER if n in SOLVERS) + tuple(
    n for n in SOLVERS if n not in _SEED_ORDER
)
"""Every registered solver: the seed's two first (CCD, then Jacobian transpose), then DLS and
FABRIK, then any solver registered later."""

_WALL_CLOCK_NOTE: Final = (
    "values under 'wall_clock' are wall-clock measurements on the machine that made this file "
    "and vary from run to run; everything else is deterministic for the level"
)
_UNITS: Final = {
    "sim_time": "s",
    "time_to_reach": "s",
    "final_error": "px",
    "mean_error": "px",
    "tracking_error": "px",
    "path_length": "px",
    "mean_squared_jerk": "rad^2/s^6",
    "torque_limited": "share of joint-ticks",
    "solver_us_per_tick": "us",
}


@dataclass(frozen=True, eq=False)
class SolverRun:
    """One solver's run of a level, and what it measured.

    Attributes:
        solver: the solver's registry name.
        status: ``passed``, ``failed`` or ``diverged``, as in ``results.json``.
        score: the run's score, 0..100, as in ``results.json``.
        steps: per-step outcomes (time to reach in s, final and mean error in px).
        ticks: physics ticks run.
        sim_time: simulated time the level took, s.
        path_length: distance the end effector travelled, px (sum of per-tick displacements);
            in a tree, every effector's distance added up.
        mean_squared_jerk: mean over ticks of the summed squared jerk of the joint angles,
            rad^2/s^6 (NaN with fewer than four poses).
        tracking_error: mean error over the follow steps weighted by their duration, px; None
            when the level has no follow step.
        iterations_per_tick: mean solver iterations per solver call.
        torque_limited: share of joint-ticks with the motor at its torque limit (0..1): where the
            physics, not the solver, set the pace.
        solver_calls: how many times the solver was called (each tick with a target; 60 times a
            second once an answer arrives near the chain, see ``Controller.ik_rate``).
        solver_us_per_tick: mean wall-clock time of one solver call, microseconds; varies from
            run to run (None without a call).
        times: (ticks,) simulated time at the end of each tick, s (a diverged run keeps the
            ticks before the one that blew up; so do ``errors``, ``path`` and ``targets``).
        errors: (ticks,) end-effector distance to the target after each tick, px (NaN without
            a target).
        path: (ticks + 1, 2) end-effector position at the start and after each tick, px (a
            tree's first effector).
        angles: (ticks + 1, n) measured local joint angles at the start and after each tick, rad.
        targets: (ticks, 2) the target during each tick, px (NaN without a target; a tree's
            first effector).
        effectors: the effectors' names, in the order of the last axis but one of ``paths``
            and ``effector_targets`` (``("tip",)`` for a chain).
        paths: (ticks + 1, k, 2) every effector's position at the start and after each tick, px.
        effector_targets: (ticks, k, 2) every effector's target during each tick, px (NaN
            without one).
        footing: a creature's footing per leg, as in ``results.json``; empty without a gait.
    """

    solver: str
    status: str
    score: float
    steps: tuple[StepOutcome, ...]
    ticks: int
    sim_time: float
    path_length: float
    mean_squared_jerk: float
    tracking_error: float | None
    iterations_per_tick: float
    torque_limited: float
    solver_calls: int
    solver_us_per_tick: float | None
    times: np.ndarray
    errors: np.ndarray
    path: np.ndarray
    angles: np.ndarray
    targets: np.ndarray
    effectors: tuple[str, ...] = ("tip",)
    paths: np.ndarray = field(default_factory=lambda: np.zeros((0, 1, 2)))
    effector_targets: np.ndarray = field(default_factory=lambda: np.zeros((0, 1, 2)))
    footing: dict[str, dict[str, float | int]] = field(default_factory=dict)

    @property
    def path_lengths(self) -> dict[str, float]:
        """Distance each effector travelled, px, by name."""
        return {name: _travel(self.paths[:, j]) for j, name in enumerate(self.effectors)}

    def as_dict(self) -> dict[str, object]:
        """Plain data in a fixed key order; timing under ``wall_clock``. A tree's runs add each
        effector's path length, a creature's its footing."""
        tree = {}
        if self.effectors != (CHAIN_EFFECTOR,):
            tree["path_lengths"] = {k: _plain(v) for k, v in self.path_lengths.items()}
        if self.footing:
            tree["footing"] = self.footing
        return {
            "status": self.status,
            "score": _plain(self.score),
            "steps_passed": sum(s.passed for s in self.steps),
            "steps_total": len(self.steps),
            "ticks": self.ticks,
            "sim_time": _plain(self.sim_time),
            "path_length": _plain(self.path_length),
            "mean_squared_jerk": _plain(self.mean_squared_jerk),
            "tracking_error": _plain(self.tracking_error),
            "iterations_per_tick": _plain(self.iterations_per_tick),
            "torque_limited": _plain(self.torque_limited),
            "solver_calls": self.solver_calls,
            "steps": [s.as_dict() for s in self.steps],
            **tree,
            "wall_clock": {"solver_us_per_tick": _plain(self.solver_us_per_tick)},
        }


@dataclass(frozen=True, eq=False)
class Comparison:
    """Several solvers' runs of one level, plus what the plot needs of the level.

    Attributes:
        level: the level's name.
        tick_rate: physics ticks per second.
        runs: one :class:`SolverRun` per solver, in the order asked for.
        base: where the chain is mounted, px.
        reach: the chain's length, px.
        start_pose: (n + 1, 2) joint positions then the end effector before the first tick, px;
            for a tree, a line that walks every bone out and back from the base.
        reach_points: (k, 2) the reach targets in the order the script ran them, px (in a
            tree, each reach step's effectors' targets in the step's order).
        tolerance: the reach steps' arrival tolerance, px, when they share one (else None).
    """

    level: str
    tick_rate: int
    runs: tuple[SolverRun, ...]
    base: tuple[float, float]
    reach: float
    start_pose: np.ndarray
    reach_points: np.ndarray
    tolerance: float | None

    def run(self, solver: str) -> SolverRun:
        """The run of ``solver``; ValueError if it was not compared."""
        for run in self.runs:
            if run.solver == solver:
                return run
        raise ValueError(
            f"solver {solver!r} is not in this comparison; it has: "
            + ", ".join(r.solver for r in self.runs)
        )

    def as_dict(self) -> dict[str, object]:
        """The content of ``compare.json``: plain data in a fixed key order."""
        return {
            "level": self.level,
            "tick_rate": self.tick_rate,
            "note": _WALL_CLOCK_NOTE,
            "units": dict(_UNITS),
            "solvers": {run.solver: run.as_dict() for run in self.runs},
        }

    def plot_data(self) -> ComparisonPlot:
        """What the picture shows of this comparison, as plain data for
        :func:`ikgame.render.plot.render_comparison`.

        >>> lvl = Level.model_validate({"level": {"name": "x", "duration": 0.1},
        ...     "chain": {"links": [{"length": 80.0, "repeat": 2}]},
        ...     "script": [{"reach": [90, 60]}]})
        >>> plot = compare_level(lvl, ["ccd", "dls"]).plot_data()
        >>> [(t.solver, len(t.errors)) for t in plot.traces], plot.reach_points.tolist()
        ([('ccd', 24), ('dls', 24)], [[90.0, 60.0]])
        """
        return ComparisonPlot(
            level=self.level,
            traces=tuple(
                SolverTrace(
                    solver=run.solver,
                    status=run.status,
                    sim_time=run.sim_time,
                    path_length=run.path_length,
                    times=run.times,
                    errors=run.errors,
                    path=run.path,
                    other_paths=tuple(run.paths[:, j] for j in range(1, len(run.effectors))),
                    target_trails=tuple(_moving_targets(run)),
                )
                for run in self.runs
            ),
            base=self.base,
            reach=self.reach,
            start_pose=self.start_pose,
            reach_points=self.reach_points,
            tolerance=self.tolerance,
        )


def compare_level(
    level: Level,
    solvers: Sequence[str] = DEFAULT_SOLVERS,
    progress: Callable[[float], None] | None = None,
) -> Comparison:
    """Run ``level`` once per solver in the physics world and measure each run.

    Smoothness is the mean squared jerk of the joint angles: the third finite difference of the
    per-tick joint angle series divided by dt^3, squared, summed over joints and averaged over
    ticks, in rad^2/s^6. Lower is smoother. Solver time is the mean wall-clock time of the
    solver call alone (physics and bookkeeping excluded), in microseconds.
    ``progress(fraction)`` is called now and then with the fraction of the work done.

    >>> lvl = Level.model_validate({"level": {"name": "x", "duration": 0.1},
    ...     "chain": {"links": [{"length": 80.0, "repeat": 2}]}, "script": [{"reach": [90, 60]}]})
    >>> [run.ticks for run in compare_level(lvl, ["ccd", "dls"]).runs]
    [24, 24]
    """
    names = _check_solvers(solvers)
    runs = []
    for index, name in enumerate(names):
        report = None
        if progress is not None:
            report = _scaled(progress, index / len(names), 1 / len(names))
        runs.append(_run_solver(level, name, report))
    if progress is not None:
        progress(1.0)
    world = World(level)
    tolerances = {step.tolerance for step in level.script if hasattr(step, "tolerance")}
    return Comparison(
        level=level.level.name,
        tick_rate=level.world.tick_rate,
        runs=tuple(runs),
        base=(float(level.chain.base[0]), float(level.chain.base[1])),
        reach=world.skeleton.reach,
        start_pose=_start_pose(world),
        reach_points=_reach_points(runs[0]),
        tolerance=tolerances.pop() if len(tolerances) == 1 else None,
    )


def _step_ticks(run: SolverRun, step: StepOutcome) -> np.ndarray:
    """Which of the run's ticks belong to ``step`` (a tick belongs to the step it ended in)."""
    ended = run.sim_time if step.ended is None else step.ended
    return (run.times > step.started + 1e-9) & (run.times <= ended + 1e-9)


def _start_pose(world: World) -> np.ndarray:
    """The pose before the first tick as one line: a chain's joints then its tip; a tree's
    bones walked depth first from the base, each out to its tip and back (a line the picture
    draws as the tree), px.

    >>> lvl = Level.model_validate({"level": {"name": "x", "duration": 0.1},
    ...     "chain": {"angle": 0.0, "bones": [{"name": "a", "length": 10.0},
    ...     {"name": "b", "parent": "a", "length": 5.0, "angle": 90.0},
    ...     {"name": "c", "parent": "a", "length": 5.0, "angle": -90.0}]},
    ...     "script": [{"wait": 0.1}]})
    >>> _start_pose(World(lvl)).round(6).tolist()
    [[0.0, 0.0], [0.0, 0.0], [10.0, 0.0], [10.0, 5.0], [10.0, 0.0], [10.0, -5.0], [10.0, 0.0], [0.0, 0.0], [0.0, 0.0]]
    """
    joints = world.joint_positions()
    if not world.is_tree:
        return joints
    count = len(world.parents)
    starts, ends = joints[:count], joints[count:]
    children: list[list[int]] = [[] for _ in range(count + 1)]  # the last: the base's
    for i, parent in enumerate(world.parents):
        children[parent].append(i)  # -1, a root, is the base's
    base = np.asarray(world.skeleton.base, dtype=float)
    line = [base]
    # Depth first without recursion: a tree may be 200 bones deep.
    stack: list[tuple[int, bool]] = [(root, False) for root in reversed(children[-1])]
    while stack:
        link, back = stack.pop()
        if back:
            line.append(starts[link])
            if world.parents[link] < 0:
                line.append(base)
            continue
        if world.parents[link] < 0:
            line.append(starts[link])
        line.append(ends[link])
        stack.append((link, True))
        stack += [(child, False) for child in reversed(children[link])]
    return np.array(line, dtype=float)


def _step_effectors(run: SolverRun, step: StepOutcome) -> list[int]:
    """Which of the run's effectors ``step`` moves: those it names in a tree, else the tip."""
    if run.effectors == (CHAIN_EFFECTOR,):
        return [0]
    return [run.effectors.index(name) for name in step.effectors]


def _reach_points(run: SolverRun) -> np.ndarray:
    """The reach targets in the order the script ran them, read off the run itself (so the
    picture needs to know nothing of how a level spells its steps)."""
    points = []
    for step in run.steps:
        if step.kind == "reach":
            ticks = _step_ticks(run, step)
            for j in _step_effectors(run, step):
                targets = run.effector_targets[ticks, j]
                targets = targets[np.all(np.isfinite(targets), axis=1)]
                if len(targets):
                    points.append(targets[0])
    return np.array(points, dtype=float).reshape(-1, 2)


def _moving_targets(run: SolverRun) -> list[np.ndarray]:
    """The target's path during each step whose target moves (a follow step), px."""
    trails = []
    for step in run.steps:
        if step.kind == "reach":
            continue
        ticks = _step_ticks(run, step)
        for j in _step_effectors(run, step):
            targets = run.effector_targets[ticks, j]
            targets = targets[np.all(np.isfinite(targets), axis=1)]
            if len(targets) > 1 and np.ptp(targets, axis=0).max() > 0.0:
                trails.append(targets)
    return trails


def _check_solvers(solvers: Sequence[str]) -> tuple[str, ...]:
    valid = ", ".join(SOLVERS)
    if isinstance(solvers, str):
        raise ValueError(f"solvers must be a list of names, not the string {solvers!r}")
    names = tuple(solvers)
    if not names:
        raise ValueError(f"name at least one solver; valid solvers: {valid}")
    unknown = [name for name in names if name not in SOLVERS]
    if unknown:
        raise ValueError(f"unknown solver {unknown[0]!r}; valid solvers: {valid}")
    if len(set(names)) != len(names):
        raise ValueError(f"each solver may be compared once, got {list(names)}")
    return names


def _scaled(progress: Callable[[float], None], start: float, span: float):
    return lambda fraction: progress(start + span * fraction)


class _TimedSolve:
    """Solver functions that also add up the wall-clock time of their calls.

    The timing hook: :class:`~ikgame.control.controller.Controller` calls ``self.solver.solve``
    (a chain) or ``self.solver.solve_targets`` (a tree) once per tick with a target, so
    replacing both methods with :meth:`wrap` of them times the solver (recovery included) alone.
    ``Simulation(level, solver=name)`` pins the solver for the run (a level's ``set`` steps do
    not switch it), so nothing replaces the wrapper once it is in place.
    """

    def __init__(self) -> None:
        self.calls = 0
        self.iterations = 0
        self.nanoseconds = 0

    def wrap(self, solve: Callable[..., Solution]) -> Callable[..., Solution]:
        """``solve``, timed."""

        def timed(
            angles: np.ndarray,
            target: np.ndarray | TargetSet,
            *,
            max_iterations: int,
            tolerance: float,
        ) -> Solution:
            start = time.perf_counter_ns()
            solution = solve(angles, target, max_iterations=max_iterations, tolerance=tolerance)
            self.nanoseconds += time.perf_counter_ns() - start
            self.calls += 1
            self.iterations += solution.iterations
            return solution

        return timed


def _run_solver(level: Level, name: str, progress: Callable[[float], None] | None) -> SolverRun:
    sim = Simulation(level, solver=name, record=False)
    timed = _TimedSolve()
    solver = sim.controller.solver
    solver.solve = timed.wrap(solver.solve)
    solver.solve_targets = timed.wrap(solver.solve_targets)
    effectors = tuple(sim.effector_names)
    times, errors, targets = [], [], []
    limited = 0
    path = [sim.world.effector_positions()]
    angles = [sim.joint_angles()]
    total = round(level.level.duration * level.world.tick_rate)
    report_every = max(1, total // 100)
    while not sim.done:
        aims = sim.targets
        target = [aims.get(effector, (math.nan, math.nan)) for effector in effectors]
        info = sim.step()
        if sim.diverged:
            # The blown-up tick's pose is meaningless; the run ends at the last sane one.
            break
        times.append(info.time)
        errors.append(info.error)
        limited += int(info.torque_limited.sum())
        targets.append(target)
        path.append(sim.world.effector_positions())
        angles.append(sim.joint_angles())
        if progress is not None and sim.tick % report_every == 0:
            progress(sim.tick / total)
    result = sim.result
    paths = np.array(path, dtype=float).reshape(-1, len(effectors), 2)
    aims_arr = np.array(targets, dtype=float).reshape(-1, len(effectors), 2)
    angles_arr = np.array(angles, dtype=float)
    return SolverRun(
        solver=name,
        status=result.status,
        score=result.score,
        steps=result.steps,
        ticks=result.ticks,
        sim_time=result.sim_time,
        path_length=sum(_travel(paths[:, j]) for j in range(len(effectors))),
        mean_squared_jerk=_mean_squared_jerk(angles_arr, sim.dt),
        tracking_error=_tracking_error(result.steps),
        iterations_per_tick=timed.iterations / timed.calls if timed.calls else 0.0,
        torque_limited=limited / max(1, len(times) * sim.world.count),
        solver_calls=timed.calls,
        solver_us_per_tick=timed.nanoseconds / timed.calls / 1e3 if timed.calls else None,
        times=np.array(times, dtype=float),
        errors=np.array(errors, dtype=float),
        path=paths[:, 0],
        angles=angles_arr,
        targets=aims_arr[:, 0],
        effectors=effectors,
        paths=paths,
        effector_targets=aims_arr,
        footing=dict(result.footing),
    )


def _travel(path: np.ndarray) -> float:
    """Length of a (ticks + 1, 2) path, px: the sum of its per-tick displacements."""
    return float(np.hypot(*np.diff(path, axis=0).T).sum())


def squared_jerk(angles: np.ndarray, dt: float) -> np.ndarray:
    """Summed squared jerk of a joint angle series, one value per four consecutive poses.

    ``angles`` is (k, n), one row per tick ``dt`` s apart (radians); entry ``i`` of the result
    is the sum over joints of ``(third finite difference of rows i..i+3 / dt^3)^2``, rad^2/s^6.
    :attr:`SolverRun.mean_squared_jerk` is its mean.

    >>> squared_jerk(np.array([[0.0], [0.0], [0.0], [1.0]]), 0.5).tolist()
    [64.0]
    """
    angles = np.asarray(angles, dtype=float)
    if angles.ndim != 2:
        raise ValueError(f"angles must be (ticks, joints), got shape {angles.shape}")
    if not (math.isfinite(dt) and dt > 0):
        raise ValueError(f"dt must be a positive number of seconds, got {dt!r}")
    # Free joints are read wrapped to [-pi, pi]; a wrap is not motion.
    jerk = np.diff(np.unwrap(angles, axis=0), n=3, axis=0) / dt**3
    return (jerk**2).sum(axis=1)


def _mean_squared_jerk(angles: np.ndarray, dt: float) -> float:
    """Mean over ticks of :func:`squared_jerk`, rad^2/s^6 (NaN with fewer than four poses)."""
    return float(squared_jerk(angles, dt).mean()) if len(angles) >= 4 else math.nan


def _tracking_error(steps: Sequence[StepOutcome]) -> float | None:
    follows = [s for s in steps if s.kind == "follow" and s.mean_error is not None]
    if not follows:
        return None
    weights = [max((s.ended or s.started) - s.started, 0.0) for s in follows]
    if sum(weights) == 0.0:
        return float(np.mean([s.mean_error for s in follows]))
    return float(np.average([s.mean_error for s in follows], weights=weights))


def _plain(value: float | None) -> float | None:
    """Six significant digits: enough for any of these measurements, and stable in JSON."""
    if value is None or not math.isfinite(value):
        return None
    return float(f"{value:.6g}")


def write_comparison(out_dir: str | Path, comparison: Comparison) -> list[Path]:
    """Write ``compare.json`` and ``compare.png`` into ``out_dir``, each atomically.

    >>> write_comparison  # doctest: +ELLIPSIS
    <function write_comparison at ...>
    """
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise ValueError(f"{out} exists and is not a folder")
    buffer = io.BytesIO()
    render_comparison(comparison.plot_data()).save(buffer, format="PNG", optimize=True)
    return [
        write_json(out / "compare.json", comparison.as_dict()),
        write_atomic(out / "compare.png", buffer.getvalue()),
    ]


def comparison_table(comparison: Comparison) -> Table:
    """A rich table with one row per solver: status, score, time to reach each target (s), mean
    final error of the reach steps (px, when the level has some), tracking error (px, when it has
    follow steps), the farthest a planted foot slid (px, for a creature), path length (px), mean
    squared jerk (rad^2/s^6), solver time (us per tick) and sim time (s).

    >>> comparison_table  # doctest: +ELLIPSIS
    <function comparison_table at ...>
    """
    steps = comparison.runs[0].steps
    reach_steps = [s.index for s in steps if s.kind == "reach"]
    tracking = any(run.tracking_error is not None for run in comparison.runs)
    footing = any(run.footing for run in comparison.runs)
    table = Table(title=f"{escape(comparison.level)}: solver comparison", show_edge=False)
    table.add_column("solver")
    table.add_column("status")
    table.add_column("score", justify="right")
    for number, _ in enumerate(reach_steps, start=1):
        table.add_column(f"reach {number} (s)", justify="right")
    if reach_steps:
        table.add_column("final error (px)", justify="right")
    if tracking:
        table.add_column("tracking error (px)", justify="right")
    if footing:
        table.add_column("foot slip (px)", justify="right")
    for column in ("path (px)", "jerk (rad²/s⁶)", "solver (µs/tick)", "sim time (s)"):
        table.add_column(column, justify="right")
    colour = {"passed": "green", "failed": "yellow", "diverged": "red"}
    for run in comparison.runs:
        by_index = {s.index: s for s in run.steps}
        times = [_fmt(by_index[i].time_to_reach, ".2f", "failed") for i in reach_steps]
        finals = [by_index[i].final_error for i in reach_steps]
        finals = [e for e in finals if e is not None and math.isfinite(e)]
        cells = [
            run.solver,
            f"[{colour.get(run.status, 'white')}]{run.status}[/]",
            f"{run.score:.0f}",
            *times,
        ]
        if reach_steps:
            cells.append(_fmt(float(np.mean(finals)) if finals else None, ".2f"))
        if tracking:
            cells.append(_fmt(run.tracking_error, ".2f"))
        if footing:
            slips = [float(leg["slip"]) for leg in run.footing.values()]
            cells.append(_fmt(max(slips) if slips else None, ".2f"))
        cells += [
            _fmt(run.path_length, ".0f"),
            _fmt(run.mean_squared_jerk, ".3g"),
            _fmt(run.solver_us_per_tick, ".0f"),
            f"{run.sim_time:.2f}",
        ]
        table.add_row(*cells)
    return table


def _fmt(value: float | None, spec: str, missing: str = "-") -> str:
    if value is None or not math.isfinite(value):
        return missing
    return format(value, spec)
