"""Benchmarks, measured side by side in one run: ``python benchmarks/run.py`` (``--quick`` for a
short run, as in CI).

Every number that has a reference is printed next to it and as a ratio, measured in the same run,
interleaved, so that a busy or slower machine shifts both alike; each ratio is printed next to its
target. Timings are medians of repeats. Sections:

- tick: a full ``Simulation.step()`` against a bare ``pymunk.Space.step`` of the same bodies,
  joints and motors (``space.iterations = 20``, 1/240 s, no Python between steps; without the
  return sweep the world gives chains of over ``SWEEP_LINKS`` links), at 3 to 1000
  links, with a reach and a circle target, and the growth exponent of each, in CPU time;
- levels: headless speed as a multiple of real time per shipped level, in-process and as a whole
  ``python -m ikgame run LEVEL --no-frames`` process, and the longest single tick of a run (a
  hitch a game loop would show); start-up of ``ikgame --version``;
- solvers: time per IK solve against ikpy on the same planar chains and tolerance;
- search: the obstacle planner's gap measure in numpy against compiled (the ``fast`` extra), a
  call and whole stress-level runs whose searches are long;
- export: frames per second at three sizes against ``pymunk.pygame_util`` + ``pygame.image.save``
  and against minimal Pillow drawing (lines + PNG save);
- memory: peak resident memory of a whole long export, worker processes included.

ikpy and pygame-ce are optional (``pip install -e '.[bench]'``); their rows are skipped with a
line saying so when they are missing.
"""

from __future__ import annotations

import argparse
import functools
import math
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path

import _checkout  # noqa: F401  (first: this checkout's ikgame)
import numpy as np
from chains import chain_level
from quality import STRESS_DIR

from ikgame.kinematics import SOLVERS, Skeleton, _compiled, _compiled_gaps, forward_kinematics
from ikgame.kinematics.clearance import Clearance, Obstacles
from ikgame.level.library import LEVELS_DIR, shipped_levels
from ikgame.level.loader import load_level
from ikgame.level.model import Level
from ikgame.physics.world import SWEEP_LINKS
from ikgame.render.camera import Camera
from ikgame.render.export import export_run
from ikgame.sim import Simulation

ROOT = Path(__file__).resolve().parents[1]
BARE_ITERATIONS = 20  # pymunk iterations of the bare reference step
SEARCH_LEVELS = ["55_pocket_behind_wall_both_folds", "73_seven_links_rocks_low_gaps"]
# A floor, a shelf with a lip, a wall and two rocks: the search benchmark's room (px).
SEARCH_SEGMENTS = np.array(
    [
        [-600.0, -20.0, 600.0, -20.0, 4.0],
        [-370.0, 100.0, -90.0, 100.0, 5.0],
        [-370.0, 100.0, -370.0, 50.0, 5.0],
        [-190.0, -20.0, -190.0, 38.0, 5.0],
    ]
)
SEARCH_CIRCLES = np.array([[-150.0, 200.0, 30.0], [100.0, 150.0, 20.0]])
EXPORT_LEVEL = "13_conductor"  # the showpiece: obstacles, props, goals, trail, dashed path
MEMORY_LEVEL = "06_circle"

# The targets each measure is checked against; None where there is only a number to print.
TICK_TARGETS = {10: 3.0, 100: 2.0, 1000: 1.5}  # full tick / bare step, at most
REAL_TIME_TARGET = 100.0  # x real time, at least, for a 10-link level in-process
WORST_TICK_TARGET = 16.7  # ms: no tick longer than one frame of a 60 fps game loop
VERSION_TARGET = 0.15  # s, whole process
RUN_TARGET = 0.6  # s, whole process, default level, --no-frames
EXPORT_TARGET = 1.0  # ikgame / pygame frames per second at 960x540, one process, at least
MEMORY_TARGET = 250.0  # MB, peak of an 18,000-frame run


def _env() -> dict[str, str]:
    """The environment for child processes, with this checkout importable, reading the bytecode
    that :func:`_compile_bytecode` wrote."""
    paths = [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])]
    return os.environ | {"PYTHONPATH": os.pathsep.join(paths)}


def _compile_bytecode() -> None:
    """Write the package's bytecode caches, as installing it does (pip compiles what it
    installs; an editable checkout writes them on its first run), so that whole processes are
    timed as a user runs them and not compiling every module from source, which a
    ``PYTHONDONTWRITEBYTECODE`` set in the environment would make them do every time."""
    import compileall

    compileall.compile_dir(ROOT / "ikgame", quiet=1)


def _verdict(value: float, target: float | None, *, at_most: bool) -> str:
    if target is None:
        return ""
    met = value <= target if at_most else value >= target
    sign = "<=" if at_most else ">="
    return f"target {sign} {target:g}: {'met' if met else 'MISSED'}"


def _header(title: str) -> None:
    print(f"\n== {title}")


# -- tick ------------------------------------------------------------------------------------------


def _per_tick(step: Callable[[], object], ticks: int) -> float:
    # CPU time of this process: the other jobs of a busy machine do not count against either
    # side (its caches being shared still does).
    start = time.process_time()
    for _ in range(ticks):
        step()
    return (time.process_time() - start) / ticks


def _in_python(step: Callable[[], object], ticks: int) -> float:
    """:func:`_per_tick` with the solver's compiled pass turned off."""
    os.environ["IKGAME_COMPILED"] = "0"
    try:
        return _per_tick(step, ticks)
    finally:
        del os.environ["IKGAME_COMPILED"]


def bench_tick(sizes: list[int], repeats: int) -> None:
    _header("tick: full Simulation.step() against a bare pymunk Space.step of the same space")
    print(f"   bare step: space.iterations = {BARE_ITERATIONS}, dt = 1/240 s, nothing in between")
    print("   CPU time per tick of this process, median of interleaved repeats")
    compiled = _compiled._kernel() is not None
    if compiled:
        print(
            f"   python: the same tick with the solver's compiled pass turned off "
            f"(IKGAME_COMPILED=0; chains of {_compiled.COMPILED_LINKS}+ links use it)"
        )
    else:
        print("   numba is not installed: no compiled pass to compare (pip install -e '.[fast]')")
    print(f"   {'links':>6} {'target':<7}{'full':>11}{'bare':>11}{'ratio':>8}{'python':>11}   ")
    fits: dict[str, list[tuple[int, float, float]]] = {"reach": [], "circle": []}
    for links in sizes:
        ticks = max(4, min(400, 40_000 // links))
        for target in ("reach", "circle"):
            level = chain_level(links, target)
            sim = Simulation(level, record=False)
            dt = sim.dt
            _per_tick(sim.step, ticks)  # warm up: the chain leaves its start pose
            # The same bodies, joints and motors in the same state, stepped with nothing else.
            bare = sim.world.space.copy()
            bare.iterations = BARE_ITERATIONS
            if links > SWEEP_LINKS:
                # Without the return sweep: a copy keeps the order the world added its
                # constraints in, and the sweep's pivot and motor per link come last.
                bare.remove(*list(bare.constraints)[-2 * links :])
            python = None
            if compiled and links >= _compiled.COMPILED_LINKS:
                # The same run again in Python, from the same state (the same floats).
                python = Simulation(level, record=False)
                _in_python(python.step, ticks)
            full_times, bare_times, python_times = [], [], []
            for _ in range(repeats):
                full_times.append(_per_tick(sim.step, ticks))
                bare_times.append(_per_tick(lambda: bare.step(dt), ticks))  # noqa: B023
                if python is not None:
                    python_times.append(_in_python(python.step, ticks))
            full, plain = statistics.median(full_times), statistics.median(bare_times)
            fits[target].append((links, full, plain))
            ratio = full / plain
            slow = f"{statistics.median(python_times) * 1e6:>9.0f}us" if python_times else " " * 11
            print(
                f"   {links:>6} {target:<7}{full * 1e6:>9.0f}us{plain * 1e6:>9.0f}us{ratio:>7.1f}x"
                f"{slow}   {_verdict(ratio, TICK_TARGETS.get(links), at_most=True)}"
            )
    if len(sizes) >= 2:
        for target, rows in fits.items():
            x = np.log([r[0] for r in rows])
            full_slope = np.polyfit(x, np.log([r[1] for r in rows]), 1)[0]
            bare_slope = np.polyfit(x, np.log([r[2] for r in rows]), 1)[0]
            print(
                f"   growth exponent ({target}): full tick {full_slope:.2f}, bare step "
                f"{bare_slope:.2f}   target: about 1 (linear in links)"
            )


# -- the obstacle search -----------------------------------------------------------------------------


def _search_run(path: Path, solver: str) -> float:
    """CPU s of a whole run of the stress level at ``path`` with ``solver``."""
    sim = Simulation(load_level(path), solver=solver, record=False)
    start = time.process_time()
    while not sim.done:
        sim.step()
    return time.process_time() - start


def bench_search(levels: list[str], repeats: int) -> None:
    _header("search: the obstacle planner's gap measure, numpy against compiled (the fast extra)")
    try:
        import numba
    except ImportError:
        print("   numba is not installed: no compiled gaps to compare (pip install -e '.[fast]')")
        return
    kernel = _compiled_gaps._measure(_compiled_gaps._compile(numba))
    # Built now, so that no run pays for compiling it (a run builds it once it has measured
    # COMPILE_AFTER pairs, on a thread of its own), and put back after: the sections after this
    # one measure the process as a run would have it.
    built, _compiled_gaps._build.gaps = _compiled_gaps._build.gaps, kernel
    try:
        _bench_gaps()
        _bench_search_runs(levels, repeats)
    finally:
        _compiled_gaps._build.gaps = built


def _bench_gaps() -> None:
    room = Clearance(
        Skeleton.chain([60.0] * 7, base_angle=math.pi / 2),
        np.full(7, 6.0),
        Obstacles.from_arrays(SEARCH_SEGMENTS, SEARCH_CIRCLES),
    )
    rng = np.random.default_rng(0)
    print("   one gap measure of a 7-link chain among 6 obstacles, us a call, median of repeats")
    print(f"   {'poses':>6}{'numpy':>10}{'compiled':>10}{'ratio':>8}")
    for poses in (1, 20, 100):
        pts = room.points(rng.uniform(-2.0, 2.0, (poses, 7)))
        measure = functools.partial(room._gaps, pts)
        calls = 4000 // poses
        numpy_times, compiled_times = [], []
        for _ in range(5):
            numpy_times.append(_in_python(measure, calls))
            compiled_times.append(_per_tick(measure, calls))
        slow, fast = statistics.median(numpy_times), statistics.median(compiled_times)
        print(f"   {poses:>6}{slow * 1e6:>8.0f}us{fast * 1e6:>8.0f}us{slow / fast:>7.1f}x")


def _bench_search_runs(levels: list[str], repeats: int) -> None:
    print("   whole runs of stress levels whose searches are long, CPU s, median of repeats")
    print(f"   {'level':<40}{'solver':<8}{'numpy':>8}{'compiled':>10}{'ratio':>8}")
    for name in levels:
        path = STRESS_DIR / f"{name}.toml"
        numpy_times, compiled_times = [], []
        for _ in range(repeats):
            numpy_times.append(_in_python(lambda: _search_run(path, "fabrik"), 1))  # noqa: B023
            compiled_times.append(_search_run(path, "fabrik"))
        slow, fast = statistics.median(numpy_times), statistics.median(compiled_times)
        print(f"   {name:<40}{'fabrik':<8}{slow:>7.2f}s{fast:>9.2f}s{slow / fast:>7.1f}x")


# -- levels and start-up ---------------------------------------------------------------------------


def _wall(command: list[str]) -> float:
    start = time.perf_counter()
    subprocess.run(command, check=True, env=_env(), capture_output=True, cwd=ROOT)
    return time.perf_counter() - start


def bench_levels(repeats: int, whole_process: bool) -> None:
    _header("levels: headless speed as a multiple of real time (higher is better)")
    print("   in-process: CPU time of this process; process: wall time of a whole run;")
    print("   worst tick: the longest single Simulation.step() of the run, CPU ms (a separate run)")
    print(
        f"   {'level':<22}{'links':>6}{'sim s':>7}{'in-process':>12}{'process':>10}{'worst tick':>12}"
    )
    with tempfile.TemporaryDirectory() as tmp:
        for path in shipped_levels():
            level = load_level(path)
            walls, sim = [], None
            for _ in range(repeats):
                start = time.process_time()  # CPU time, as for the tick
                sim = Simulation(level, record=False)
                sim.run()
                walls.append(time.process_time() - start)
            assert sim is not None
            inproc = sim.time / statistics.median(walls)
            process = ""
            if whole_process:
                command = [sys.executable, "-m", "ikgame", "run", str(path), "--no-frames"]
                command += ["--quiet", "--force", "--out", tmp]
                process = (
                    f"{sim.time / statistics.median(_wall(command) for _ in range(repeats)):>9.1f}x"
                )
            worst = _worst_tick(level)
            target = REAL_TIME_TARGET if sim.world.count == 10 else None
            verdicts = [_verdict(inproc, target, at_most=False)]
            verdicts.append(f"worst tick {_verdict(worst, WORST_TICK_TARGET, at_most=True)}")
            print(
                f"   {path.stem:<22}{sim.world.count:>6}{sim.time:>7.2f}{inproc:>11.1f}x{process:>10}"
                f"{worst:>9.1f} ms   {'; '.join(v for v in verdicts if v)}"
            )


def _worst_tick(level: Level) -> float:
    """The longest single tick of a whole run of ``level``, CPU ms: what a game loop calling
    ``step()`` once a frame would see as a hitch."""
    sim = Simulation(level, record=False)
    worst = 0.0
    while not sim.done:
        start = time.process_time()
        sim.step()
        worst = max(worst, time.process_time() - start)
    return worst * 1000.0


def bench_startup(repeats: int) -> None:
    _header("start-up: whole process, wall time (lower is better)")
    print("   with the package's bytecode written first, as an install writes it")
    python = [sys.executable, "-m", "ikgame"]
    with tempfile.TemporaryDirectory() as tmp:
        rows = [
            ("ikgame --version", [*python, "--version"], VERSION_TARGET),
            (
                "ikgame run --no-frames",
                [*python, "run", "--no-frames", "--quiet", "--force", "--out", tmp],
                RUN_TARGET,
            ),
            ("python -c pass", [sys.executable, "-c", "pass"], None),
        ]
        for name, command, target in rows:
            wall = statistics.median(_wall(command) for _ in range(repeats))
            print(f"   {name:<26}{wall:>7.3f} s   {_verdict(wall, target, at_most=True)}")


# -- solvers ---------------------------------------------------------------------------------------


def _ikpy_chain(lengths: np.ndarray):  # noqa: ANN202 - ikpy is optional
    from ikpy.chain import Chain
    from ikpy.link import OriginLink, URDFLink

    links = [OriginLink()]
    offsets = [0.0, *lengths[:-1]]
    for i, offset in enumerate(offsets):
        links.append(URDFLink(f"joint{i}", [offset, 0, 0], [0, 0, 0], rotation=[0, 0, 1]))
    links.append(URDFLink("tip", [lengths[-1], 0, 0], [0, 0, 0], joint_type="fixed"))
    mask = [False] + [True] * len(lengths) + [False]
    return Chain(links, active_links_mask=mask)


def bench_solvers(sizes: list[int], problems: int, repeats: int) -> None:
    _header("solvers: time per solve, 10 iterations or tolerance 0.01 px, warm start nearby")
    try:
        import ikpy  # noqa: F401
    except ImportError:
        ikpy_note = "ikpy not installed (pip install -e '.[bench]'): its column is skipped"
    else:
        ikpy_note = ""
    names = sorted(SOLVERS)
    columns = names + ([] if ikpy_note else ["ikpy"])
    print(f"   {'links':>6}" + "".join(f"{name:>20}" for name in columns))
    print(f"   {'':>6}" + "".join(f"{'us  (error px)':>20}" for _ in columns))
    rng = np.random.default_rng(7)
    tolerance = 0.01
    for n in sizes:
        lengths = np.full(n, 400.0 / n)
        skeleton = Skeleton.chain(lengths)
        starts = rng.uniform(-0.3, 0.3, (problems, n))
        targets = [forward_kinematics(skeleton, s + 0.05)[0][-1] for s in starts]
        cells = []
        for name in names:
            solve = SOLVERS[name]
            errors: list[float] = []

            def run(
                solve=solve, skeleton=skeleton, starts=starts, targets=targets, errors=errors
            ) -> None:
                errors.clear()
                for start, target in zip(starts, targets, strict=True):
                    solution = solve(
                        skeleton, start, target, max_iterations=10, tolerance=tolerance
                    )
                    errors.append(solution.error)

            cells.append(_timed_cell(run, problems, repeats, errors))
        if not ikpy_note:
            chain = _ikpy_chain(lengths)
            errors = []

            # ikpy takes seconds per solve on long chains: fewer problems keep the run short.
            few = max(2, problems * 10 // n)

            def run_ikpy(
                chain=chain, starts=starts[:few], targets=targets[:few], errors=errors
            ) -> None:
                errors.clear()
                for start, target in zip(starts, targets, strict=True):
                    full = np.concatenate([[0.0], start, [0.0]])
                    angles = chain.inverse_kinematics(
                        [target[0], target[1], 0.0], initial_position=full, tol=tolerance
                    )
                    tip = chain.forward_kinematics(angles)[:2, 3]
                    errors.append(float(np.hypot(*(tip - target))))

            cells.append(_timed_cell(run_ikpy, few, repeats, errors))
        print(f"   {n:>6}" + "".join(cells))
    if ikpy_note:
        print(f"   {ikpy_note}")


def _timed_cell(run: Callable[[], None], problems: int, repeats: int, errors: list[float]) -> str:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        times.append((time.perf_counter() - start) / problems)
    return f"{statistics.median(times) * 1e6:>9.0f} ({statistics.median(errors):8.3f})"


# -- export ----------------------------------------------------------------------------------------


def _recorded(level: Level, frames: int) -> Simulation:
    sim = Simulation(level)
    while len(sim.snapshots) < frames and not sim.done:
        sim.step()
    return sim


def _pygame_fps(level: Level, frames: int, size: tuple[int, int], out: Path) -> float | None:
    """Frames per second of pymunk's own pygame debug drawing plus ``pygame.image.save``, timing
    only the drawing and saving, on the same run, space and frame moments as the export."""
    try:
        os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
        os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
        import pygame
        import pymunk
        from pymunk import pygame_util
    except ImportError:
        return None
    pygame.display.init()
    pygame_util.positive_y_is_up = True
    surface = pygame.Surface(size)
    options = pygame_util.DrawOptions(surface)
    sim = _recorded(level, frames)
    camera = Camera.fit(sim.scene, sim.snapshots, size)
    ox, oy = camera.world_to_pixel([[0.0, 0.0]])[0]
    s = camera.scale
    options.transform = pymunk.Transform(s, 0, 0, s, ox, size[1] - oy)
    sim = Simulation(level)
    spent, drawn = 0.0, 0
    while drawn < frames and not sim.done:
        before = len(sim.snapshots)
        sim.step()
        if len(sim.snapshots) > before:
            start = time.perf_counter()
            surface.fill((246, 242, 233))
            sim.world.space.debug_draw(options)
            pygame.image.save(surface, str(out / f"{drawn:06d}.png"))
            spent += time.perf_counter() - start
            drawn += 1
    return drawn / spent


def _pillow_fps(sim: Simulation, size: tuple[int, int], out: Path) -> float:
    """Frames per second of the least a Pillow export can do: the chain as lines, saved as PNG."""
    from PIL import Image, ImageDraw

    camera = Camera.fit(sim.scene, sim.snapshots, size)
    start = time.perf_counter()
    for index, snap in enumerate(sim.snapshots):
        image = Image.new("RGB", size, (246, 242, 233))
        draw = ImageDraw.Draw(image)
        points = [tuple(p) for p in camera.world_to_pixel(snap.joints)]
        draw.line(points, fill=(60, 90, 160), width=6)
        image.save(out / f"{index:06d}.png")
    return len(sim.snapshots) / (time.perf_counter() - start)


def _export_fps(sim: Simulation, size: tuple[int, int], out: Path, **options: object) -> float:
    start = time.perf_counter()
    export_run(out, sim.scene, sim.snapshots, size=size, motion=False, progress=False, **options)
    return len(sim.snapshots) / (time.perf_counter() - start)


def bench_export(frames: int, repeats: int, sizes: list[tuple[int, int]]) -> None:
    _header(f"export: frames per second, {EXPORT_LEVEL}, {frames} frames (higher is better)")
    level = load_level(LEVELS_DIR / f"{EXPORT_LEVEL}.toml")
    sim = _recorded(level, frames)
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    columns = ["png", "png+gif", "png+gif 2w", "pygame png", "pillow min"]
    print(f"   {'size':<11}" + "".join(f"{c:>12}" for c in columns) + "   png / pygame")
    missing_pygame = False
    for size in sizes:
        rows: dict[str, list[float]] = {c: [] for c in columns}
        with tempfile.TemporaryDirectory() as tmp:
            for k in range(repeats):
                base = Path(tmp) / str(k)
                rows["png"].append(_export_fps(sim, size, base / "a", gif=False, workers=1))
                rows["png+gif"].append(_export_fps(sim, size, base / "b", workers=1))
                rows["png+gif 2w"].append(_export_fps(sim, size, base / "c", workers=2))
                (base / "d").mkdir(parents=True)
                pygame_fps = _pygame_fps(level, frames, size, base / "d")
                if pygame_fps is None:
                    missing_pygame = True
                else:
                    rows["pygame png"].append(pygame_fps)
                (base / "e").mkdir(parents=True)
                rows["pillow min"].append(_pillow_fps(sim, size, base / "e"))
        medians = {c: statistics.median(v) if v else math.nan for c, v in rows.items()}
        ratio = medians["png"] / medians["pygame png"]
        target = EXPORT_TARGET if size == (960, 540) else None
        print(
            f"   {size[0]}x{size[1]:<6}"
            + "".join(f"{medians[c]:>12.1f}" for c in columns)
            + f"   {ratio:.2f}x  {_verdict(ratio, target, at_most=False)}"
        )
    print(f"   2w: two worker processes ({cores} cores here); the GIF is drawn from every frame")
    if missing_pygame:
        print("   pygame-ce not installed (pip install -e '.[bench]'): its column is skipped")


# -- memory ----------------------------------------------------------------------------------------


def _long_level(folder: Path, seconds: float) -> Path:
    """A copy of a shipped level whose circle goes on for ``seconds``."""
    text = (LEVELS_DIR / f"{MEMORY_LEVEL}.toml").read_text()
    text = text.replace("duration = 18.0", f"duration = {seconds + 1:.1f}", 1)
    text = text.replace("duration = 8.0", f"duration = {seconds:.1f}", 1)
    path = folder / "long.toml"
    path.write_text(text.replace("#:schema ../assets/level.schema.json\n", ""))
    return path


def _tree_rss(pid: int) -> int:
    """Resident memory of the descendants of ``pid`` (not ``pid`` itself), bytes (Linux /proc)."""
    children: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                ppid = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                continue
            children.setdefault(ppid, []).append(int(entry.name))
    total, todo = 0, list(children.get(pid, []))
    while todo:
        current = todo.pop()
        todo.extend(children.get(current, []))
        try:
            for line in Path(f"/proc/{current}/status").read_text().splitlines():
                if line.startswith("VmRSS:"):
                    total += int(line.split()[1]) * 1024
        except OSError:
            continue
    return total


# Runs a command and prints the largest resident memory of it and its descendants (ru_maxrss, KB).
_MAXRSS = (
    "import resource, subprocess, sys; subprocess.run(sys.argv[1:], check=True); "
    "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)"
)


def bench_memory(runs: list[tuple[int, int | None]]) -> None:
    _header(f"memory: peak resident memory of a whole export, {MEMORY_LEVEL} made longer")
    if not Path("/proc/self/status").exists():
        print("   needs Linux /proc to add up worker processes: skipped")
        return
    print(
        f"   {'frames':>7}{'workers':>9}{'wall s':>8}{'largest process':>17}{'all processes':>15}"
    )
    with tempfile.TemporaryDirectory() as tmp:
        for frames, workers in runs:
            level = _long_level(Path(tmp), frames / 30.0)
            out = Path(tmp) / f"out-{frames}-{workers}"
            command = [sys.executable, "-c", _MAXRSS, sys.executable, "-m", "ikgame", "run"]
            command += [str(level), "--quiet", "--out", str(out)]
            command += [] if workers is None else ["--workers", str(workers)]
            start = time.perf_counter()
            proc = subprocess.Popen(
                command, env=_env(), cwd=ROOT, stdout=subprocess.PIPE, text=True
            )
            peak = [0]

            def sample(proc=proc, peak=peak) -> None:
                while proc.poll() is None:
                    peak[0] = max(peak[0], _tree_rss(proc.pid))
                    time.sleep(0.05)

            sampler = threading.Thread(target=sample)
            sampler.start()
            largest_kb = int(proc.communicate()[0].split()[-1])
            sampler.join()
            wall = time.perf_counter() - start
            total_mb = peak[0] / 2**20
            print(
                f"   {frames:>7}{workers or 'auto':>9}{wall:>8.1f}{largest_kb / 1024:>14.0f} MB"
                f"{total_mb:>12.0f} MB   {_verdict(total_mb, MEMORY_TARGET, at_most=True)}"
            )
    print("   all processes: sampled every 50 ms, so a short peak can be missed; target for the")
    print("   18,000-frame limit, which these show flat in the frame count")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer sizes and repeats (CI)")
    parser.add_argument(
        "--only",
        metavar="LIST",
        help="comma-separated sections: tick, levels, startup, solvers, search, export, memory",
    )
    args = parser.parse_args(argv)
    sections = set(
        (args.only or "tick,levels,startup,solvers,search,export,memory")
        .replace(" ", "")
        .split(",")
    )
    quick = args.quick
    started = time.perf_counter()
    print(
        f"ikgame benchmarks{' (quick)' if quick else ''}: python {sys.version.split()[0]}, "
        f"{os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}"
    )
    if "tick" in sections:
        bench_tick([3, 10, 100, 1000] if quick else [3, 10, 30, 100, 200, 1000], 3)
    if sections & {"levels", "startup"}:
        _compile_bytecode()
    if "levels" in sections:
        bench_levels(1 if quick else 2, whole_process=True)
    if "startup" in sections:
        bench_startup(3 if quick else 7)
    if "solvers" in sections:
        bench_solvers([10] if quick else [10, 30, 100], 10 if quick else 20, 3)
    if "search" in sections:
        bench_search(SEARCH_LEVELS[:1] if quick else SEARCH_LEVELS, 1 if quick else 2)
    if "export" in sections:
        sizes = [(960, 540)] if quick else [(480, 270), (960, 540), (1920, 1080)]
        bench_export(30 if quick else 60, 1 if quick else 2, sizes)
    if "memory" in sections:
        bench_memory([(300, None)] if quick else [(300, 1), (300, 2), (900, None)])
    print(f"\ndone in {time.perf_counter() - started:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
