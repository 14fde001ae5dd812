"""The chain's dynamics over Python floats, for short chains and small trees.

On a few links numpy's per-call overhead costs more than the arithmetic: the servo walks them
link by link instead. Every sum here adds the same numbers in the same order as the numpy code of
:mod:`ikgame.control.dynamics`, so both give the same floats (tested), and which one runs
changes nothing but the time.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ikgame.control.dynamics import (
    ChainInertia,
    ListLoads,
    at_limits,
    ease,
    give_way,
    listed_factor,
    plus_loads,
)

Loads = ListLoads
"""Joint torques, then the x and y of the pivot forces, per joint."""

_Pulled = tuple[list[float], list[float], list[float], list[float]]
"""See :meth:`FloatInertia.pulled`."""


class FloatInertia:
    """A :class:`ChainInertia` as lists of floats, with its sums along the links."""

    def __init__(self, chain: ChainInertia) -> None:
        self.count = chain.count
        self.parents = chain.parent_list
        self.chain = chain.is_chain
        self.length_array = np.asarray(chain.lengths, dtype=float)
        self.lengths: list[float] = self.length_array.tolist()
        self.masses: list[float] = np.asarray(chain.masses, dtype=float).tolist()
        self.moments: list[float] = np.asarray(chain.moments, dtype=float).tolist()
        self.mass_beyond: list[float] = chain.mass_beyond.tolist()
        self.moment_beyond: list[float] = chain.moment_beyond.tolist()
        # (child, parent) pairs from the last child to the first: the order sums gather in.
        self.hanging = [(i, p) for i, p in reversed(list(enumerate(self.parents))) if p >= 0]
        self._pulled: tuple[tuple[float, float], _Pulled] | None = None

    def pulled(self, gravity: tuple[float, float]) -> _Pulled:
        """A serial chain's loads of ``gravity`` (px/s^2) that no pose changes, as
        :meth:`_ChainPose.rest` sums them tip to base: per joint, the x and y of the force on
        everything beyond it, and those plus the next joint's (the pair its torque turns).
        Worked out again only when the gravity changes."""
        pulled = self._pulled
        if pulled is not None and pulled[0] == gravity:
            return pulled[1]
        n, masses = self.count, self.masses
        gx, gy = 0.0 - gravity[0], 0.0 - gravity[1]
        force_x, force_y, pair_x, pair_y = [0.0] * n, [0.0] * n, [0.0] * n, [0.0] * n
        gsx = gsy = gbx = gby = -0.0
        for i in range(n - 1, -1, -1):
            m = masses[i]
            gsx += m * gx
            gsy += m * gy
            force_x[i], force_y[i], pair_x[i], pair_y[i] = gsx, gsy, gsx + gbx, gsy + gby
            gbx, gby = gsx, gsy
        forces = force_x, force_y, pair_x, pair_y
        self._pulled = gravity, forces
        return forces

    def along(self, values: list[float]) -> list[float]:
        """Each link's value plus all its ancestors' (``ChainInertia.along``)."""
        if self.chain:
            out = values[:]
            for i in range(1, self.count):
                out[i] = out[i - 1] + out[i]
            return out
        out = values[:]
        for i, parent in enumerate(self.parents):
            if parent >= 0:
                out[i] = out[i] + out[parent]
        return out

    def beyond(self, values: list[float]) -> list[float]:
        """Each link's value plus everything hanging from it (``ChainInertia.beyond``)."""
        out = values[:]
        for child, parent in self.hanging:
            out[parent] = out[child] + out[parent]
        return out

    def with_children(self, values: list[float]) -> list[float]:
        """Each link's value plus those of the links hanging from its end."""
        out = values[:]
        for child, parent in self.hanging:
            out[parent] = out[parent] + values[child]
        return out

    def pose(self, world_angles: np.ndarray) -> FloatPose:
        """The geometry at ``world_angles`` (n,) radians."""
        return (_ChainPose if self.chain else FloatPose)(self, world_angles)


class FloatPose:
    """:class:`~ikgame.control.dynamics.Pose` over lists: loads and inertia at one instant."""

    def __init__(self, inertia: FloatInertia, world_angles: np.ndarray) -> None:
        self.inertia_of = inertia
        self.lx: list[float] = (inertia.length_array * np.cos(world_angles)).tolist()
        self.ly: list[float] = (inertia.length_array * np.sin(world_angles)).tolist()
        self.hx = [0.5 * x for x in self.lx]
        self.hy = [0.5 * y for y in self.ly]

    def loads(
        self,
        omega: list[float] | None = None,
        alpha: list[float] | None = None,
        gravity: tuple[float, float] | None = None,
    ) -> Loads:
        """:meth:`Pose.loads <ikgame.control.dynamics.Pose.loads>` over lists."""
        tree = self.inertia_of
        n = tree.count
        if alpha is not None:
            ax = [0.0 + a * -y for a, y in zip(alpha, self.ly, strict=True)]
            ay = [0.0 + a * x for a, x in zip(alpha, self.lx, strict=True)]
        else:
            ax, ay = [0.0] * n, [0.0] * n
        if omega is not None:
            ax = [a - w * w * x for a, w, x in zip(ax, omega, self.lx, strict=True)]
            ay = [a - w * w * y for a, w, y in zip(ay, omega, self.ly, strict=True)]
        jx, jy = tree.along(ax), tree.along(ay)
        gx, gy = (0.0, 0.0) if gravity is None else gravity
        masses = tree.masses
        if gravity is None:
            fx = [m * (j - 0.5 * a) for m, j, a in zip(masses, jx, ax, strict=True)]
            fy = [m * (j - 0.5 * a) for m, j, a in zip(masses, jy, ay, strict=True)]
        else:
            fx = [m * (j - 0.5 * a - gx) for m, j, a in zip(masses, jx, ax, strict=True)]
            fy = [m * (j - 0.5 * a - gy) for m, j, a in zip(masses, jy, ay, strict=True)]
        fx, fy = tree.beyond(fx), tree.beyond(fy)
        px, py = tree.with_children(fx), tree.with_children(fy)
        spin = [hx * qy - hy * qx for hx, hy, qx, qy in zip(self.hx, self.hy, px, py, strict=True)]
        if alpha is not None:
            spin = [s + i * a for s, i, a in zip(spin, tree.moments, alpha, strict=True)]
        return tree.beyond(spin), fx, fy

    def turning(self, accelerations: list[float]) -> Loads:
        """The loads of joint ``accelerations`` alone (rad/s^2, child - parent): :meth:`loads`
        of their :meth:`~FloatInertia.along`."""
        return self.loads(alpha=self.inertia_of.along(accelerations))

    def inertia(self) -> list[float]:
        """:meth:`Pose.inertia <ikgame.control.dynamics.Pose.inertia>` over lists."""
        tree = self.inertia_of
        jx = [a - x for a, x in zip(tree.along(self.lx), self.lx, strict=True)]
        jy = [a - y for a, y in zip(tree.along(self.ly), self.ly, strict=True)]
        cx = [j + h for j, h in zip(jx, self.hx, strict=True)]
        cy = [j + h for j, h in zip(jy, self.hy, strict=True)]
        masses = tree.masses
        first_x = tree.beyond([m * c for m, c in zip(masses, cx, strict=True)])
        first_y = tree.beyond([m * c for m, c in zip(masses, cy, strict=True)])
        second = tree.beyond([m * (x * x + y * y) for m, x, y in zip(masses, cx, cy, strict=True)])
        return [
            b + max(s - 2.0 * (x * fx + y * fy) + mass * (x * x + y * y), 0.0)
            for b, s, x, y, fx, fy, mass in zip(
                tree.moment_beyond, second, jx, jy, first_x, first_y, tree.mass_beyond, strict=True
            )
        ]

    def rest(
        self, gravity: tuple[float, float], rates: list[float]
    ) -> tuple[Loads, Loads, list[float]]:
        """What the servo asks of the pose before it knows the motion it wants: the loads of
        ``gravity`` alone (px/s^2); those plus the loads of the swing at joint ``rates`` alone
        (rad/s, child - parent), each added to each; and :meth:`inertia`."""
        hold = self.loads(gravity=gravity)
        swing = self.loads(omega=self.inertia_of.along(rates))
        coasting = (
            [a + b for a, b in zip(hold[0], swing[0], strict=True)],
            [a + b for a, b in zip(hold[1], swing[1], strict=True)],
            [a + b for a, b in zip(hold[2], swing[2], strict=True)],
        )
        return hold, coasting, self.inertia()


class _ChainPose(FloatPose):
    """:class:`FloatPose` of a serial chain: each evaluation is one pass out along the links and
    one back, with no list built between them (the loop, not the arithmetic, is what a short
    chain pays for). Sums start from -0.0, which adds nothing to any float (0.0 would turn a
    -0.0 into 0.0), so each adds exactly what ``np.cumsum`` does."""

    def loads(
        self,
        omega: list[float] | None = None,
        alpha: list[float] | None = None,
        gravity: tuple[float, float] | None = None,
    ) -> Loads:
        tree = self.inertia_of
        n = tree.count
        lx, ly, masses = self.lx, self.ly, tree.masses
        gx, gy = (0.0, 0.0) if gravity is None else gravity
        if alpha is None and omega is None:
            # Gravity alone: every centre's acceleration is 0.0 - g, as numpy's zeros give, so
            # the forces are the chain's pulled ones (the pass back's sums) and only the
            # torques turn with the pose.
            force_x, force_y, pair_x, pair_y = tree.pulled((gx, gy))
            hx, hy = self.hx, self.hy
            torques, torque = [0.0] * n, -0.0
            for i in range(n - 1, -1, -1):
                torque += hx[i] * pair_y[i] - hy[i] * pair_x[i]
                torques[i] = torque
            return torques, force_x[:], force_y[:]
        own_x, own_y = [0.0] * n, [0.0] * n
        jx = jy = -0.0
        for i in range(n):
            x, y = lx[i], ly[i]
            # The accelerations start from numpy's zeros, which alpha and omega add to.
            if alpha is None:
                ax = ay = 0.0
            else:
                ax, ay = 0.0 + alpha[i] * -y, 0.0 + alpha[i] * x
            if omega is not None:
                w = omega[i]
                ax, ay = ax - w * w * x, ay - w * w * y
            jx += ax
            jy += ay
            # Each joint accelerates with everything before it; each centre with half its
            # link.
            own_x[i] = masses[i] * (jx - 0.5 * ax - gx)
            own_y[i] = masses[i] * (jy - 0.5 * ay - gy)
        return self._back(own_x, own_y, alpha)

    def turning(self, accelerations: list[float]) -> Loads:
        # loads(alpha=along(accelerations)) in the one pass out: the sum along starts from
        # -0.0 too (the first link's own value, exactly, as along keeps it).
        n = self.inertia_of.count
        lx, ly, masses = self.lx, self.ly, self.inertia_of.masses
        own_x, own_y, alpha = [0.0] * n, [0.0] * n, [0.0] * n
        jx = jy = a = -0.0
        for i in range(n):
            a += accelerations[i]
            alpha[i] = a
            ax, ay = 0.0 + a * -ly[i], 0.0 + a * lx[i]
            jx += ax
            jy += ay
            # (no gravity: subtracting loads' 0.0 for it changes no float)
            own_x[i] = masses[i] * (jx - 0.5 * ax)
            own_y[i] = masses[i] * (jy - 0.5 * ay)
        return self._back(own_x, own_y, alpha)

    def _back(self, own_x: list[float], own_y: list[float], alpha: list[float] | None) -> Loads:
        """The pass back: each joint carries its link's ``own`` force and everything beyond."""
        n = self.inertia_of.count
        hx, hy, moments = self.hx, self.hy, self.inertia_of.moments
        fx, fy, torques = [0.0] * n, [0.0] * n, [0.0] * n
        sx = sy = torque = beyond_x = beyond_y = -0.0
        for i in range(n - 1, -1, -1):
            sx += own_x[i]
            sy += own_y[i]
            spin = hx[i] * (sy + beyond_y) - hy[i] * (sx + beyond_x)
            if alpha is not None:
                spin += moments[i] * alpha[i]
            torque += spin
            fx[i], fy[i], torques[i] = sx, sy, torque
            beyond_x, beyond_y = sx, sy
        return torques, fx, fy

    def inertia(self) -> list[float]:
        return self.rest((0.0, 0.0), [0.0] * self.inertia_of.count)[2]

    def rest(
        self, gravity: tuple[float, float], rates: list[float]
    ) -> tuple[Loads, Loads, list[float]]:
        tree = self.inertia_of
        n = tree.count
        lx, ly, hx, hy, masses = self.lx, self.ly, self.hx, self.hy, tree.masses
        # Out: the swing's joint accelerations, and the joints' places for the inertia.
        swing_x, swing_y, jx, jy = [0.0] * n, [0.0] * n, [0.0] * n, [0.0] * n
        w = ax_sum = ay_sum = ex = ey = -0.0
        for i in range(n):
            x, y, m = lx[i], ly[i], masses[i]
            w += rates[i]
            ww = w * w
            ax, ay = 0.0 - ww * x, 0.0 - ww * y
            ax_sum += ax
            ay_sum += ay
            # (the swing's loads leave gravity out: subtracting 0.0 changes no float)
            swing_x[i], swing_y[i] = m * (ax_sum - 0.5 * ax), m * (ay_sum - 0.5 * ay)
            ex += x
            ey += y
            jx[i], jy[i] = ex - x, ey - y
        # Back: gravity's loads (every centre accelerates at -g: only the torques depend on the
        # pose), those plus the swing's, the inertia.
        hold_x, hold_y, pair_x, pair_y = tree.pulled(gravity)
        hold_t, swing_t, inertia = [0.0] * n, [0.0] * n, [0.0] * n
        mass_beyond, moment_beyond = tree.mass_beyond, tree.moment_beyond
        g_torque = -0.0
        ssx = ssy = s_torque = sbx = sby = -0.0
        first_x = first_y = second = -0.0
        for i in range(n - 1, -1, -1):
            h_x, h_y, gsx, gsy = hx[i], hy[i], hold_x[i], hold_y[i]
            g_torque += h_x * pair_y[i] - h_y * pair_x[i]
            hold_t[i] = g_torque
            ssx += swing_x[i]
            ssy += swing_y[i]
            s_torque += h_x * (ssy + sby) - h_y * (ssx + sbx)
            swing_t[i], swing_x[i], swing_y[i] = g_torque + s_torque, gsx + ssx, gsy + ssy
            sbx, sby = ssx, ssy
            # The link's centre and its mass moments, summed from the tip.
            x, y, m = jx[i], jy[i], masses[i]
            cx, cy = x + h_x, y + h_y
            first_x += m * cx
            first_y += m * cy
            second += m * (cx * cx + cy * cy)
            spread = second - 2.0 * (x * first_x + y * first_y) + mass_beyond[i] * (x * x + y * y)
            inertia[i] = moment_beyond[i] + (0.0 if 0.0 > spread else spread)
        # Copies of the kept forces: the loads returned are the caller's.
        return (hold_t, hold_x[:], hold_y[:]), (swing_t, swing_x, swing_y), inertia


def fit_floats(
    bias: Loads,
    push: Loads,
    wanted: list[float],
    limits: list[float],
    head: Callable[[int], Loads] | None = None,
    weak: tuple[list[bool], Callable[[int], Loads]] | None = None,
    turning: Callable[[list[float]], Loads] | None = None,
) -> tuple[list[float], Loads, list[bool], bool]:
    """:func:`~ikgame.control.dynamics.fit_drive` over lists: the accelerations, the loads,
    which joints are saturated, and whether the loads are those of the motion."""
    # bias + push, the torques first: the forces are needed only when those fit.
    torques, fits = [], True
    for b, p, lim in zip(bias[0], push[0], limits, strict=True):
        t = b + p
        torques.append(t)
        if not abs(t) <= lim:
            fits = False
    if fits:
        fx = [b + p for b, p in zip(bias[1], push[1], strict=True)]
        fy = [b + p for b, p in zip(bias[2], push[2], strict=True)]
        return wanted, (torques, fx, fy), [False] * len(limits), True
    if weak is not None:
        gave = give_way(bias, push, wanted, limits, *weak)
        if gave is not None:
            return *gave, True
    scale, binding = None, 0
    if all(abs(b) <= lim for b, lim in zip(bias[0], limits, strict=True)):
        scale, binding = listed_factor(bias[0], push[0], limits)
    if head is not None and scale is not None and binding < len(limits) - 1:
        near = head(binding)
        start = plus_loads(bias, near, 1.0)
        rest = plus_loads(push, near, -1.0)
        tail, _ = listed_factor(start[0], rest[0], limits)
        lead: float | None = 1.0
        if tail is None:
            # As in fit_drive: the joints up to it scaled with the rest coasting, then the rest.
            lead, _ = listed_factor(bias[0], near[0], limits)
            if lead is not None:
                start = plus_loads(bias, near, lead)
                tail, _ = listed_factor(start[0], rest[0], limits)
        if tail is not None and lead is not None:
            accelerations = [w * lead if j <= binding else w * tail for j, w in enumerate(wanted)]
            loads = plus_loads(start, rest, tail)
            return accelerations, loads, at_limits(loads[0], limits), True
    if scale is not None:
        if turning is not None and scale < 1.0:
            eased = ease(bias, push, wanted, limits, binding, scale, turning)
            if eased is not None:
                return *eased, True
        loads = plus_loads(bias, push, scale)
        return [scale * w for w in wanted], loads, at_limits(loads[0], limits), True
    bt, bx, by = bias
    loads = ([min(max(b, -lim), lim) for b, lim in zip(bt, limits, strict=True)], bx, by)
    return wanted, loads, at_limits(loads[0], limits), False


def end_motion(
    lengths: list[float],
    base: tuple[float, float],
    base_angle: float,
    angles: list[float],
    rates: list[float],
) -> tuple[tuple[float, float], tuple[float, float]]:
    """A serial chain's end effector (px) and its velocity (px/s) at joint ``rates`` (rad/s,
    child - parent), the Jacobian times the rates, in one pass out along the links.

    >>> end_motion([10.0, 10.0], (0.0, 0.0), 0.0, [0.0, 0.0], [1.0, 0.0])
    ((20.0, 0.0), (0.0, 20.0))
    """
    x, y = base
    heading = base_angle
    cos, sin = math.cos, math.sin
    # Each joint's rate turns everything beyond it: the end moves by the sum over joints of
    # rate x (end - joint), which is (sum of rates so far) x each link.
    turning = vx = vy = 0.0
    for length, angle, rate in zip(lengths, angles, rates, strict=True):
        heading += angle
        turning += rate
        dx, dy = length * cos(heading), length * sin(heading)
        x += dx
        y += dy
        vx -= turning * dy
        vy += turning * dx
    return (x, y), (vx, vy)


def damped_rates(
    lengths: list[float],
    base: tuple[float, float],
    base_angle: float,
    angles: list[float],
    velocity: tuple[float, float],
    damping: float,
) -> list[float]:
    """Joint rates (rad/s) that move a serial chain's end effector at ``velocity`` (px/s):
    ``J^T (J J^T + damping I)^-1 v``, the damped least-norm answer, with ``damping`` in px^2.

    >>> [round(r, 6) for r in damped_rates([10.0], (0.0, 0.0), 0.0, [0.0], (0.0, 10.0), 1.0)]
    [0.990099]
    """
    xs, ys = [], []
    x, y = base
    heading = base_angle
    cos, sin = math.cos, math.sin
    for length, angle in zip(lengths, angles, strict=True):
        xs.append(x)
        ys.append(y)
        heading += angle
        x += length * cos(heading)
        y += length * sin(heading)
    # Column i of the Jacobian is the arm from joint i to the end, turned a quarter turn.
    arms_x, arms_y = [], []
    a = d = damping
    b = 0.0
    for joint_x, joint_y in zip(xs, ys, strict=True):
        ax, ay = x - joint_x, y - joint_y
        arms_x.append(ax)
        arms_y.append(ay)
        a += ay * ay
        b -= ay * ax
        d += ax * ax
    det = a * d - b * b
    vx, vy = velocity
    u, w = (d * vx - b * vy) / det, (a * vy - b * vx) / det
    return [ax * w - ay * u for ax, ay in zip(arms_x, arms_y, strict=True)]
