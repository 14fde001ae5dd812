"""Rendering: a camera, colour themes, Pillow frames, and exports (PNG frames, GIF, APNG, contact
sheet, baked motion)."""

from ikgame.render.camera import Camera
from ikgame.render.debug_draw import PillowDrawOptions
from ikgame.render.export import check_out_dir, export_run, motion_json, parse_size, trail_at
from ikgame.render.pillow import render_snapshot, to_draw_coords
from ikgame.render.plot import ComparisonPlot, SolverTrace, render_comparison
from ikgame.render.theme import Theme, available_themes, load_theme

__all__ = [
    "Camera",
    "ComparisonPlot",
    "PillowDrawOptions",
    "SolverTrace",
    "Theme",
    "available_themes",
    "check_out_dir",
    "export_run",
    "load_theme",
    "motion_json",
    "parse_size",
    "render_comparison",
    "render_snapshot",
    "to_draw_coords",
    "trail_at",
]
