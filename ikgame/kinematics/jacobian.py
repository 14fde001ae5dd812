"""Jacobian solvers for a chain: Jacobian transpose with an adaptive step, damped least squares.

Both linearise the end effector around the current angles, ``dP = J dtheta``, where column ``i``
of ``J`` is the perpendicular of ``P - p_i`` (rotating joint ``i`` swings everything beyond it
about ``p_i``). Both take a step, keep it only when the error fell by a fair share of what the
linear model promised (``SUFFICIENT_DECREASE``), and adapt their step (Jacobian transpose) or
damping (damped least squares) from the outcome, so the error never rises from one iteration to
the next. Steps are clamped to the joint limits,
which is projected gradient descent: a joint pushed into its limit just stays there.

A straight chain whose target lies on its own line (inside its reach, or behind the base) is a
saddle: the gradient vanishes there although the target can be reached. When a solver stops
moving, :func:`_escape_saddle` looks for a direction of negative curvature of the squared error
and bends the chain along it; only when there is none (a true minimum, such as a chain stretched
toward a target out of reach) does the solve end in ``FAILURE``.

Angles are radians, lengths and positions pixels.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from numbers import Real
from typing import Final

import numpy as np

from ikgame.kinematics._floats import check_chain
from ikgame.kinematics.ccd import TRIVIAL_ARC_LENGTH
from ikgame.kinematics.skeleton import Skeleton, check_angles, check_point
from ikgame.kinematics.solver import Solution, SolveStatus

__all__ = ["jacobian", "solve_jacobian_transpose", "solve_dls"]

GAIN_GROW: Final = 2.0
"""Jacobian transpose: factor (dimensionless) on the step gain after a step that lowered the error.

The seed grows its step by 7 while the error falls. Our step is a gain on the exact line-search
step of the linearised problem, which is already the right size wherever the linearisation
holds, so growing only needs to win back what rejections took: doubling does that in a few
iterations without overshooting."""

GAIN_SHRINK: Final = 0.5
"""Jacobian transpose: factor (dimensionless) on the step gain after a rejected step.

The seed divides by 7; halving loses less when a single long step overshot."""

GAIN_MAX: Final = 1.0
"""Jacobian transpose: largest gain (dimensionless) on the linearised line-search step.

Gains above 1 overshoot the linear model; on random chains of 3 to 30 links they needed more
iterations, both for distant targets and for tracking a moving one."""

DAMPING_BIAS: Final = 1e-4
"""Damped least squares: floor on lambda^2 as a fraction of reach^2 (dimensionless).

``J J^T`` scales with reach^2 (px^2); the floor keeps it invertible at a singular pose (a
straight chain) even when the error is zero."""

MU_INITIAL: Final = 1.0
"""Damped least squares: starting Levenberg-Marquardt factor on the damping (dimensionless)."""

MU_DOWN: Final = 0.5
"""Damped least squares: factor on mu after an accepted step (trust the linear model more)."""

MU_UP: Final = 4.0
"""Damped least squares: factor on mu after a rejected step (damp harder, shorter step)."""

MU_MIN: Final = 1e-3
"""Damped least squares: smallest mu, so that however well the steps go, a chain nearing a
singular pose is still damped in proportion to its error."""

MU_MAX: Final = 1e12
"""Damped least squares: largest mu, which keeps lambda^2 finite; a step this damped is trivial."""

MAX_STEP: Final = 0.5
"""Damped least squares: largest change of any joint in one iteration, radians.

The linear model swaps a rotation's arc for its tangent; at 0.5 rad the two differ by about an
eighth of the lever arm, still a useful prediction, while far targets take only a few steps.
Near a singular pose the damped step can be far longer than that and land anywhere."""

ERROR_CLAMP: Final = 1.0
"""Both solvers: longest error vector a step aims to cancel, as a fraction of the reach.

A target farther than the whole chain gives a step no better direction, only a longer (worse)
linear extrapolation; clamping also keeps squared distances finite for absurd targets."""

SUFFICIENT_DECREASE: Final = 0.1
"""Both solvers: a step is kept only if the squared error fell by at least this fraction
(dimensionless) of the fall the linear model promised.

Merely lower is not enough: toward a target out of reach the linear step can swing the chain
past the best pose to a mirror image that is a hair better, and then swing back, forever."""

ESCAPE_ANGLE: Final = 0.05
"""Saddle escape: largest joint change of the bend out of a saddle, radians (about 3 degrees)."""

NEGATIVE_CURVATURE: Final = 1e-9
"""Saddle escape: curvature below ``-NEGATIVE_CURVATURE * reach^2`` (px^2/rad^2) counts as
negative; anything closer to zero is rounding noise in a Hessian of size about reach^2."""

_TWO_PI: Final = 2.0 * math.pi


def jacobian(skeleton: Skeleton, angles: np.ndarray) -> np.ndarray:
    """The (2, n) positional Jacobian of a chain's end effector, px per radian.

    Column ``i`` is ``d(end effector) / d(angle i)``, the perpendicular of ``end - joint_i``.

    >>> jacobian(Skeleton.chain([10, 10]), np.zeros(2))[1].tolist()
    [20.0, 10.0]
    """
    check_chain(skeleton)
    points = _chain_points(skeleton, check_angles(angles, skeleton.count))
    arms = points[-1] - points[:-1]
    return np.vstack((-arms[:, 1], arms[:, 0]))


def solve_jacobian_transpose(
    skeleton: Skeleton,
    angles: np.ndarray,
    target: np.ndarray,
    *,
    max_iterations: int = 10,
    tolerance: float = 1.0,
) -> Solution:
    """Steepest descent on the squared error: ``delta = alpha * J^T e`` with an adaptive alpha.

    ``alpha`` is a gain times ``(e . J J^T e) / |J J^T e|^2``, the step that minimises the
    linearised error along ``J^T e``; it needs no tuning to the chain's size. As in the seed, the
    gain grows while the error falls (up to ``GAIN_MAX``) and shrinks when it does not, and a
    step that did not lower the error enough is undone. ``angles`` (radians) warm-starts the
    solve; ``tolerance`` is in px. The status is ``SUCCESS`` within the tolerance, ``FAILURE``
    when no step gets closer (see the module notes), else ``PROCESSING``.

    >>> sol = solve_jacobian_transpose(Skeleton.chain([100, 100]), np.zeros(2), (0, 150))
    >>> sol.status.value, sol.error <= 1.0
    ('success', True)
    """
    gain = 1.0

    def propose(current: np.ndarray, arms: np.ndarray, ex: float, ey: float) -> np.ndarray:
        gradient = arms[:, 0] * ey - arms[:, 1] * ex
        # J J^T e = J g: how the end effector would move along the gradient.
        vx = -float(gradient @ arms[:, 1])
        vy = float(gradient @ arms[:, 0])
        speed_sq = vx * vx + vy * vy
        if speed_sq == 0.0:
            # g = J^T e lies in J's row space, so J g = 0 only when g = 0: a stall.
            return gradient
        return gradient * (gain * (ex * vx + ey * vy) / speed_sq)

    def adapt(improved: bool) -> None:
        nonlocal gain
        gain = _next_gain(gain, improved=improved)

    return _descend(skeleton, angles, target, max_iterations, tolerance, propose, adapt)


def solve_dls(
    skeleton: Skeleton,
    angles: np.ndarray,
    target: np.ndarray,
    *,
    max_iterations: int = 10,
    tolerance: float = 1.0,
) -> Solution:
    """Damped least squares: ``delta = J^T (J J^T + lambda^2 I)^-1 e``, Levenberg-Marquardt style.

    ``lambda^2 = mu * (|e|^2 / 2 + DAMPING_BIAS * reach^2)`` (Sugihara 2011): the damping fades
    as the end effector closes in, so the last steps are nearly Gauss-Newton, and it is strong
    while the target is far or out of reach, where a Gauss-Newton step near a singular pose
    would be huge. ``mu`` falls after an accepted step and rises after a rejected one, which
    damps harder exactly where the linearisation fails. A step is scaled down to change no
    joint by more than ``MAX_STEP``; joints pushing into a limit drop out of the step so the
    others make up for them. ``angles`` (radians) warm-starts the solve; ``tolerance`` is in px.
    The status is as for :func:`solve_jacobian_transpose`.

    >>> sol = solve_dls(Skeleton.chain([100, 100]), np.zeros(2), (0, 150))
    >>> sol.status.value, sol.error <= 1.0
    ('success', True)
    """
    bias = DAMPING_BIAS * skeleton.reach**2
    has_limits = bool(skeleton.limited.any())
    mu = MU_INITIAL

    def propose(current: np.ndarray, arms: np.ndarray, ex: float, ey: float) -> np.ndarray:
        damping = mu * (0.5 * (ex * ex + ey * ey) + bias)
        rx = arms[:, 0]
        ry = arms[:, 1]
        step = _damped_step(rx, ry, ex, ey, damping)
        if has_limits:
            free = ~_pressing(skeleton, current, step)
            if not free.all():
                step = _damped_step(rx * free, ry * free, ex, ey, damping)
        return _capped(step)

    def adapt(improved: bool) -> None:
        nonlocal mu
        mu = _next_mu(mu, improved=improved)

    return _descend(skeleton, angles, target, max_iterations, tolerance, propose, adapt)


def _descend(
    skeleton: Skeleton,
    angles: object,
    target: object,
    max_iterations: object,
    tolerance: object,
    propose: Callable[[np.ndarray, np.ndarray, float, float], np.ndarray],
    adapt: Callable[[bool], None],
) -> Solution:
    """The loop both Jacobian solvers share: step, keep the step only if it helped, adapt.

    ``propose(angles, arms, ex, ey)`` returns a joint step from the current angles, the arms
    ``end - joint_i`` (n, 2) and the (clamped) error vector; ``adapt(improved)`` hears whether
    it was kept. A step that moves the end effector less than ``TRIVIAL_ARC_LENGTH``, or gains
    less than that, is a stall: escape a saddle if there is one, else end in ``FAILURE``.
    """
    current, target, tolerance = _check_solve_inputs(
        skeleton, angles, target, max_iterations, tolerance
    )
    error_clamp = ERROR_CLAMP * skeleton.reach
    points = _chain_points(skeleton, current)
    error = _distance(points[-1], target)
    used = 0
    while error > tolerance:
        if used == max_iterations:
            return _solution(skeleton, current, SolveStatus.PROCESSING, used, error)
        used += 1
        arms = points[-1] - points[:-1]
        ex, ey = _clamped_error(target - points[-1], error, error_clamp)
        trial = skeleton.clamp(current + propose(current, arms, ex, ey))
        trial_points = _chain_points(skeleton, trial)
        trial_error = _distance(trial_points[-1], target)
        stalled = _distance(trial_points[-1], points[-1]) < TRIVIAL_ARC_LENGTH
        improved = trial_error < error and _enough(
            trial - current, arms, target - points[-1], error, trial_error
        )
        if improved:
            stalled = stalled or error - trial_error < TRIVIAL_ARC_LENGTH
            current, points, error = trial, trial_points, trial_error
        if stalled:
            escaped = _escape_saddle(skeleton, current, points, target, error)
            if escaped is None:
                return _solution(skeleton, current, SolveStatus.FAILURE, used, error)
            current, points, error = escaped
        else:
            adapt(improved)
    return _solution(skeleton, current, SolveStatus.SUCCESS, used, error)


def _enough(
    step: np.ndarray, arms: np.ndarray, error_vector: np.ndarray, error: float, trial_error: float
) -> bool:
    """Whether a step lowered ``|e|^2 / 2`` by at least ``SUFFICIENT_DECREASE`` of what the
    linear model ``e - J step`` promised."""
    jx = -float(step @ arms[:, 1])
    jy = float(step @ arms[:, 0])
    promised = float(error_vector[0]) * jx + float(error_vector[1]) * jy - 0.5 * (jx * jx + jy * jy)
    # Factored so that a huge error does not overflow when squared.
    achieved = 0.5 * (error - trial_error) * (error + trial_error)
    return achieved >= SUFFICIENT_DECREASE * promised


def _next_gain(gain: float, *, improved: bool) -> float:
    """The Jacobian-transpose gain after a step: grown (to ``GAIN_MAX``) or shrunk."""
    return min(gain * GAIN_GROW, GAIN_MAX) if improved else gain * GAIN_SHRINK


def _next_mu(mu: float, *, improved: bool) -> float:
    """The damped-least-squares factor after a step: lowered (to ``MU_MIN``) or raised."""
    return max(mu * MU_DOWN, MU_MIN) if improved else min(mu * MU_UP, MU_MAX)


def _pressing(skeleton: Skeleton, angles: np.ndarray, step: np.ndarray) -> np.ndarray:
    """(n,) bool: the joints on a limit that ``step`` (radians) pushes further into it."""
    return ((angles <= skeleton.lower) & (step < 0.0)) | ((angles >= skeleton.upper) & (step > 0.0))


def _capped(step: np.ndarray) -> np.ndarray:
    """``step`` scaled down, if need be, to change no joint by more than ``MAX_STEP``."""
    largest = float(np.abs(step).max())
    if largest > MAX_STEP:
        step *= MAX_STEP / largest
    return step


def _damped_step(
    rx: np.ndarray, ry: np.ndarray, ex: float, ey: float, damping: float
) -> np.ndarray:
    """``J^T (J J^T + damping I)^-1 e`` for the arms ``(rx, ry)``, the 2x2 system in closed form.

    Column ``i`` of ``J`` is ``(-ry_i, rx_i)``.
    """
    a = float(ry @ ry) + damping
    b = -float(rx @ ry)
    c = float(rx @ rx) + damping
    # Positive definite (damping > 0), so the determinant is > 0.
    det = a * c - b * b
    y0 = (c * ex - b * ey) / det
    y1 = (a * ey - b * ex) / det
    return rx * y1 - ry * y0


def _clamped_error(error_vector: np.ndarray, length: float, limit: float) -> tuple[float, float]:
    """``error_vector`` (of length ``length``, px) shortened to at most ``limit`` px."""
    scale = min(1.0, limit / length)
    return float(error_vector[0]) * scale, float(error_vector[1]) * scale


def _escape_saddle(
    skeleton: Skeleton,
    angles: np.ndarray,
    points: np.ndarray,
    target: np.ndarray,
    error: float,
) -> tuple[np.ndarray, np.ndarray, float] | None:
    """Bend a stalled chain along the Hessian's most negative curvature, if that lowers the error.

    For ``f = |target - P|^2 / 2``, ``d2f / (dtheta_i dtheta_j) = J_i . J_j + e . (P - p_k)``
    with ``k = max(i, j)`` and ``e = target - P``. Returns ``(angles, points, error)`` of the
    better of the two bends, or None when ``f`` curves upward every way (a true minimum) or
    neither bend helps (the way out is blocked by limits).
    """
    arms = points[-1] - points[:-1]
    columns = np.vstack((-arms[:, 1], arms[:, 0]))
    pull = arms @ (target - points[-1])
    later = np.maximum.outer(np.arange(skeleton.count), np.arange(skeleton.count))
    eigenvalues, eigenvectors = np.linalg.eigh(columns.T @ columns + pull[later])
    if eigenvalues[0] >= -NEGATIVE_CURVATURE * skeleton.reach**2:
        return None
    bend = eigenvectors[:, 0] * (ESCAPE_ANGLE / float(np.abs(eigenvectors[:, 0]).max()))
    best = None
    for trial in (skeleton.clamp(angles + bend), skeleton.clamp(angles - bend)):
        trial_points = _chain_points(skeleton, trial)
        trial_error = _distance(trial_points[-1], target)
        if trial_error < error and (best is None or trial_error < best[2]):
            best = (trial, trial_points, trial_error)
    return best


def _check_solve_inputs(
    skeleton: Skeleton,
    angles: object,
    target: object,
    max_iterations: object,
    tolerance: object,
) -> tuple[np.ndarray, np.ndarray, float]:
    """Validated ``(start angles clamped to the limits, target, tolerance)`` for a solve.

    The start is a new array, so a solver never changes the caller's angles.
    """
    check_chain(skeleton)
    tol = _check_settings(max_iterations, tolerance)
    start = skeleton.clamp(check_angles(angles, skeleton.count))
    return start, check_point(target), tol


def _check_settings(max_iterations: object, tolerance: object) -> float:
    """Check a solve's iteration budget and tolerance; return the tolerance as a float, px."""
    if (
        isinstance(max_iterations, bool)
        or not isinstance(max_iterations, int | np.integer)
        or max_iterations < 1
    ):
        raise ValueError(f"max_iterations must be an integer >= 1, got {max_iterations!r}")
    # A float is the common case, and the abstract Real check costs more than the solve's checks.
    if type(tolerance) is not float and (
        isinstance(tolerance, bool) or not isinstance(tolerance, Real)
    ):
        raise ValueError(f"tolerance must be a number of px, got {tolerance!r}")
    tol = float(tolerance)
    if not math.isfinite(tol) or tol < 0.0:
        raise ValueError(f"tolerance must be finite and >= 0 px, got {tolerance!r}")
    return tol


def _chain_points(skeleton: Skeleton, angles: np.ndarray) -> np.ndarray:
    """Forward kinematics of a chain without input checks: (n + 1, 2) joints then the end, px.

    :func:`~ikgame.kinematics.skeleton.forward_kinematics` validates its input on every call,
    which would cost more than the rest of an iteration.
    """
    world = angles.cumsum()
    world += skeleton.base_angle
    steps = np.empty((skeleton.count + 1, 2))
    steps[0] = skeleton.base
    np.multiply(skeleton.lengths, np.cos(world), out=steps[1:, 0])
    np.multiply(skeleton.lengths, np.sin(world), out=steps[1:, 1])
    return steps.cumsum(axis=0)


def _wrap_free(skeleton: Skeleton, angles: np.ndarray) -> np.ndarray:
    """Free joints wrapped to [-pi, pi] as :func:`~ikgame.kinematics.ccd.wrap_angle` does;
    limited joints untouched, so none is ever moved the long way round through its limit."""
    if skeleton.all_limited:
        return angles.copy()
    wrapped = np.fmod(angles, _TWO_PI)
    wrapped[wrapped < -math.pi] += _TWO_PI
    wrapped[wrapped > math.pi] -= _TWO_PI
    return np.where(skeleton.limited, angles, wrapped)


def _solution(
    skeleton: Skeleton, angles: np.ndarray, status: SolveStatus, used: int, error: float
) -> Solution:
    # Wrapping moves nothing, so it is done once here rather than after every step.
    return Solution(_wrap_free(skeleton, angles), status, used, error)


def _distance(a: np.ndarray, b: np.ndarray) -> float:
    return math.hypot(float(a[0] - b[0]), float(a[1] - b[1]))
