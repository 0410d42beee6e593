"""A recorded drive made deterministically: the simulator stepped, the recorder polled by hand."""

from astiop.config import load_settings
from astiop.recording import SessionRecorder
from astiop.robot.factory import make_sim_gateway
from astiop.sim.simulator import Simulator
from astiop.store import Store

GOTO = "ros2 service call /goto_position astiop_msgs/srv/GotoPosition \"{name: '%s'}\""


def record_trip(folder, place: str = "inspection_zone_a"):
    """A seeded drive to `place`, polled at 10 Hz of sim time and flushed every poll, with one
    agent turn finished half-way and 2 s kept after arrival. Returns the file; the store it
    used is folder/rec.db."""
    settings = load_settings({}, env={}, path=folder / "none.toml")
    store = Store(folder / "rec.db")
    sim = Simulator(seed=0)
    gateway = make_sim_gateway(settings, store, sim=sim)
    path = folder / "trip.mcap"
    recorder = SessionRecorder(path, gateway, store, flush_s=0.0)
    assert gateway.run(GOTO % place, confirm=lambda _c: True).executed
    arrived = 0
    for i in range(400):
        sim.step(0.1)
        recorder.poll()
        if i == 50:
            turn = store.start_interaction(model="rules", mode="rules", prompt="where is it?")
            store.update_interaction(turn, status="done", answer="x 5.0, y 3.5")
        arrived += sim.goal is None
        if arrived > 20:
            break
    recorder.stop()
    store.close()
    return path
