"""Interactive tools around a level: a live window (``ikgame play``) and a watcher that re-runs a
level when its files change (``ikgame watch``). The window needs the ``play`` extra (pygame-ce),
the watcher the ``watch`` extra (watchfiles); both are imported only when used."""

from ikgame.app.state import BINDINGS, KeyPress, MouseDown, MouseMove, MouseUp, PlayState

__all__ = ["BINDINGS", "KeyPress", "MouseDown", "MouseMove", "MouseUp", "PlayState"]
