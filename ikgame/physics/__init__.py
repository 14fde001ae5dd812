"""The pymunk world of a level."""

from ikgame.physics.world import World, build_skeleton

__all__ = ["World", "build_skeleton"]
