"""What an interactive window shows and does, without the window: a level running live under the
player's hands.

:class:`PlayState` holds the simulation, the pause and single-step state, the target the mouse
holds, the gravity switch and the help overlay. It takes plain input events
(:class:`KeyPress`, :class:`MouseDown`, :class:`MouseMove`, :class:`MouseUp`) through
:meth:`PlayState.handle` and real time through :meth:`PlayState.advance`, and draws itself with
the same Pillow renderer as the exports (:meth:`PlayState.image`). The pygame window in
:mod:`ikgame.app.window` only translates its events and shows the image, so everything here is
tested without a display and with a fake clock.

Frame pacing is fixed-step: real time accumulates and the simulation runs whole ticks of the
level's tick rate from it, so the physics never depends on the display's frame rate. A slow frame
means fewer frames drawn, not different physics; at most :data:`MAX_CATCH_UP` seconds are caught
up per frame, so after a long stall (a window being dragged, a debugger) the simulation resumes
where it was rather than racing to catch up.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, replace
from functools import lru_cache
from pathlib import Path
from typing import Final

import numpy as np
from PIL import Image, ImageDraw, ImageFont

from ikgame._files import atomic_open
from ikgame.level.loader import LevelError, level_theme, load_level
from ikgame.level.model import SOLVER_NAMES, Level
from ikgame.render.camera import Camera
from ikgame.render.export import TRAIL_SECONDS
from ikgame.render.pillow import render_snapshot
from ikgame.render.theme import Theme, load_theme
from ikgame.sim import RunResult, Simulation
from ikgame.skins import level_sprites
from ikgame.snapshot import Sprite, effector_positions

__all__ = [
    "BINDINGS",
    "MAX_CATCH_UP",
    "Binding",
    "KeyPress",
    "MouseDown",
    "MouseMove",
    "MouseUp",
    "PlayState",
]

MAX_CATCH_UP: Final = 0.25  # s of simulated time run per frame at most, however long it took
MESSAGE_SECONDS: Final = 4.0  # s a notice (screenshot saved, reload failed) stays on screen
PANEL_ALPHA: Final = 0.86  # opacity of the help and status panels over the scene


@dataclass(frozen=True)
class Binding:
    """Keys (pygame key names, as ``pygame.key.name`` gives them) bound to one action, and the
    line the help overlay shows for it."""

    keys: tuple[str, ...]
    action: str
    help: str


BINDINGS: Final = (
    Binding(("space",), "pause", "pause / resume"),
    Binding((".", "s"), "step", "one tick, while paused"),
    Binding(("r",), "restart", "restart the level"),
    Binding(("tab", "n"), "solver", "next solver"),
    Binding(("g",), "gravity", "gravity on / off"),
    Binding(("p",), "screenshot", "save a screenshot (PNG) into the output folder"),
    Binding(("h", "f1"), "help", "show / hide this help"),
    Binding(("escape", "q"), "quit", "quit"),
)
"""Every key the window answers to; the help overlay is drawn from this table."""

_ACTIONS: Final = {key: b.action for b in BINDINGS for key in b.keys}
_KEY_LABELS: Final = {"escape": "esc", "f1": "F1"}


@dataclass(frozen=True)
class KeyPress:
    """A key went down; ``name`` as ``pygame.key.name`` spells it (``"space"``, ``"f1"``)."""

    name: str


@dataclass(frozen=True)
class MouseDown:
    """The (left) mouse button went down at ``pixel``, image px from the top-left corner."""

    pixel: tuple[float, float]


@dataclass(frozen=True)
class MouseMove:
    """The mouse moved to ``pixel``."""

    pixel: tuple[float, float]


@dataclass(frozen=True)
class MouseUp:
    """The mouse button was released."""


Event = KeyPress | MouseDown | MouseMove | MouseUp


class PlayState:
    """A level running live: input events in, whole physics ticks out, a picture on demand.

    ``theme`` overrides the level's own theme (None: the level's, else ``light``); ``solver``
    overrides the level's solver like ``ikgame run --solver``. Screenshots go into ``out_dir``.

    >>> from ikgame.level import DEFAULT_LEVEL
    >>> state = PlayState(DEFAULT_LEVEL, size=(320, 180))
    >>> state.advance(0.1)  # a tenth of a second of real time: 24 ticks at 240 ticks/s
    24
    >>> state.advance(2.0)  # a stalled frame catches up MAX_CATCH_UP s, not 2 s
    60
    >>> state.handle(KeyPress("space")); state.advance(1.0), state.paused
    (0, True)
    >>> state.image().size
    (320, 180)
    """

    def __init__(
        self,
        level_path: str | Path,
        *,
        solver: str | None = None,
        size: tuple[int, int] = (960, 540),
        theme: Theme | None = None,
        out_dir: str | Path = ".",
    ) -> None:
        self.level_path = Path(level_path)
        self.size = size
        self.out_dir = Path(out_dir)
        self.paused = False
        self.help = False
        self.quit = False
        self.gravity_on = True
        self.held: np.ndarray | None = None  # the world point the mouse holds, px
        self._grabbed = "tip"  # the effector the mouse holds
        self.message = ""
        # Counts changes to what the window shows: an unchanged picture is not drawn again.
        self.revision = 0
        self._theme_override = theme
        self._solver = solver
        self._message_left = 0.0
        self._backlog = 0.0  # real time not yet simulated, s
        self._pending_steps = 0
        self._actions = {
            "pause": self._do_pause,
            "step": self._do_step,
            "restart": self.restart,
            "solver": self._do_solver,
            "gravity": self._do_gravity,
            "screenshot": self.screenshot,
            "help": self._do_help,
            "quit": self._do_quit,
        }
        level = load_level(self.level_path)
        self._load(level, level_sprites(level, self.level_path))

    def _load(self, level: Level, sprites: tuple[tuple[Sprite | None, ...], ...]) -> None:
        """Start ``level`` (already validated, its ``sprites`` decoded) from its beginning."""
        self.level = level
        self._sprites = sprites
        if self._theme_override is not None:
            self.theme = self._theme_override
        else:
            self.theme = load_theme(level_theme(self.level, self.level_path) or "light")
        self.restart()

    def restart(self) -> None:
        """The level from its start, with the solver picked last and gravity on."""
        self.revision += 1
        self.sim = Simulation(self.level, solver=self._solver, record=False)
        links, props = self._sprites
        # The window draws what an export draws, skins included.
        self.scene = replace(self.sim.scene, link_sprites=links, prop_sprites=props)
        # The mouse can drive the chain anywhere within its reach, so the view holds the whole
        # reach around the base (a recorded run is not there yet to fit to); a level's own
        # [world] bounds win, as in exports.
        self.camera = Camera.fit(self.scene, self.level.chain.base, self.size)
        self.gravity_on = True
        self._gravity = tuple(self.sim.world.space.gravity)
        self._trail: deque[np.ndarray] = deque(
            maxlen=max(2, round(TRAIL_SECONDS * self.level.world.fps) + 1)
        )
        self._drawable = self.sim.snapshot()  # the latest state without a NaN in it
        self._trail.append(effector_positions(self.scene, self._drawable))
        self._backlog = 0.0
        self._pending_steps = 0
        # Ticks after the run ended, and the telemetry of the latest of them.
        self._extra_ticks = 0
        self._extra: tuple[str, float, np.ndarray] | None = None
        self.result: RunResult | None = None  # once the run is over
        if self.held is not None and self._grabbed in self.sim.effector_names:
            self.sim.set_target(self._grabbed, self.held)
        else:
            self.held = None

    def reload(self) -> bool:
        """Read the level file again and restart it; on a broken file keep the running level,
        show the first problem, and return False."""
        try:
            level = load_level(self.level_path)
            sprites = level_sprites(level, self.level_path)
        except LevelError as exc:
            self.notify(f"not reloaded: {exc.problems[0]}")
            return False
        self._load(level, sprites)
        self.notify(f"reloaded {self.level_path.name}")
        return True

    def notify(self, text: str) -> None:
        """Show ``text`` for a few seconds."""
        self.message = text
        self._message_left = MESSAGE_SECONDS
        self.revision += 1

    def handle(self, event: Event) -> None:
        """Apply one input event."""
        self.revision += 1
        if isinstance(event, MouseDown):
            self.held = self.pixel_to_world(event.pixel)
            # The mouse takes the effector nearest to where it pressed (a chain's only one).
            reached = self.sim.world.effector_positions()
            nearest = int(np.argmin(np.hypot(*(reached - self.held).T)))
            self._grabbed = self.sim.effector_names[nearest]
            self.sim.set_target(self._grabbed, self.held)
        elif isinstance(event, MouseMove):
            if self.held is not None:
                self.held = self.pixel_to_world(event.pixel)
                self.sim.set_target(self._grabbed, self.held)
        elif isinstance(event, MouseUp):
            self.held = None
            self.sim.set_target(self._grabbed, None)
        elif isinstance(event, KeyPress):
            action = _ACTIONS.get(event.name)
            if action is not None:
                self._actions[action]()

    def pixel_to_world(self, pixel: tuple[float, float]) -> np.ndarray:
        """The world point (px, y up) under window pixel ``pixel`` (its centre).

        >>> from ikgame.level import DEFAULT_LEVEL
        >>> state = PlayState(DEFAULT_LEVEL, size=(320, 180))
        >>> bool(np.allclose(state.camera.world_to_pixel([state.pixel_to_world((10, 20))]),
        ...                  [[10.5, 20.5]]))
        True
        """
        x, y = pixel
        return self.camera.pixel_to_world([[x + 0.5, y + 0.5]])[0]

    def advance(self, seconds: float) -> int:
        """Let ``seconds`` of real time pass: run the whole ticks it holds (at most
        :data:`MAX_CATCH_UP` s of them), or the single steps asked for while paused. Returns
        the number of ticks run."""
        if not (math.isfinite(seconds) and seconds >= 0):
            raise ValueError(f"seconds must be a finite number >= 0, got {seconds!r}")
        self._message_left = max(0.0, self._message_left - seconds)
        if self._message_left == 0.0 and self.message:
            self.message = ""
            self.revision += 1
        if self.paused:
            ticks, self._pending_steps = self._pending_steps, 0
        else:
            self._backlog = min(self._backlog + seconds, MAX_CATCH_UP)
            ticks = int(self._backlog / self.sim.dt + 1e-9)
            self._backlog -= ticks * self.sim.dt
        ran = 0
        for _ in range(ticks):
            if self.sim.diverged:
                break
            self._tick()
            ran += 1
        self.revision += ran
        return ran

    def _tick(self) -> None:
        sim = self.sim
        if sim.done:
            self._play_on()
        else:
            sim.step()
        if not self.gravity_on and tuple(sim.world.space.gravity) != (0.0, 0.0):
            # A level's `set` step changed gravity while it was switched off: that is the
            # gravity to come back to.
            self._gravity = tuple(sim.world.space.gravity)
            sim.world.set_gravity((0.0, 0.0))
        ticks = sim.tick + self._extra_ticks
        fps, rate = self.level.world.fps, self.level.world.tick_rate
        if ticks * fps // rate != (ticks - 1) * fps // rate:
            self._trail.append(effector_positions(self.scene, sim.snapshot()))

    def _play_on(self) -> None:
        """A tick after the run is over: its result stays as it ended, while the chain keeps
        following the target (the mouse, or the script's last point) for as long as the player
        likes."""
        sim = self.sim
        if self._extra_ticks == 0:
            # Judged now, before the player moves anything; the simulation keeps it from here.
            self.result = sim.result
        info = sim.play_on()
        self._extra_ticks += 1
        if sim.diverged:
            return
        self._extra = (info.solver_status, info.error, info.torque_limited)

    def _do_pause(self) -> None:
        self.paused = not self.paused
        self._backlog = 0.0

    def _do_step(self) -> None:
        if self.paused:
            self._pending_steps += 1

    def _do_solver(self) -> None:
        current = self.sim.controller.solver_name
        self._solver = SOLVER_NAMES[(SOLVER_NAMES.index(current) + 1) % len(SOLVER_NAMES)]
        self.sim.controller.set_solver(self._solver)
        self.notify(f"solver: {self._solver}")

    def _do_gravity(self) -> None:
        self.gravity_on = not self.gravity_on
        if self.gravity_on:
            self.sim.world.set_gravity(self._gravity)
        else:
            self._gravity = tuple(self.sim.world.space.gravity)
            self.sim.world.set_gravity((0.0, 0.0))
        self.notify(f"gravity {'on' if self.gravity_on else 'off'}")

    def _do_help(self) -> None:
        self.help = not self.help

    def _do_quit(self) -> None:
        self.quit = True

    def screenshot(self) -> Path:
        """Save the frame as an export would draw it (no overlays) to the first free
        ``screenshot-NNN.png`` in the output folder, atomically; returns its path."""
        self.out_dir.mkdir(parents=True, exist_ok=True)
        number = 1
        while (self.out_dir / f"screenshot-{number:03d}.png").exists():
            number += 1
        path = self.out_dir / f"screenshot-{number:03d}.png"
        with atomic_open(path) as handle:
            self.frame().save(handle, format="PNG")
        self.notify(f"saved {path}")
        return path

    def frame(self) -> Image.Image:
        """The state now as an export frame: the scene, the trail and the HUD. After the
        physics blew up it is the last state that could be drawn, as exports end."""
        snapshot = self.sim.snapshot()
        if self._extra is not None:
            status, error, limited = self._extra
            snapshot = replace(
                snapshot,
                time=snapshot.time + self._extra_ticks * self.sim.dt,
                solver_status=status,
                error=error,
                torque_limited=limited,
            )
        if np.all(np.isfinite(snapshot.joints)) and np.all(np.isfinite(snapshot.props)):
            self._drawable = snapshot
        snapshot = self._drawable
        # (m, k, 2): a column per effector; the renderer skips points that are not finite.
        trail = np.array([*self._trail, effector_positions(self.scene, snapshot)])
        return render_snapshot(self.scene, snapshot, self.camera, self.theme, trail=trail)

    def image(self) -> Image.Image:
        """What the window shows: :meth:`frame` with the status line and, when asked for, the
        help overlay."""
        image = self.frame()
        status = [(self.status_line(),)] + ([(self.message,)] if self.message else [])
        _panel(image, status, self.theme, bottom=True)
        if self.help:
            _panel(image, help_lines(), self.theme, bottom=False)
        return image

    def status_line(self) -> str:
        """Solver, gravity, pause state, and the result once the run is over."""
        parts = [self.sim.controller.solver_name, f"gravity {'on' if self.gravity_on else 'off'}"]
        if self.held is not None:
            parts.append("holding the target")
        if self.sim.done:
            result = self.sim.result
            parts.append(f"run over: {result.status}, score {result.score:.0f}/100; r restarts")
        elif self.paused:
            parts.append("paused (. steps)")
        parts.append("h: help")
        return "  ·  ".join(parts)


def help_lines() -> list[tuple[str, str]]:
    """The help overlay's rows: the keys, and what they do.

    >>> help_lines()[0]
    ('space', 'pause / resume')
    """
    rows = [(" or ".join(_KEY_LABELS.get(k, k) for k in b.keys), b.help) for b in BINDINGS]
    rows.append(("mouse (hold)", "drag the target; release hands it back to the script"))
    return rows


@lru_cache(maxsize=4)
def _font(size: int) -> ImageFont.FreeTypeFont | ImageFont.ImageFont:
    return ImageFont.load_default(size=size)


def _panel(image: Image.Image, rows: list[tuple[str, ...]], theme: Theme, *, bottom: bool) -> None:
    """Rows of text in columns on a translucent panel, along the bottom edge or centred."""
    width, height = image.size
    size = max(8, round(height * 0.026))
    font, pad, line_height = _font(size), max(3, round(size * 0.6)), round(size * 1.35)
    draw = ImageDraw.Draw(image)
    columns = [
        max(draw.textlength(row[k], font=font) for row in rows if len(row) > k)
        for k in range(max(len(row) for row in rows))
    ]
    starts = [sum(columns[:k]) + 2 * pad * k for k in range(len(columns))]
    box_w = min(width, round(starts[-1] + columns[-1]) + 2 * pad)
    box_h = min(height, line_height * len(rows) + 2 * pad)
    left = 0 if bottom else (width - box_w) // 2
    top = height - box_h if bottom else (height - box_h) // 2
    box = (left, top, left + box_w, top + box_h)
    # Blended on the panel's own rectangle: a full-frame alpha layer would cost a frame.
    region = image.crop(box)
    solid = Image.new("RGB", region.size, theme.hud_panel)
    image.paste(Image.blend(region, solid, PANEL_ALPHA), box)
    for k, row in enumerate(rows):
        for start, text in zip(starts, row, strict=False):
            xy = (left + pad + start, top + pad + k * line_height)
            draw.text(xy, text, fill=theme.hud_text, font=font)
