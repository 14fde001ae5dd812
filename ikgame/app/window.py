"""The ``ikgame play`` window: pygame-ce shows what a :class:`~ikgame.app.state.PlayState` draws
and hands it the mouse and the keys.

pygame-ce is an optional extra (``python -m pip install 'ikgame[play]'``), imported only when a
window opens. Everything the window decides lives in :class:`~ikgame.app.state.PlayState`; this
module is the thin part that needs a display: the event pump, the blit and the loop.
"""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Callable
from types import TracebackType
from typing import Final

from ikgame.app._extras import require
from ikgame.app.state import KeyPress, MouseDown, MouseMove, MouseUp, PlayState

__all__ = ["NoDisplay", "Window", "play"]

MAX_FPS: Final = 60  # frames drawn per second at most: no display refreshes faster worth drawing
LEFT_BUTTON: Final = 1
# SDL's drivers that draw nowhere: SDL falls back to "offscreen" when it finds no display, which
# would leave a window nobody can see (or close) running; tests ask for "dummy" on purpose.
_INVISIBLE: Final = frozenset({"offscreen", "dummy"})


class NoDisplay(RuntimeError):
    """There is no display to open a window on."""


class Window:
    """A pygame window the size of ``state.size`` showing ``state``; close it with
    :meth:`close` (or use it as a context manager).

    When ``reload`` is given, a set event makes the next frame reload the level file (a watcher
    thread sets it; see :func:`play`).
    """

    def __init__(self, state: PlayState, *, reload: threading.Event | None = None) -> None:
        self.pygame = require("pygame", "play", "the window")
        self.state = state
        self.reload = reload
        pg = self.pygame
        try:
            pg.display.init()
            driver = pg.display.get_driver()
            if driver in _INVISIBLE and "SDL_VIDEODRIVER" not in os.environ:
                raise NoDisplay(f"SDL found no display, only its {driver!r} video driver")
            self.surface = pg.display.set_mode(state.size)
        except pg.error as exc:
            pg.display.quit()
            raise NoDisplay(str(exc)) from None
        except NoDisplay:
            pg.display.quit()
            raise
        self._caption()
        self._drawn = -1  # the revision on screen

    def _caption(self) -> None:
        self.pygame.display.set_caption(f"ikgame: {self.state.level.level.name}")

    def pump(self) -> None:
        """Hand every waiting pygame event to the state as a plain input event."""
        pg, state = self.pygame, self.state
        for event in pg.event.get():
            if event.type == pg.QUIT:
                state.quit = True
            elif event.type == pg.KEYDOWN:
                state.handle(KeyPress(pg.key.name(event.key)))
            elif event.type == pg.MOUSEBUTTONDOWN and event.button == LEFT_BUTTON:
                state.handle(MouseDown(event.pos))
            elif event.type == pg.MOUSEMOTION:
                state.handle(MouseMove(event.pos))
            elif event.type == pg.MOUSEBUTTONUP and event.button == LEFT_BUTTON:
                state.handle(MouseUp())
            elif event.type in (pg.VIDEOEXPOSE, pg.WINDOWEXPOSED):
                self._drawn = -1  # uncovered: the window's picture must be drawn again

    def frame(self, seconds: float) -> int:
        """One frame after ``seconds`` of real time: events, the ticks that time holds, and a
        redraw if anything changed (a paused window costs next to nothing). Returns the ticks
        run."""
        if self.reload is not None and self.reload.is_set():
            self.reload.clear()
            if self.state.reload():
                self._caption()
        self.pump()
        ticks = self.state.advance(seconds)
        if self.state.revision != self._drawn:
            self.draw()
        return ticks

    def draw(self) -> None:
        """Show the state's picture, drawn by the same Pillow renderer as the exports."""
        self._drawn = self.state.revision
        image = self.state.image()
        picture = self.pygame.image.frombytes(image.tobytes(), image.size, "RGB")
        self.surface.blit(picture, (0, 0))
        self.pygame.display.flip()

    def close(self) -> None:
        self.pygame.display.quit()

    def __enter__(self) -> Window:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()


def play(
    state: PlayState, *, watch: bool = False, clock: Callable[[], float] = time.perf_counter
) -> None:
    """Open a window on ``state`` and run it until the player quits (or closes the window).

    With ``watch`` the level is reloaded in the open window whenever its file, or a file it
    names, changes (needs the ``watch`` extra). ``clock`` gives real time in seconds.
    """
    reload = stop = watcher = None
    if watch:
        from ikgame.app.watch import watch_level

        require("watchfiles", "watch", "reloading the level")
        reload, stop = threading.Event(), threading.Event()
        watcher = threading.Thread(
            target=watch_level,
            args=(state.level_path, reload.set),
            kwargs={"stop": stop},
            name="ikgame-watch",
            daemon=True,
        )
    with Window(state, reload=reload) as window:
        if watcher is not None:
            watcher.start()
        timer = window.pygame.time.Clock()
        last = clock()
        try:
            while not state.quit:
                now = clock()
                window.frame(now - last)
                last = now
                timer.tick(MAX_FPS)
        finally:
            if stop is not None and watcher is not None:
                stop.set()
                watcher.join(timeout=5.0)
