"""Sprite skins: a level's sprite images, decoded and put in its :class:`~ikgame.snapshot.Scene`.

The level layer finds and checks the files a level names without decoding them (it does not
import Pillow); the renderer decodes bytes it is handed but reads no files and knows no level.
This module joins the two, once per run, so every picture of the run (frames, GIF, MP4, the
contact sheet, a live window) draws the same decoded images.

>>> import ikgame
>>> from ikgame.level.library import LEVELS_DIR
>>> path = LEVELS_DIR / "14_skinned_arm.toml"
>>> level = ikgame.load_level(path)
>>> scene = skin_scene(ikgame.Simulation(level).scene, level, path)
>>> [s is not None for s in scene.link_sprites], [s is not None for s in scene.prop_sprites]
([True, True, True], [True, True])
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from ikgame.level.loader import LevelError, Problem, problem_at, sprite_fields, sprite_file
from ikgame.level.model import BallProp, BoxProp, Level, LinkConfig
from ikgame.render.sprites import decode_sprite
from ikgame.snapshot import Scene, Sprite

__all__ = ["level_sprites", "skin_scene"]


def level_sprites(
    level: Level, level_file: str | Path
) -> tuple[tuple[Sprite | None, ...], tuple[Sprite | None, ...]]:
    """The sprites of ``level`` (loaded from ``level_file``): one entry per link (``repeat``
    expanded) and one per prop, None where there is none; both empty when the level has none.

    Raises :class:`~ikgame.level.loader.LevelError` naming the file, line and field of every
    image that cannot be used. Each file is read and decoded once, however many links use it.
    """
    if not sprite_fields(level):
        return (), ()
    decoded: dict[tuple[Path, tuple[float, float], float | None, float], Sprite] = {}
    problems: list[Problem] = []

    def load(
        loc: tuple[str | int, ...], config: LinkConfig | BallProp | BoxProp, span: float
    ) -> Sprite | None:
        name = config.sprite
        if name is None:
            return None
        try:
            path, _ = sprite_file(name, level_file)
            pivot, scale = config.sprite_pivot, config.sprite_scale
            key = (path, pivot, scale, span)
            if key not in decoded:
                decoded[key] = decode_sprite(path.read_bytes(), pivot, scale, span)
            return decoded[key]
        except (ValueError, OSError) as exc:
            message = str(exc) if isinstance(exc, ValueError) else f"cannot be read ({exc})"
            if not message.startswith(repr(name)):
                message = f"{name!r} {message}"
            problems.append(problem_at(level_file, loc, message))
            return None

    chain = level.chain
    links = []
    for i, link in enumerate(chain.entries):
        sprite = load(("chain", chain.entry_field, i, "sprite"), link, link.length)
        links.extend([sprite] * link.repeat)
    props = [
        load(("props", i, "sprite"), p, 2 * p.radius if isinstance(p, BallProp) else p.size[0])
        for i, p in enumerate(level.props)
    ]
    if problems:
        raise LevelError(problems)
    return _some(links), _some(props)


def skin_scene(scene: Scene, level: Level, level_file: str | Path) -> Scene:
    """``scene`` (of a run of ``level``) with the level's sprites (see :func:`level_sprites`);
    ``scene`` itself when the level has none."""
    links, props = level_sprites(level, level_file)
    if not links and not props:
        return scene
    return dataclasses.replace(scene, link_sprites=links, prop_sprites=props)


def _some(sprites: list[Sprite | None]) -> tuple[Sprite | None, ...]:
    """The list as a tuple, or empty when it holds no sprite (the renderer's "none at all")."""
    return tuple(sprites) if any(s is not None for s in sprites) else ()
