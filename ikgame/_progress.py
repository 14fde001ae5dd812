"""One progress bar for every long job: simulating, comparing, rendering."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rich.console import Console

__all__ = ["progress_bar"]


@contextmanager
def progress_bar(
    label: str, total: float, *, enabled: bool, console: Console | None = None
) -> Iterator[Callable[[float], None]]:
    """A transient rich progress bar (on ``console``, default stderr), or nothing when not
    ``enabled``; yields ``update(completed)`` with ``completed`` out of ``total``.

    >>> with progress_bar("working", 10, enabled=False) as update:
    ...     update(5)
    """
    if not enabled:
        # No bar, no rich: importing it costs a short quiet run a noticeable part of its time.
        yield _ignore
        return
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

    bar = Progress(
        TextColumn(f"{label:<11}"),
        BarColumn(),
        TextColumn("{task.percentage:>3.0f}%"),
        TimeRemainingColumn(),
        console=console if console is not None else Console(stderr=True),
        transient=True,
    )
    with bar:
        task = bar.add_task(label, total=total)
        yield lambda completed: bar.update(task, completed=completed)


def _ignore(completed: float) -> None:
    """The update of a bar that is not shown."""
