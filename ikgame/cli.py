"""The ``ikgame`` command line: run levels, and (as they come) validate, list and compare them.

Exit codes: 0 when the command did its job (a level that fails its script still ran fine),
2 for bad input (a level file, an option, an output folder that cannot be written), 1 for an
internal error; 130 / 143 when stopped by Ctrl-C / SIGTERM; ``check`` exits 3 when a run does not
reproduce. User text (file names, level values) is printed as written, never read as markup.

Start-up time is most of a short command's time, so this module imports at the top only what
building the parser needs; each command imports its own modules (the simulation, Pillow, rich,
the comparison) when it runs, and ``ikgame --version`` loads none of them.
"""

from __future__ import annotations

import argparse
import errno
import json
import math
import re
import signal
import sys
import threading
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

import ikgame
from ikgame._files import prepare_out_dir, remove_temporaries, write_atomic, write_json
from ikgame.budget import DEFAULT_BUDGET_MINUTES, RunEstimate, estimate_run
from ikgame.level.library import DEFAULT_LEVEL, resolve_level
from ikgame.level.names import SOLVER_NAMES
from ikgame.render.theme import Theme, ThemeError, available_themes, load_theme

if TYPE_CHECKING:
    from rich.console import Console

    from ikgame.level.model import Level
    from ikgame.sim import RunResult

__all__ = ["main"]

EXIT_OK, EXIT_INTERNAL, EXIT_BAD_INPUT, EXIT_NOT_REPRODUCED = 0, 1, 2, 3
EXIT_INTERRUPTED, EXIT_TERMINATED = 130, 143
_DISK_ERRORS = frozenset(
    {errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EACCES, errno.EPERM, errno.EISDIR}
)
"""Errors of the file system a user can fix: reported as bad input, not as a bug."""

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

writes into DIR:
  results.json   status (passed / failed / diverged), per-step outcomes, score
  frames/        000000.png, 000001.png ... one per recorded frame (level fps)
  run.gif        the whole run, looping
  motion.json    baked motion: per frame every joint's angle and position, for a game engine
  run.png        an animated PNG (with --apng)     sheet.png  a contact sheet (with --sheet)
  run.mp4        H.264 video at the level's fps (with --mp4; needs: pip install 'ikgame[video]')
before it starts, a run's cost is estimated from the level (ticks x links x iterations,
obstacles, props, frames x pixels); above --budget (default 30 minutes) it is refused.

exit codes: 0 the run completed (whatever its status), 2 bad input, 1 internal error,
130 / 143 stopped by Ctrl-C / SIGTERM (no results.json is written then).
"""


class UsageError(ValueError):
    """Bad input from the command line: reported in one line, exit code 2."""


class _Terminated(KeyboardInterrupt):
    """SIGTERM, raised like Ctrl-C so that every ``finally`` and ``except BaseException``
    cleans up the same way."""


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line with ``argv`` (default: ``sys.argv[1:]``); returns the exit code."""
    parser = _parser()
    args = parser.parse_args(argv)
    with _sigterm_raises():
        return _handle(args)


def _handle(args: argparse.Namespace) -> int:
    from ikgame.level.loader import LevelError

    try:
        return args.handler(args)
    except LevelError as exc:
        err = _console(stderr=True)
        for problem in exc.problems:
            err.print(f"[bold red]error:[/] {_escape(str(problem))}", soft_wrap=True)
        return EXIT_BAD_INPUT
    except UsageError as exc:
        _console(stderr=True).print(f"[bold red]error:[/] {_escape(str(exc))}", soft_wrap=True)
        return EXIT_BAD_INPUT
    except KeyboardInterrupt as exc:
        what = "terminated (SIGTERM)" if isinstance(exc, _Terminated) else "interrupted"
        notes = "; ".join(getattr(exc, "__notes__", ())) or "nothing was written"
        _console(stderr=True).print(_escape(f"{what}: {notes}"), soft_wrap=True)
        return EXIT_TERMINATED if isinstance(exc, _Terminated) else EXIT_INTERRUPTED
    except OSError as exc:
        if exc.errno not in _DISK_ERRORS or getattr(args, "debug", False):
            return _internal(args, exc)
        where = f" {exc.filename}" if exc.filename else ""
        message = _escape(f"cannot write{where}: {exc.strerror}")
        _console(stderr=True).print(f"[bold red]error:[/] {message}", soft_wrap=True)
        return EXIT_BAD_INPUT
    except Exception as exc:  # the last line of defence: report, never a bare traceback
        return _internal(args, exc)


def _internal(args: argparse.Namespace, exc: Exception) -> int:
    if getattr(args, "debug", False):
        raise exc
    err = _console(stderr=True)
    err.print(
        f"[bold red]internal error:[/] {type(exc).__name__}: {_escape(_text(exc))}", soft_wrap=True
    )
    err.print("rerun with --debug for the traceback, and please report it.")
    return EXIT_INTERNAL


def _escape(text: str) -> str:
    """``text`` with rich's markup escaped: rich is imported only for a message to print."""
    from rich.markup import escape as escape_markup

    return escape_markup(text)


def _text(exc: BaseException) -> str:
    """``str(exc)``, or its type's name when even that fails."""
    try:
        return str(exc)
    except Exception:  # a message that cannot be made (e.g. an int too long to print)
        return type(exc).__name__


def _console(*, stderr: bool = False, quiet: bool = False) -> Console | _Silent:
    """A console that prints text as written: no emoji codes (``:100:``), no highlighting;
    markup only in the literals of this module, user text always goes through ``_escape``.
    Quiet, one that prints nothing and needs no rich."""
    if quiet:
        return _Silent()
    from rich.console import Console

    return Console(stderr=stderr, highlight=False, emoji=False)


class _Silent:
    """The console of a quiet command: prints nothing. rich takes longer to import than a short
    level takes to run, and a quiet run has nothing to show with it."""

    quiet = True
    is_terminal = False

    def print(self, *objects: object, **options: object) -> None:
        """Print nothing."""


@contextmanager
def _sigterm_raises() -> Iterator[None]:
    """While the command runs, SIGTERM stops it like Ctrl-C (cleanly, files closed)."""

    def stop(signum: int, frame: object) -> None:
        raise _Terminated()

    try:
        previous = signal.signal(signal.SIGTERM, stop)
    except ValueError:  # not the main thread: leave signals alone
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


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
    _output_options(run, "output folder (default: runs/<level>)")
    run.add_argument(
        "--solver",
        choices=SOLVER_NAMES,
        help="IK solver, overriding the level's own choice",
    )
    run.add_argument(
        "--no-frames",
        action="store_true",
        help="write results.json and motion.json only, no pictures",
    )
    run.add_argument("--no-gif", action="store_true", help="skip run.gif")
    run.add_argument("--apng", action="store_true", help="also write run.png, an animated PNG")
    run.add_argument("--sheet", action="store_true", help="also write sheet.png, a contact sheet")
    run.add_argument(
        "--mp4",
        action="store_true",
        help="also write run.mp4 (H.264, yuv420p; an odd side loses one pixel); needs the video "
        "extra",
    )
    run.add_argument(
        "--size", default="960x540", metavar="WxH", help="frame size in pixels (default: 960x540)"
    )
    run.add_argument(
        "--theme",
        metavar="NAME",
        help=f"colour theme: {', '.join(available_themes())}, or a theme JSON file "
        "(default: the level's own theme, else light)",
    )
    run.add_argument(
        "--workers", type=int, metavar="N", help="processes drawing frames (default: automatic)"
    )
    _budget_options(run)
    run.add_argument(
        "--png-compression",
        type=int,
        default=1,
        choices=range(10),
        metavar="LEVEL",
        help="zlib level 0..9 of the PNG files: 1 (default) is fast, 9 makes them smaller",
    )
    run.set_defaults(handler=_cmd_run)

    check = sub.add_parser(
        "check",
        help="run a recorded run again and report whether it reproduces exactly",
        description="Read a results.json, run the same level with the same options again (in a "
        "temporary folder) and compare: the outcome, every number, and the hash of every file "
        "written (frames included). The level file must be unchanged.",
        epilog="example:\n  ikgame check runs/first-reach/results.json\n\n"
        "exit codes: 0 reproduced exactly, 3 it did not (the differences are listed), "
        "2 bad input.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    check.add_argument("results", metavar="RESULTS", type=Path, help="a results.json")
    check.add_argument(
        "--level", metavar="LEVEL", help="the level file, if it has moved since the run"
    )
    check.add_argument("--quiet", action="store_true", help="print nothing but the verdict")
    check.add_argument("--debug", action="store_true", help="show tracebacks of internal errors")
    _budget_options(check)
    check.set_defaults(handler=_cmd_check)

    compare = sub.add_parser(
        "compare",
        help="run a level once per solver and compare them",
        description="Run a level once per IK solver in the physics world; write compare.json "
        "and compare.png (error against time, end-effector paths) and print a table.",
        epilog="example:\n  ikgame compare 02_tentacle --solvers ccd,dls --out /tmp/cmp\n\n"
        "timings (solver us/tick) are wall-clock measurements and vary from run to run;\n"
        "everything else in compare.json is deterministic.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    compare.add_argument("level", nargs="?", metavar="LEVEL", help="a level file or shipped name")
    _budget_options(compare)
    compare.add_argument(
        "--solvers",
        default=",".join(SOLVER_NAMES),
        metavar="LIST",
        help=f"comma-separated solvers (default: {','.join(SOLVER_NAMES)})",
    )
    _output_options(compare, "output folder (default: runs/<level>-compare)")
    compare.set_defaults(handler=_cmd_compare)

    validate = sub.add_parser(
        "validate",
        help="check level files and list every problem",
        description="Check level files without running them. Every problem is listed with the "
        "file, the line, the field and what was expected.",
        epilog="example:\n  ikgame validate levels/*.toml my_level.toml\n\n"
        "exit codes: 0 all valid, 2 problems found.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    validate.add_argument("files", nargs="+", metavar="FILE", help="level files or folders")
    validate.add_argument("--quiet", action="store_true", help="print nothing but problems")
    validate.set_defaults(handler=_cmd_validate)

    listing = sub.add_parser(
        "list",
        help="list the shipped levels",
        description="The shipped levels in learning order: run one with 'ikgame run NAME'.",
    )
    listing.set_defaults(handler=_cmd_list)

    schema = sub.add_parser(
        "schema",
        help="print the JSON Schema of the level format",
        description="Print (or write) the JSON Schema of level files, for editors that "
        "autocomplete and check TOML against a schema (see docs/levels.md).",
    )
    schema.add_argument("--out", metavar="FILE", type=Path, help="write it to FILE instead")
    schema.set_defaults(handler=_cmd_schema)
    _live_commands(sub)
    return parser


def _output_options(parser: argparse.ArgumentParser, out_help: str) -> None:
    """--out, --force, --quiet and --debug, the same for every command that writes a folder."""
    parser.add_argument("--out", metavar="DIR", type=Path, help=out_help)
    parser.add_argument("--force", action="store_true", help="write into a non-empty folder")
    parser.add_argument("--quiet", action="store_true", help="print nothing but errors")
    parser.add_argument("--debug", action="store_true", help="show tracebacks of internal errors")


def _budget_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--budget",
        type=_minutes,
        default=DEFAULT_BUDGET_MINUTES,
        metavar="MINUTES",
        help=f"refuse a run estimated to take longer (default: {DEFAULT_BUDGET_MINUTES:g})",
    )
    parser.add_argument(
        "--no-budget", action="store_true", help="run whatever the estimate (see --budget)"
    )


def _minutes(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number of minutes: {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"must be a positive number of minutes, got {text!r}")
    return value


def _slug(name: str) -> str:
    return re.sub(r"[^a-z0-9]+", "-", name.lower()).strip("-") or "level"


def _cmd_run(args: argparse.Namespace) -> int:
    from ikgame.render.output import parse_size
    from ikgame.render.video import check_video

    level_path = resolve_level(args.level)
    level, theme, named = _load(level_path, args.theme)
    out = args.out if args.out is not None else Path("runs") / _slug(level.level.name)
    # Every option is checked before anything is written: bad input leaves no half-made folder.
    with _usage("--size"):
        size = parse_size(args.size)
    if args.workers is not None and args.workers < 1:
        raise UsageError(f"--workers: must be at least 1, got {args.workers}")
    if args.mp4:
        if args.no_frames:
            raise UsageError("--mp4: there are no pictures to encode with --no-frames")
        with _usage("--mp4"):
            check_video()
    _check_budget(estimate_run(level, frame_size=None if args.no_frames else size), args)
    with _usage("--out"):
        prepare_out_dir(out, args.force)
    console = _console(quiet=args.quiet)
    result, data, written = _run_into(out, level, level_path, theme, named, size, args, console)
    _print_summary(console, result, out, written)
    return EXIT_OK


def _run_into(
    out: Path,
    level: Level,
    level_path: Path,
    theme: Theme,
    named: dict[str, Path],
    size: tuple[int, int],
    args: argparse.Namespace,
    console: Console | _Silent,
) -> tuple[RunResult, dict[str, object], list[Path]]:
    """Simulate, export and write results.json last; a stop on the way leaves no results.json
    (and says so)."""
    from ikgame._progress import progress_bar
    from ikgame.provenance import output_hashes
    from ikgame.render.motion import write_motion
    from ikgame.sim import Simulation

    try:
        # Frames are recorded even without pictures: motion.json is written either way.
        sim = Simulation(level, solver=args.solver)
        scene = sim.scene
        if not args.no_frames:
            from ikgame.skins import skin_scene

            # Sprites are decoded before the run, so an image that cannot be used stops it at once.
            scene = skin_scene(sim.scene, level, level_path)
        enabled = _interactive(console)
        with progress_bar("simulating", 1.0, enabled=enabled, console=console) as update:
            result = sim.run(update)
        if args.no_frames:
            written = [write_motion(out, scene, sim.snapshots)]
        else:
            from ikgame.render.export import export_run

            written = export_run(
                out,
                scene,
                sim.snapshots,
                size=size,
                theme=theme,
                gif=not args.no_gif,
                apng=args.apng,
                sheet=args.sheet,
                mp4=args.mp4,
                workers=args.workers,
                progress=enabled,
                png_compression=args.png_compression,
            )
    except KeyboardInterrupt as exc:
        if out.is_dir():
            remove_temporaries(out)
        frames = sum(1 for _ in (out / "frames").glob("[0-9]*.png"))
        kept = f"{frames} frames in {out / 'frames'}" if frames else f"nothing in {out}"
        exc.add_note(f"the run was cut short: kept {kept}, no results.json")
        raise
    data = _results(result, level_path, named, size, args, output_hashes(out, written))
    written.append(write_json(out / "results.json", data))
    return result, data, written


def _cmd_compare(args: argparse.Namespace) -> int:
    from ikgame._progress import progress_bar
    from ikgame.compare import compare_level, comparison_table, write_comparison

    level, _, _ = _load(resolve_level(args.level), None)
    # Order kept, repeats dropped: "ccd,dls,ccd" compares two solvers.
    solvers = list(dict.fromkeys(name.strip() for name in args.solvers.split(",") if name.strip()))
    unknown = [name for name in solvers if name not in SOLVER_NAMES]
    if unknown or not solvers:
        raise UsageError(
            f"--solvers: unknown solver {', '.join(map(repr, unknown)) or '(none given)'}; "
            f"choose from: {', '.join(SOLVER_NAMES)}"
        )
    out = args.out if args.out is not None else Path("runs") / f"{_slug(level.level.name)}-compare"
    estimate = estimate_run(level, frame_size=None)
    _check_budget(replace(estimate, simulate_s=estimate.simulate_s * len(solvers)), args)
    with _usage("--out"):
        prepare_out_dir(out, args.force)
    console = _console(quiet=args.quiet)
    with progress_bar("comparing", 1.0, enabled=_interactive(console), console=console) as update:
        comparison = compare_level(level, solvers, progress=update)
    written = write_comparison(out, comparison)
    console.print(comparison_table(comparison))
    console.print(f"wrote {_escape(str(out))}/: {', '.join(p.name for p in written)}")
    return EXIT_OK


def _cmd_validate(args: argparse.Namespace) -> int:
    from ikgame.level.loader import LevelError
    from ikgame.level.tools import validate_files

    console = _console(quiet=args.quiet)
    paths = [resolve_level(name) for name in args.files]
    problems = validate_files(paths, check=lambda level, path: _load(path, None, level))
    if problems:
        raise LevelError(problems)
    count = sum(len(list(p.glob("*.toml"))) if p.is_dir() else 1 for p in paths)
    console.print(f"{count} level file{'s' if count != 1 else ''} valid")
    return EXIT_OK


def _cmd_list(args: argparse.Namespace) -> int:
    from ikgame.level.tools import level_rows

    console = _console()
    for row in level_rows():
        ends = "" if row["expect"] == "passed" else f", meant to end {row['expect']}"
        console.print(
            f"[bold]{Path(str(row['file'])).stem}[/]  {_escape(str(row['name']))}  "
            f"[dim]({row['links']} links, {row['steps']} steps, {row['solver']}{ends})[/]"
        )
        console.print(f"    {_escape(str(row['description']))}")
    console.print("\nrun one with: ikgame run NAME   (for example: ikgame run 02_tentacle)")
    return EXIT_OK


def _cmd_schema(args: argparse.Namespace) -> int:
    from ikgame.level.tools import schema_text

    text = schema_text()
    if args.out is None:
        sys.stdout.write(text)
    else:
        if args.out.is_dir():
            raise UsageError(
                f"--out: {args.out} is a folder; name a file such as level.schema.json"
            )
        try:
            write_atomic(args.out, text.encode("utf-8"))
        except OSError as exc:
            raise UsageError(f"--out: cannot write {args.out} ({exc.strerror})") from None
    return EXIT_OK


def _cmd_check(args: argparse.Namespace) -> int:
    from ikgame.provenance import differences, file_sha256
    from ikgame.render.output import parse_size

    try:
        recorded = json.loads(args.results.read_text(encoding="utf-8"))
        rerun, prov = recorded["rerun"], recorded["provenance"]
        # Options a results.json from an older ikgame does not record take their defaults.
        defaults = {"mp4": False, "png_compression": 1}
        options = argparse.Namespace(**(defaults | rerun), workers=None)
    except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError) as exc:
        raise UsageError(
            f"{args.results}: not the results.json of an ikgame run ({_text(exc)})"
        ) from None
    level_path = resolve_level(args.level if args.level is not None else rerun["level"])
    console = _console(quiet=args.quiet)
    if (sha := file_sha256(level_path)) != prov["level_sha256"]:
        console.print(
            _escape(f"{level_path} has changed since the run (sha256 {sha[:12]}...)"),
            soft_wrap=True,
        )
        return EXIT_NOT_REPRODUCED
    level, theme, named = _load(level_path, options.theme)
    with _usage("size"):
        size = parse_size(options.size)
    _check_budget(estimate_run(level, frame_size=None if options.no_frames else size), args)
    import tempfile

    with tempfile.TemporaryDirectory(prefix="ikgame-check-") as folder:
        _, again, _ = _run_into(
            Path(folder), level, level_path, theme, named, size, options, _console(quiet=True)
        )
    found = differences(recorded, json.loads(json.dumps(again)))
    if found:
        console.print(
            _escape(f"{args.results}: does not reproduce; differences (recorded -> now):"),
            soft_wrap=True,
        )
        for line in found:
            console.print(_escape(f"  {line}"), soft_wrap=True)
        return EXIT_NOT_REPRODUCED
    frames = again["outputs"].get("frames", {}).get("count", 0)  # type: ignore[union-attr]
    extra = f", {frames} frames identical" if frames else ""
    console.print(
        _escape(f"{args.results}: reproduces exactly ({again['status']}{extra})"), soft_wrap=True
    )
    return EXIT_OK


def _load(
    level_path: Path, theme_option: str | None, level: Level | None = None
) -> tuple[Level, Theme, dict[str, Path]]:
    """The level, the theme it runs with (``--theme``, else its own, else light) and the files
    it names (sprites, and its theme when used), by the name the level gives them; a bad theme
    file is a problem of the level, or of ``--theme``.
    """
    from ikgame.level.loader import (
        LevelError,
        Problem,
        level_theme,
        load_level,
        sprite_fields,
        sprite_file,
    )

    if level is None:
        level = load_level(level_path)
    # load_level has checked every sprite file: resolving them again cannot fail.
    named = {name: sprite_file(name, level_path)[0] for _, name in sprite_fields(level)}
    if theme_option is not None:
        with _usage("--theme"):
            return level, load_theme(theme_option), named
    try:
        own = level_theme(level, level_path)
    except ValueError as exc:
        raise LevelError([Problem(str(level_path), None, "level.theme", str(exc))]) from None
    try:
        theme = load_theme(own or "light")
    except ThemeError as exc:
        reason = f"{exc.reason} (the theme of {level_path})"
        raise LevelError([Problem(str(exc.file), exc.line, exc.field, reason)]) from None
    if isinstance(own, Path):
        named[str(level.level.theme)] = own
    return level, theme, named


def _check_budget(estimate: RunEstimate, args: argparse.Namespace) -> None:
    if args.no_budget or estimate.seconds <= args.budget * 60:
        return
    minutes = math.ceil(estimate.seconds / 60)
    raise UsageError(
        f"this run is estimated at {estimate.describe()}, over the budget of {args.budget:g} "
        f"minutes; shorten the level, or pass --budget {minutes} (or --no-budget) to run it"
    )


def _interactive(console: Console | _Silent) -> bool:
    return console.is_terminal and not console.quiet


class _usage:
    """Turn a ValueError from checking an option into a UsageError naming the option."""

    def __init__(self, option: str) -> None:
        self.option = option

    def __enter__(self) -> None:
        return None

    def __exit__(self, kind: type | None, exc: BaseException | None, tb: object) -> bool:
        from ikgame.level.loader import LevelError

        if isinstance(exc, ValueError) and not isinstance(exc, UsageError | LevelError):
            raise UsageError(f"{self.option}: {exc}") from None
        return False


def _results(
    result: RunResult,
    level_path: Path,
    named: dict[str, Path],
    size: tuple[int, int],
    args: argparse.Namespace,
    outputs: dict[str, object],
) -> dict[str, object]:
    from ikgame.provenance import provenance

    data = result.as_dict()
    options = dict(data["options"])
    options.update({"level_file": level_path.name, "solver_override": args.solver})
    data["options"] = options
    # What `ikgame check` needs to run it again: the level as named and every output option.
    data["rerun"] = {
        "level": args.level if args.level is not None else DEFAULT_LEVEL.stem,
        "solver": args.solver,
        "no_frames": args.no_frames,
        "no_gif": args.no_gif,
        "apng": args.apng,
        "sheet": args.sheet,
        "mp4": args.mp4,
        "png_compression": args.png_compression,
        "size": f"{size[0]}x{size[1]}",
        "theme": args.theme,
    }
    data["provenance"] = provenance(level_path, named)
    data["outputs"] = outputs
    return data


def _print_summary(
    console: Console | _Silent, result: RunResult, out: Path, written: list[Path]
) -> None:
    if console.quiet:
        return
    from rich.table import Table

    colour = {"passed": "green", "failed": "yellow", "diverged": "red"}[result.status]
    expected = (
        "" if result.status == result.expect else f" [dim](designed to end {result.expect})[/]"
    )
    console.print(
        f"[bold]{_escape(result.level)}[/] ({result.solver}): [bold {colour}]{result.status}[/]"
        f"{expected}, score {result.score:.0f}/100, after {result.sim_time:.2f} s simulated "
        f"({result.ticks} ticks)"
    )
    table = Table(show_edge=False, pad_edge=False)
    columns = ("step", "kind", "result", "time to reach (s)", "error: final / mean (px)")
    for column in columns:
        table.add_column(column, justify="right" if "(" in column else "left")
    for step in result.steps:
        errors = [e for e in (step.final_error, step.mean_error) if e is not None]
        table.add_row(
            str(step.index + 1),
            step.kind,
            "[green]passed[/]" if step.passed else f"[yellow]failed[/] {_escape(step.note)}",
            "-" if step.time_to_reach is None else f"{step.time_to_reach:.2f}",
            " / ".join(f"{e:.1f}" for e in errors) or "-",
        )
    for goal in result.goals:
        x, y = goal.final_position
        table.add_row(
            f"goal {goal.index + 1}",
            _escape(goal.name),
            "[green]passed[/]" if goal.passed else "[yellow]failed[/]",
            "-",
            f"{_escape(goal.prop)} ended at ({x:.0f}, {y:.0f})",
        )
    console.print(table)
    if result.footing:
        worst = {k: max(leg[k] for leg in result.footing.values()) for k in ("slip", "sink")}
        steps = sum(leg["steps"] for leg in result.footing.values())
        console.print(
            f"footing: {steps} steps by {len(result.footing)} feet; planted feet slid at most "
            f"{worst['slip']:.1f} px and sank at most {worst['sink']:.1f} px"
        )
    frames = sum(1 for p in written if p.parent.name == "frames")
    others = [p.name for p in written if p.parent.name != "frames"]
    listed = ([f"frames/ ({frames} PNG)"] if frames else []) + others
    console.print(f"wrote {_escape(str(out))}/: {', '.join(listed)}")


# -- live commands: a window on a running level, and re-running a level as it is edited ----------

_PLAY_EPILOG = """\
examples:
  ikgame play                                 the default level in a 960x540 window
  ikgame play 12_push_the_ball --solver dls
  ikgame play my_level.toml --watch           reload the level each time the file is saved

in the window:
{keys}

The window is drawn by the same renderer as 'ikgame run' frames. The simulation runs at the
level's tick rate whatever the display's frame rate; without mouse input a level ends exactly as
'ikgame run' ends it. Needs the play extra: python -m pip install 'ikgame[play]'
(--watch also the watch extra: python -m pip install 'ikgame[play,watch]').
"""

_WATCH_EPILOG = """\
examples:
  ikgame watch my_level.toml                  results and frames in runs/<level>/
  ikgame watch my_level.toml --no-frames --out /tmp/try

Runs the level as 'ikgame run' does, then again whenever the level file or a file it names (its
theme) is saved: the result table or the level's problems are printed, and the outputs are
rewritten file by file atomically. Ctrl-C stops watching (exit code 0) and leaves the last
outputs whole. Needs the watch extra: python -m pip install 'ikgame[watch]'
"""


class _KeysHelp(argparse.RawDescriptionHelpFormatter):
    """Fills the play command's key list in when its help is printed: the list lives with the
    window's state, which imports the simulation and Pillow, too much for every start-up."""

    def _fill_text(self, text: str, width: int, indent: str) -> str:
        if "{keys}" in text:
            from ikgame.app.state import help_lines

            keys = "\n".join(f"  {keys:<14} {what}" for keys, what in help_lines())
            text = text.replace("{keys}", keys)
        return super()._fill_text(text, width, indent)


def _live_commands(sub: argparse._SubParsersAction) -> None:

    play = sub.add_parser(
        "play",
        help="play a level live in a window: drag the target with the mouse",
        description="Run a level live in a window (pygame-ce) at its tick rate: drag the target "
        "with the mouse, pause, step, restart, switch solvers, toggle gravity, take screenshots.",
        epilog=_PLAY_EPILOG,
        formatter_class=_KeysHelp,
    )
    play.add_argument("level", nargs="?", metavar="LEVEL", help="a level file or shipped name")
    play.add_argument("--solver", choices=SOLVER_NAMES, help="IK solver to start with")
    play.add_argument(
        "--size", default="960x540", metavar="WxH", help="window size in pixels (default: 960x540)"
    )
    play.add_argument("--theme", metavar="NAME", help="colour theme (default: the level's own)")
    play.add_argument(
        "--out", metavar="DIR", type=Path, help="screenshot folder (default: runs/<level>)"
    )
    play.add_argument("--watch", action="store_true", help="reload the level when its file changes")
    play.add_argument("--debug", action="store_true", help="show tracebacks of internal errors")
    play.set_defaults(handler=_cmd_play)

    watch = sub.add_parser(
        "watch",
        help="re-run a level whenever its file changes",
        description="Run a level, then run it again each time its file (or a file it names) "
        "changes, printing the results or the level's problems.",
        epilog=_WATCH_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    watch.add_argument("level", metavar="LEVEL", help="a level file or shipped name")
    _output_options(watch, "output folder (default: runs/<level>)")
    watch.add_argument("--solver", choices=SOLVER_NAMES, help="IK solver, as for run")
    watch.add_argument(
        "--no-frames",
        action="store_true",
        help="write results.json and motion.json only, no pictures",
    )
    watch.set_defaults(handler=_cmd_watch)


def _extra(module: str, extra: str, purpose: str) -> None:
    from ikgame.app._extras import MissingExtra, require

    try:
        require(module, extra, purpose)
    except MissingExtra as exc:
        raise UsageError(str(exc)) from None


def _cmd_play(args: argparse.Namespace) -> int:
    from ikgame.render.output import parse_size

    _extra("pygame", "play", "ikgame play")
    if args.watch:
        _extra("watchfiles", "watch", "ikgame play --watch")
    from ikgame.app.state import PlayState
    from ikgame.app.window import NoDisplay, play

    with _usage("--size"):
        size = parse_size(args.size)
    theme = None
    if args.theme is not None:
        with _usage("--theme"):
            theme = load_theme(args.theme)
    state = PlayState(resolve_level(args.level), solver=args.solver, size=size, theme=theme)
    state.out_dir = (
        args.out if args.out is not None else Path("runs") / _slug(state.level.level.name)
    )
    try:
        play(state, watch=args.watch)
    except NoDisplay as exc:
        raise UsageError(f"cannot open a window: {exc}; ikgame play needs a desktop") from None
    return EXIT_OK


def _cmd_watch(
    args: argparse.Namespace,
    *,
    stop: threading.Event | None = None,
    ready: Callable[[], None] | None = None,
) -> int:
    """``stop`` and ``ready`` let a caller other than the terminal end the watch and know when
    it is in place (see :func:`ikgame.app.watch.watch_level`)."""
    from ikgame.level.tools import validate_files

    _extra("watchfiles", "watch", "ikgame watch")
    from ikgame.app.watch import level_files, watch_level

    level_path = resolve_level(args.level)
    # Every run goes through the run command itself: same checks, outputs, messages and table.
    argv = ["run", str(level_path)]
    for option, value in (("--out", args.out), ("--solver", args.solver)):
        if value is not None:
            argv += [option, str(value)]
    flags = {"--no-frames": args.no_frames, "--quiet": args.quiet, "--debug": args.debug}
    argv += [flag for flag, on in flags.items() if on]
    forced = args.force

    def run() -> int:
        nonlocal forced
        code = main([*argv, "--force"] if forced else argv)
        # Once written, the folder holds this watch's own outputs: rewrite them on each change.
        forced = forced or code == EXIT_OK
        return code

    console = _console(quiet=args.quiet)

    def again() -> None:
        console.print(f"\n[bold]{_escape(level_path.name)}[/] changed: running it again")
        if run() == EXIT_INTERRUPTED:
            raise KeyboardInterrupt

    try:
        code = run()
        if code == EXIT_INTERRUPTED:
            raise KeyboardInterrupt
        if code != EXIT_OK and not validate_files([level_path]):
            return code  # the options are wrong, not the level: no edit to it can help
        names = ", ".join(_escape(str(path)) for path in sorted(level_files(level_path)))
        console.print(f"watching {names} for changes (Ctrl-C stops)")
        watch_level(level_path, again, stop=stop, ready=ready)
    except KeyboardInterrupt:
        # Every file is written atomically: what is on disk now is whole.
        console.print("stopped watching")
    return EXIT_OK
