"""The map view's viewport alone: what a terminal cell is in metres at each zoom and pan, and what
a cell points at (a robot of the fleet, or the floor)."""

from __future__ import annotations

import math

import pytest

from astiop.widgets.map_viewport import ROBOT_RADIUS_M, Frame, Viewport, pick

BOUNDS = (0.0, 0.0, 40.0, 25.0)  # the warehouse, metres
W, H = 80, 60  # pixels: 80 columns, 30 rows of cells


def test_the_fitted_frame_shows_the_whole_map_left_aligned_and_centred_vertically():
    frame = Viewport().frame(W, H, BOUNDS)
    assert frame.s == 2.0  # 80 px over 40 m; 60 px over 25 m would be 2.4
    assert (frame.x0, frame.y0) == (0.0, 0.0)
    assert frame.top == 55  # 50 px of map, 5 px of margin above and below
    # row 2 holds the map's top edge (pixel row 54 is its first): half a metre wide, one high
    assert frame.cell_box(0, 2) == pytest.approx((0.0, 24.5, 0.5, 25.5))
    assert frame.cell_of(0.25, 24.9) == (0, 2) and frame.cell_of(39.9, 0.1) == (79, 27)


@pytest.mark.parametrize("zoom_steps", [0, 1, 3])
def test_a_cells_centre_is_in_that_cell_at_every_zoom(zoom_steps):
    view = Viewport()
    for _ in range(zoom_steps):
        view.zoom_by(1.5, W, H, BOUNDS, about=(12.0, 8.0))
    frame = view.frame(W, H, BOUNDS)
    for col, row in [(0, 0), (17, 9), (79, 29)]:
        x, y = frame.cell_centre(col, row)
        assert frame.cell_of(x, y) == (col, row)
        xa, ya, xb, yb = frame.cell_box(col, row)
        assert xb - xa == pytest.approx(1 / frame.s) and yb - ya == pytest.approx(2 / frame.s)
    assert frame.s == pytest.approx(2.0 * 1.5**zoom_steps)


def test_zooming_keeps_the_point_under_the_mouse_and_out_again_is_the_fit():
    view = Viewport()
    before = view.frame(W, H, BOUNDS).cell_of(30.0, 5.0)
    view.zoom_by(1.5, W, H, BOUNDS, about=(30.0, 5.0))
    after = view.frame(W, H, BOUNDS)
    assert after.s == pytest.approx(3.0)
    col, row = after.cell_of(30.0, 5.0)
    assert abs(col - before[0]) <= 1 and abs(row - before[1]) <= 1
    view.zoom_by(1 / 1.5, W, H, BOUNDS, about=(30.0, 5.0))
    assert view.fitted and view.frame(W, H, BOUNDS) == Viewport().frame(W, H, BOUNDS)


def test_panning_moves_the_view_by_whole_cells_and_fit_brings_it_back():
    view = Viewport()
    view.zoom_by(2.0, W, H, BOUNDS, about=None)
    frame = view.frame(W, H, BOUNDS)
    x, y = frame.cell_centre(10, 10)
    view.pan_cells(4, -3, frame)  # the view right and up: the point moves left and down
    moved = view.frame(W, H, BOUNDS)
    assert moved.cell_of(x, y) == (6, 13)
    view.fit()
    assert view.frame(W, H, BOUNDS) == Viewport().frame(W, H, BOUNDS)
    view.zoom_by(1000.0, W, H, BOUNDS, about=None)
    assert view.zoom == 32.0  # bounded


def test_a_cell_on_a_robot_picks_the_robot_else_the_floor():
    frame = Frame(2.0, 0.0, 0.0, 50)
    robots = [("astibot_1", 10.2, 10.3), ("astibot_2", 10.9, 10.3)]
    col, row = frame.cell_of(10.2, 10.3)
    assert pick(frame, col, row, robots).robot == "astibot_1"  # the nearer of two
    far = frame.cell_of(10.9 + ROBOT_RADIUS_M + 1.0, 10.3)  # past both bodies
    p = pick(frame, *far, robots)
    assert p.robot is None
    assert math.isclose(p.x, frame.cell_centre(*far)[0]) and frame.cell_of(p.x, p.y) == far
