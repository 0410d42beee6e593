"""What each MCP tool does to the robot, through the gateway only. Every argument is checked
here before any command is built; a refusal is a `Refused` with its one-line reason."""

from __future__ import annotations

import asyncio
import base64
import math
import re
import threading
import time

from mcp.types import ImageContent, TextContent

from astiop.agent import goals
from astiop.agent.intent import Intent
from astiop.agent.rules import command_for, nav_action, plan_intents
from astiop.bounded import MAX_COMMAND_CHARS, has_controls, one_line, preview
from astiop.mcp.approval import Policy, clear, needs_approval
from astiop.mcp.audit import CALL, AuditTrail, Call
from astiop.mcp.mission_tools import MissionTools
from astiop.mcp.refusals import Refused
from astiop.robot.camera import age_of, png_of
from astiop.robot.gateway import RobotGateway
from astiop.robot.safety import Review
from astiop.ros2.render import STAMPED, goto_command
from astiop.store import Store
from astiop.transports.base import Execution

__all__ = ["CALL", "TOOL_CLASSES", "Call", "Refused", "RobotTools"]

# Every tool and its class, in one table: "read" tools never move the robot; "actuate" tools
# are not registered with --read-only. A test holds it complete.
TOOL_CLASSES: dict[str, str] = {
    "robot_state": "read",
    "fleet_status": "read",
    "list_locations": "read",
    "read_topic": "read",
    "ros2_query": "read",
    "camera_frame": "read",
    "go_to_location": "actuate",
    "go_to_pose": "actuate",
    "move": "actuate",
    "dock": "actuate",
    "undock": "actuate",
    "stop": "actuate",
    "estop": "actuate",
    "ros2_command": "actuate",
    "mission_status": "read",
    "start_mission": "actuate",
    "cancel_mission": "actuate",
    "list_alerts": "read",
    "acknowledge_alert": "actuate",  # moves no robot, but changes what every station sees
}

MAX_MOVE_S = 3.0
DRIVE_PERIOD_S = 0.1  # well inside the teleop lapse
TOPIC_RE = re.compile(r"^/?[A-Za-z_][A-Za-z0-9_/]{0,254}$")
NAME_RE = re.compile(r"^[A-Za-z0-9_-]{1,64}$")
TRIGGER = "std_srvs/srv/Trigger"


def finite(name: str, value: float, limit: float = 1e6) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise Refused(f"{name} must be a finite number")
    if abs(value) > limit:
        raise Refused(f"{name} must be between -{limit:g} and {limit:g}")
    return float(value)


def bounded_text(name: str, value: str, limit: int = MAX_COMMAND_CHARS) -> str:
    if len(value) > limit:
        raise Refused(f"{name} is longer than {limit} characters")
    if has_controls(value):
        raise Refused(f"{name} contains control characters")
    return value.strip()


class RobotTools(MissionTools):
    def __init__(self, gateway: RobotGateway, store: Store, policy: Policy):
        self.gateway = gateway
        self.store = store
        self.policy = policy
        self.audit = AuditTrail(store)
        self.last_goal: dict[str, str] = {}
        self.name = ""  # the robot's name in a fleet (approvals say it)
        self._actuating = threading.Lock()  # one actuation at a time (stop and estop excepted)

    # -- reads ----------------------------------------------------------------------------
    def robot_state(self) -> dict:
        gw = self.gateway
        state = gw.state()
        profile = gw.profile
        pose, odom, battery, status = (
            profile.name(r) or "" for r in ("pose", "odometry", "battery", "status")
        )
        times = gw.message_times([n for n in (pose, odom, battery, status) if n])

        def age(*names: str) -> float | None:
            for name in names:
                if name in times:
                    return round(max(0.0, state.t - times[name]), 2)
            return None

        out: dict = {"robot": gw.label, "robot_clock_s": state.t}
        p = state.pose
        out["pose"] = None if p is None else {
            "x_m": round(p.x, 3), "y_m": round(p.y, 3),
            "theta_deg": round(math.degrees(p.theta), 1), "age_s": age(pose, odom),
        }  # fmt: skip
        b = state.battery
        out["battery"] = None if b is None else {
            "percent": round(b.percentage * 100, 1), "voltage_v": round(b.voltage, 2),
            "charging": b.charging, "age_s": age(battery),
        }  # fmt: skip
        s = state.status
        out["status"] = None if s is None else {
            "state": state.state_word, "mode": s.mode, "active_goal": s.active_goal,
            "docked": s.docked, "speed_m_s": round(s.speed, 3), "age_s": age(status),
        }  # fmt: skip
        out["faults"] = {
            "fault": (s.fault if s else None) or None,
            "e_stop_engaged": state.e_stopped,
            "age_s": age(status),
        }
        out["last_goal"] = dict(self.last_goal) or None
        out["note"] = "measured: as the robot reported it; age_s is how old that report is"
        return out

    def list_locations(self) -> list[dict]:
        return [loc.as_json() for loc in self.store.list_locations()]

    def camera_frame(self) -> list[ImageContent | TextContent]:
        """The camera role's current frame as a PNG image, and a text part with its topic, size
        and age; one line of text when there is none (no camera, no frame yet, unreadable)."""
        gw = self.gateway
        reading = gw.camera()
        frame = reading.frame
        if frame is None:
            return [TextContent(type="text", text=reading.note)]
        png, _ = png_of(frame)
        age = age_of(frame, gw.state().t)
        said = "age unknown" if age is None else f"{age:.2f} s old (robot clock)"
        text = f"camera frame from {frame.topic}, {frame.width} x {frame.height} px, {said}"
        data = base64.b64encode(png).decode("ascii")
        return [
            ImageContent(type="image", data=data, mime_type="image/png"),
            TextContent(type="text", text=text),
        ]

    def read_topic(self, topic: str) -> str:
        topic = bounded_text("topic", topic, 256)
        if not TOPIC_RE.match(topic):
            raise Refused(f"not a topic name: {preview(topic)}")
        return self._read(f"ros2 topic echo {topic} --once")

    def ros2_query(self, command: str) -> str:
        return self._read(self._command_text(command))

    def _read(self, text: str) -> str:
        """Review once and run that very review: a second review could see a newer catalog in
        which the command acts (a service that appeared since), and with confirm_actuation off
        it would run unconfirmed from a read-only tool."""
        review = self.gateway.review(text)
        checked = review.checked
        if checked.valid and checked.kind != "read":
            raise Refused("this command acts on the robot: use ros2_command")
        ex = self.gateway.run(checked.text, confirm=_only(review), review=review)
        self._record(ex)
        if ex.kind != checked.kind:  # run() reviewed it again and it changed: said, never hidden
            raise Refused(
                f"the command changed from {checked.kind} to {ex.kind} after it was reviewed"
                + ("; it was sent" if ex.executed else "; nothing was sent")
            )
        if not ex.executed:
            raise Refused(ex.reason or "refused")
        if ex.error:
            raise Refused(f"the robot did not answer: {ex.error}")
        return ex.output

    # -- actuation --------------------------------------------------------------------------
    def go_to_location(self, name: str) -> str:
        name = bounded_text("name", name, 256)
        loc = self.store.get_location(name) if NAME_RE.match(name) else None
        if loc is None:
            known = ", ".join(x.name for x in self.store.list_locations()) or "none"
            raise Refused(f"no location named {preview(name)} (known: {known})")
        profile = self.gateway.profile
        if nav_action(profile):  # Nav2: the place's pose as a goal
            text = command_for(Intent("navigate", xy=(loc.x, loc.y), theta=loc.theta), profile)
        else:
            text = goto_command(loc.name)
        if text is None:
            raise Refused(f"this robot has nothing that goes to {preview(name)}")
        return self._actuate(text, goal=(loc.name, (loc.x, loc.y)))

    def go_to_pose(self, x: float, y: float, theta_deg: float) -> str:
        x, y = finite("x", x), finite("y", y)
        theta = math.radians(finite("theta_deg", theta_deg) % 360.0)
        text = command_for(Intent("navigate", xy=(x, y), theta=theta), self.gateway.profile)
        if text is None:
            raise Refused("this robot has no way to be sent to a pose (no navigation role)")
        return self._actuate(text, goal=(f"({x:.2f}, {y:.2f})", (x, y)))

    def dock(self) -> str:
        return self._actuate(self._trigger("dock"), goal=("dock", None))

    def undock(self) -> str:
        return self._actuate(self._trigger("undock"), goal=("undock", None))

    def _trigger(self, role: str) -> str:
        name = self.gateway.profile.name(role)
        if name is None:
            raise Refused(f"this robot has no {role} service (`astiop robot profile`)")
        return f"ros2 service call {name} {TRIGGER}"

    def ros2_command(self, command: str) -> str:
        return self._actuate(self._command_text(command))

    def stop(self) -> str:
        profile = self.gateway.profile
        texts = plan_intents([Intent("stop")], profile)  # a Nav2 robot: its goals cancelled too
        if not texts:
            raise Refused("this robot has neither a stop service nor a velocity command")
        outputs, failed = [], []
        for text in texts:  # each one, whatever happened to the one before
            ex = self.gateway.run(text, confirm=lambda _c: True)
            self._record(ex)
            if not ex.executed or ex.error:
                failed.append(ex.reason or ex.error)
            outputs.append(ex.output)
        if failed:
            raise Refused(f"stop failed: {'; '.join(failed)}")
        if profile.has("stop"):
            said = "stop sent: motion stopped and any goal canceled (commanded)"
        elif len(texts) > 1:
            said = "its navigation goals canceled and zero velocity sent: this robot has no stop service (commanded)"
        else:
            said = "zero velocity sent: this robot has no stop service (commanded)"
        return "\n".join([said, *outputs])

    def estop(self) -> str:
        failures = self.gateway.estop()
        self._record(Execution("E-STOP", True, "; ".join(failures), "actuate", executed=True))
        text = "E-STOP engaged and latched: no motion runs until the operator releases it"
        return text + "".join(f"\nfailed: {f}" for f in failures)

    def move(self, vx: float = 0.0, vy: float = 0.0, wz: float = 0.0, seconds: float = 1.0) -> str:
        vx, vy, wz = finite("vx", vx), finite("vy", vy), finite("wz", wz)
        seconds = finite("seconds", seconds)
        if not 0 < seconds <= MAX_MOVE_S:
            raise Refused(f"seconds must be more than 0 and at most {MAX_MOVE_S:g}")
        gw = self.gateway
        name = gw.profile.name("velocity_command") or "/cmd_vel"
        type_ = gw.catalog.topics[name].type if name in gw.catalog.topics else ""
        twist = f"{{linear: {{x: {vx:g}, y: {vy:g}}}, angular: {{z: {wz:g}}}}}"
        values = f"{{twist: {twist}}}" if type_ == STAMPED else twist
        # reviewed and approved as what it is: this velocity at 10 Hz for `seconds`
        times = max(1, round(seconds / DRIVE_PERIOD_S))
        type_ = type_ or "geometry_msgs/msg/Twist"
        text = f'ros2 topic pub -t {times} -r {1 / DRIVE_PERIOD_S:g} {name} {type_} "{values}"'
        with self._one_actuation():
            review = self._clearance(text)
            msg = review.checked.message or {}
            msg = msg.get("twist", msg)
            lin, ang = msg.get("linear", {}), msg.get("angular", {})
            cvx, cvy, cwz = lin.get("x", 0.0), lin.get("y", 0.0), ang.get("z", 0.0)
            before = gw.state().pose
            t_end = time.monotonic() + seconds
            sent, drives = None, 0
            while time.monotonic() < t_end:
                sent = gw.drive(cvx, cvy, cwz)
                if not sent.executed or sent.error:
                    break
                drives += 1
                time.sleep(DRIVE_PERIOD_S)
            gw.drive(0.0, 0.0, 0.0)
            assert sent is not None
            sent.command = text
            self._record(sent)
            after = gw.state().pose
        why = sent.reason or sent.error
        if not drives:
            raise Refused(why or "the robot refused the velocity")
        line = f"commanded vx {cvx:g} m/s, vy {cvy:g} m/s, wz {cwz:g} rad/s for {seconds:g} s"
        notes = "".join(f"\nnote: {n}" for n in review.checked.notes)
        if before is not None and after is not None:
            moved = math.dist((before.x, before.y), (after.x, after.y))
            turn = math.degrees(math.remainder(after.theta - before.theta, math.tau))
            line += (
                f"; measured: moved {moved:.2f} m, turned {turn:.0f} deg, now at "
                f"x {after.x:.2f}, y {after.y:.2f}"
            )
        if why:
            raise Refused(f"stopped early ({why}); {line}")
        return line + notes

    def _actuate(self, text: str, goal: tuple[str, tuple | None] | None = None) -> str:
        with self._one_actuation():
            review = self._clearance(text)
            # exactly what was reviewed and approved: run() reviews nothing again
            ex = self.gateway.run(review.checked.text, confirm=_only(review), review=review)
        self._record(ex)
        if not ex.executed:
            raise Refused(ex.reason or "refused")
        if ex.error:
            raise Refused(f"sent, but the robot answered with an error: {ex.error}")
        values = ex.values if isinstance(ex.values, dict) else {}
        if goal is None:
            return ex.output + "".join(f"note: {n}\n" for n in ex.notes)
        if not goals.started(ex):
            raise Refused(f"the robot refused the goal: {values.get('message') or ex.output}")
        started = goals.started_text(self.gateway, ex)
        self._follow(started, goal[1])
        if started.startswith(goals.SENT):  # on a navigator's goal topic: no answer
            return (
                f"{started} (published on the navigator's goal topic, which answers nothing; "
                "robot_state reports its progress)"
            )
        return f"{started} (the goal is accepted, not reached; robot_state reports its outcome)"

    def _clearance(self, text: str):
        call = CALL.get()
        lease = self.gateway.lease
        if lease is not None and not lease.held and needs_approval(self.gateway.review(text)):
            self.gateway.take_control()  # taken if no one holds it; else refused below, named
        cl = clear(
            self.gateway, self.store, self.policy, text, call.client, call.what, robot=self.name
        )
        if not cl.cleared:
            ex = Execution(text, cl.review.checked.valid, cl.refusal, cl.review.checked.kind)
            self._record(ex)
            raise Refused(cl.refusal)
        return cl.review

    def _one_actuation(self):
        if not self._actuating.acquire(blocking=False):
            raise Refused("another actuation is waiting for approval or running; try again")
        return _Release(self._actuating)

    def _command_text(self, command: str) -> str:
        command = bounded_text("command", command)
        if not command.startswith("ros2 "):
            raise Refused("a command starts with 'ros2 '")
        return command

    def _follow(self, started: str, target: tuple | None) -> None:
        """Follow the goal to its end in a thread; its outcome goes to the interaction and
        to robot_state's last_goal."""
        call = CALL.get()
        self.last_goal = {"goal": started, "outcome": "still going"}
        mine = self.last_goal

        def follow() -> None:
            try:
                outcome, text = asyncio.run(goals.follow(self.gateway, started, 900.0, target))
            except Exception as exc:  # noqa: BLE001 - the server keeps serving
                outcome, text = "unknown", f"the goal could not be followed: {one_line(exc)}"
            mine["outcome"] = text
            self.audit.outcome(call, outcome)

        threading.Thread(target=follow, name="mcp-goal", daemon=True).start()

    def _record(self, ex: Execution) -> None:
        self.audit.command(ex)  # a store that cannot write still serves, and says so


def _only(review: Review):
    """A confirmation for exactly the reviewed command: should run() ever review it again, the
    new review is not what was approved (or read), and nothing is sent."""
    return lambda checked: checked is review.checked


class _Release:
    def __init__(self, lock: threading.Lock):
        self.lock = lock

    def __enter__(self) -> None:
        return None

    def __exit__(self, *exc) -> None:
        self.lock.release()
