"""The ``ikgame`` command line: run levels, and (as they come) validate, list and compare them.

Exit codes: 0 when the command did its job (a level that fails its script still ran fine),
2 for bad input (a level file, an option), 1 for an internal error.
"""

from __future__ import annotations

import argparse
import re
from collections.abc import Sequence
from pathlib import Path

from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn
from rich.table import Table

import ikgame
from ikgame._files import write_json
from ikgame.level.library import DEFAULT_LEVEL, resolve_level
from ikgame.level.loader import LevelError, load_level
from ikgame.level.model import SOLVER_NAMES
from ikgame.sim import RunResult, Simulation

__all__ = ["main"]

EXIT_OK, EXIT_INTERNAL, EXIT_BAD_INPUT = 0, 1, 2

_DESCRIPTION = """\
ikgame: a 2D physics sandbox for procedural animation.

A motorised chain of rigid links lives in a pymunk world; every physics tick an inverse-kinematics
solver turns the level script's current target into desired joint angles and drives the joint
motors toward them. Levels are TOML files (see docs/levels.md).
"""

_RUN_EPILOG = """\
examples:
  ikgame run                                  the default level, results in runs/first-reach/
  ikgame run levels/02_tentacle.toml --no-frames
  ikgame run my_level.toml --solver dls --out /tmp/try --force

writes DIR/results.json (status, per-step outcomes), and unless --no-frames the frames.
exit codes: 0 the run completed (whatever its status), 2 bad input, 1 internal error.
"""


class UsageError(ValueError):
    """Bad input from the command line: reported in one line, exit code 2."""


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line with ``argv`` (default: ``sys.argv[1:]``); returns the exit code."""
    parser = _parser()
    args = parser.parse_args(argv)
    err = Console(stderr=True, highlight=False)
    try:
        return args.handler(args)
    except LevelError as exc:
        for problem in exc.problems:
            err.print(f"[bold red]error:[/] {problem}", soft_wrap=True)
        return EXIT_BAD_INPUT
    except UsageError as exc:
        err.print(f"[bold red]error:[/] {exc}", soft_wrap=True)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        err.print("interrupted")
        return 130
    except Exception as exc:  # the last line of defence: report, never a bare traceback
        if getattr(args, "debug", False):
            raise
        err.print(f"[bold red]internal error:[/] {type(exc).__name__}: {exc}", soft_wrap=True)
        err.print("rerun with --debug for the traceback, and please report it.")
        return EXIT_INTERNAL


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="ikgame",
        description=_DESCRIPTION,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"ikgame {ikgame.__version__}")
    sub = parser.add_subparsers(title="commands", metavar="COMMAND", required=True)

    run = sub.add_parser(
        "run",
        help="run a level and write its results (and frames)",
        description="Run a level in the physics world and write results.json (and frames).",
        epilog=_RUN_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    run.add_argument(
        "level",
        nargs="?",
        metavar="LEVEL",
        help=f"a level file, or a shipped level's name (default: {DEFAULT_LEVEL.stem})",
    )
    run.add_argument(
        "--out", metavar="DIR", type=Path, help="output folder (default: runs/<level>)"
    )
    run.add_argument(
        "--solver",
        choices=SOLVER_NAMES,
        help="IK solver, overriding the level's own choice",
    )
    run.add_argument("--no-frames", action="store_true", help="write results only, no pictures")
    run.add_argument("--quiet", action="store_true", help="print nothing but errors")
    run.add_argument("--force", action="store_true", help="write into a non-empty output folder")
    run.add_argument("--debug", action="store_true", help="show tracebacks of internal errors")
    run.set_defaults(handler=_cmd_run)
    return parser


def _slug(name: str) -> str:
    return re.sub(r"[^a-z0-9]+", "-", name.lower()).strip("-") or "level"


def _cmd_run(args: argparse.Namespace) -> int:
    level_path = resolve_level(args.level)
    level = load_level(level_path)
    out = args.out if args.out is not None else Path("runs") / _slug(level.level.name)
    _check_out_dir(out, args.force)
    console = Console(quiet=args.quiet, highlight=False)
    sim = Simulation(level, solver=args.solver, record=not args.no_frames)
    with _progress(console, "simulating") as update:
        result = sim.run(update)
    write_json(out / "results.json", _results(result, level_path, args))
    _print_summary(console, result, out)
    return EXIT_OK


def _results(result: RunResult, level_path: Path, args: argparse.Namespace) -> dict[str, object]:
    data = result.as_dict()
    options = dict(data["options"])
    options.update({"level_file": level_path.name, "solver_override": args.solver})
    data["options"] = options
    return data


def _check_out_dir(out: Path, force: bool) -> None:
    if out.exists() and not out.is_dir():
        raise UsageError(f"--out {out}: exists and is not a folder")
    if out.is_dir() and any(out.iterdir()) and not force:
        raise UsageError(f"--out {out}: folder is not empty (use --force to write into it)")


class _progress:
    """A rich progress bar on a terminal; nothing elsewhere. Yields ``update(fraction)``."""

    def __init__(self, console: Console, label: str) -> None:
        self.enabled = console.is_terminal and not console.quiet
        self.bar = Progress(
            TextColumn(f"{label:<11}"),
            BarColumn(),
            TextColumn("{task.percentage:>3.0f}%"),
            TimeRemainingColumn(),
            console=console,
            transient=True,
            disable=not self.enabled,
        )

    def __enter__(self):
        self.bar.__enter__()
        task = self.bar.add_task("", total=1.0)
        return lambda fraction: self.bar.update(task, completed=fraction)

    def __exit__(self, *exc: object) -> None:
        self.bar.__exit__(*exc)


def _print_summary(console: Console, result: RunResult, out: Path) -> None:
    colour = {"passed": "green", "failed": "yellow", "diverged": "red"}[result.status]
    console.print(
        f"[bold]{result.level}[/] ({result.solver}): [bold {colour}]{result.status}[/] "
        f"after {result.sim_time:.2f} s simulated ({result.ticks} ticks)"
    )
    table = Table(show_edge=False, pad_edge=False)
    for column in ("step", "kind", "result", "time to reach (s)", "final error (px)"):
        table.add_column(column, justify="right" if "(" in column else "left")
    for step in result.steps:
        table.add_row(
            str(step.index + 1),
            step.kind,
            "[green]passed[/]" if step.passed else f"[yellow]failed[/] {step.note}",
            "-" if step.time_to_reach is None else f"{step.time_to_reach:.2f}",
            "-" if step.final_error is None else f"{step.final_error:.1f}",
        )
    console.print(table)
    console.print(f"results: {out / 'results.json'}")
