"""The console's safety keys (E-STOP, its release) and the y/n it asks from worker threads
before anything moves the robot: a helper the app holds and hands itself to."""

from __future__ import annotations

import threading
from collections.abc import Callable

from textual.app import App

from astiop.robot.fleet_watch import FleetWatch
from astiop.ros2.render import sent_text
from astiop.ros2.validation import Checked
from astiop.screens.base import robot_name
from astiop.screens.modals import ConfirmModal
from astiop.services import Services
from astiop.transports.state import RobotState


class SafetyKeys:
    """`app` shows the questions and runs the workers; `sampled` is the robot's last sampled
    state (a /stop the robot latched shows there); the services' gateway is the current
    robot's, whichever that is now."""

    def __init__(
        self,
        app: App,
        services: Services,
        fleet: FleetWatch | None,
        sampled: Callable[[], RobotState],
        confirm_timeout_s: float = 120.0,
    ) -> None:
        self.app = app
        self.services = services
        self.fleet = fleet
        self.sampled = sampled
        self.confirm_timeout_s = confirm_timeout_s

    @property
    def current_robot(self) -> str:
        return robot_name(self.services, self.fleet)

    def estop(self) -> None:
        if isinstance(self.app.screen, ConfirmModal):
            self.app.screen.dismiss(False)  # the E-STOP answers any open question with "no"
        self.app.run_worker(self._estop, thread=True, group="estop", exit_on_error=False)

    def _estop(self) -> None:
        fleet: dict[str, list[str]] = {}
        others = None
        if self.fleet is not None:  # every robot of the fleet, each by its own gateway, at once
            current, every = self.current_robot, self.fleet
            others = threading.Thread(target=lambda: fleet.update(every.estop_all(current)))
            others.start()
        failures = self.services.gateway.estop()
        text = "E-STOP engaged: all motion stopped. ctrl+r releases it."
        if others is not None:
            others.join()
            failures += [f"{name}: {'; '.join(f)}" for name, f in fleet.items() if f]
            text = f"E-STOP engaged on {len(fleet) + 1} robots. ctrl+r releases them."
        if failures:
            text += "\n" + "\n".join(failures)
        self.app.call_from_thread(
            self.app.notify, text, severity="error", title="E-STOP", markup=False
        )

    def release_estop(self) -> None:
        robot_holds = self.sampled().state_word == "e_stopped"
        if not (self.services.gateway.e_stopped or robot_holds):  # a /stop the robot latched
            self.app.notify("The e-stop is not engaged.")
            return

        graph = self.services.gateway.station_latch
        pressed = graph.press if graph is not None and graph.engaged else None

        def done(ok: bool | None) -> None:
            if ok:
                self.app.run_worker(
                    lambda: self._release(pressed), thread=True, group="estop", exit_on_error=False
                )

        question = "Release the e-stop? The robot may move again."
        if pressed is not None and not pressed.is_here():  # pressed at another station
            question = f"Release the e-stop pressed by {pressed.words}? The robot may move again."
        if self.fleet is not None:
            names = ", ".join(name for name, _, _ in self.fleet.robots)
            question = f"Release the e-stop of {names}? They may move again."
        self.app.push_screen(ConfirmModal(question), done)

    def _release(self, pressed=None) -> None:
        failures = self.services.gateway.release_estop(pressed)
        if failures and failures[0].startswith("pressed again since"):  # not what was asked
            self.app.call_from_thread(self.app.notify, failures[0], severity="error", markup=False)
            return
        # the latch of every robot goes too: this console's robots are all it holds
        self.services.store.release_estop("console")
        if self.fleet is not None:
            failures += self.fleet.release_all(self.current_robot)
        if failures:  # the latch let go; the robot's own stop did not
            text = "E-stop released here; the robot still holds:\n" + "\n".join(failures)
            self.app.call_from_thread(self.app.notify, text, severity="error", markup=False)
        else:
            self.app.call_from_thread(self.app.notify, "E-stop released.")

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

    def confirm_reaction_from_thread(self, question: str) -> bool:
        """A watch's reaction that moves the robot is armed once approved, its steps shown:
        asked always (confirmation off too), as `astiop watch add` asks; it moves the robot
        later, when no one may be looking."""
        return self._ask_from_thread(question, None)

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

        self.app.call_from_thread(self.app.push_screen, modal, done)
        if ready.wait(timeout_s):
            return bool(answer and answer[0])

        def expire() -> None:
            if self.app.screen is modal:  # dismiss() closes whatever is on top
                modal.dismiss(False)
            self.app.notify(
                f"No answer within {timeout_s:g} s: the command was not sent.",
                severity="warning",
                title="confirmation timed out",
            )

        self.app.call_from_thread(expire)
        return False
