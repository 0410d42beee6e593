"""The fast lane: no process, no ROS, no console, no browser (docs/development.md). A unit test
that starts a process fails here and says so: it belongs in another layer."""

from __future__ import annotations

import subprocess

import pytest


class _NoProcess(subprocess.Popen):
    def __init__(self, args, *rest, **kwargs):
        pytest.fail(
            f"a unit test starts no process ({args!r}): move it to tests/system or tests/ros",
            pytrace=False,
        )


@pytest.fixture(autouse=True)
def _no_processes(monkeypatch):
    monkeypatch.setattr(subprocess, "Popen", _NoProcess)
