"""The comparison plot, drawn from synthetic traces: like the rest of the renderer it reads plain
data only, so no simulation is needed to exercise it."""

from __future__ import annotations

import ast
import math
from pathlib import Path

import numpy as np
import pytest

import ikgame.render.plot as plot_module
from ikgame.render.plot import (
    SOLVER_COLOURS,
    ComparisonPlot,
    SolverTrace,
    _finite_segments,
    render_comparison,
)

SOLVERS = ("ccd", "jacobian_transpose", "dls", "fabrik")
TARGET = (60.0, 90.0)
START = (120.0, 0.0)  # the effector of the straight start pose below


def make_trace(solver: str, *, delay: float = 0.0, **overrides) -> SolverTrace:
    """An effector closing on TARGET exponentially over 2 s, ``delay`` s later than the others."""
    times = np.arange(1, 241) / 120.0
    closing = np.exp(-4.0 * np.clip(times - delay, 0.0, None))
    path = np.array(TARGET) + np.outer(np.r_[1.0, closing], np.subtract(START, TARGET))
    fields = dict(
        solver=solver,
        status="passed",
        sim_time=float(times[-1]),
        path_length=float(np.hypot(*np.diff(path, axis=0).T).sum()),
        times=times,
        errors=np.hypot(*(path[1:] - TARGET).T),
        path=path,
    )
    fields.update(overrides)
    return SolverTrace(**fields)


def make_plot(traces=None, **overrides) -> ComparisonPlot:
    fields = dict(
        level="Synthetic",
        traces=tuple(make_trace(s, delay=0.1 * i) for i, s in enumerate(SOLVERS))
        if traces is None
        else traces,
        base=(0.0, 0.0),
        reach=120.0,
        start_pose=[(0.0, 0.0), (40.0, 0.0), (80.0, 0.0), START],
        reach_points=[TARGET],
        tolerance=6.0,
    )
    fields.update(overrides)
    return ComparisonPlot(**fields)


def pixels(image) -> np.ndarray:
    return np.asarray(image.convert("RGB"), dtype=int)


def near(image_pixels: np.ndarray, colour) -> int:
    """How many pixels are within a small distance of ``colour``."""
    return int((np.abs(image_pixels.reshape(-1, 3) - colour).sum(axis=1) < 30).sum())


def test_plot_has_the_requested_size_and_every_solver_colour():
    image = render_comparison(make_plot(), size=(900, 420))
    assert image.size == (900, 420)
    rgb = pixels(image)
    assert len(np.unique(rgb.reshape(-1, 3), axis=0)) > 50  # not blank
    for solver in SOLVERS:
        assert near(rgb, SOLVER_COLOURS[solver]) > 100, solver


def test_default_size_and_sequences_are_accepted_as_arrays():
    trace = make_trace("ccd", times=[0.5, 1.0], errors=[40.0, 2.0], path=[START, TARGET])
    plot = make_plot((trace,))
    assert isinstance(trace.times, np.ndarray) and trace.path.shape == (2, 2)
    assert plot.reach_points.shape == (1, 2) and plot.start_pose.shape == (4, 2)
    assert render_comparison(plot).size == (1200, 560)


def test_a_solver_without_a_fixed_colour_gets_one_of_its_own():
    rgb = pixels(render_comparison(make_plot((make_trace("ccd"), make_trace("newton")))))
    assert near(rgb, SOLVER_COLOURS["ccd"]) > 100
    assert near(rgb, plot_module._EXTRA_COLOURS[0]) > 100


def test_ticks_without_a_target_break_the_error_line():
    nan = math.nan
    times = np.arange(1.0, 8.0)
    errors = np.array([nan, nan, 5.0, 4.0, nan, 3.0, nan])
    # A lone sample is doubled so that it still draws as a (zero-length) line.
    assert _finite_segments(times, errors) == [[(3.0, 5.0), (4.0, 4.0)], [(6.0, 3.0), (6.0, 3.0)]]
    waiting = make_trace("ccd", errors=np.r_[np.full(30, nan), make_trace("ccd").errors[30:]])
    assert render_comparison(make_plot((waiting,))).size == (1200, 560)


def test_a_run_without_any_target_still_draws():
    trace = make_trace("dls", errors=np.full(240, math.nan))
    plot = make_plot((trace,), reach_points=np.empty((0, 2)), tolerance=None)
    assert render_comparison(plot, size=(600, 300)).size == (600, 300)


def test_a_target_trail_is_drawn_in_the_path_panel_only():
    angle = np.linspace(0.0, 2 * math.pi, 100)
    trail = np.c_[40.0 * np.cos(angle), 60.0 + 40.0 * np.sin(angle)]
    plain = pixels(render_comparison(make_plot((make_trace("ccd"),))))
    trailed = pixels(render_comparison(make_plot((make_trace("ccd", target_trails=(trail,)),))))
    changed = np.flatnonzero(np.any(plain != trailed, axis=2).any(axis=0))
    assert changed.size and changed.min() >= 600  # the right half: the path panels


def test_a_trees_other_effectors_are_drawn_in_the_solvers_colour_in_the_path_panel():
    # Inside the first path's extent, so the map keeps its scale and only the new line differs.
    other = np.c_[np.linspace(20.0, 40.0, 50), np.linspace(20.0, 70.0, 50)]
    one = pixels(render_comparison(make_plot((make_trace("ccd"),))))
    two = pixels(render_comparison(make_plot((make_trace("ccd", other_paths=(other,)),))))
    changed = np.any(one != two, axis=2)
    assert changed.any() and np.flatnonzero(changed.any(axis=0)).min() >= 600
    assert near(two[changed], SOLVER_COLOURS["ccd"]) > near(one[changed], SOLVER_COLOURS["ccd"])


def test_the_tolerance_is_marked_in_the_error_panel_only():
    marked = pixels(render_comparison(make_plot()))
    unmarked = pixels(render_comparison(make_plot(tolerance=None)))
    changed = np.flatnonzero(np.any(marked != unmarked, axis=2).any(axis=0))
    assert changed.size and changed.max() < 600  # the left half: the error panel


@pytest.mark.parametrize("size", [(100, 100), (1200.0, 560), "big", (1200,), (True, 560)])
def test_bad_plot_sizes_are_refused(size):
    with pytest.raises(ValueError, match="size must be"):
        render_comparison(make_plot(), size=size)


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: make_trace("ccd", errors=[1.0, 2.0]), "one value per tick, got 240 and 2"),
        (lambda: make_trace("ccd", path=np.zeros((5, 3))), r"path must be \(k,2\)"),
        (lambda: make_trace("ccd", path=[]), "every path must have at least one point"),
        (lambda: make_trace("ccd", other_paths=([],)), "every path must have at least one point"),
        (lambda: make_trace("ccd", other_paths=([1.0, 2.0],)), "each of other_paths must be"),
        (lambda: make_trace("ccd", times=np.zeros((2, 120))), r"times must be \(k\)"),
        (lambda: make_trace("ccd", target_trails=([1.0, 2.0],)), "each target trail must be"),
        (lambda: make_plot(traces=()), "at least one solver trace"),
        (lambda: make_plot(reach_points=[1.0, 2.0]), r"reach_points must be \(k,2\)"),
    ],
)
def test_malformed_plot_data_is_refused_with_the_field_named(make, message):
    with pytest.raises(ValueError, match=message):
        make()


def test_the_plot_module_imports_no_physics_or_simulation():
    """The render layer draws what it is given: the data flows from the simulation to it."""
    tree = ast.parse(Path(plot_module.__file__).read_text(encoding="utf-8"))
    imported = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            imported |= {alias.name.split(".")[0] for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            imported.add((node.module or "").split(".")[0])
    assert imported <= {
        "__future__",
        "collections",
        "dataclasses",
        "math",
        "typing",
        "numpy",
        "PIL",
    }
