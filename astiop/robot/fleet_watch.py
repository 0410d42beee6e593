"""Every robot of a fleet watched at once: a gateway per robot, its state read off the caller's
thread, one row per robot with what it reported and how long ago; the E-STOP of all of them in
parallel. The console's Fleet screen and `astiop fleet list` read the same rows."""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, replace

from astiop.robot.gateway import RobotGateway
from astiop.transports.state import RobotState

STALE_S = 3.0  # a robot not heard for this long is stale: what it last said may no longer hold
LOW_BATTERY = 0.2
FIRST_ROW_S = 0.1  # a robot's row read this often until its battery and pose came in
FIRST_FOR_S = 5.0  # (a robot with no battery topic is not read that often for long)
FIND_S = 1.0  # how often robots that join later are looked for on the graph
# the robots found since the last look: (name, namespace, how its gateway is opened)
FindMore = Callable[[], list[tuple[str, str, Callable[[], RobotGateway]]]]


@dataclass(frozen=True)
class FleetRow:
    name: str
    namespace: str
    make: str = ""
    state: str = "unknown"
    battery: float | None = None  # 0..1
    x: float | None = None
    y: float | None = None
    theta: float | None = None
    speed: float | None = None
    goal: str = ""
    age_s: float | None = None  # since its state last changed on our side (None: never heard)
    error: str = ""  # why it could not be reached, or how its E-STOP failed
    control: str = ""  # who controls it (its lease): "this console", a holder, "free"
    plan: tuple[tuple[float, float], ...] = ()  # the path it follows now (map frame, metres)

    @property
    def stale(self) -> bool:
        return self.age_s is None or self.age_s > STALE_S

    @property
    def low_battery(self) -> bool:
        return self.battery is not None and self.battery < LOW_BATTERY

    def as_json(self) -> dict:
        return {
            "name": self.name,
            "namespace": self.namespace,
            "make": self.make,
            "state": self.state,
            "battery_percent": None if self.battery is None else round(self.battery * 100, 1),
            "x_m": None if self.x is None else round(self.x, 2),
            "y_m": None if self.y is None else round(self.y, 2),
            "theta_deg": None if self.theta is None else round(math.degrees(self.theta), 1),
            "speed_m_s": None if self.speed is None else round(self.speed, 2),
            "goal": self.goal,
            **({"control": self.control} if self.control else {}),
            **({"error": self.error} if self.error else {}),
        }


def row_of(name: str, namespace: str, gateway: RobotGateway) -> FleetRow:
    """The robot's row as its gateway reads it now."""
    make = gateway.profile.make if gateway.profile else ""
    st = gateway.state()
    return row_from(name, namespace, make, st, _age(st))


def _age(st: RobotState) -> float | None:
    """How long ago the robot was last heard: 0 while its readings come (a live backend keeps
    only fresh ones), how long it has been silent once it is lost, None before it said anything."""
    if st.lost_s is not None:
        return st.lost_s
    if st.pose is None and st.battery is None and st.status is None:
        return None
    return 0.0


STILL_MOVING = 0.02  # m/s


def _state_said(st: RobotState) -> str:
    """The row's state word; a robot held by the E-STOP that still reports motion (a hung node
    resumed with its goal) is never shown as held alone, nor as navigating."""
    word = st.state_word
    own = st.status.state if st.status else ""
    moving = own in ("navigating", "docking") or (st.speed or 0.0) > STILL_MOVING
    if word == "e_stopped" and moving:
        return "e_stopped, STILL MOVING"
    return word


def row_from(name: str, namespace: str, make: str, st: RobotState, age_s: float | None):
    pose = st.pose
    return FleetRow(
        name=name,
        namespace=namespace,
        make=make,
        state=_state_said(st),
        battery=st.battery.percentage if st.battery else None,
        x=pose.x if pose else None,
        y=pose.y if pose else None,
        theta=pose.theta if pose else None,
        speed=st.speed,
        goal=st.status.active_goal if st.status else "",
        age_s=age_s,
        plan=tuple(st.plan),
    )


def control_of(gateway: RobotGateway) -> str:
    """Who controls the robot, by its lease: this console, another holder, or no one."""
    lease = gateway.lease
    if lease is None:
        return ""
    if lease.held:
        return "this console"
    try:
        holder = lease.other_holder()
    except Exception:  # noqa: BLE001 - a busy store: said as unknown
        return "?"
    return holder.words if holder else "free"


class FleetWatch:
    """`robots`: (name, namespace, open) with `open()` making that robot's gateway. Each robot's
    row is refreshed every `period_s` by a thread of its own (a robot slow to answer holds up
    no other); `on_rows(rows)` is called from those threads."""

    def __init__(
        self,
        robots: list[tuple[str, str, Callable[[], RobotGateway]]],
        on_rows: Callable[[list[FleetRow]], None] = lambda _rows: None,
        period_s: float = 0.5,
    ):
        self.robots = robots
        self.on_rows = on_rows
        self.period_s = period_s
        self.gateways: dict[str, RobotGateway] = {}
        self._given: dict[str, RobotGateway] = {}  # made and started by the caller
        self.settings_for: Callable[[str], object] | None = None  # a robot's own settings
        self._rows = {name: FleetRow(name, ns) for name, ns, _ in robots}
        self._failed: dict[str, str] = {}  # robots whose E-STOP failed, and how
        self._control: dict[str, str] = {}  # who controls each robot, as last read
        self._lock = threading.Lock()
        self._halt = threading.Event()
        self._threads: list[threading.Thread] = []
        # robots that join later: polled every FIND_S while the watch runs, each one found
        # (name, namespace, open) added to the watch; `stop_finding()` at the close
        self.find_more: FindMore | None = None
        self.stop_finding: Callable[[], None] = lambda: None

    def adopt(self, name: str, gateway: RobotGateway) -> None:
        """Watch `name` through a gateway the caller made (the console's current robot): one
        connection to it, not two. Closed with the others."""
        self._given[name] = gateway

    def start(self) -> FleetWatch:
        """Watch every robot (once: started again, nothing more)."""
        if self._threads:
            return self
        for name, ns, open_ in list(self.robots):
            self._start_watching(name, ns, open_)
        if self.find_more is not None:
            self._spawn(self._find, "fleet-find", self.find_more)
        return self

    def _spawn(self, target: Callable[..., None], name: str, *args: object) -> None:
        t = threading.Thread(target=target, args=args, name=name, daemon=True)
        t.start()
        self._threads.append(t)

    def _start_watching(self, name: str, ns: str, open_) -> None:
        self._spawn(self._watch, f"fleet-{name}", name, ns, open_)

    def add(self, name: str, ns: str, open_: Callable[[], RobotGateway]) -> bool:
        """A robot found after the start, watched from now (False: it is watched already)."""
        with self._lock:
            if name in self._rows:
                return False
            self.robots = sorted([*self.robots, (name, ns, open_)], key=lambda r: r[0])
            self._rows[name] = FleetRow(name, ns)
        self._start_watching(name, ns, open_)
        self.on_rows(self.rows())
        return True

    def _find(self, find_more: FindMore) -> None:
        started = time.monotonic()  # a fleet still being discovered is looked at more often
        while not self._halt.wait(0.25 if time.monotonic() - started < 5.0 else FIND_S):
            try:
                for name, ns, open_ in find_more():
                    self.add(name, ns, open_)
            except Exception:  # noqa: BLE001 - a graph not read this time: next time
                continue

    def names(self) -> list[tuple[str, str]]:
        """Every robot watched now, (name, namespace)."""
        return [(name, ns) for name, ns, _ in self.robots]

    def rows(self) -> list[FleetRow]:
        with self._lock:
            return [self._rows[name] for name, _, _ in self.robots]

    def _set(self, row: FleetRow) -> None:
        with self._lock:
            self._rows[row.name] = row
        self.on_rows(self.rows())

    def _watch(self, name: str, ns: str, open_) -> None:
        try:
            gateway = self._given.get(name)
            if gateway is None:
                gateway = open_()
                gateway.watch_lightly(True)  # for its row; the current robot's is whole
                gateway.start()
        except Exception as exc:  # noqa: BLE001 - one robot not reached is its own row
            self._set(FleetRow(name, ns, error=f"not reached: {exc}"))
            return
        with self._lock:
            self.gateways[name] = gateway
        self._spawn(self._watch_control, f"fleet-{name}-control", name, gateway)
        # until its battery and pose came in (for FIRST_FOR_S at most), read more often
        whole, first_until = False, time.monotonic() + FIRST_FOR_S
        while not self._halt.is_set():
            try:
                row = replace(row_of(name, ns, gateway), control=self._control.get(name, "…"))
                whole = whole or (row.battery is not None and row.x is not None)
                failed = self._failed.get(name)
                self._set(replace(row, error=failed) if failed else row)
            except Exception as exc:  # noqa: BLE001
                self._set(FleetRow(name, ns, error=f"not read: {exc}"))
            quick = not whole and time.monotonic() < first_until
            self._halt.wait(FIRST_ROW_S if quick else self.period_s)

    def _watch_control(self, name: str, gateway: RobotGateway) -> None:
        """Who controls the robot, read apart from its state: the first read opens its lease's
        channel on the robot's graph and waits for the holders there (up to seconds)."""
        while not self._halt.is_set():
            self._control[name] = control_of(gateway)
            self._halt.wait(self.period_s)

    def estop_all(self, skip: str = "") -> dict[str, list[str]]:
        """Every watched robot stopped at once, each by its own gateway; a robot not reached is
        a failure of its own. The failures by robot name (empty: stopped). `skip`: a robot the
        caller stops itself (the console's current one, first)."""
        results: dict[str, list[str]] = {}
        names = [n for n, _, _ in self.robots if n != skip]
        for name in names:  # every robot's zero velocity first, in one pass: a thread takes
            gateway = self.gateway_of(name)  # milliseconds to start on a busy process
            if gateway is not None:
                gateway.zero_now()
        threads = [
            threading.Thread(target=lambda n=n: results.__setitem__(n, self.estop(n)))
            for n in names
        ]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        return results

    def estop(self, name: str) -> list[str]:
        """One robot stopped and latched; its failures (a robot not reached is one), its row
        red until it is released, whatever it reports meanwhile."""
        gateway = self.gateway_of(name)
        try:
            failures = gateway.estop() if gateway else ["not reached: no connection to it"]
        except Exception as exc:  # noqa: BLE001
            failures = [str(exc)]
        if failures:
            self._failed[name] = "E-STOP failed: " + "; ".join(failures)
            self._set(replace(self._rows[name], error=self._failed[name]))
        return failures

    def release(self, name: str) -> list[str]:
        """One robot's latch and its own stop (/release, where it latches one) let go."""
        self._failed.pop(name, None)
        gateway = self.gateway_of(name)
        if gateway is None:
            return ["not reached: no connection to it"]
        try:
            return gateway.release_estop()
        except Exception as exc:  # noqa: BLE001
            return [str(exc)]

    def release_all(self, skip: str = "") -> list[str]:
        """Each robot's release; what failed, named."""
        names = [n for n, _, _ in self.robots if n != skip]
        return [f"{n}: {f}" for n in names for f in self.release(n)]

    def gateway_of(self, name: str) -> RobotGateway | None:
        """The robot's gateway, once it was reached (the caller's own at once)."""
        with self._lock:
            return self.gateways.get(name) or self._given.get(name)

    def close(self) -> None:
        self._halt.set()
        for t in self._threads:
            t.join(timeout=2)
        self.stop_finding()
        for gateway in {
            id(g): g for g in [*self.gateways.values(), *self._given.values()]
        }.values():
            gateway.close()
