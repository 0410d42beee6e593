"""The Dashboard's map as the operator's instrument, through Pilot: a click (or the keyboard's
cursor) points at metres within the cell at any zoom; the point's menu sends the robot through
the same review, safety and confirmation as a typed goal, or saves the place; a zone is drawn
corner by corner and stored; a fleet's other robots are drawn, named, and picked by a click."""

from __future__ import annotations

from textual.widgets import Input

from astiop.screens.map_actions import PointMenuModal
from astiop.store import Store
from astiop.widgets.map_view import WarehouseMapView
from tests.console.test_tui_approvals import asked
from tests.tui_helpers import console, sim_of, wait_for

SIZE = (120, 40)
AISLE = (12.0, 8.75)  # open floor between the racks, near the dock


def _view(app) -> WarehouseMapView:
    return app.screen.query_one(WarehouseMapView)


async def _click_at(pilot, view: WarehouseMapView, x: float, y: float) -> tuple[int, int]:
    """Click the cell holding (x, y); its (column, row). The map has a border of one cell."""
    col, row = view.frame.cell_of(x, y)
    await pilot.click(view, offset=(col + 1, row + 1))
    await pilot.pause()
    return col, row


async def _menu(pilot, app) -> PointMenuModal:
    await wait_for(pilot, lambda: isinstance(app.screen, PointMenuModal))
    return app.screen


async def test_a_click_points_within_its_cell_at_two_zoom_levels(tmp_path):
    app = console(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.pause()
        view = _view(app)
        sizes = []
        for zoom_keys in ((), ("plus", "plus")):
            await pilot.press(*zoom_keys)
            frame = view.frame
            await _click_at(pilot, view, *AISLE)
            menu = await _menu(pilot, app)
            # the cell's centre: within half a cell of the point clicked on
            assert abs(menu.x - AISLE[0]) <= 0.5 / frame.s + 0.005
            assert abs(menu.y - AISLE[1]) <= 1.0 / frame.s + 0.005
            sizes.append(1 / frame.s)
            await pilot.press("escape")
            await pilot.pause()
        assert sizes[1] < sizes[0] / 2  # zoomed 2.25×: a cell is that much smaller
        assert "zoom 2.25× (+/-, wheel)" in str(view.border_subtitle)
        await pilot.press("0")  # fit
        assert view.viewport.fitted


async def test_sending_from_the_map_is_the_typed_goal_reviewed_confirmed_and_refused_in_keepout(
    tmp_path,
):
    store = Store(tmp_path / "console.db")  # the console's database (tui_helpers)
    store.add_zone("loading_bay", "keepout", [(14, 7.5), (16, 7.5), (16, 10), (14, 10)])
    store.close()
    app = console(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.pause()
        view = _view(app)
        await _click_at(pilot, view, *AISLE)
        menu = await _menu(pilot, app)
        x, y = menu.x, menu.y
        assert f"Send {app.current_robot} here ({x:.2f}, {y:.2f})" in str(
            menu.query_one("OptionList").get_option_at_index(0).prompt
        )
        await pilot.press("enter")  # send
        await wait_for(pilot, lambda: asked(app) != "")
        from_map = asked(app)
        assert "It moves the robot" in from_map and sim_of(app).goal is None  # not yet
        await pilot.press("y")
        await wait_for(pilot, lambda: sim_of(app).goal is not None)
        goal = sim_of(app).goal.final_pose
        assert abs(goal[0] - x) < 1e-3 and abs(goal[1] - y) < 1e-3, goal
        # the same words typed in chat make the same command, asked the same way
        await pilot.press("f2")
        await pilot.pause()
        app.screen.query_one(Input).value = f"send the robot to x {x:.2f} y {y:.2f}"
        await pilot.press("enter")
        await wait_for(pilot, lambda: asked(app) != "")
        assert asked(app) == from_map
        await pilot.press("n")
        await app.workers.wait_for_complete()
        # inside the keepout zone: refused in one line naming it, nothing asked, nothing sent
        await pilot.press("f1")
        await pilot.pause()
        before = sim_of(app).goal
        await _click_at(pilot, view, 15.0, 8.75)
        await _menu(pilot, app)
        await pilot.press("enter")
        await app.workers.wait_for_complete()
        await pilot.pause()
        said = [n.message for n in app._notifications]
        assert any("keepout zone 'loading_bay'" in m and "\n" not in m for m in said), said
        assert asked(app) == "" and sim_of(app).goal is before


async def test_a_drag_from_the_point_gives_the_goal_its_heading(tmp_path):
    """Pressed on the floor and let go three rows up: the robot is sent there facing +90°
    (the map's north), said in the menu and the confirmation, arrived at with that heading."""
    import math

    app = console(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.pause()
        view = _view(app)
        col, row = view.frame.cell_of(*AISLE)
        await pilot.mouse_down(view, offset=(col + 1, row + 1))
        await pilot.mouse_up(view, offset=(col + 1, row + 1 - 3))
        menu = await _menu(pilot, app)
        assert menu.theta is not None and abs(menu.theta - math.pi / 2) < 1e-3
        assert abs(menu.x - AISLE[0]) <= 0.5 / view.frame.s + 0.005  # the point pressed
        assert "facing 90°" in str(menu.query_one("OptionList").get_option_at_index(0).prompt)
        await pilot.press("enter")
        await wait_for(pilot, lambda: asked(app) != "")
        assert "theta: 1.5708" in asked(app)
        await pilot.press("y")
        await wait_for(pilot, lambda: sim_of(app).goal is not None)
        assert abs(sim_of(app).goal.final_pose[2] - math.pi / 2) < 1e-3
        # a plain click still asks with no heading
        await _click_at(pilot, view, *AISLE)
        menu = await _menu(pilot, app)
        assert menu.theta is None
        assert "facing" not in str(menu.query_one("OptionList").get_option_at_index(0).prompt)


async def test_the_keyboard_alone_saves_a_point_and_draws_a_zone(tmp_path):
    app = console(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.pause()
        view = _view(app)
        assert app.focused is view  # the Dashboard's keys are the map's at once
        await pilot.press("right", "right", "down")
        col, row = view.cursor
        x, y = view.frame.cell_centre(col, row)
        await pilot.press("enter")
        await _menu(pilot, app)
        await pilot.press("down", "enter")  # save this point as…
        await wait_for(pilot, lambda: type(app.screen).__name__ == "FormModal")
        app.screen.query_one("#field-name", Input).value = "by_the_dock"
        await pilot.press("enter")
        await wait_for(pilot, lambda: app.services.store.get_location("by_the_dock") is not None)
        loc = app.services.store.get_location("by_the_dock")
        assert (loc.x, loc.y) == (round(x, 2), round(y, 2))
        await wait_for(pilot, lambda: any(p.name == "by_the_dock" for p in view.places))
        # a zone: z, three corners (space at the cursor, or clicks), enter, its name and kind
        await pilot.press("z")
        corners = []
        for target in ((11.0, 8.0), (13.0, 8.0), (12.0, 10.0)):
            await _click_at(pilot, view, *target)
            corners.append(tuple(round(v, 2) for v in view.frame.cell_centre(*view.cursor)))
        await pilot.press("backspace")  # the last undone, then added again from the keyboard
        assert view.draft == corners[:2]
        await pilot.press("space")
        assert len(view.draft) == 3
        await pilot.press("enter")
        await wait_for(pilot, lambda: type(app.screen).__name__ == "FormModal")
        app.screen.query_one("#field-name", Input).value = "aisle_slow"
        app.screen.query_one("#field-kind", Input).value = "speed"
        app.screen.query_one("#field-speed", Input).value = "0.3"
        await pilot.press("enter")
        await wait_for(pilot, lambda: app.services.store.get_zone("aisle_slow") is not None)
        zone = app.services.store.get_zone("aisle_slow")
        assert zone.kind == "speed" and zone.speed == 0.3 and list(zone.corners) == corners
        await wait_for(pilot, lambda: any(z.name == "aisle_slow" for z in view.zones))
        # a bad zone (two corners) is said in one line and nothing is stored
        await pilot.press("z", "space", "right", "right", "space", "enter")
        await pilot.pause()
        assert any("at least 3 corners, 2 given" in n.message for n in app._notifications)
        assert [z.name for z in app.services.store.list_zones()] == ["aisle_slow"]


async def test_the_fleets_other_robots_are_drawn_named_and_picked_by_a_click(tmp_path):
    from tests.console.test_tui_fleet import fleet_console

    app, fleet, runner = fleet_console(tmp_path)  # astibot_2 is the current robot
    fleet.robots[0].goto(37.6, 21.0, 0.0, "cps_storage")  # astibot_1 follows a plan
    runner.start()
    try:
        async with app.run_test(size=SIZE) as pilot:
            view = _view(app)
            await wait_for(
                pilot, lambda: {r.name for r in view.others} == {"astibot_1", "astibot_3"}
            )
            await wait_for(pilot, lambda: any(r.plan for r in view.others if r.name == "astibot_1"))
            text = "\n".join(view.render_line(y).text for y in range(view.size.height))
            assert "astibot_1" in text and "astibot_3" in text and "other robots" in text
            assert "astibot_2" not in text  # the current robot is the one drawn as the robot
            other = next(r for r in view.others if r.name == "astibot_3")
            await _click_at(pilot, view, other.x, other.y)
            await wait_for(pilot, lambda: app.current_robot == "astibot_3")
            assert not isinstance(app.screen, PointMenuModal)  # a robot picked, no menu
            await wait_for(pilot, lambda: "astibot_2" in {r.name for r in view.others})
    finally:
        runner.stop()


async def test_a_click_on_a_rack_is_said_in_one_line_and_asks_nothing(tmp_path):
    app = console(tmp_path)
    async with app.run_test(size=SIZE) as pilot:
        await pilot.pause()
        view = _view(app)
        x0, y0, x1, y1 = app.services.gateway.map_geometry().shelves[0]
        await _click_at(pilot, view, (x0 + x1) / 2, (y0 + y1) / 2)
        await pilot.pause()
        said = [n.message for n in app._notifications]
        assert any("is on a rack: pick a point of the floor" in m for m in said), said
        assert not isinstance(app.screen, PointMenuModal) and sim_of(app).goal is None


def test_a_point_on_an_occupied_cell_of_a_robots_map_is_not_floor():
    import numpy as np

    from astiop.screens.map_actions import occupied
    from astiop.transports.state import OccupancyGrid

    cells = np.zeros((100, 200), dtype=np.int8)  # 20 x 10 m at 0.1 m, origin (-5, -2)
    cells[50, 120] = 100  # the cell holding (7.0..7.1, 3.0..3.1)
    grid = OccupancyGrid(0.1, -5.0, -2.0, 200, 100, cells)
    assert occupied(grid, 7.05, 3.05) == "an occupied cell of the robot's map"
    assert occupied(grid, 7.15, 3.05) == "" and occupied(grid, 50.0, 3.0) == ""
    assert occupied(None, 7.05, 3.05) == ""  # no map: nothing known to be in the way
