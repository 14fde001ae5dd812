"""Frames per second of the ``ikgame play`` window: ``python benchmarks/play_fps.py``.

Each frame is what the window does 60 times a second: read events, run the physics ticks of
1/60 s of real time, draw the state with the Pillow renderer (the same as exported frames, plus
the status line), and blit it. SDL's dummy video driver stands in for a display, so the number
is the drawing cost without the final copy to the screen. Needs the play extra (pygame-ce).

Two rates are printed: by the wall clock, and by the CPU time the process got. On a busy shared
machine the first falls with the load; the second is what a core to itself would give.
"""

from __future__ import annotations

import argparse
import os
import time

from ikgame.app.state import PlayState
from ikgame.app.window import Window
from ikgame.level.library import resolve_level
from ikgame.render.export import parse_size

LEVELS = ("01_first_reach", "02_tentacle", "12_push_the_ball", "13_conductor")


def measure(level: str, size: tuple[int, int], frames: int) -> tuple[float, float, float]:
    """Frames per second of the window by the wall clock and by CPU time, and of its physics
    alone (wall clock), over ``frames`` frames."""
    state = PlayState(resolve_level(level), size=size)
    with Window(state) as window:
        window.frame(0.0)  # the static layers are drawn once per run: not part of a frame
        physics = 0.0
        start, cpu = time.perf_counter(), time.process_time()
        for _ in range(frames):
            window.pump()
            tick_start = time.perf_counter()
            state.advance(1 / 60)
            physics += time.perf_counter() - tick_start
            window.draw()
        elapsed, cpu = time.perf_counter() - start, time.process_time() - cpu
    return frames / elapsed, frames / cpu, frames / physics


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", default="960x540", help="window size (default: 960x540)")
    parser.add_argument("--frames", type=int, default=180, help="frames per level (default: 180)")
    parser.add_argument("levels", nargs="*", default=list(LEVELS), help="levels to measure")
    args = parser.parse_args(argv)
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    size = parse_size(args.size)
    print(f"ikgame play at {size[0]}x{size[1]}, {args.frames} frames of 1/60 s each")
    print(f"  {'level':<20}{'frames/s (wall)':>17}{'(CPU time)':>12}{'physics alone':>15}")
    for level in args.levels:
        fps, cpu_fps, physics_fps = measure(level, size, args.frames)
        print(f"  {level:<20}{fps:>17.1f}{cpu_fps:>12.1f}{physics_fps:>15.0f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
