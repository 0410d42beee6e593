"""The robot's state sampled off the UI thread, through the gateway, and posted to the app."""

from __future__ import annotations

import threading

from astiop.screens.messages import RobotStateSampled


class StateSampler(threading.Thread):
    """Reads the robot's state through the gateway and posts it to the app."""

    def __init__(self, app, hz: float, seq: int = 0):
        super().__init__(name="astiop-sampler", daemon=True)
        self.seq = seq  # events up to here were read at start
        self.app = app
        self.period = 1.0 / hz
        self.every = max(int(hz), 1)  # topic statistics about once a second
        self.halt = threading.Event()

    def run(self) -> None:
        graph, store = self.app.services.gateway, self.app.services.store
        seq, n, failing = self.seq, 0, False
        while not self.halt.wait(self.period):
            try:
                state = graph.state()
                events = graph.events_since(seq)
                stats = graph.topic_stats() if n % self.every == 0 else None
                failing = False
            except Exception as exc:  # noqa: BLE001 - say it once, keep sampling
                if not failing:
                    self.app.call_from_thread(
                        self.app.notify, f"robot state: {exc}", severity="error", markup=False
                    )
                failing = True
                continue
            n += 1
            if events:
                seq = events[-1].seq
                store.keep_robot_events(events)
            self.app.post_message(RobotStateSampled(state, events, stats))
        store.close()
