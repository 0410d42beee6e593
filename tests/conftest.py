from __future__ import annotations

import gc
import hashlib
import os

import pytest

from astiop.store import Store


def _dds_on_the_loopback() -> None:
    """Set before anything in this worker starts rclpy: DDS stays on 127.0.0.1, and each xdist
    worker has its own domain, so parallel tests never see each other's robots. The base is
    drawn from the run's id, so two test runs on one machine rarely share domains."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "gw0")
    index = int(worker[2:]) if worker[2:].isdigit() else 0
    run = os.environ.get("PYTEST_XDIST_TESTRUNUID", str(os.getpid()))
    default = 1 + int(hashlib.sha256(run.encode()).hexdigest(), 16) % 22 * 4  # 1..85
    base = int(os.environ.get("TEST_ROS_DOMAIN_BASE", default))
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    os.environ["ROS_LOCALHOST_ONLY"] = "1"
    os.environ["ROS_DOMAIN_ID"] = str(min(base + index, 101))  # 101: the last valid one


_dds_on_the_loopback()


@pytest.fixture
def store(tmp_path) -> Store:
    s = Store(tmp_path / "astiop.db")
    yield s
    s.close()


@pytest.fixture(autouse=True)
def _isolated_config(tmp_path, monkeypatch):
    # No test reads the developer's own settings or database.
    monkeypatch.setenv("ASTIOP_CONFIG", str(tmp_path / "no-config.toml"))
    monkeypatch.setenv("ASTIOP_DB", str(tmp_path / "default.db"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))  # the embedded model's cache
    # `astiop estop` leaves no keeper of its press on the graph: a test's robot ends with the
    # test, and the next test on this worker's domain starts clean (test_stations.py: the keeper)
    monkeypatch.setenv("ASTIOP_ROBOT__ESTOP_KEEPER", "false")
    for name in ("ASTIOP_MODEL", "ASTIOP_ROBOT"):
        monkeypatch.delenv(name, raising=False)


def pytest_collection_modifyitems(items):
    # The slow tests first: four workers then end together on short ones, not on one long tail.
    items.sort(key=lambda item: item.get_closest_marker("slow") is None)


def pytest_collection_finish(session):
    # What is imported by now lives to the end: keep it out of every later collection.
    gc.freeze()


@pytest.fixture(autouse=True)
def _collect_garbage():
    # CPython 3.11.7 bug (fixed in 3.11.8): a finalizer that runs during ast.parse, as pytest's
    # failure report and its import hooks call it, raises "AST constructor recursion depth
    # mismatch" and turns a plain failure into an INTERNALERROR. Finalize each test's garbage.
    yield
    gc.collect()
