"""Per-tick joint control: IK solver -> desired angles -> motor rates."""

from ikgame.control.controller import Command, Controller, joint_error
from ikgame.control.gait import Footing, FootState, Gait, GaitParams, Terrain, default_groups

__all__ = [
    "Command",
    "Controller",
    "FootState",
    "Footing",
    "Gait",
    "GaitParams",
    "Terrain",
    "default_groups",
    "joint_error",
]
