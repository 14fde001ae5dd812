"""Benchmarks, measured side by side in one run: ``python benchmarks/run.py``.

Prints ratios rather than bare timings, so the numbers mean the same on a slower machine:
- simulation speed as a multiple of real time, per shipped level, without rendering;
- the controller's cost per tick next to pymunk's own ``Space.step`` on the same world;
- each solver's time per solve on chains of 10 and 100 links;
- frame export (PNG frames + GIF) in frames per second, serial and with worker processes.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from ikgame.kinematics import SOLVERS, Skeleton, forward_kinematics
from ikgame.level.library import shipped_levels
from ikgame.level.loader import load_level
from ikgame.sim import Simulation


def _best_of(fn, repeat: int = 3) -> float:
    """Fastest of ``repeat`` wall-clock runs, s: the least disturbed by the rest of the machine."""
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return best


def bench_levels() -> None:
    print("simulation speed, no rendering (x real time; higher is better)")
    print(f"  {'level':<28}{'links':>6}{'sim s':>8}{'wall s':>8}{'x real':>8}")
    for path in shipped_levels():
        level = load_level(path)
        sims = []

        def run(level=level, sims=sims):
            sim = Simulation(level, record=False)
            sim.run()
            sims.append(sim)

        wall = _best_of(run)
        sim = sims[-1]
        print(
            f"  {path.stem:<28}{sim.world.count:>6}{sim.time:>8.2f}{wall:>8.3f}"
            f"{sim.time / wall:>8.1f}"
        )


def bench_tick_split(level_path: Path, ticks: int = 2000) -> None:
    """Time the parts of a tick on one world: controller vs pymunk's step."""
    level = load_level(level_path)
    sim = Simulation(level, record=False)
    controller_s = physics_s = 0.0
    for _ in range(ticks):
        if sim.done:
            break
        t0 = time.perf_counter()
        command = sim.controller.command(sim.world.joint_angles(), sim.target)
        sim.world.set_rates(command.rates)
        t1 = time.perf_counter()
        sim.world.space.step(sim.dt)
        t2 = time.perf_counter()
        sim.script.observe(sim.time, sim.dt, sim.world.end_effector())
        sim.tick += 1
        controller_s += t1 - t0
        physics_s += t2 - t1
    n = sim.tick
    print(f"\none tick of {level_path.stem} ({sim.world.count} links, mean over {n} ticks)")
    print(f"  pymunk Space.step        {physics_s / n * 1e6:8.1f} us   1.00")
    print(
        f"  controller (IK + motors) {controller_s / n * 1e6:8.1f} us"
        f"   {controller_s / physics_s:.2f} x Space.step"
    )


def bench_solvers() -> None:
    print("\nsolver time per solve (10 iterations, warm start near the target; lower is better)")
    rng = np.random.default_rng(7)
    names = sorted(SOLVERS)
    print(f"  {'links':>6}" + "".join(f"{name:>20}" for name in names))
    for n in (10, 100):
        skeleton = Skeleton.chain(np.full(n, 400.0 / n), base_angle=np.pi / 2)
        starts = rng.uniform(-0.3, 0.3, (20, n))
        targets = [forward_kinematics(skeleton, s + 0.05)[0][-1] for s in starts]
        row = []
        for name in names:
            solve = SOLVERS[name]

            def run(solve=solve, skeleton=skeleton, starts=starts, targets=targets):
                for start, target in zip(starts, targets, strict=True):
                    solve(skeleton, start, target, max_iterations=10, tolerance=0.01)

            row.append(_best_of(run) / len(starts) * 1e6)
        base = row[names.index("ccd")]
        print(f"  {n:>6}" + "".join(f"{us:>11.0f} us {us / base:>4.1f}x" for us in row))


def bench_export(frames: int = 120) -> None:
    try:
        from ikgame.render.export import export_run
    except ImportError:
        print("\nexport: ikgame.render not available")
        return
    level = load_level(shipped_levels()[1])
    sim = Simulation(level)
    while len(sim.snapshots) < frames and not sim.done:
        sim.step()
    snaps = sim.snapshots[:frames]
    print(
        f"\nexport at 960x540, PNG frames + GIF, {len(snaps)} frames (frames/s; higher is better)"
    )
    results = {}
    for workers in (1, 2):
        with tempfile.TemporaryDirectory() as tmp:
            wall = _best_of(
                lambda tmp=tmp, workers=workers: export_run(
                    Path(tmp) / "out", sim.scene, snaps, workers=workers, progress=False
                ),
                repeat=1,
            )
        results[workers] = len(snaps) / wall
        print(
            f"  workers={workers}: {results[workers]:6.1f} frames/s   {results[workers] / results[1]:.2f}x"
        )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--skip-export", action="store_true", help="leave out the export benchmark")
    args = parser.parse_args(argv)
    bench_levels()
    bench_tick_split(shipped_levels()[1])
    bench_solvers()
    if not args.skip_export:
        bench_export()
    return 0


if __name__ == "__main__":
    sys.exit(main())
