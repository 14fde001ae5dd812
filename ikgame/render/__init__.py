"""Rendering: a camera, colour themes, Pillow frames, and exports (PNG frames, GIF, APNG, contact
sheet, baked motion).

Names are imported on first use: loading a theme does not load Pillow.
"""

from typing import TYPE_CHECKING

from ikgame._lazy import lazy_exports

__all__, __getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "ikgame.render.camera": ["Camera"],
        "ikgame.render.debug_draw": ["PillowDrawOptions"],
        "ikgame.render.export": ["export_run", "trail_at"],
        "ikgame.render.motion": ["motion_json", "write_motion"],
        "ikgame.render.output": ["check_out_dir", "parse_size"],
        "ikgame.render.pillow": ["render_snapshot", "to_draw_coords"],
        "ikgame.render.plot": ["ComparisonPlot", "SolverTrace", "render_comparison"],
        "ikgame.render.theme": ["Theme", "available_themes", "load_theme"],
    },
)

if TYPE_CHECKING:
    from ikgame.render.camera import Camera
    from ikgame.render.debug_draw import PillowDrawOptions
    from ikgame.render.export import export_run, trail_at
    from ikgame.render.motion import motion_json, write_motion
    from ikgame.render.output import check_out_dir, parse_size
    from ikgame.render.pillow import render_snapshot, to_draw_coords
    from ikgame.render.plot import ComparisonPlot, SolverTrace, render_comparison
    from ikgame.render.theme import Theme, available_themes, load_theme
