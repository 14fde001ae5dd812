"""Atomic file writes (a reader sees the old file or the new one, never half of one), and the
output folder a run writes into."""

from __future__ import annotations

import json
import os
import re
import tempfile
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO

__all__ = [
    "atomic_open",
    "write_atomic",
    "write_json",
    "prepare_out_dir",
    "remove_temporaries",
    "OUTPUT_FILES",
]

OUTPUT_FILES = (
    "results.json",  # first: a folder never claims a completed run it does not hold
    "motion.json",
    "run.gif",
    "run.png",
    "sheet.png",
    "run.mp4",
    "compare.json",
    "compare.png",
)
"""The files a command writes at the top of its output folder."""
FRAMES_DIR = "frames"
_FRAME = re.compile(r"\d{6}\.png")
_TEMP = re.compile(r"\..+\.[0-9a-f]{12}\.tmp")
"""The temporary names of :func:`atomic_open`, left behind only by a killed process."""


@contextmanager
def atomic_open(path: str | Path) -> Iterator[IO[bytes]]:
    """A binary file whose contents appear at ``path`` only once the block ends without error.

    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> with atomic_open(d / "a.bin") as fp:
    ...     _ = fp.write(b"hi")
    >>> (d / "a.bin").read_bytes()
    b'hi'
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    temp = path.with_name(f".{path.name}.{uuid.uuid4().hex[:12]}.tmp")
    try:
        # Opened inside the try: a Ctrl-C or SIGTERM right after the file exists still removes
        # it. Mode 0o666 lets the umask decide, as for any new file (mkstemp makes it private).
        fd = os.open(temp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0), 0o666)
        with os.fdopen(fd, "wb") as handle:
            yield handle
        os.replace(temp, path)
    except BaseException:
        temp.unlink(missing_ok=True)
        raise


def write_atomic(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` through a temporary file in the same folder and a rename.

    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> write_atomic(d / "a.txt", b"hi").read_bytes()
    b'hi'
    """
    with atomic_open(path) as handle:
        handle.write(data)
    return Path(path)


def write_json(path: str | Path, data: object) -> Path:
    """Write ``data`` as indented JSON (keys in the order given), atomically.

    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> write_json(d / "a.json", {"b": 1, "a": 2}).read_text()
    '{\\n  "b": 1,\\n  "a": 2\\n}\\n'
    """
    text = json.dumps(data, indent=2, allow_nan=False, ensure_ascii=False) + "\n"
    return write_atomic(path, text.encode("utf-8"))


def prepare_out_dir(path: str | os.PathLike[str], force: bool) -> Path:
    """Make ``path`` ready for a new run, or raise ``ValueError`` before anything is written.

    A missing or empty folder is fine; one with files in it only with ``force``, and then the
    files an earlier run wrote there (:data:`OUTPUT_FILES`, ``frames/NNNNNN.png``, temporary
    files of a killed run) are removed first, ``results.json`` before the rest, so the folder
    never mixes two runs. Nothing else is touched, and symlinks are never followed: an output
    name that is a symlink or a folder is refused. The folder is created and a probe file
    written to prove it is writable; on failure the folders made are removed again.

    >>> import tempfile, pathlib
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "run"
    >>> prepare_out_dir(out, force=False).is_dir()
    True
    """
    out = Path(path)
    if out.is_symlink() and not out.exists():
        raise ValueError(f"output path {out} is a symlink to nothing")
    if out.exists() and not out.is_dir():
        raise ValueError(f"output path {out} exists and is not a folder")
    if out.is_dir():
        if not force and any(out.iterdir()):
            raise ValueError(
                f"output folder {out} is not empty; use --force to replace the run in it"
            )
        for name in (*OUTPUT_FILES, FRAMES_DIR):
            entry = out / name
            wanted = entry.is_dir() if name == FRAMES_DIR else entry.is_file()
            if entry.is_symlink() or (entry.exists() and not wanted):
                kind = "a symlink" if entry.is_symlink() else "not what ikgame writes there"
                raise ValueError(f"{entry} is {kind}; move it away, ikgame writes only real files")
    made = _make_dirs(out)
    try:
        with tempfile.TemporaryFile(dir=out):
            pass
    except OSError as exc:
        for folder in reversed(made):
            folder.rmdir()
        raise ValueError(f"cannot write into {out} ({exc.strerror})") from None
    _clear_run(out)
    return out


def _make_dirs(out: Path) -> list[Path]:
    """Create ``out`` and its missing parents; return the folders made, outermost first."""
    missing = [p for p in (out, *out.parents) if not p.exists()][::-1]
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        for folder in reversed([p for p in missing if p.is_dir()]):
            folder.rmdir()
        raise ValueError(f"cannot create {out} ({exc.strerror})") from None
    return missing


def _clear_run(out: Path) -> None:
    for name in OUTPUT_FILES:
        (out / name).unlink(missing_ok=True)
    remove_temporaries(out, frames=True)
    frames = out / FRAMES_DIR
    if frames.is_dir() and not frames.is_symlink() and not any(frames.iterdir()):
        frames.rmdir()


def remove_temporaries(out: Path, *, frames: bool = False) -> None:
    """Remove the temporary files of :func:`atomic_open` from ``out`` and ``out/frames`` (and
    with ``frames``, the frame files too): what a stopped or killed run left behind. Symlinks
    are never followed.

    >>> import tempfile, pathlib
    >>> out = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (out / ".run.gif.0123456789ab.tmp").write_bytes(b"")
    >>> remove_temporaries(out); list(out.iterdir())
    []
    """
    folder = out / FRAMES_DIR
    for place in (out, folder) if folder.is_dir() and not folder.is_symlink() else (out,):
        for entry in place.iterdir():
            ours = _TEMP.fullmatch(entry.name) or (
                frames and place == folder and _FRAME.fullmatch(entry.name)
            )
            if ours and entry.is_file() and not entry.is_symlink():
                entry.unlink(missing_ok=True)
