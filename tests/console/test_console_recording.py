"""The console's recording: a failing read is said once in the console, and closing the console
lets the robot go even when the recording cannot be finished."""

import pytest

from astiop.recording import RecordingError, summary
from tests.tui_helpers import console, sim_of, wait_for

SIZE = (120, 40)


def _recording_notices(app) -> list[str]:
    return [
        n.message for n in app._notifications if n.title == "recording" and n.severity == "error"
    ]


async def test_a_failing_robot_read_is_said_once_in_the_console_and_recording_goes_on(
    tmp_path, monkeypatch
):
    from astiop.transports.base import BackendError

    path = tmp_path / "console.mcap"
    app = console(tmp_path, record=path)
    async with app.run_test(size=SIZE) as pilot:
        gateway, recorder = app.services.gateway, app.recording.recorder
        await wait_for(pilot, lambda: "/robot_pose" in recorder.counts)
        calls = []

        def dropped(names):
            calls.append(names)
            raise BackendError("the robot link dropped")

        monkeypatch.setattr(gateway, "messages", dropped)
        await wait_for(pilot, lambda: len(calls) >= 5)
        await wait_for(pilot, lambda: _recording_notices(app) != [])
        monkeypatch.undo()
        before = recorder.counts["/robot_pose"]
        sim_of(app).step(2.0)  # the robot's clock moves on: a new pose to record
        await wait_for(pilot, lambda: recorder.counts["/robot_pose"] > before)
        notices = _recording_notices(app)
        assert len(notices) == 1 and "the robot link dropped" in notices[0]
    assert summary(path)["/robot_pose"] == before + 1  # finished when the console closed


async def test_the_console_lets_the_robot_go_even_when_its_recording_cannot_be_finished(
    tmp_path, monkeypatch
):
    app = console(tmp_path, record=tmp_path / "lost.mcap")
    closed = []
    gateway = app.services.gateway
    close = gateway.close
    monkeypatch.setattr(gateway, "close", lambda: (closed.append(True), close()))
    with pytest.raises(RecordingError, match="cannot finish"):
        async with app.run_test(size=SIZE) as pilot:
            recorder = app.recording.recorder
            await wait_for(pilot, lambda: "/robot_pose" in recorder.counts)
            recorder._file.close()  # the file is gone from under the recording
    assert closed == [True]
