"""The console's safety keys (E-STOP, its release) and the y/n it asks from worker threads
before anything moves the robot; a mixin of the app."""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol

from textual.screen import Screen

from astiop.robot.fleet_watch import FleetWatch
from astiop.ros2.render import sent_text
from astiop.ros2.validation import Checked
from astiop.screens.modals import ConfirmModal
from astiop.services import Services
from astiop.transports.state import RobotState


class SafetyHost(Protocol):
    """What `ConsoleSafety` needs of the app it is mixed into."""

    services: Services
    fleet: FleetWatch | None
    robot_state: RobotState
    confirm_timeout_s: float

    @property
    def screen(self) -> Screen: ...

    @property
    def current_robot(self) -> str: ...

    def notify(self, message: str, **kwargs: Any) -> None: ...

    def run_worker(self, work: Any, **kwargs: Any) -> Any: ...

    def call_from_thread(self, callback: Callable[..., Any], *args: Any, **kwargs: Any) -> Any: ...

    def push_screen(self, screen: Any, callback: Any = None, **kwargs: Any) -> Any: ...


if TYPE_CHECKING:
    _Host = SafetyHost
else:
    _Host = object


class ConsoleSafety(_Host):
    def action_estop(self) -> None:
        if isinstance(self.screen, ConfirmModal):
            self.screen.dismiss(False)  # the E-STOP answers any open question with "no"
        self.run_worker(self._estop, thread=True, group="estop", exit_on_error=False)

    def _estop(self) -> None:
        fleet: dict[str, list[str]] = {}
        others = None
        if self.fleet is not None:  # every robot of the fleet, each by its own gateway, at once
            current = self.current_robot
            others = threading.Thread(target=lambda: fleet.update(self.fleet.estop_all(current)))
            others.start()
        failures = self.services.gateway.estop()
        text = "E-STOP engaged: all motion stopped. ctrl+r releases it."
        if others is not None:
            others.join()
            failures += [f"{name}: {'; '.join(f)}" for name, f in fleet.items() if f]
            text = f"E-STOP engaged on {len(fleet) + 1} robots. ctrl+r releases them."
        if failures:
            text += "\n" + "\n".join(failures)
        self.call_from_thread(self.notify, text, severity="error", title="E-STOP", markup=False)

    def action_release_estop(self) -> None:
        robot_holds = self.robot_state.state_word == "e_stopped"
        if not (self.services.gateway.e_stopped or robot_holds):  # a /stop the robot latched
            self.notify("The e-stop is not engaged.")
            return

        graph = self.services.gateway.station_latch
        pressed = graph.press if graph is not None and graph.engaged else None

        def done(ok: bool | None) -> None:
            if ok:
                self.run_worker(
                    lambda: self._release(pressed), thread=True, group="estop", exit_on_error=False
                )

        question = "Release the e-stop? The robot may move again."
        if pressed is not None and not pressed.is_here():  # pressed at another station
            question = f"Release the e-stop pressed by {pressed.words}? The robot may move again."
        if self.fleet is not None:
            names = ", ".join(name for name, _, _ in self.fleet.robots)
            question = f"Release the e-stop of {names}? They may move again."
        self.push_screen(ConfirmModal(question), done)

    def _release(self, pressed=None) -> None:
        failures = self.services.gateway.release_estop(pressed)
        if failures and failures[0].startswith("pressed again since"):  # not what was asked
            self.call_from_thread(self.notify, failures[0], severity="error", markup=False)
            return
        # the latch of every robot goes too: this console's robots are all it holds
        self.services.store.release_estop("console")
        if self.fleet is not None:
            failures += self.fleet.release_all(self.current_robot)
        if failures:  # the latch let go; the robot's own stop did not
            text = "E-stop released here; the robot still holds:\n" + "\n".join(failures)
            self.call_from_thread(self.notify, text, severity="error", markup=False)
        else:
            self.call_from_thread(self.notify, "E-stop released.")

    def confirm_from_thread(
        self, checked: Checked, timeout_s: float | None = None, robot: str = ""
    ) -> bool:
        """The gateway's confirmation hook, called from a worker thread: ask with a modal that
        shows the command as it will be sent (after clamping), naming the robot in a fleet."""
        robot = robot or checked.namespace.strip("/") or (self.current_robot if self.fleet else "")
        on = f" on {robot}" if robot else ""
        return self._ask_from_thread(
            f"Run this command{on}? It moves the robot.\n\n{sent_text(checked)}", timeout_s
        )

    def confirm_mission_from_thread(self, steps, forever: bool = False) -> bool:
        """A mission is approved whole, every step shown, before its first step runs (as each
        command is, unless the operator turned confirmation off)."""
        from astiop.missions.steps import describe

        if not self.services.settings.robot.confirm_actuation:
            return True

        listed = describe(steps, forever).replace("; ", "\n")
        return self._ask_from_thread(
            f"Start this mission of {len(steps)} steps? It moves the robot.\n\n{listed}", None
        )

    def replace_mission_from_thread(self, running: str, steps, forever: bool = False) -> bool:
        """A new mission while one runs: asked always (confirmation off too), every step of the
        new one shown; yes ends the running one as replaced, then starts the new one."""
        from astiop.missions.steps import describe

        listed = describe(steps, forever).replace("; ", "\n")
        return self._ask_from_thread(
            f"{running[:1].upper()}{running[1:]}. Replace it?\n\nThe new mission of "
            f"{len(steps)} steps (it moves the robot):\n{listed}",
            None,
        )

    def _ask_from_thread(self, question: str, timeout_s: float | None) -> bool:
        timeout_s = self.confirm_timeout_s if timeout_s is None else timeout_s
        answer: list[bool] = []
        ready = threading.Event()
        modal = ConfirmModal(question)

        def done(ok: bool | None) -> None:
            answer.append(bool(ok))
            ready.set()

        self.call_from_thread(self.push_screen, modal, done)
        if ready.wait(timeout_s):
            return bool(answer and answer[0])

        def expire() -> None:
            if self.screen is modal:  # dismiss() closes whatever is on top
                modal.dismiss(False)
            self.notify(
                f"No answer within {timeout_s:g} s: the command was not sent.",
                severity="warning",
                title="confirmation timed out",
            )

        self.call_from_thread(expire)
        return False
