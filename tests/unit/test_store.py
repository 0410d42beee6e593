import math
import sqlite3

import pytest

from astiop.store import SCHEMA_VERSION, LocationError, Store, StoreError
from astiop.warehouse import default_map

SEEDED = {
    "charging_dock",
    "assembly_station",
    "cps_storage",
    "shipping",
    "inspection_zone_a",
    "inspection_zone_b",
}


def _inside_rect(x, y, rect, margin=0.0):
    x0, y0, x1, y1 = rect
    return x0 - margin <= x <= x1 + margin and y0 - margin <= y <= y1 + margin


def test_new_database_is_seeded_in_free_space(store):
    names = {loc.name for loc in store.list_locations()}
    assert names >= SEEDED
    wmap = default_map()
    for loc in store.list_locations():
        assert wmap.inside_bounds(loc.x, loc.y)
        # The robot's half-diagonal is 0.62 m: every seed leaves room for the whole base.
        for _, rect in wmap.static_rects:
            assert not _inside_rect(loc.x, loc.y, rect, margin=0.65), (loc.name, rect)


def test_wal_and_schema_version(store):
    assert store.db.conn.execute("PRAGMA journal_mode").fetchone()[0] == "wal"
    assert store.db.conn.execute("PRAGMA user_version").fetchone()[0] == SCHEMA_VERSION


def test_reopen_keeps_data_and_does_not_reseed(tmp_path):
    s = Store(tmp_path / "a.db")
    s.remove_location("shipping")
    s.add_location("dock2", 3.0, 4.0, math.radians(90))
    s.close()
    s2 = Store(tmp_path / "a.db")
    names = {loc.name for loc in s2.list_locations()}
    assert "shipping" not in names and "dock2" in names
    assert s2.get_location("DOCK2").theta == pytest.approx(math.pi / 2)


@pytest.mark.parametrize("name", ["", "has space", "semi;colon", "ü", "x" * 65])
def test_bad_names_are_refused(store, name):
    before = store.list_locations()
    with pytest.raises(LocationError):
        store.add_location(name, 5, 5)
    assert store.list_locations() == before


def test_duplicate_names_ignore_case(store):
    with pytest.raises(LocationError, match="already exists"):
        store.add_location("Charging_Dock", 5, 5)
    store.add_location("bay-1", 5, 5)
    with pytest.raises(LocationError):
        store.rename_location("bay-1", "SHIPPING")


@pytest.mark.parametrize("x,y", [(-1, 5), (41, 5), (5, -0.1), (5, 25.5), (math.nan, 1)])
def test_out_of_bounds_is_refused(store, x, y):
    with pytest.raises(LocationError):
        store.add_location("p", x, y)
    assert store.get_location("p") is None


def test_places_belong_to_a_map(tmp_path):
    s = Store(tmp_path / "a.db")
    s.use_map("turtlebot3_burger", (0.0, 0.0, 4.0, 4.0))  # the seeded six are not its places
    assert s.list_locations() == [] and s.get_location("shipping") is None
    assert s.other_maps() == {"warehouse": len(SEEDED)}
    with pytest.raises(LocationError, match="on the map turtlebot3_burger"):
        s.require_location("shipping")
    with pytest.raises(LocationError, match="outside the geofence"):
        s.add_location("far", 10.0, 2.0)  # inside the warehouse, outside this map's fence
    s.add_location("shipping", 1.0, 2.0)  # a name is unique on its own map only
    s.rename_location("shipping", "bench")
    s.close()
    again = Store(tmp_path / "a.db")
    assert {loc.name for loc in again.list_locations()} == SEEDED  # the warehouse's
    assert again.get_location("shipping").x == pytest.approx(37.6)
    again.use_map("turtlebot3_burger", None)  # no fence known: only finite numbers are checked
    assert [(loc.name, loc.x) for loc in again.list_locations()] == [("bench", 1.0)]
    again.add_location("far", 100.0, -3.0)
    again.remove_location("bench")
    again.use_map("warehouse", default_map().bounds)
    assert {loc.name for loc in again.list_locations()} == SEEDED


def test_a_place_saved_on_the_wrong_map_is_moved(store):
    store.move_location("shipping", "turtlebot3_burger")
    assert store.get_location("shipping") is None
    with pytest.raises(LocationError, match="on the map warehouse"):
        store.move_location("shipping", "x")
    store.use_map("turtlebot3_burger", None)
    assert store.get_location("shipping").x == pytest.approx(37.6)
    store.add_location("dock", 1.0, 1.0)
    store.use_map("warehouse", None)
    store.add_location("dock", 2.0, 2.0)
    with pytest.raises(LocationError, match="has a place named 'dock' already"):
        store.move_location("dock", "turtlebot3_burger")
    assert store.get_location("dock").x == 2.0  # left where it was


def test_rename_and_remove(store):
    store.rename_location("shipping", "Shipping_Bay")
    assert store.get_location("shipping_bay").name == "Shipping_Bay"
    store.remove_location("shipping_bay")
    with pytest.raises(LocationError, match="no location named"):
        store.remove_location("shipping_bay")


def test_random_bytes_file_is_refused_and_untouched(tmp_path):
    path = tmp_path / "junk.db"
    junk = bytes(range(256)) * 40
    path.write_bytes(junk)
    with pytest.raises(StoreError, match="not a SQLite database"):
        Store(path)
    assert path.read_bytes() == junk


def test_newer_schema_is_refused(tmp_path):
    path = tmp_path / "future.db"
    conn = sqlite3.connect(path)
    conn.execute(f"PRAGMA user_version = {SCHEMA_VERSION + 1}")
    conn.execute("CREATE TABLE locations (x)")
    conn.commit()
    conn.close()
    before = path.read_bytes()
    with pytest.raises(StoreError, match="newer"):
        Store(path)
    assert path.read_bytes() == before


def test_foreign_sqlite_database_is_refused(tmp_path):
    path = tmp_path / "other.db"
    conn = sqlite3.connect(path)
    conn.execute("CREATE TABLE invoices (id)")
    conn.commit()
    conn.close()
    with pytest.raises(StoreError, match="another application"):
        Store(path)


def test_connection_per_thread(store):
    import threading

    seen = {}

    def worker():
        seen["names"] = [loc.name for loc in store.list_locations()]
        seen["conn"] = store.db.conn

    t = threading.Thread(target=worker)
    t.start()
    t.join()
    assert seen["conn"] is not store.db.conn
    assert "shipping" in seen["names"]


def test_interactions_are_committed_as_they_happen(store, tmp_path):
    iid = store.start_interaction(model="rules", mode="command", prompt="battery?")
    store.add_command(
        iid,
        seq=0,
        command="ros2 topic echo /battery_status --once",
        valid=1,
        kind="read",
        executed=1,
        output="percentage: 0.9",
        values={"p": 0.9},
    )
    # A second connection (another process would be the same) sees it before any close.
    other = sqlite3.connect(store.path)
    assert other.execute("SELECT prompt FROM interactions").fetchone()[0] == "battery?"
    assert other.execute("SELECT count(*) FROM commands").fetchone()[0] == 1


def test_ten_writers_adding_one_name_are_told_the_same(tmp_path):
    import threading

    from astiop.store.records import LocationError

    path = tmp_path / "w.db"
    Store(path).close()
    stores = [Store(path) for _ in range(10)]
    start, said = threading.Barrier(10), []

    def add(store):
        start.wait()
        try:
            store.add_location("bay_7", 1.0, 2.0)
            said.append("added")
        except LocationError as exc:
            said.append(str(exc))

    writers = [threading.Thread(target=add, args=(s,)) for s in stores]
    for w in writers:
        w.start()
    for w in writers:
        w.join(30)
    for s in stores:
        s.close()
    exists = "a location named 'bay_7' already exists (names ignore case)"
    assert sorted(said) == sorted(["added"] + [exists] * 9), said
