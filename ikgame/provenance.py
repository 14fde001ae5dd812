"""What a run was made from and what it wrote, so that it can be checked by running it again.

``results.json`` carries a ``provenance`` block (:func:`provenance`): the versions of ikgame,
Python, pymunk, numpy and Pillow, and the SHA-256 of the level file and of every file the level
names; and an ``outputs`` block (:func:`output_hashes`): the SHA-256 of every file the run wrote,
the frames folded into one hash. ``ikgame check RESULTS.json`` runs the level again with the
recorded options and compares (:func:`differences`).
"""

from __future__ import annotations

import hashlib
import platform
from collections.abc import Iterable, Mapping
from importlib import metadata
from pathlib import Path

import numpy as np
import pymunk

import ikgame

__all__ = ["provenance", "output_hashes", "differences", "file_sha256"]


def file_sha256(path: str | Path) -> str:
    """The SHA-256 of a file's bytes, as hex.

    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "a"
    >>> _ = p.write_bytes(b"")
    >>> file_sha256(p)[:12]
    'e3b0c44298fc'
    """
    digest = hashlib.sha256()
    with Path(path).open("rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def provenance(level_file: str | Path, named: Mapping[str, Path]) -> dict[str, object]:
    """The versions a run ran on and the hashes of the files it read.

    ``named`` maps each file the level names (as written in the level) to its real path.

    >>> from ikgame.level import DEFAULT_LEVEL
    >>> sorted(provenance(DEFAULT_LEVEL, {})["versions"])
    ['ikgame', 'numpy', 'pillow', 'pymunk', 'python']
    """
    return {
        "versions": {
            "ikgame": ikgame.__version__,
            "python": platform.python_version(),
            "pymunk": pymunk.version,
            "numpy": np.__version__,
            # Read from the installed metadata: importing Pillow would cost a run without
            # pictures its start-up.
            "pillow": metadata.version("pillow"),
        },
        "level_sha256": file_sha256(level_file),
        "named_files_sha256": {name: file_sha256(path) for name, path in sorted(named.items())},
    }


def output_hashes(out: Path, written: Iterable[Path]) -> dict[str, object]:
    """The SHA-256 of each file written into ``out``; the frames, in order, as one hash.

    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (d / "run.gif").write_bytes(b"")
    >>> output_hashes(d, [d / "run.gif"])["run.gif"][:12]
    'e3b0c44298fc'
    """
    frames = hashlib.sha256()
    count = 0
    files: dict[str, object] = {}
    for path in written:
        if path.suffix == ".mp4":
            continue  # H.264 encoders need not repeat their bytes; the frames they encode are hashed
        if path.parent.name == "frames" and path.parent.parent == out:
            frames.update(bytes.fromhex(file_sha256(path)))
            count += 1
        else:
            files[path.relative_to(out).as_posix()] = file_sha256(path)
    if count:
        files["frames"] = {"count": count, "sha256": frames.hexdigest()}
    return files


def differences(recorded: object, again: object, path: str = "") -> list[str]:
    """Where two JSON values differ, as ``path: recorded -> again`` lines (at most 20).

    >>> differences({"a": 1, "b": [1, 2]}, {"a": 1, "b": [1, 3]})
    ['b[1]: 2 -> 3']
    """
    found: list[str] = []
    _diff(recorded, again, path, found)
    return found[:20]


def _diff(a: object, b: object, path: str, found: list[str]) -> None:
    if isinstance(a, dict) and isinstance(b, dict):
        for key in list(a) + [k for k in b if k not in a]:
            where = f"{path}.{key}" if path else str(key)
            if key not in a or key not in b:
                found.append(
                    f"{where}: {'missing' if key not in a else a[key]!r} -> "
                    f"{'missing' if key not in b else b[key]!r}"
                )
            else:
                _diff(a[key], b[key], where, found)
    elif isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _diff(x, y, f"{path}[{i}]", found)
    elif a != b or type(a) is not type(b):
        found.append(f"{path}: {_short(a)} -> {_short(b)}")


def _short(value: object) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."
