"""Watch a level file, and the files it names, for changes: what ``ikgame watch`` re-runs on and
what ``ikgame play --watch`` reloads on.

The watching itself is watchfiles' (the ``watch`` extra: ``python -m pip install
'ikgame[watch]'``), which listens to the operating system's change notifications rather than
polling. The folders that hold the files are watched, not the files: editors often save by
writing a new file and renaming it over the old one, which a watch on the old file would miss.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from pathlib import Path
from typing import Final

from ikgame.app._extras import require
from ikgame.level.loader import LevelError, level_theme, load_level, sprite_fields, sprite_file

__all__ = ["level_files", "watch_level"]

WAKE_MS: Final = 200  # ms between checks of the stop event (and the first "ready" call)
DEBOUNCE_MS: Final = 400  # ms at most to gather the changes of one save into one re-run


def level_files(level_path: str | Path) -> frozenset[Path]:
    """The level file and every file it names (its theme file and sprite images), as real
    paths. A level that does not load names only itself, until it is fixed.

    >>> from ikgame.level import DEFAULT_LEVEL
    >>> [p.name for p in level_files(DEFAULT_LEVEL)]
    ['01_first_reach.toml']
    """
    path = Path(level_path)
    files = {path.resolve()}
    try:
        level = load_level(path)
        theme = level_theme(level, path)
        sprites = [sprite_file(name, path)[0] for _, name in sprite_fields(level)]
    except (LevelError, ValueError):
        return frozenset(files)
    if isinstance(theme, Path):
        files.add(theme.resolve())
    files.update(sprite.resolve() for sprite in sprites)
    return frozenset(files)


def watch_level(
    level_path: str | Path,
    on_change: Callable[[], None],
    *,
    stop: threading.Event | None = None,
    ready: Callable[[], None] | None = None,
) -> None:
    """Call ``on_change()`` after each change to the level file or a file it names, until
    ``stop`` is set (or Ctrl-C, which is raised as ``KeyboardInterrupt``).

    ``ready()`` is called once the watch is in place: a change made after it is never missed.
    Changes made while ``on_change`` runs are reported after it returns. When an edit makes the
    level name other files (a new theme), those are watched from then on.
    """
    watchfiles = require("watchfiles", "watch", "watching files")
    stop = stop if stop is not None else threading.Event()
    while not stop.is_set():
        files = level_files(level_path)
        folders = sorted({path.parent for path in files})

        def wanted(_change: object, name: str, files: frozenset[Path] = files) -> bool:
            return Path(name).resolve() in files

        for changes in watchfiles.watch(
            *folders,
            watch_filter=wanted,
            debounce=DEBOUNCE_MS,
            stop_event=stop,
            rust_timeout=WAKE_MS,
            yield_on_timeout=True,
            recursive=False,
        ):
            if ready is not None:
                ready()
                ready = None
            if not changes:
                continue
            on_change()
            if level_files(level_path) != files:
                break
