"""Draw docs/figures/trees.png: a skeleton tree before and after ``solve_dls_targets``.

The figure illustrates the tree section of ``docs/kinematics.md``: a body (the base) with two
legs whose hips sit at ``root_offsets``, and a neck that forks into two arms. Both feet reach
their targets; the arms' targets lie too far apart for both, so the arms settle at the weighted
least-squares compromise (the right arm weighs twice as much); the tail has no target and holds
its pose. The poses come from ``ikgame.kinematics`` itself, so the picture cannot drift from the
code. The drawing helpers are those of ``kinematics_figure.py``.

Run from the repository root::

    python docs/figures/trees_figure.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from kinematics_figure import (
    EFFECTOR,
    GHOST,
    INK,
    LINK,
    LINK_OUTLINE,
    MUTED,
    SUPERSAMPLE,
    TARGET_COLOUR,
    WIDTH,
    Canvas,
    _draw_grid,
)

from ikgame.kinematics import Skeleton, TargetSet, forward_kinematics, solve_dls_targets

OUTPUT = Path(__file__).with_name("trees.png")
TOLERANCE = 0.5  # arrival distance, world px

# Links in parents-first order: left leg (0, 1), right leg (2, 3), neck (4) with two arms
# (5, 6), tail (7). Hips and the neck sit at their root offsets in the body's frame.
LENGTHS = (55.0, 50.0, 55.0, 50.0, 40.0, 45.0, 45.0, 60.0)
PARENTS = (-1, 0, -1, 2, -1, 4, 4, -1)
OFFSETS = ((-50, 0), (0, 0), (50, 0), (0, 0), (30, 15), (0, 0), (0, 0), (-70, 10))
LIMITS = ((-2.8, -0.4), (-2.0, 0.0), (-2.8, -0.4), (-2.0, 0.0), None, None, None, (0.5, 3.0))
START = (-1.4, -0.6, -1.8, 0.6, 1.2, 0.6, -0.6, 2.5)  # radians
FEET = ((-80.0, -85.0), (75.0, -95.0))  # world px
HANDS = ((-10.0, 150.0), (160.0, 60.0))  # world px, too far apart for both
HAND_WEIGHTS = (1.0, 2.0)


def main(output: Path = OUTPUT) -> Path:
    """Solve the figure's targets, draw both poses, write ``output``."""
    skeleton = Skeleton.tree(LENGTHS, PARENTS, limits=LIMITS, root_offsets=OFFSETS)
    targets = TargetSet([1, 3, 5, 6], FEET + HANDS, weights=(1.0, 1.0) + HAND_WEIGHTS)
    before = np.array(START)
    solution = solve_dls_targets(skeleton, before, targets, max_iterations=200, tolerance=TOLERANCE)
    n = skeleton.count
    points_before = forward_kinematics(skeleton, before)[0]
    points_after = forward_kinematics(skeleton, solution.angles)[0]

    canvas = Canvas(np.vstack((points_before, points_after, targets.points)))
    _draw_grid(canvas)
    body = np.array(((-75.0, -12.0), (75.0, -12.0), (75.0, 25.0), (-75.0, 25.0)))
    canvas.draw.polygon([canvas.px(p) for p in body], fill=GHOST, outline=INK)
    canvas.text((0.0, -2.0), (0, 0), "base (the body)", INK, small=True)

    for points, colour, outline in (
        (points_before, GHOST, MUTED),
        (points_after, LINK, LINK_OUTLINE),
    ):
        for i in range(n):
            canvas.line(points[i], points[n + i], outline, 9)
            canvas.line(points[i], points[n + i], colour, 6)
        for i in range(n):
            canvas.dot(points[i], 4.5, "#fbf8f1", outline)
    for i in skeleton.effectors:
        canvas.dot(points_after[n + i], 6, EFFECTOR, LINK_OUTLINE)

    cross = 8 / canvas.scale
    for j, (link, target) in enumerate(zip(targets.links, targets.points, strict=True)):
        canvas.dashed(points_after[n + link], target, TARGET_COLOUR, 1.2, dash=4.0)
        canvas.line(target - (cross, 0), target + (cross, 0), TARGET_COLOUR, 2)
        canvas.line(target - (0, cross), target + (0, cross), TARGET_COLOUR, 2)
        label = f"w = {targets.weights[j]:g}, {solution.errors[j]:.1f} px"
        # Beside each target, away from the links that reach for it.
        left = target[0] < 0 and target[1] < 0
        offset = (-12, 10) if left else (12, 10 if target[1] < 0 else -12)
        anchor = "rm" if left else "lm"
        canvas.text(target, offset, label, TARGET_COLOUR, small=True, anchor=anchor)
    canvas.text(points_after[0], (-8, 8), "hip at root_offsets[0]", MUTED, small=True, anchor="rt")
    canvas.text(points_after[n + 7], (-10, 0), "no target: holds its pose", MUTED, anchor="rm")

    title = "solve_dls_targets: the feet reach, the arms pulled apart settle at the compromise"
    status = (
        f"{solution.status.value} after {solution.iterations} iterations: no pose reaches all "
        f"four targets; weighted least squares, tolerance {TOLERANCE} px"
    )
    for line, y, font in ((title, 16, canvas.font), (status, 34, canvas.small)):
        canvas.draw.text(
            (WIDTH * SUPERSAMPLE / 2, y * SUPERSAMPLE), line, fill=INK, font=font, anchor="mm"
        )

    output.parent.mkdir(parents=True, exist_ok=True)
    canvas.finish().save(output, optimize=True)
    return output


if __name__ == "__main__":
    written = main(Path(sys.argv[1]) if len(sys.argv) > 1 else OUTPUT)
    print(f"wrote {written} ({written.stat().st_size} bytes)")
