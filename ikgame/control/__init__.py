"""Per-tick joint control: IK solver -> desired angles -> motor rates."""

from ikgame.control.controller import Command, Controller, joint_error

__all__ = ["Command", "Controller", "joint_error"]
