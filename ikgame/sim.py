"""The simulation loop: level script -> controller -> pymunk world, at a fixed timestep.

A :class:`Simulation` is what a game loop drives: call :meth:`Simulation.step` once per tick
(or :meth:`Simulation.run` to the end), read or override the target from code, and read the
pose. Each tick is a short sequence of named steps: apply the script's changes, target, solve,
command motors, step the world, observe. Snapshots (plain arrays) are recorded at the level's fps
for the renderer.

The run ends when the script is done, the level's duration is up, or the physics diverged;
goals are judged then (end a script with a ``wait`` to give props time to settle).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np

from ikgame.control.blockage import BlockWatch
from ikgame.control.controller import Controller
from ikgame.control.dynamics import ChainInertia
from ikgame.control.gait import Footing, Gait, GaitParams, Terrain
from ikgame.control.servo import Servo
from ikgame.kinematics import Avoider, Clearance, Obstacles, SolveStatus, TargetSet
from ikgame.level.model import (
    CHAIN_EFFECTOR,
    MAX_COORD,
    BallProp,
    CircleObstacle,
    FollowCircle,
    FollowLine,
    FollowLissajous,
    FollowPolyline,
    Level,
    ReachStep,
    SegmentObstacle,
    SetChanges,
)
from ikgame.level.scoring import GoalOutcome, GoalTracker, level_score
from ikgame.level.script import ScriptRunner, StepOutcome, follow_path
from ikgame.physics.world import World
from ikgame.snapshot import PropShape, Scene, Snapshot

__all__ = ["Simulation", "RunResult", "TickInfo", "run_level"]

Status = Literal["passed", "failed", "diverged"]


@dataclass(frozen=True, eq=False)
class TickInfo:
    """Telemetry of one tick, for logging or plotting.

    Attributes:
        tick: ticks done, including this one.
        time: simulated time at the end of the tick, s.
        solver_status: ``"success"``, ``"processing"`` or ``"failure"`` (the CCD article's
            states; ``"failure"`` also for a target the motors cannot hold the end at, the
            chain resting in the pose nearest it that they hold), or ``"blocked"``: the solver
            reaches the target but the chain, pushing
            against something or at its torque limits, makes no progress toward it, so it holds
            its pose until the target moves (see :mod:`ikgame.control.blockage`).
        iterations: solver iterations used this tick.
        error: end-effector distance to the target after the tick, px (nan without a target);
            for several effectors, the largest of :attr:`errors`.
        torque_limited: (n,) which motors hit their torque limit this tick.
        errors: (k,) each effector's distance to its target, px (nan for an effector without
            one), in the order of the level's effectors.
    """

    tick: int
    time: float
    solver_status: str
    iterations: int
    error: float
    torque_limited: np.ndarray
    errors: np.ndarray = field(default_factory=lambda: np.zeros(0))


@dataclass(frozen=True)
class RunResult:
    """What a run achieved; ``as_dict()`` is the content of ``results.json``.

    Attributes:
        level: the level's name.
        solver: the solver used at the start.
        status: ``passed`` (every step and goal passed), ``failed`` or ``diverged`` (the
            physics blew up).
        steps: per-step outcomes.
        ticks: physics ticks run.
        sim_time: simulated time, s.
        options: the options the run was made with.
        goals: per-goal outcomes.
        score: 0..100, see :mod:`ikgame.level.scoring`.
        expect: the status the level is designed to end with.
        divergence: for a ``diverged`` run, the body that blew up and the tick, else empty.
        footing: for a creature with a gait, per leg the steps it took and how far its foot
            slid while planted and sank into the ground (px); else empty.
    """

    level: str
    solver: str
    status: Status
    steps: tuple[StepOutcome, ...]
    ticks: int
    sim_time: float
    options: dict[str, object] = field(default_factory=dict)
    goals: tuple[GoalOutcome, ...] = ()
    score: float = 0.0
    expect: str = "passed"
    divergence: str = ""
    footing: dict[str, dict[str, float | int]] = field(default_factory=dict)

    def as_dict(self) -> dict[str, object]:
        """Plain data in a fixed key order."""
        return (
            {
                "level": self.level,
                "solver": self.solver,
                "status": self.status,
                "expect": self.expect,
                "score": self.score,
                "steps_passed": sum(s.passed for s in self.steps),
                "steps_total": len(self.steps),
                "goals_passed": sum(g.passed for g in self.goals),
                "goals_total": len(self.goals),
                "ticks": self.ticks,
                "sim_time": round(self.sim_time, 6),
                "steps": [s.as_dict() for s in self.steps],
                "goals": [g.as_dict() for g in self.goals],
                "options": dict(self.options),
            }
            | ({"divergence": self.divergence} if self.divergence else {})
            | ({"footing": self.footing} if self.footing else {})
        )


class Simulation:
    """A level running in a pymunk world under IK control.

    ``solver`` overrides the level's solver for the whole run, so a level's ``set`` steps do
    not change it (a comparison of solvers stays a comparison).

    >>> from ikgame.level.model import Level
    >>> lvl = Level.model_validate({"level": {"name": "x", "duration": 2.0},
    ...     "world": {"gravity": [0.0, 0.0]}, "chain": {"links": [{"length": 80.0, "repeat": 2}]},
    ...     "script": [{"reach": [100.0, 60.0]}]})
    >>> sim = Simulation(lvl)
    >>> sim.run().status
    'passed'
    """

    def __init__(self, level: Level, *, solver: str | None = None, record: bool = True) -> None:
        self.level = level
        self.world = World(level)
        inertia = ChainInertia(
            np.array([link.length for link in level.chain.expanded_links]),
            self.world.link_masses,
            self.world.link_moments,
            parents=None if self.world.skeleton.is_chain else self.world.parents,
        )
        servo = Servo(
            inertia,
            max_torque=self.world.max_torque,
            max_speed=self.world.max_speed,
            gain=level.chain.gain,
        )
        self.controller = Controller(
            self.world.skeleton,
            solver or level.chain.solver,
            max_speed=self.world.max_speed,
            gain=level.chain.gain,
            iterations=level.chain.iterations,
            arrival=level.chain.arrival,
            servo=servo,
        )
        self._solver_pinned = solver is not None
        self._start_solver = self.controller.solver_name
        chain = level.chain
        self.effector_names = chain.effector_names
        """The end effectors' names, in link order (a chain's one is ``"tip"``)."""
        self._effector_links = np.array(chain.effector_links, dtype=np.int64)
        self._effector_weights = np.array(
            [chain.expanded_links[i].weight for i in chain.effector_links], dtype=float
        )
        self.script = ScriptRunner(level.script, effectors=level.script_effectors)
        self.goals = GoalTracker(level.goals, [p.name for p in level.props])
        self.dt = 1.0 / level.world.tick_rate
        self.tick = 0
        self.diverged = False
        self._divergence = ""
        self.record = record
        self.snapshots: list[Snapshot] = []
        self._overrides: dict[str, np.ndarray] = {}
        # The script's upcoming targets last aimed at, and that aim (see _upcoming).
        self._next: tuple[object, np.ndarray | TargetSet | None] = (None, None)
        self._max_ticks = round(level.level.duration * level.world.tick_rate)
        self._fps = level.world.fps
        self._tick_rate = level.world.tick_rate
        self._last = TickInfo(
            0,
            0.0,
            "processing",
            0,
            math.nan,
            np.zeros(self.world.count, bool),
            np.full(len(self.effector_names), math.nan),
        )
        self._result: RunResult | None = None
        self.scene = _scene(level, self.world, self.script)
        self.controller.avoider = _avoider(level, self.world, self.scene)
        self._has_goals = bool(level.goals)
        self._watch = BlockWatch(dt=self.dt, arrival=level.chain.arrival)
        self._blocked_target: np.ndarray | TargetSet | None = None
        self._blocked_in_step = False
        self.gait, self._footing = _gait(level, self.world, self.scene)
        """The creature's :class:`~ikgame.control.gait.Gait` when the level has a ``[gait]``."""
        self._gait_targets: dict[str, np.ndarray] = {}
        self._reached = self.world.effector_positions()
        if self._has_goals:
            self.goals.observe(0.0, self.world.prop_states())

    @property
    def time(self) -> float:
        """Simulated time, s."""
        return self.tick * self.dt

    @property
    def target(self) -> np.ndarray | None:
        """The point the chain's tip aims at, px: the code's override if set, else the script's.

        For a skeleton of several effectors, the first effector's (read :attr:`targets` for
        all of them, and aim them with :meth:`set_target`).
        """
        return self.targets.get(self.effector_names[0])

    @target.setter
    def target(self, point: tuple[float, float] | np.ndarray | None) -> None:
        """Aim at ``point`` from code (px); ``None`` hands control back to the script."""
        if point is None:
            self._overrides.clear()
            return
        if len(self.effector_names) > 1:
            raise ValueError(
                f"this skeleton has {len(self.effector_names)} effectors "
                f"({', '.join(self.effector_names)}): aim one with set_target(name, point)"
            )
        self.set_target(self.effector_names[0], point)

    @property
    def targets(self) -> dict[str, np.ndarray]:
        """Every effector's target now, px, by name: the code's overrides, else the gait's
        (for a creature's feet), else the script's; effectors without a target are absent."""
        return self.script.targets | self._gait_targets | self._overrides

    def set_target(self, effector: str, point: tuple[float, float] | np.ndarray | None) -> None:
        """Aim the effector named ``effector`` at ``point`` (px) from code; ``None`` hands it
        back to the script (or the gait).

        >>> from ikgame.level import DEFAULT_LEVEL, load_level
        >>> sim = Simulation(load_level(DEFAULT_LEVEL), record=False)
        >>> sim.set_target("tip", (100.0, 200.0)); sim.target.tolist()
        [100.0, 200.0]
        """
        if effector not in self.effector_names:
            raise ValueError(
                f"no effector is named {effector!r} (effectors: {', '.join(self.effector_names)})"
            )
        if point is None:
            self._overrides.pop(effector, None)
        else:
            self._overrides[effector] = _check_target(point)

    @property
    def done(self) -> bool:
        """True when the script has finished, the level's time is up, or the run diverged."""
        return self.diverged or self.script.done or self.tick >= self._max_ticks

    @property
    def last_tick(self) -> TickInfo:
        """Telemetry of the latest tick."""
        return self._last

    def joint_angles(self) -> np.ndarray:
        """(n,) measured local joint angles, radians."""
        return self.world.joint_angles()

    def joint_positions(self) -> np.ndarray:
        """World joint positions, px: (n + 1, 2), the joints then the tip, for a chain; (2n, 2),
        the link starts then the link ends, for a tree of bones."""
        return self.world.joint_positions()

    def step(self) -> TickInfo:
        """Advance one tick and return its telemetry; a no-op once :attr:`done`."""
        if self.done:
            return self._last
        # Frames are taken before the tick, at t = k / fps: a run of T seconds has T x fps frames.
        if self.record and self.tick * self._fps >= len(self.snapshots) * self._tick_rate:
            self.snapshots.append(self.snapshot())
        if self.script.pending:
            self._apply(self.script.take_changes())
        info = self._tick()
        if info is None:
            return self._last
        finished = len(self.script.outcomes)
        if self.world.is_tree:
            reached = dict(zip(self.effector_names, self._reached, strict=True))
            self.script.observe(self.time, self.dt, reached)
            if self.gait is not None:
                self._footing.observe(self.gait.feet, reached)
        else:
            self.script.observe(self.time, self.dt, self._reached[0])
        self._note_blocked(finished)
        if self._has_goals:
            self.goals.observe(self.time, self.world.prop_states())
        self._last = info
        return info

    def play_on(self) -> TickInfo:
        """One tick of control and physics toward :attr:`target` after the run is over.

        For a live window that lets the chain follow the mouse once the level has ended: the
        script, the goals and the recorded frames stay as they ended, and :attr:`result` with
        them (the clock does not move on either).
        """
        if self.diverged:
            return self._last
        info = self._tick(count=False)
        return self._last if info is None else info

    def _tick(self, *, count: bool = True) -> TickInfo | None:
        """Target, solve, command the motors, step the world, watch for a jam; None if the
        physics blew up."""
        if self.gait is not None:
            base = self.world.base_body
            self._gait_targets = self.gait.update(
                self.time + self.dt, self.dt, tuple(base.position), base.angle
            )
        target = self._goal()
        base_motion = self.world.base_motion()
        self._release_if_moved(target, carried=base_motion is not None)
        angles, velocities = self.world.joint_state()
        command = self.controller.command(
            angles,
            target,
            velocities=velocities,
            gravity=self.world.gravity,
            dt=self.dt,
            base_motion=base_motion,
            upcoming=None if self.controller.avoider is None else self._upcoming(),
        )
        drive = command.drive
        self.world.drive(drive.rates, drive.torques, drive.forces, drive.budgets)
        self.world.step(self.dt)
        self.tick += count
        if self.world.diverged():
            self.diverged = True
            self._divergence = f"{self.world.divergence()} blew up at tick {self.tick}"
            return None
        if self.world.skeleton is not self.controller.skeleton:
            # The base moved: the solver must work from where it is now.
            self.controller.skeleton = self.world.skeleton
        # Where every effector ended the tick, read once for the errors and the script.
        self._reached = self.world.effector_positions()
        errors, error = self._errors(target)
        limited = self.world.torque_limited()
        status = command.solution.status.value
        avoider = self.controller.avoider
        if base_motion is not None or (avoider is not None and avoider.planning):
            # A moving base moves every target relative to the chain, as a moving target does:
            # there is no jam to judge until it stands still (and holding the joints would
            # only let it carry the end effector away). Nor is a chain waiting for its way
            # round the obstacles jammed: its error stands still until the plan is found, and
            # the first push after it is no sign of a jam.
            self._watch.reset()
        elif target is not None and self._blocked_target is None:
            reachable = command.solution.status is not SolveStatus.FAILURE

            def pushing() -> bool:
                # A joint that stalled at its torque limit has stopped pushing, but only because
                # pushing got it nowhere; a chain the planner holds off the obstacles that keep
                # it from its target (jammed) only because pushing would get it nowhere.
                return (
                    bool(limited.any())
                    or self.controller.servo.any_stalled
                    or (avoider is not None and avoider.jammed)
                    or self.world.touching()
                )

            if self._watch.observe(
                error=error, reachable=reachable, pushing=pushing, touching=self.world.touching
            ):
                self._blocked_target = target.copy() if isinstance(target, np.ndarray) else target
                self.controller.hold(self.world.joint_angles())
        if self._blocked_target is not None:
            status = "blocked"
        return TickInfo(
            self.tick,
            self.time,
            status,
            command.solution.iterations,
            error,
            limited,
            errors,
        )

    def _goal(self) -> np.ndarray | TargetSet | None:
        """What the controller aims at this tick (see :meth:`_aim`)."""
        return self._aim(self.targets)

    def _upcoming(self) -> np.ndarray | TargetSet | None:
        """What the controller will aim at once the script's next step begins, when the script
        alone sets the targets and knows it now (see :attr:`ScriptRunner.upcoming`)."""
        upcoming = self.script.upcoming
        if upcoming is None or self.gait is not None or self._overrides:
            return None
        if self._next[0] is not upcoming:
            self._next = (upcoming, self._aim(upcoming))
        return self._next[1]

    def _aim(self, targets: dict[str, np.ndarray]) -> np.ndarray | TargetSet | None:
        """What the controller aims at for the effectors' ``targets``: the tip's point for a
        chain, else the set of every targeted effector (in link order, with its weight)."""
        if not self.world.is_tree:
            # A chain aims its tip at a point. A tree aims a set of targets, even a single one
            # (its root may sit off the base, which the chain solvers refuse).
            return targets.get(CHAIN_EFFECTOR)
        aimed = [j for j, name in enumerate(self.effector_names) if name in targets]
        if not aimed:
            return None
        return TargetSet(
            self._effector_links[aimed],
            [targets[self.effector_names[j]] for j in aimed],
            self._effector_weights[aimed],
        )

    def _errors(self, target: np.ndarray | TargetSet | None) -> tuple[np.ndarray, float]:
        """(k,) each effector's distance to its target after the tick, px (nan for an effector
        without one), and the largest of them (nan without a target)."""
        errors = np.array([math.nan] * len(self.effector_names))  # np.full costs more
        if isinstance(target, TargetSet):
            aimed = np.searchsorted(self._effector_links, target.links)
            errors[aimed] = np.hypot(*(self._reached[aimed] - target.points).T)
            return errors, float(np.nanmax(errors))
        if target is None:
            return errors, math.nan
        (x, y), (tx, ty) = self._reached[0].tolist(), target.tolist()
        error = float(np.hypot(x - tx, y - ty))
        errors[0] = error
        return errors, error

    def _note_blocked(self, finished: int) -> None:
        """Mark the steps that ended while the chain was blocked, in their outcome's note."""
        if self._blocked_target is not None:
            self._blocked_in_step = True
        outcomes = self.script.outcomes
        if len(outcomes) > finished and self._blocked_in_step:
            last = outcomes[finished]
            note = "blocked" if not last.note else f"{last.note}, blocked"
            outcomes[finished] = replace(last, note=note)
        if len(outcomes) > finished:
            self._blocked_in_step = False

    def _release_if_moved(self, target: np.ndarray | TargetSet | None, *, carried: bool) -> None:
        """A blocked chain tries again once a target has moved (or is handed back), or the base
        has begun to carry it (``carried``)."""
        blocked = self._blocked_target
        if blocked is None:
            return
        if carried or target is None or _moved_by(target, blocked) > self.controller.arrival:
            self._blocked_target = None
            self._watch.reset()
            self.controller.release()

    def run(self, progress: Callable[[float], None] | None = None) -> RunResult:
        """Step until :attr:`done`; ``progress(fraction)`` is called now and then. Returns the result."""
        report_every = max(1, self._max_ticks // 200)
        while not self.done:
            self.step()
            if progress is not None and self.tick % report_every == 0:
                progress(self.tick / self._max_ticks)
        if progress is not None:
            progress(1.0)
        return self.result

    def _apply(self, changes: list[SetChanges]) -> None:
        """Apply the changes of ``set`` steps to the world and the controller."""
        for change in changes:
            if change.gravity is not None:
                self.world.set_gravity(change.gravity)
                self.controller.servo.retry()
            if change.solver is not None and not self._solver_pinned:
                self.controller.set_solver(change.solver)
            if change.gain is not None:
                self.controller.gain = change.gain
            if change.base is not None or change.angle is not None:
                angle = None if change.angle is None else math.radians(change.angle)
                self.world.move_base(change.base, change.over, angle)

    @property
    def result(self) -> RunResult:
        """The run's result so far (final once :attr:`done`)."""
        if self._result is not None:
            return self._result
        if self.done:
            finished = len(self.script.outcomes)
            self.script.finish(self.time)
            self._note_blocked(finished)
            outcomes = tuple(self.script.outcomes)
            goals = self.goals.finish(self.time, self.world.prop_states())
        else:
            outcomes, goals = tuple(self.script.outcomes), ()
        passed = bool(outcomes) and all(o.passed for o in (*outcomes, *goals))
        status: Status = "diverged" if self.diverged else "passed" if passed else "failed"
        result = RunResult(
            level=self.level.level.name,
            solver=self._start_solver,
            status=status,
            steps=outcomes,
            ticks=self.tick,
            sim_time=self.time,
            options={"tick_rate": self.level.world.tick_rate, "fps": self._fps},
            goals=goals,
            score=level_score(
                [o.score for o in outcomes],
                [g.score for g in goals],
                passed=passed,
                diverged=self.diverged,
            ),
            expect=self.level.level.expect,
            divergence=self._divergence,
            footing={} if self._footing is None else self._footing.as_dict(),
        )
        if self.done:
            self._result = result
        return result

    def snapshot(self) -> Snapshot:
        """The state now, as plain arrays."""
        joints = self.world.joint_positions()
        angles = self.world.joint_angles()
        if self.world.is_tree:
            targets = self.targets
            aims = np.array(
                [targets.get(name, (math.nan, math.nan)) for name in self.effector_names],
                dtype=float,
            )
            target, errors = None, self._last.errors.copy()
        else:
            target, aims, errors = self.target, None, None
        return Snapshot(
            time=self.time,
            tick=self.tick,
            joints=joints,
            angles=angles,
            world_angles=self.world.skeleton.world_angles(angles),
            target=None if target is None else target.copy(),
            step_index=self.script.step_index,
            error=self._last.error,
            solver_status=self._last.solver_status,
            torque_limited=self._last.torque_limited.copy(),
            props=self.world.prop_states(),
            targets=aims,
            errors=errors,
        )


def _moved_by(target: np.ndarray | TargetSet, before: np.ndarray | TargetSet) -> float:
    """How far (px) the farthest target moved from ``before``; inf when the set changed."""
    if isinstance(target, TargetSet) and isinstance(before, TargetSet):
        if not np.array_equal(target.links, before.links):
            return math.inf
        return float(np.max(np.hypot(*(target.points - before.points).T)))
    if isinstance(target, TargetSet) or isinstance(before, TargetSet):
        return math.inf
    return float(np.hypot(*(target - before)))


def _check_target(point: object) -> np.ndarray:
    """``point`` as a (2,) float array, or ``ValueError``: two real numbers (not strings, not
    bools), each within ``MAX_COORD`` px of the origin, the range of every level coordinate.

    >>> _check_target((3, 4.5)).tolist()
    [3.0, 4.5]
    >>> _check_target(("1", "2"))
    Traceback (most recent call last):
    ...
    ValueError: target must be two numbers (x, y) in px within +-100000, got ('1', '2')
    """
    values = list(point) if isinstance(point, tuple | list | np.ndarray) else None
    ok = values is not None and len(values) == 2
    ok = ok and all(
        isinstance(v, int | float | np.integer | np.floating) and not isinstance(v, bool | np.bool_)
        for v in values
    )
    arr = np.asarray(values if ok else (math.nan, math.nan), dtype=float)
    if not (ok and arr.shape == (2,) and np.all(np.abs(arr) <= MAX_COORD)):
        raise ValueError(
            f"target must be two numbers (x, y) in px within +-{MAX_COORD:g}, got {point!r}"
        )
    return arr


def run_level(level: Level, *, solver: str | None = None, record: bool = True) -> Simulation:
    """Run ``level`` to the end and return the finished :class:`Simulation`.

    >>> from ikgame.level import DEFAULT_LEVEL, load_level
    >>> run_level(load_level(DEFAULT_LEVEL), record=False).result.status
    'passed'
    """
    sim = Simulation(level, solver=solver, record=record)
    sim.run()
    return sim


def _gait(level: Level, world: World, scene: Scene) -> tuple[Gait | None, Footing | None]:
    """The level's gait, its feet resting where the start pose puts them (in the body's
    frame), standing on the level's obstacles; and what measures how the feet hold."""
    if level.gait is None:
        return None, None
    config = level.gait
    names = level.chain.effector_names
    links = [level.chain.effector_links[names.index(leg)] for leg in config.legs]
    skeleton = world.skeleton
    c, s = math.cos(skeleton.base_angle), math.sin(skeleton.base_angle)
    feet = world.link_ends(np.array(links))
    rest = (feet - skeleton.base) @ np.array(((c, -s), (s, c)))
    # How far below its rest spot each foot can reach: its leg stretched, less the way from the
    # hip to the rest spot.
    hips = skeleton.root_points()[links]
    lengths = skeleton.ancestors[links] @ skeleton.lengths
    spare = lengths - np.hypot(*(feet - hips).T)
    # A foot's end is the centre of its round tip: it stands its radius above the ground.
    radius = float(world.link_widths[links].max()) / 2
    ground = Terrain(*_grown(scene.segments, scene.circles, radius))
    gait = Gait(
        GaitParams(
            stride=config.stride,
            step_height=config.step_height,
            step_time=config.step_time,
            threshold=config.step_threshold,
        ),
        dict(zip(config.legs, rest, strict=True)),
        ground,
        position=skeleton.base,
        angle=skeleton.base_angle,
        groups=config.step_groups,
        reach=max(float(spare.min()), 1.0),
    )
    return gait, Footing(config.legs, ground, settle=max(level.chain.arrival, 1.0))


def _grown(segments: np.ndarray, circles: np.ndarray, by: float) -> tuple[np.ndarray, np.ndarray]:
    """Segment and circle obstacles ``by`` px thicker (the ground a round tip's centre meets)."""
    grown_segments, grown_circles = segments.copy(), circles.copy()
    grown_segments[:, 4] += by
    grown_circles[:, 2] += by
    return grown_segments, grown_circles


def _avoider(level: Level, world: World, scene: Scene) -> Avoider | None:
    """What keeps the skeleton clear of the level's static obstacles (None without any, and for
    a creature with a gait: its feet stand on the ground by design)."""
    if level.gait is not None:
        return None
    obstacles = Obstacles.from_arrays(scene.segments, scene.circles)
    if not len(obstacles):
        return None
    # A tree re-plans when its motors leave the planned line: a hand of the two-armed torso
    # strays below a clear line onto the floor beside it and catches there. A chain mostly
    # follows its line within the margin: re-planning whenever it strayed sent fourteen of the
    # quality suite's runs onto routes that failed. Without replan, the avoider re-plans only
    # for a chain that rests pressed into an obstacle.
    room = Clearance(world.skeleton, world.link_widths / 2.0, obstacles)
    # Its search's work and its waits the same in simulated time at any tick rate.
    return Avoider(room, replan=world.is_tree, tick_rate=level.world.tick_rate)


def _scene(level: Level, world: World, script: ScriptRunner) -> Scene:
    segments = [(*o.a, *o.b, o.radius) for o in level.obstacles if isinstance(o, SegmentObstacle)]
    circles = [(*o.center, o.radius) for o in level.obstacles if isinstance(o, CircleObstacle)]
    targets = []
    for _, step in script.steps:
        if isinstance(step, ReachStep):
            targets.extend(step.points)
        elif isinstance(step, FollowLine | FollowCircle | FollowLissajous | FollowPolyline):
            targets.append(follow_path(step)(0.0))
    props = tuple(
        PropShape("ball", (p.radius, p.radius))
        if isinstance(p, BallProp)
        else PropShape("box", p.size)
        for p in level.props
    )
    tree = {}
    if world.is_tree:
        names = level.chain.effector_names
        aims: dict[str, list[tuple[float, float]]] = {name: [] for name in names}
        for _, step in script.steps:
            if isinstance(step, ReachStep):
                for name, point in step.targets(script.default_effector).items():
                    aims[name].append(point)
            elif isinstance(step, FollowLine | FollowCircle | FollowLissajous | FollowPolyline):
                aims[step.effector or script.default_effector].append(follow_path(step)(0.0))
        tree = {
            "parents": world.parents.copy(),
            "effector_links": world.effector_links.copy(),
            "effector_names": names,
            "effector_targets": tuple(
                np.array(aims[name], dtype=float).reshape(-1, 2) for name in names
            ),
        }
    return Scene(
        level_name=level.level.name,
        segments=np.array(segments, dtype=float).reshape(-1, 5),
        circles=np.array(circles, dtype=float).reshape(-1, 3),
        link_widths=world.link_widths.copy(),
        reach=world.skeleton.reach,
        targets=np.array(targets, dtype=float).reshape(-1, 2),
        goals=np.array([g.region for g in level.goals], dtype=float).reshape(-1, 4),
        props=props,
        bounds=level.world.bounds,
        step_count=len(script.steps),
        fps=float(level.world.fps),
        **tree,
    )
