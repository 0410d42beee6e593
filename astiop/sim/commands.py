"""The simulator's commands: stop and release, teleop velocity, the E-STOP input, the conveyor's
transfers, obstacles placed and removed."""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import pymunk

from astiop.sim.conveyor import Conveyor
from astiop.sim.goal import Goal
from astiop.sim.navigation import GoalError
from astiop.sim.world import World

TELEOP_TIMEOUT_S = 0.5
STOP_LATCHED = "the stop is latched: /release to move again"


@dataclass
class Teleop:
    v: tuple[float, float, float] = (0.0, 0.0, 0.0)
    until: float = -1.0


class CommandsHost(Protocol):
    """What `CommandsMixin` needs of the simulator it is mixed into."""

    lock: threading.RLock
    t: float
    goal: Goal | None
    fault: str
    e_stopped: bool
    stop_latched: bool
    _ignored_said: bool
    _teleop: Teleop
    _target: tuple[float, float, float]
    _v: list[float]
    _applied: tuple[float, float, float]
    control: pymunk.Body
    conveyor: Conveyor
    world: World

    @property
    def pose(self) -> tuple[float, float, float]: ...

    @property
    def held(self) -> bool: ...

    def speed(self) -> float: ...

    def cancel(self, reason: str = "canceled by the operator") -> bool: ...

    def _event(self, kind: str, message: str, severity: str = "info") -> None: ...


if TYPE_CHECKING:
    _Host = CommandsHost
else:
    _Host = object


class CommandsMixin(_Host):
    def _check_can_move(self) -> None:
        if self.e_stopped:
            raise GoalError("the robot is e-stopped; release the e-stop first")
        if self.stop_latched:
            raise GoalError(STOP_LATCHED)
        if self.fault:
            raise GoalError(f"the robot has a fault ({self.fault}); call /stop to acknowledge it")

    def stop(self) -> str:
        """Stop all motion, cancel the goal and acknowledge a collision fault; then hold the
        base (no /cmd_vel, goal, dock or conveyor job) until /release."""
        with self.lock:
            had_goal = self.cancel("stopped by /stop")
            self._teleop = Teleop()
            self._target = (0.0, 0.0, 0.0)
            if self.fault:
                self._event("fault", f"fault acknowledged: {self.fault}")
                self.fault = ""
            if not self.stop_latched:
                self.stop_latched = True
                self._event("stop", "stop latched: /release to move again", "warning")
            return "stopped; goal canceled" if had_goal else "stopped"

    def release(self) -> str:
        """/release: let go of a latched /stop and of the E-STOP input."""
        with self.lock:
            if not self.held:
                return "released; nothing was held"
            if self.e_stopped:
                self.e_stopped = False
                self._event("estop", "e-stop released")
            if self.stop_latched:
                self.stop_latched = False
                self._event("stop", "stop released: the robot may move again")
            self._ignored_said = False  # the next hold says it again
            return "released: the robot may move again"

    def set_cmd_vel(
        self, vx: float, vy: float, wz: float, timeout: float = TELEOP_TIMEOUT_S
    ) -> None:
        """Teleop velocity in the robot frame; it lapses unless repeated within `timeout`.
        Held (E-STOP, latched /stop), the base stays at rest: a zero Twist agrees with that,
        any other is refused and said once per hold."""
        with self.lock:
            if self.held:
                if vx == vy == wz == 0.0:
                    return
                self._say_ignored()
            self._check_can_move()
            if self.goal is not None:
                self.cancel("overridden by /cmd_vel")
            self._teleop = Teleop((float(vx), float(vy), float(wz)), self.t + timeout)

    def clear_fault(self) -> None:
        """For a base with no fault latch (a TurtleBot3's motors just stall against a wall):
        its next command moves it again."""
        with self.lock:
            if self.fault:
                self._event("fault", f"cleared by the next command: {self.fault}")
                self.fault = ""

    def _say_ignored(self) -> None:
        if not self._ignored_said:
            self._ignored_said = True
            why = "the robot is e-stopped" if self.e_stopped else "the stop is latched"
            self._event("stop", f"/cmd_vel ignored: {why} (/release to move again)", "warning")

    def _clear_teleop(self) -> None:
        self._teleop = Teleop()

    def estop(self) -> None:
        with self.lock:
            if not self.e_stopped:
                self.e_stopped = True
                self.cancel("e-stop")
                self.conveyor.abort()
                self._teleop = Teleop()
                self._v[:] = (0.0, 0.0, 0.0)
                self.control.velocity, self.control.angular_velocity = (0, 0), 0.0
                self._applied = (0.0, 0.0, 0.0)
                self._event("estop", "E-STOP engaged", "error")

    def release_estop(self) -> None:
        """The E-STOP's release is the robot's /release: it lets go of a latched /stop too."""
        self.release()

    def conveyor_transfer(self, direction: int) -> str:
        with self.lock:
            self._check_can_move()
            word = "load" if direction > 0 else "unload"
            if self.conveyor.running:
                raise GoalError("the conveyor is already running")
            if self.goal is not None or self.speed() > 0.02:
                raise GoalError(f"cannot {word} while moving")
            st, dist = self.world.nearest_station(*self.pose[:2])
            if st is None or st.kind != "conveyor" or dist > 0.3:
                raise GoalError(
                    f"cannot {word} here: not at a conveyor station "
                    "(assembly_station, cps_storage, shipping)"
                )
            if direction > 0 and self.conveyor.loaded:
                raise GoalError("the conveyor already carries a load")
            if direction < 0 and not self.conveyor.loaded:
                raise GoalError("the conveyor is empty: nothing to unload")
            self.conveyor.start(direction)
            self._event("conveyor", f"{word}ing at {st.name}")
            return f"{word}ing at {st.name}"

    def add_obstacle(self, kind: str, x: float, y: float, theta: float = 0.0):
        with self.lock:
            ob = self.world.add_obstacle(kind, x, y, theta)
            self._event("world", f"{kind} {ob.id} placed at ({x:.1f}, {y:.1f})")
            return ob

    def remove_obstacle(self, obstacle_id: int):
        with self.lock:
            ob = self.world.remove_obstacle(obstacle_id)
            self._event("world", f"{ob.kind} {ob.id} removed")
            return ob
