"""The gateway's reading of the robot's graph: its profile and map, read whole before a role is
said to be missing (a new process discovers a robot in rounds)."""

from __future__ import annotations

import time

from astiop.robot.safety import SafetyPolicy
from astiop.ros2.catalog import Catalog
from astiop.ros2.profile import match_profile
from astiop.ros2.profile_types import Profile
from astiop.ros2.validation import Checked, validate
from astiop.store import Store
from astiop.transports.base import RobotTransport

SETTLED_S = 2.0  # a robot graph unchanged this long has been read whole


class GraphReading:
    """The robot's graph as the gateway reads it: handed the robot's backend, the safety policy
    whose geofence the robot's map sets, the store whose places are that map's (None: none)
    and how long a read may wait."""

    def __init__(
        self, backend: RobotTransport, safety: SafetyPolicy, store: Store | None, timeout_s: float
    ):
        self.backend = backend
        self.safety = safety
        self.store = store
        self.timeout_s = timeout_s

    @property
    def catalog(self) -> Catalog:
        return self.backend.catalog

    def settled_profile(self, timeout_s: float) -> Profile:
        """The profile once the robot's graph has been read whole: read again until two reads
        SETTLED_S apart match the same names (a new process discovers a robot in rounds, and a
        role matched on half a graph is a wrong answer), or `timeout_s`."""
        deadline = time.monotonic() + timeout_s
        names = {r: m.name for r, m in self.profile.matches.items()}
        while time.monotonic() < deadline:
            time.sleep(min(SETTLED_S, max(0.0, deadline - time.monotonic())))
            self.backend.refresh()
            now = {r: m.name for r, m in self.profile.matches.items()}
            if now == names and any(now.values()):
                break
            names = now
        self.use_map()
        return self.profile

    def confirm_missing(self) -> Profile:
        """Before saying a robot lacks something: a process still discovering it reads its
        graph until it has settled (a role missing from half a graph is a wrong answer)."""
        if self.backend.discovering():
            return self.settled_profile(self.timeout_s)
        return self.profile

    def use_map(self) -> None:
        """The robot's map from its profile: the store's places are that map's, and goals are
        fenced by the profile's geofence, else by the extent of the robot's own map."""
        profile = self.profile
        fence = profile.map.geofence
        if fence is None:
            geometry = self.backend.map_geometry()
            fence = geometry.bounds if geometry is not None else None
        if fence is not None:
            self.safety.geofence = fence
        if self.store is not None:
            self.store.use_map(profile.map_name, fence)

    @property
    def profile(self) -> Profile:
        """Which of the robot's names play which role (ros2/profile.py)."""
        cat = self.backend.catalog
        return cat.profile if cat.profile is not None else match_profile(cat)

    def serves(self, name: str, timeout_s: float) -> bool:
        """Whether the robot serves `name`, reading its graph again until it appears: a new
        process's first read may have found only part of it. False once the robot's base is
        seen and its services stay the same for SETTLED_S without it, or after `timeout_s`."""
        deadline = time.monotonic() + timeout_s
        seen, since = None, time.monotonic()
        while name not in self.catalog.services:
            services = set(self.catalog.services)
            if services != seen:
                seen, since = services, time.monotonic()
            settled = time.monotonic() - since > SETTLED_S
            if time.monotonic() > deadline or ("/cmd_vel" in self.catalog.topics and settled):
                return False
            time.sleep(0.3)
            self.backend.refresh()
        return True

    def _refresh(self) -> bool:
        if time.monotonic() - self.backend.refreshed_at < self.backend.refresh_every_s:
            return False
        return self.backend.refresh()

    def checked_once_heard(self, text: str, checked: Checked) -> Checked:
        """`checked` names what the graph lacks: read the graph again. A process still
        discovering the robot reads it until the name is heard of, or the graph has not changed
        for SETTLED_S; a name under a namespace the graph has nothing of yet (a fleet's robot
        whose participant comes seconds after another's), until discovery is over."""
        if not self.backend.discovering():
            return validate(text, self.catalog) if self._refresh() else checked
        cmd = checked.command  # a parameter's command names its node, not a topic (name None)
        name = (cmd.name or str(cmd.args.get("node") or "")) if cmd else ""
        namespace = "/" + name.strip("/").split("/")[0] if name.count("/") > 1 else ""
        seen, changed_at = _names(self.catalog), time.monotonic()
        while self.backend.discovering():
            time.sleep(0.25)
            self.backend.refresh(settle=False)
            checked = validate(text, self.catalog)
            if checked.valid or not checked.reason.startswith("there is no"):
                return checked
            now = _names(self.catalog)
            if now != seen:
                seen, changed_at = now, time.monotonic()
            heard_of = not namespace or any(n.startswith(namespace + "/") for n in now)
            if heard_of and time.monotonic() - changed_at >= SETTLED_S:
                break
        return checked


def _names(catalog: Catalog) -> set[str]:
    return {*catalog.topics, *catalog.services, *catalog.actions}
