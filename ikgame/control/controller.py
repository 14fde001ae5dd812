"""Per-tick joint control: IK solver -> desired angles -> motor commands.

Each tick the solver is warm-started from the measured pose and returns desired local angles
within the joint limits. Given a :class:`~ikgame.control.servo.Servo` (as the physics world's
chain is), the angle errors become velocities the motors can brake from in time and feed-forward
torques within the limits; without one (a chain with no dynamics), each joint is simply asked
for a relative angular velocity proportional to its error (``gain``, 1/s), clamped by its speed
limit (rad/s).

Because the gain is in 1/s, the pose approaches the desired one with time constant ``1 / gain``
seconds (where the motors have torque to spare) whatever the tick rate.

With a servo, an answer that arrives near the chain is solved afresh ``ik_rate`` times a second
(a game's frame rate), not every tick: in between, the servo drives toward it every tick,
carried along with a moving target by the same joint rates that carry the chain with it.
Anything else (a new target, a chain on its way to a farther answer, an answer still on its way,
a search, a plan round obstacles, a moving base) is solved every tick, but for a tree a moving
base carries toward targets beyond its reach: the answer leaning toward them is kept for a frame
too. A chain with strong
motors whose end is about to sweep through a still target on its way to a farther answer is
caught there instead (see :mod:`~ikgame.control.catching`): the answer is then the pose it stops
on, and from rest the one from where it stopped.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Final

import numpy as np

from ikgame.control._floats import damped_rates, end_motion
from ikgame.control.catching import catch_pose, time_to_nearest
from ikgame.control.servo import FLOAT_LINKS, SECTION_LINKS, Servo, ServoCommand
from ikgame.kinematics import (
    RobustSolver,
    Skeleton,
    Solution,
    SolveStatus,
    TargetSet,
    forward_kinematics,
    solve_dls,
    stacked_jacobian,
    wrap_angle,
)
from ikgame.kinematics.clearance import Avoider
from ikgame.kinematics.jacobian import jacobian
from ikgame.kinematics.recovery import STRAINED, holds_along

__all__ = ["Command", "Controller", "joint_error"]

JUMP: Final = 4.0
"""A target whose motion would need joint rates over this many times their speed limits has
jumped rather than moved."""

IK_RATE: Final = 60.0
"""How often (Hz) a :class:`Controller` with a servo solves afresh for an answer that arrives
near the chain: a game's frame rate. Between solves the servo drives toward the answer every
tick."""

NEAR: Final = 0.05
"""Radians: an answer within this of the measured pose on every joint is near the chain, and
solved afresh only :data:`IK_RATE` times a second. One farther off is solved every tick while
the chain travels to it, as the answer from each pose on the way can differ."""

SETTLING: Final = 0.02
"""rad/s: a joint turning slower than this is at rest; an answer near the chain for a target
that holds still is kept while the chain comes in to it (see :meth:`Controller._reuse`)."""

CATCH_WITHIN: Final = 6.0
"""px: a pose on the way whose end is this near a still target is one the chain may stop on,
caught there (see :meth:`Controller._caught`): a level's default reach tolerance."""

FINISH_ITERATIONS: Final = 4
"""How many times the controller's iterations the damped least-squares answer that finishes a
caught chain's way may take (see :meth:`Controller._finish`): solved anew at the IK rate with
the usual few, a chain against tight limits crept the last 3 px over 0.7 s (rest jitter 1.1
px); given them at once, it comes to rest on the answer."""

KEPT_STRAIN: Final = 0.5
"""Share of its motors' torque limits past which holding an answer still strains them: such an
answer, for a still target, is kept while the chain comes in to it (see
:meth:`Controller._reuse`)."""


def joint_error(desired: np.ndarray, measured: np.ndarray, limited: np.ndarray) -> np.ndarray:
    """Signed angle error per joint, radians.

    A free joint takes the short way round (wrapped to [-pi, pi]). A limited joint is measured
    in its limits' frame and is never wrapped, so it never tries the long way through a limit.

    >>> joint_error(np.array([3.0, 3.0]), np.array([-3.0, -3.0]), np.array([False, True]))
    array([-0.28318531,  6.        ])
    """
    error = np.asarray(desired, dtype=float) - measured
    if not limited.all():
        free = ~limited
        error[free] = [wrap_angle(e) for e in error[free].tolist()]
    return error


@dataclass(frozen=True, eq=False)
class Command:
    """One tick's decision: the solution and the motor rates it turned into.

    Attributes:
        solution: the solver's desired angles, status, iterations and kinematic error.
        rates: (n,) commanded relative angular velocity per joint (child - parent), rad/s.
        drive: the servo's feed-forward loads and motor budgets, when the controller has one.
    """

    solution: Solution
    rates: np.ndarray
    drive: ServoCommand | None = None


class Controller:
    """Turns a target into motor rates; ``command(measured, target)`` once per tick.

    >>> ctl = Controller(Skeleton.chain([100.0]), "ccd", max_speed=np.array([1.0]))
    >>> ctl.command(np.zeros(1), np.array([0.0, 100.0])).rates.tolist()
    [1.0]
    """

    def __init__(
        self,
        skeleton: Skeleton,
        solver: str,
        *,
        max_speed: np.ndarray,
        gain: float = 12.0,
        iterations: int = 10,
        arrival: float = 0.5,
        servo: Servo | None = None,
        avoider: Avoider | None = None,
        ik_rate: float | None = IK_RATE,
    ) -> None:
        # Stalls (limits, coils, the long way round a stop) are recovered from, and a settled
        # chain's answer is cached, by one solver object that lives with the chain.
        self.solver = RobustSolver(skeleton, solver)
        """The chain's solver, with recovery and a cache (see :class:`RobustSolver`)."""
        self.avoider = avoider
        """Keeps the commanded poses and the way to them clear of static obstacles, if set."""
        self.skeleton = skeleton
        self.max_speed = np.asarray(max_speed, dtype=float)
        self._speeds = self.max_speed.tolist()
        self.servo = servo
        self.gain = gain
        self.iterations = int(iterations)
        self.arrival = float(arrival)
        self._limited = skeleton.limited
        self._all_limited = bool(self._limited.all())
        self._held: np.ndarray | None = None
        self._holding = False
        self._last_target: np.ndarray | TargetSet | None = None
        self._gravity: tuple[float, float] | None = None
        self.ik_rate = ik_rate
        self._fresh: _Fresh | None = None
        self._lean: _Lean | None = None
        self._catch: _Catch | None = None
        # The pose the avoider plans the next target's way from, and the solver answering there.
        self._ahead: tuple[np.ndarray, RobustSolver] | None = None

    @property
    def ik_rate(self) -> float | None:
        """How often (Hz) an answer that arrives is solved afresh (see the module); None solves
        every tick."""
        return self._ik_rate

    @ik_rate.setter
    def ik_rate(self, value: float | None) -> None:
        if value is not None and not (math.isfinite(value) and value > 0):
            raise ValueError(f"ik_rate must be a positive number (Hz) or None, got {value!r}")
        self._ik_rate = None if value is None else float(value)

    @property
    def gain(self) -> float:
        """Servo gain, 1/s."""
        return self._gain

    @gain.setter
    def gain(self, value: float) -> None:
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"gain must be a positive number (1/s), got {value!r}")
        self._gain = float(value)
        if self.servo is not None:
            self.servo.gain = self._gain

    @property
    def skeleton(self) -> Skeleton:
        """The chain being driven; set it when the base moves."""
        return self.solver.skeleton

    @skeleton.setter
    def skeleton(self, skeleton: Skeleton) -> None:
        self.solver.skeleton = skeleton
        # The solver's, read on every tick without the two properties in between.
        self._skeleton = skeleton
        self._fresh = None
        self._catch = None
        # The damping of the target's pseudo-inverse (see _goal_rates), px^2, per chain.
        self._damping = (0.01 * skeleton.reach) ** 2
        self._lengths = skeleton.lengths.tolist()
        self._base = tuple(skeleton.base.tolist())
        # A short chain's tip is carried along over floats (see _chain_rates).
        self._float_chain = skeleton.is_chain and skeleton.count <= FLOAT_LINKS
        if self.avoider is not None:
            self.avoider.clearance.skeleton = skeleton

    @property
    def solver_name(self) -> str:
        """The solver in use (``ccd``, ``jacobian_transpose``, ``dls``, ``fabrik``)."""
        return self.solver.solver_name

    def set_solver(self, name: str) -> None:
        """Switch solver from the next tick on (``ccd``, ``jacobian_transpose``, ``dls``, ``fabrik``)."""
        self.solver.solver_name = name
        self._fresh = self._lean = None
        self._catch = None

    def _goal_rates(
        self,
        measured: np.ndarray,
        target: np.ndarray | TargetSet | None,
        dt: float,
        base_motion: tuple[np.ndarray, float] | None,
    ) -> tuple[np.ndarray | None, bool]:
        """Joint rates (rad/s) that carry the end effectors along with moving targets, and
        whether a target jumped.

        The least-norm rates for the targets' velocities relative to the base (a damped
        pseudo-inverse of the stacked Jacobian), so the chain moves with its targets, and holds
        a still target while its base is carried, instead of lagging behind; the servo only
        closes the error on top. Rates beyond a joint's speed limit are scaled down together,
        keeping the direction (per branch on the base, for a tree of several). Rates over
        ``JUMP`` times the limit mean a target jumped (a new reach step): a new goal to brake
        toward, not a motion to follow.
        """
        previous, self._last_target = self._last_target, target
        if target is None or previous is None:
            return None, False
        if isinstance(target, TargetSet) != isinstance(previous, TargetSet):
            return None, True
        if self._float_chain and not isinstance(target, TargetSet):
            return self._chain_rates(measured, target, previous, dt, base_motion)
        skeleton = self._skeleton
        if isinstance(target, TargetSet):
            if not np.array_equal(previous.links, target.links):
                return None, True
            points, links = target.points, target.links
            velocity = (target.points - previous.points) / dt
        else:
            points, links = target[None, :], None
            velocity = ((target - previous) / dt)[None, :]
        if base_motion is not None:
            # The base carries each effector at its own velocity plus its spin about the base.
            base_velocity, spin = base_motion
            arms = points - skeleton.base
            velocity = velocity - base_velocity - spin * np.column_stack((-arms[:, 1], arms[:, 0]))
        if not velocity.any():
            return None, False
        if links is None:
            arms = jacobian(skeleton, measured)
        else:
            arms = stacked_jacobian(skeleton, measured, links)
        velocity = velocity.reshape(-1)
        eye = np.eye(len(velocity))
        rates = arms.T @ np.linalg.solve(arms @ arms.T + self._damping * eye, velocity)
        # Branches on the base move independently (a creature's legs; a chain is one branch):
        # each is scaled on its own, so a swinging leg at its speed limit does not slow the
        # planted ones, and a leg whose target jumped gets no rates while the others keep theirs.
        over = np.abs(rates) / self.max_speed
        roots = skeleton.roots
        worst = np.zeros(skeleton.count)
        np.maximum.at(worst, roots, over)
        per_link = worst[roots]
        jumped = per_link > JUMP
        return np.where(jumped, 0.0, rates / np.maximum(per_link, 1.0)), bool(jumped.any())

    def _chain_rates(
        self,
        measured: np.ndarray,
        target: np.ndarray,
        previous: np.ndarray,
        dt: float,
        base_motion: tuple[np.ndarray, float] | None,
    ) -> tuple[np.ndarray | None, bool]:
        """:meth:`_goal_rates` of a short chain's tip over floats, the same numbers: the 2x2
        system in closed form (np.linalg.solve and the checked Jacobian cost more than the
        system itself), one branch to scale, and no numpy call on two or ten numbers."""
        (tx, ty), (px, py) = target.tolist(), previous.tolist()
        vx, vy = (tx - px) / dt, (ty - py) / dt
        bx, by = self._base
        if base_motion is not None:
            (bvx, bvy), spin = base_motion[0].tolist(), base_motion[1]
            vx, vy = vx - bvx - spin * -(ty - by), vy - bvy - spin * (tx - bx)
        if not (vx or vy):
            return None, False
        rates = damped_rates(
            self._lengths,
            self._base,
            self._skeleton.base_angle,
            measured.tolist(),
            (vx, vy),
            self._damping,
        )
        # One branch: every rate is scaled by the one furthest over its speed limit (as
        # np.maximum.at and np.maximum take it: a NaN wins).
        worst = 0.0
        for rate, speed in zip(rates, self._speeds, strict=True):
            over = abs(rate) / speed
            if over > worst or over != over:
                worst = over
        if worst > JUMP:
            return np.zeros(len(rates)), True
        if worst <= 1.0:
            return np.array(rates), False  # divided by 1.0, each rate is itself
        return np.array([rate / worst for rate in rates]), False

    def _know_strain(self, gravity: tuple[float, float] | np.ndarray) -> None:
        """Tell a chain's solver, and its avoider for the clear answers it finds, what holding
        a pose still under ``gravity`` (px/s^2) takes of the motors, so that they prefer poses
        the motors can hold (see :attr:`RobustSolver.strain`)."""
        pull = (float(gravity[0]), float(gravity[1]))
        if pull == self._gravity:
            return
        self._gravity = pull
        if self._fresh is not None:
            # What the kept answer asks of the motors was asked under the gravity before.
            self._fresh.strain = None
        servo = self.servo
        solver = self.solver
        known = servo is not None and self.skeleton.is_chain
        solver.most_strain = servo.most_strain(pull) if known else math.inf
        if not known or solver.most_strain <= KEPT_STRAIN:
            # Nothing to ask (no servo, or a tree); or no pose asks as much of the motors as
            # any of the strain's uses looks for (the least, KEPT_STRAIN; without gravity,
            # nothing at all), and nothing need ask it: every shipped chain is so.
            solver.strain = solver.strain_slope = None
        else:
            world = self._skeleton.world_angles
            solver.strain = lambda angles: servo.strain(world(angles), pull)
            # The servo's slope is per joint turning everything beyond it: a chain's local
            # angles.
            solver.strain_slope = lambda angles: servo.strain_slope(world(angles), pull)
        if self.avoider is not None:
            self.avoider.clearance.strain = solver.strain

    def hold(self, measured: np.ndarray) -> None:
        """Stop pushing: hold the ``measured`` pose (radians) instead of solving, until
        :meth:`release`. The response to a blocked chain: pressing on against an obstacle or a
        stalled motor only grinds."""
        self._held = self.skeleton.clamp(np.asarray(measured, dtype=float).copy())
        self._holding = True
        self._fresh = None
        self._catch = None
        # A cached answer is one the chain could not get to: solve afresh when released.
        self.solver.reset()
        if self.avoider is not None:
            self.avoider.reset()

    def release(self) -> None:
        """Solve toward the target again after :meth:`hold`."""
        self._holding = False
        self._fresh = self._lean = None
        self._catch = None

    @property
    def holding(self) -> bool:
        """True between :meth:`hold` and :meth:`release`."""
        return self._holding

    def command(
        self,
        measured: np.ndarray,
        target: np.ndarray | TargetSet | None,
        *,
        velocities: np.ndarray | None = None,
        gravity: tuple[float, float] | np.ndarray = (0.0, 0.0),
        dt: float | None = None,
        base_motion: tuple[np.ndarray, float] | None = None,
        upcoming: np.ndarray | TargetSet | None = None,
    ) -> Command:
        """Motor commands toward ``target`` from the ``measured`` local angles (radians).

        ``target`` is the tip's target point (px) or, for a tree, a
        :class:`~ikgame.kinematics.TargetSet` of effector links and points. With a servo,
        ``velocities`` (rad/s, child - parent), ``gravity`` (px/s^2) and the tick ``dt`` (s)
        are needed too, and while the base moves ``base_motion``: its velocity (px/s) and spin
        (rad/s). With no target the chain holds the last pose it was asked for (or its current
        one). ``upcoming`` is the target that will follow this one, if known (a level script's
        next step): while the chain rests (every joint slower than :data:`SETTLING`), the
        avoider plans the way there on ticks it has no search of its own (see
        :meth:`~ikgame.kinematics.Avoider.foresee`).
        """
        servo = self.servo
        if servo is not None and (velocities is None or dt is None):
            raise ValueError("a controller with a servo needs the joint velocities and dt")
        goal_rates, jumped, moved = None, False, False
        if servo is not None:
            self._know_strain(gravity)
            moved = target is not None and _moved(target, self._last_target)
            goal_rates, jumped = self._goal_rates(measured, target, dt, base_motion)
        if target is None or self._holding:
            self._fresh = self._lean = None
            if self._held is None:
                self._held = self.skeleton.clamp(measured.copy())
            solution = Solution(self._held, SolveStatus.SUCCESS, 0, 0.0)
        else:
            solution = None
            if servo is not None and base_motion is None and not jumped:
                self._lean = None  # the base stands: nothing carries the chain
                solution = self._reuse(moved, goal_rates, dt, measured, velocities)
            elif servo is not None and not (moved or jumped):
                solution = self._leaning(dt)
            if solution is None:
                solution = self._caught(measured, target, velocities, moved, base_motion, dt)
            if solution is None:
                solution = self._solve(measured, target)
            self._held = solution.angles
            if (
                upcoming is not None
                and self.avoider is not None
                and base_motion is None
                and velocities is not None
                and _largest(velocities) <= SETTLING
            ):
                self.avoider.foresee(
                    self._wrapped(measured), upcoming, self.arrival, self._solve_ahead
                )
        if self._all_limited:
            error = solution.angles - measured  # joint_error with nothing to wrap
        else:
            error = joint_error(solution.angles, measured, self._limited)
        if servo is None:
            rates = np.clip(self.gain * error, -self.max_speed, self.max_speed)
            return Command(solution, rates)
        if moved or self._rested_short(solution, error, velocities):
            # The goal may be within the torque budget now: stalled joints try again.
            servo.retry()
        steered = self.avoider is not None and not self.avoider.idle
        drive = servo.command(
            error,
            self._skeleton.world_angles(measured),
            velocities,
            gravity,
            dt,
            goal_rates,
            steered=steered,
            together=not steered
            and _largest(error) > NEAR
            and (self._weightless_way() or self._strained_way(solution, error)),
        )
        return Command(solution, drive.rates, drive)

    def _caught(
        self,
        measured: np.ndarray,
        target: np.ndarray | TargetSet,
        velocities: np.ndarray | None,
        moved: bool,
        base_motion: tuple[np.ndarray, float] | None,
        dt: float | None,
    ) -> Solution | None:
        """The answer where a chain's end was caught on its way to a still target (see
        :mod:`~ikgame.control.catching`), or None to solve as usual.

        A chain is caught where its end heads at the target and must brake now to stop at it
        (:func:`~ikgame.control.catching.catch_pose`), the pose it would stop on putting the end
        within :data:`CATCH_WITHIN` of it, while the solver's answer lies further on than that
        pose is from the chain: the end would meet the target early and sweep on. Caught, the
        chain stops on that pose, which is refined once as the chain comes in to it (the answer
        from where it will stop, see :meth:`_finish`, if near); at rest it finishes from where
        it is, for as long as the target holds still. Only a chain whose motors hold any pose
        with torque to spare (the strain left unasked, see :meth:`_know_strain`) and that no
        avoider steers is caught: a pose on the way is no pose weak motors were checked to
        hold, nor one checked clear of obstacles.

        On `60_tight_limits_seven` (FABRIK, seven links limited to +-12 deg), the end passed the
        fifth target at 1,000 px/s, 15 deg from the answer on some joints, and swung 17.6% of
        the approach past it; caught, 0.5%. FABRIK's 150 to 185 light links under gravity (59,
        65, 72) went 6-7% past their third targets; caught, not at all.
        """
        avoider = self.avoider
        if (
            self.servo is None
            or velocities is None
            or dt is None
            or moved
            or base_motion is not None
            or isinstance(target, TargetSet)
            or self.solver.strain is not None
            or (avoider is not None and not avoider.idle)
        ):
            self._catch = None
            return None
        catch = self._catch
        start = self._wrapped(measured)
        if catch is not None:
            if catch.finishing or _largest(velocities) <= SETTLING:
                catch.finishing = True
                return self._finish(measured, target)
            if not catch.refined and _largest(catch.pose - start) <= NEAR:
                catch.refined = True
                refined = self._finish(catch.pose, target)
                if _largest(refined.angles - catch.pose) <= NEAR:
                    catch.pose, catch.error = refined.angles, refined.error
            return Solution(catch.pose, SolveStatus.SUCCESS, 0, catch.error)
        held = self._held
        if held is None or _largest(held - start) <= NEAR:
            return None  # on the answer's doorstep: it is braked toward as it is
        skeleton = self._skeleton
        (ex, ey), velocity = self._end_motion(measured, velocities)
        tx, ty = target.tolist()
        ahead = time_to_nearest((tx - ex, ty - ey), velocity)
        if ahead is None:
            return None
        braking = self.servo.braking(skeleton.world_angles(measured), velocities, self._gravity)
        pose = catch_pose(start, velocities, ahead, braking, dt)
        if pose is None:
            return None
        pose = skeleton.clamp(pose)
        if _largest(held - pose) <= max(NEAR, _largest(pose - start)):
            return None  # the end meets the target past halfway to the answer: no whip
        error = float(np.hypot(*(np.asarray(target) - forward_kinematics(skeleton, pose)[0][-1])))
        if error > CATCH_WITHIN:
            return None  # the chain's turning bends the end's way: not caught yet
        self._catch = _Catch(pose, error)
        return Solution(pose, SolveStatus.SUCCESS, 0, error)

    def _end_motion(
        self, measured: np.ndarray, velocities: np.ndarray
    ) -> tuple[tuple[float, float], tuple[float, float]]:
        """A chain's end (px) and its velocity (px/s) at the ``measured`` angles (radians) and
        joint ``velocities`` (rad/s)."""
        if self._float_chain:
            return end_motion(
                self._lengths,
                self._base,
                self._skeleton.base_angle,
                measured.tolist(),
                velocities.tolist(),
            )
        end = forward_kinematics(self._skeleton, measured)[0][-1]
        velocity = jacobian(self._skeleton, measured) @ velocities
        return (float(end[0]), float(end[1])), (float(velocity[0]), float(velocity[1]))

    def _finish(self, pose: np.ndarray, target: np.ndarray) -> Solution:
        """The answer from ``pose`` (radians) for a chain caught on its way, its end near the
        target: the solver's, if near the pose (within :data:`NEAR`), else the damped
        least-squares answer from it, either steered clear of obstacles (see :meth:`_steered`:
        only the answer taken is). Solved afresh, a solver whose answers swing the whole
        chain (FABRIK) can answer a pose far from one whose end is within pixels of the target,
        and the chain would whip through the target again on its way there."""
        start = self._wrapped(pose)
        solution = self.solver.solve(
            start, target, max_iterations=self.iterations, tolerance=self.arrival
        )
        if _largest(solution.angles - start) > NEAR:
            solution = solve_dls(
                self._skeleton,
                start,
                target,
                max_iterations=FINISH_ITERATIONS * self.iterations,
                tolerance=self.arrival,
            )
        return self._steered(start, solution, target)

    def _weightless_way(self) -> bool:
        """True for a chain of up to :data:`~ikgame.control.servo.SECTION_LINKS` links without
        gravity: far from its goal (some joint more than :data:`NEAR` off), the servo then
        brings every joint in together, along the straight line in joint space.

        Without gravity every pose holds with no torque, so nothing on the way asks the far
        joints to fold in first (under gravity that shortens an arm the near joints lift: see
        :meth:`_strained_way`), and each joint alone does harm. The light far joints, with the
        most torque for their inertia, near their goals first, and stopping their relative
        motion late in the near joints' swing throws the far links' momentum onto the near
        joints. On `45_zero_g_ten_light_links` (DLS, third target, the base swinging 120 deg
        while the chain unfolds) the six far joints asked 20 to 160 rad/s^2 to stop unfolding,
        which took eight times the torque limits of the two joints at the base; one factor for
        every joint's acceleration (a chain this short is scaled as a whole) left each 7 to 15%
        of its braking, the base motor pushed on at 0.7 to 0.9 of its limit (the chain's kinetic
        energy rose from 24,000 to 151,000 in 0.28 s), the base hit its stop at 2.7 rad/s and
        the tip passed the target by 47.5% of the approach. Brought in together, every joint's
        velocity is in proportion to its error, so the chain's braking is one stop of the whole
        motion, the one the servo's *braking together* checks the torques of: 0.0%, and every
        solver reaches 45's targets 0.2 to 0.4 s sooner. A longer chain keeps the accelerations
        of the joints up to one that runs out whole, so the far joints' stopping does not take
        the near ones' braking; brought in together there, a joint with a long way to go set
        every joint's pace, and `33_zero_g_thirty_five_links` took 0.59 and 0.67 s instead of
        0.52 to reach its targets with CCD and FABRIK.
        """
        return (
            self._gravity is not None
            and not any(self._gravity)
            and self.skeleton.is_chain
            and self.skeleton.count <= SECTION_LINKS
        )

    def _strained_way(self, solution: Solution, error: np.ndarray) -> bool:
        """True, for a chain far from its goal (some joint more than :data:`NEAR` off), when
        holding that goal still strains its motors (past :data:`KEPT_STRAIN` of some limit)
        but they can hold it (within :data:`~ikgame.kinematics.recovery.STRAINED`), and every
        pose on the straight line in joint space to it is one the motors can hold
        (:func:`~ikgame.kinematics.recovery.holds_along`): the servo then brings every joint
        in together, along that line.

        Each joint alone, the light far joints get up to speed sooner and arrive first, and the
        pose on the way, the far joints bent and the near ones not yet, can ask more of a weak
        motor than the goal or any pose on the line does. Seven weakening links hanging
        (`40_seven_weak_links_hanging`) went to such a pose on their way to a goal that asked
        at most 0.76 of any motor: three joints past their limits, they stalled there and the
        arm hung 65 px off the target; six (`44_six_weak_links_bent_back`), on their way to a
        goal that asked 0.92 along a line that asked no more, went through poses asking 1.25
        and collapsed. Where the line itself is past the motors (an arm lifted out straight),
        the far joints folding in first shortens the arm the near ones lift, and the joints
        are left to come in each at its own pace: brought in together, the five weak links of
        `29_five_weak_links` stalled lifting their stretched arm.
        """
        strain = self.solver.strain
        if strain is None:
            return False
        goal = solution.angles
        fresh = self._fresh
        # The solver's own answer, kept: its strain was asked once (see _straining).
        kept = fresh is not None and not fresh.carried and fresh.angles is goal
        if not KEPT_STRAIN < (self._strain(fresh) if kept else strain(goal)) <= STRAINED:
            return False
        return holds_along(strain, goal - error, error)

    def _rested_short(self, solution: Solution, error: np.ndarray, velocities: np.ndarray) -> bool:
        """True when a joint stalled and the chain has come to rest (every joint slower than
        :data:`SETTLING`) short of a goal the motors can hold (within
        :data:`~ikgame.kinematics.recovery.STRAINED`), through poses they can hold (every one
        on the straight line in joint space to it, :func:`~ikgame.kinematics.recovery.holds_along`):
        the stalled joints then try again.

        A joint stalls when it is carried away from its goal at its torque limit while its
        load takes over half of it; the stall lasts until the target moves (or the goal comes
        to lie the other way), so that an arm its torque cannot hold comes to rest rather than
        swing. But the chain's own swing can
        carry a weak far joint off on the way to a goal the motors hold: brought in together,
        the last of the five weak links of `29_five_weak_links` was pushed 34 deg back from a
        goal that asked 0.94 of its motors, stalled, and the arm rested 30 px off the target.
        At rest that swing has passed, and a goal they can hold along a way they can hold is
        no load the motors cannot beat.
        """
        servo = self.servo
        strain = self.solver.strain
        if strain is None or servo is None or not servo.any_stalled:
            return False
        if _largest(velocities) > SETTLING:
            return False
        goal = solution.angles
        return strain(goal) <= STRAINED and holds_along(strain, goal - error, error)

    def _solve(self, measured: np.ndarray, target: np.ndarray | TargetSet) -> Solution:
        """The solver's answer from the ``measured`` pose (see :meth:`_steered`)."""
        start = self._wrapped(measured)
        tree = isinstance(target, TargetSet)
        solve = self.solver.solve_targets if tree else self.solver.solve
        solution = solve(start, target, max_iterations=self.iterations, tolerance=self.arrival)
        solution = self._steered(start, solution, target)
        self._lean = _Lean(solution) if tree and self.solver.leaning else None
        return solution

    def _leaning(self, dt: float) -> Solution | None:
        """The answer leaning toward targets beyond reach while the base carries the chain
        (see :attr:`RobustSolver.leaning`), kept for :data:`IK_RATE`'s frame; None when it
        must be solved now.

        It changes only as the base moves: solved every tick, a ten-bone body crossing the
        stage (`17_head_and_tail`) spent over a third of its run in the ten passes of a solve
        that cannot arrive. Kept, it costs no iterations."""
        lean = self._lean
        if lean is None or self._ik_rate is None:
            return None
        lean.ticks += 1
        if lean.ticks * dt * self._ik_rate > 1.0 - 1e-9:
            return None
        return replace(lean.solution, iterations=0)

    def _steered(
        self, start: np.ndarray, solution: Solution, target: np.ndarray | TargetSet
    ) -> Solution:
        """The answer ``solution`` from the pose ``start``, steered clear of obstacles; one
        that arrives is kept to be driven toward until the next solve."""
        avoider = self.avoider
        if avoider is not None:
            solution = avoider.steer(start, solution, target, self.arrival)
        # Only a servo's answers are driven toward between solves (see _reuse).
        settled = (
            self.servo is not None
            and self._ik_rate is not None
            and solution.status is SolveStatus.SUCCESS
            and (avoider is None or avoider.idle)
            and _largest(solution.angles - start) <= NEAR
        )
        self._fresh = _Fresh(solution, solution.angles) if settled else None
        return solution

    def _wrapped(self, measured: np.ndarray) -> np.ndarray:
        """The ``measured`` pose, its free joints wrapped to [-pi, pi]."""
        if self._all_limited:
            return np.array(measured, dtype=float)  # nothing to wrap
        wrapped = [wrap_angle(a) for a in np.asarray(measured, dtype=float).tolist()]
        return np.where(self._limited, measured, wrapped)

    def _solve_ahead(self, start: np.ndarray, target: np.ndarray | TargetSet) -> Solution:
        """The solver's answer for ``target`` from the pose ``start``, as a solver of the same
        kind gives it on its first call for that target and, asked again from the same pose
        (the same array), on its next ones. It is a solver of its own: the chain's keeps the
        answer and the search for the target it is on."""
        ahead = self._ahead
        if ahead is None or ahead[0] is not start:
            solver = RobustSolver(self._skeleton, self.solver.solver_name)
            solver.strain = self.solver.strain
            solver.strain_slope = self.solver.strain_slope
            solver.most_strain = self.solver.most_strain
            ahead = self._ahead = (start, solver)
        solver = ahead[1]
        solve = solver.solve_targets if isinstance(target, TargetSet) else solver.solve
        return solve(start, target, max_iterations=self.iterations, tolerance=self.arrival)

    def _reuse(
        self,
        moved: bool,
        goal_rates: np.ndarray | None,
        dt: float,
        measured: np.ndarray,
        velocities: np.ndarray,
    ) -> Solution | None:
        """The last answer that arrived, while it is not yet time to solve afresh (see
        :data:`IK_RATE`), carried along with a moving target by ``goal_rates`` (rad/s); None
        when it must be solved now.

        An answer for a target that holds still, the solver's own (not carried) and one that
        holding still strains the motors (past :data:`KEPT_STRAIN` of some limit), is solved
        afresh only when the chain is not coming in to it: a joint carried away from it, or
        every joint at rest (:data:`SETTLING`) with one still short of it by more than the
        servo's creep. Solved afresh from a pose in motion, the answer chases the chain's own
        lag: where the joints near the base come in slowly (weak motors holding heavy links),
        the solver bends the light far joints to make up for them, which the motors nearer the
        base, with little torque to spare, then cannot carry, and the arm sags and comes back.
        Where the motors have torque to spare, solving afresh on the way steers the end's
        course (sixty light links coming in with their answer kept passed the target by 8% of
        the approach), and solved from where the motors hold a chain that stopped short, the
        answer brings the end the last pixels.
        """
        fresh = self._fresh
        if fresh is None or self._ik_rate is None:
            return None
        fresh.ticks += 1
        if fresh.ticks * dt * self._ik_rate > 1.0 - 1e-9:
            if (
                moved
                or fresh.carried
                or not self._straining(fresh)
                or not self._coming_in(fresh.angles, measured, velocities)
            ):
                return None
            fresh.ticks = 0
        if moved:
            if goal_rates is None:
                return None
            fresh.angles = self._skeleton.clamp(fresh.angles + goal_rates * dt)
            fresh.carried = True
        answer = fresh.solution
        return Solution(fresh.angles, SolveStatus.SUCCESS, 0, answer.error, answer.errors)

    def _straining(self, fresh: _Fresh) -> bool:
        """True when holding the ``fresh`` answer still takes more than :data:`KEPT_STRAIN` of
        some motor's torque limit (see :attr:`RobustSolver.strain`)."""
        return self._strain(fresh) > KEPT_STRAIN

    def _strain(self, fresh: _Fresh) -> float:
        """What holding the ``fresh`` answer still takes of the motors' torque limits (the
        largest share), asked once per answer (see :attr:`RobustSolver.strain`)."""
        if fresh.strain is None:
            strain = self.solver.strain
            fresh.strain = 0.0 if strain is None else strain(fresh.angles)
        return fresh.strain

    def _coming_in(self, goal: np.ndarray, measured: np.ndarray, velocities: np.ndarray) -> bool:
        """True while no joint is carried away from ``goal`` (radians) and some joint still
        turns toward it, or every joint is at rest within the servo's creep of it."""
        short = 2.0 * SETTLING / self.gain
        moving = off = False
        for error, velocity in zip(
            joint_error(goal, measured, self._limited).tolist(), velocities.tolist(), strict=True
        ):
            if abs(velocity) > SETTLING:
                if error * velocity < 0.0:
                    return False
                moving = True
            elif abs(error) > short:
                off = True
        return moving or not off


@dataclass(eq=False)
class _Catch:
    """Where a chain's end was caught on its way (see :meth:`Controller._caught`): the pose it
    stops on (radians), its end's distance from the target there (px), whether that pose was
    refined as the chain came in to it, and whether the chain has come to rest and finishes
    from where it stopped."""

    pose: np.ndarray
    error: float
    refined: bool = False
    finishing: bool = False


@dataclass(eq=False)
class _Lean:
    """An answer leaning toward targets beyond reach (see :meth:`Controller._leaning`) and
    the ticks since it was solved."""

    solution: Solution
    ticks: int = 0


@dataclass(eq=False)
class _Fresh:
    """An answer that arrived, where a moving target has carried it since (radians), the
    ticks since it was solved, whether it was carried (so is not the solver's own) and what
    holding it still takes of the motors, once asked (see :meth:`Controller._straining`)."""

    solution: Solution
    angles: np.ndarray
    ticks: int = 0
    carried: bool = False
    strain: float | None = None


def _largest(values: np.ndarray) -> float:
    """``float(np.abs(values).max())``: the largest magnitude, NaN if any is NaN.

    >>> _largest(np.array([0.01, -0.1])), _largest(np.array([0.1, np.nan]))
    (0.1, nan)
    """
    if len(values) > FLOAT_LINKS:
        return float(np.abs(values).max())
    # Joint by joint over floats: numpy's calls cost more on a few joints.
    largest = 0.0
    for value in values.tolist():
        size = abs(value)
        if size != size:
            return size
        if size > largest:
            largest = size
    return largest


def _moved(target: np.ndarray | TargetSet, last: np.ndarray | TargetSet | None) -> bool:
    """True when ``target`` differs from the ``last`` one (a point, or a set of targets)."""
    if last is None or isinstance(target, TargetSet) != isinstance(last, TargetSet):
        return True
    if isinstance(target, TargetSet):
        return not (
            np.array_equal(target.links, last.links) and np.array_equal(target.points, last.points)
        )
    # Two floats each: compared as lists, without numpy's calls.
    return target.tolist() != last.tolist()
