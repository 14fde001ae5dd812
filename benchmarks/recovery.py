"""Recovery from limit traps, measured: ``python benchmarks/recovery.py [--cases 500]``.

Prints two Markdown tables (docs/solvers.md quotes them):

- **Reached**: on a fixed seeded set of random chains (1 to 30 links; limits free, wide, tight or
  one-sided; starts straight, coiled against the limits or anywhere within them) with targets
  that are the forward kinematics of poses within the limits, how many each raw solver and each
  ``RobustSolver`` reach within 0.5 px, called as a controller calls them without physics: 10
  iterations a call, each call starting from the last answer, at most 100 calls.
- **Cost per call**: iterations and wall-clock microseconds of the raw solver and of
  ``RobustSolver`` tracking a moving target (the common case: the plain solve arrives), and on a
  settled chain (same target, the answer fed back). Microseconds vary with the machine; the
  iterations do not.
"""

from __future__ import annotations

import argparse
import math
import time

import _checkout  # noqa: F401  (first: this checkout's ikgame)
import numpy as np

from ikgame.kinematics import SOLVERS, RobustSolver, Skeleton, SolveStatus, forward_kinematics

TOLERANCE = 0.5  # px
ITERATIONS = 10  # per call, the levels' default
CALLS = 100  # most calls per case
SEED = 12345


def _limit(rng: np.random.Generator) -> tuple[float, float] | None:
    kind = rng.choice(["free", "wide", "tight", "left", "right"], p=[0.2, 0.25, 0.2, 0.175, 0.175])
    if kind == "free":
        return None
    if kind == "wide":
        half = rng.uniform(math.radians(30), math.radians(170))
        return (-half, half)
    if kind == "tight":
        half = rng.uniform(math.radians(3), math.radians(15))
        return (-half, half)
    near = rng.uniform(math.radians(5), math.radians(30))
    far = rng.uniform(math.radians(90), math.radians(170))
    return (near, far) if kind == "left" else (-far, -near)


def _in_limits(rng: np.random.Generator, skeleton: Skeleton) -> np.ndarray:
    low = np.maximum(skeleton.lower, -math.pi)
    high = np.minimum(skeleton.upper, math.pi)
    return low + rng.uniform(0, 1, skeleton.count) * (high - low)


def cases(count: int) -> list[tuple[Skeleton, np.ndarray, np.ndarray]]:
    """``count`` seeded (chain, start, reachable target) cases."""
    rng = np.random.default_rng(SEED)
    made = []
    for _ in range(count):
        n = int(rng.choice([1, 2, 3, 4, 5, 6, 8, 10, 12, 16, 20, 25, 30]))
        skeleton = Skeleton.chain(
            rng.uniform(10, 100, n),
            base=rng.uniform(-200, 200, 2),
            base_angle=rng.uniform(-math.pi, math.pi),
            limits=[_limit(rng) for _ in range(n)],
        )
        target = forward_kinematics(skeleton, _in_limits(rng, skeleton))[0][-1]
        start = [
            skeleton.clamp(np.zeros(n)),
            np.maximum(skeleton.lower, -2.8),
            np.minimum(skeleton.upper, 2.8),
            _in_limits(rng, skeleton),
        ][int(rng.integers(4))]
        made.append((skeleton, start, target))
    return made


def _reached(solve, start: np.ndarray, target: np.ndarray) -> tuple[bool, int]:
    """Whether tick-by-tick calls arrive, and the most iterations one call took."""
    angles, most = start, 0
    for _ in range(CALLS):
        sol = solve(angles, target)
        most = max(most, sol.iterations)
        angles = sol.angles
        if sol.status is SolveStatus.SUCCESS:
            return True, most
    return False, most


def reached_table(count: int) -> None:
    made = cases(count)
    print(f"| solver | raw: reached of {count} | with recovery: reached | most iterations a call |")
    print("|---|---|---|---|")
    for name in sorted(SOLVERS):
        raw = robust = most = 0
        for skeleton, start, target in made:
            raw += _reached(
                lambda a, t, s=skeleton, name=name: SOLVERS[name](
                    s, a, t, max_iterations=ITERATIONS, tolerance=TOLERANCE
                ),
                start,
                target,
            )[0]
            solver = RobustSolver(skeleton, name)
            ok, heaviest = _reached(
                lambda a, t, r=solver: r.solve(
                    a, t, max_iterations=ITERATIONS, tolerance=TOLERANCE
                ),
                start,
                target,
            )
            robust += ok
            most = max(most, heaviest)
        print(f"| {name} | {raw} | {robust} | {most} |")


def _chain(links: int) -> Skeleton:
    limit = (-math.radians(150), math.radians(150))
    return Skeleton.chain([300.0 / links] * links, base_angle=math.pi / 2, limits=[limit] * links)


def _circle(tick: int) -> np.ndarray:
    phase = 2 * math.pi * tick / 960
    return np.array([120 * math.cos(phase), 150 + 60 * math.sin(phase)])


def _per_call(solve, links: int) -> tuple[float, float, float, float]:
    """(iterations, median µs) tracking a circle, then (iterations, median µs) settled."""
    skeleton = _chain(links)
    angles = np.full(links, 0.1)
    for _ in range(CALLS):
        angles = solve(skeleton, angles, _circle(0)).angles
    results = []
    for targets in ([_circle(t) for t in range(1, 481)], [_circle(480)] * 200):
        iterations, micros = [], []
        for target in targets:
            start = time.perf_counter()
            sol = solve(skeleton, angles, target)
            micros.append((time.perf_counter() - start) * 1e6)
            iterations.append(sol.iterations)
            angles = sol.angles
        results += [float(np.mean(iterations)), float(np.median(micros))]
    return tuple(results)  # type: ignore[return-value]


def cost_table() -> None:
    print(
        "| solver | links | tracking, raw: iterations, µs | tracking, with recovery | "
        "settled, raw | settled, with recovery |"
    )
    print("|---|---|---|---|---|---|")
    for name in sorted(SOLVERS):
        for links in (3, 10, 30):
            raw = _per_call(
                lambda s, a, t, name=name: SOLVERS[name](
                    s, a, t, max_iterations=ITERATIONS, tolerance=TOLERANCE
                ),
                links,
            )
            robust = RobustSolver(_chain(links), name)
            wrapped = _per_call(
                lambda s, a, t, r=robust: r.solve(
                    a, t, max_iterations=ITERATIONS, tolerance=TOLERANCE
                ),
                links,
            )
            cells = [
                f"{raw[0]:.2f}, {raw[1]:.0f}",
                f"{wrapped[0]:.2f}, {wrapped[1]:.0f}",
                f"{raw[2]:.2f}, {raw[3]:.0f}",
                f"{wrapped[2]:.2f}, {wrapped[3]:.0f}",
            ]
            print(f"| {name} | {links} | " + " | ".join(cells) + " |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=500, help="random cases per solver")
    args = parser.parse_args()
    reached_table(args.cases)
    print()
    cost_table()


if __name__ == "__main__":
    main()
