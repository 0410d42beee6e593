"""The simulator's commands: stop and release, teleop velocity, the E-STOP input, the conveyor's
transfers, obstacles placed and removed."""

from __future__ import annotations

import threading

from astiop.sim.base import Base, Teleop
from astiop.sim.clock import Clock, SimEvents
from astiop.sim.conveyor import Conveyor
from astiop.sim.goal import GoalError
from astiop.sim.holds import Holds
from astiop.sim.navigation import Navigation
from astiop.sim.world import Obstacle, World

TELEOP_TIMEOUT_S = 0.5


class SimCommands:
    """Each command takes `lock`; it holds the base (`holds`) or moves it (`base`'s teleop),
    cancels the goal through `navigation`, runs the conveyor, or changes the world."""

    def __init__(
        self,
        *,
        lock: threading.RLock,
        clock: Clock,
        events: SimEvents,
        holds: Holds,
        base: Base,
        navigation: Navigation,
        conveyor: Conveyor,
        world: World,
    ) -> None:
        self.lock = lock
        self.clock = clock
        self.events = events
        self.holds = holds
        self.base = base
        self.navigation = navigation
        self.conveyor = conveyor
        self.world = world
        self._ignored_said = False  # /cmd_vel ignored during this hold: said once

    def stop(self) -> str:
        """Stop all motion, cancel the goal and acknowledge a collision fault; then hold the
        base (no /cmd_vel, goal, dock or conveyor job) until /release."""
        with self.lock:
            holds = self.holds
            had_goal = self.navigation.cancel("stopped by /stop")
            self.base.teleop = Teleop()
            self.base.target = (0.0, 0.0, 0.0)
            if holds.fault:
                self.events.say("fault", f"fault acknowledged: {holds.fault}")
                holds.fault = ""
            if not holds.stop_latched:
                holds.stop_latched = True
                self.events.say("stop", "stop latched: /release to move again", "warning")
            return "stopped; goal canceled" if had_goal else "stopped"

    def release(self) -> str:
        """/release: let go of a latched /stop and of the E-STOP input."""
        with self.lock:
            holds = self.holds
            if not holds.held:
                return "released; nothing was held"
            if holds.e_stopped:
                holds.e_stopped = False
                self.events.say("estop", "e-stop released")
            if holds.stop_latched:
                holds.stop_latched = False
                self.events.say("stop", "stop released: the robot may move again")
            self._ignored_said = False  # the next hold says it again
            return "released: the robot may move again"

    def set_cmd_vel(
        self, vx: float, vy: float, wz: float, timeout: float = TELEOP_TIMEOUT_S
    ) -> None:
        """Teleop velocity in the robot frame; it lapses unless repeated within `timeout`.
        Held (E-STOP, latched /stop), the base stays at rest: a zero Twist agrees with that,
        any other is refused and said once per hold."""
        with self.lock:
            if self.holds.held:
                if vx == vy == wz == 0.0:
                    return
                self._say_ignored()
            self.holds.check_can_move()
            if self.navigation.goal is not None:
                self.navigation.cancel("overridden by /cmd_vel")
            self.base.teleop = Teleop((float(vx), float(vy), float(wz)), self.clock.t + timeout)

    def clear_fault(self) -> None:
        """For a base with no fault latch (a TurtleBot3's motors just stall against a wall):
        its next command moves it again."""
        with self.lock:
            if self.holds.fault:
                self.events.say("fault", f"cleared by the next command: {self.holds.fault}")
                self.holds.fault = ""

    def _say_ignored(self) -> None:
        if not self._ignored_said:
            self._ignored_said = True
            why = "the robot is e-stopped" if self.holds.e_stopped else "the stop is latched"
            self.events.say("stop", f"/cmd_vel ignored: {why} (/release to move again)", "warning")

    def estop(self) -> None:
        with self.lock:
            if not self.holds.e_stopped:
                self.holds.e_stopped = True
                self.navigation.cancel("e-stop")
                self.conveyor.abort()
                self.base.halt()
                self.events.say("estop", "E-STOP engaged", "error")

    def release_estop(self) -> None:
        """The E-STOP's release is the robot's /release: it lets go of a latched /stop too."""
        self.release()

    def conveyor_transfer(self, direction: int) -> str:
        with self.lock:
            self.holds.check_can_move()
            word = "load" if direction > 0 else "unload"
            if self.conveyor.running:
                raise GoalError("the conveyor is already running")
            if self.navigation.goal is not None or self.base.speed() > 0.02:
                raise GoalError(f"cannot {word} while moving")
            st, dist = self.world.nearest_station(*self.base.pose[:2])
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
            self.events.say("conveyor", f"{word}ing at {st.name}")
            return f"{word}ing at {st.name}"

    def add_obstacle(self, kind: str, x: float, y: float, theta: float = 0.0) -> Obstacle:
        with self.lock:
            ob = self.world.add_obstacle(kind, x, y, theta)
            self.events.say("world", f"{kind} {ob.id} placed at ({x:.1f}, {y:.1f})")
            return ob

    def remove_obstacle(self, obstacle_id: int) -> Obstacle:
        with self.lock:
            ob = self.world.remove_obstacle(obstacle_id)
            self.events.say("world", f"{ob.kind} {ob.id} removed")
            return ob
