"""`ros2 service call` and `ros2 action send_goal` over real DDS, as ros2service/verb/call.py
and ros2action/verb/send_goal.py do them (humble and jazzy): waiting for the server as long as
it takes, the request and the response printed as rclpy's repr, a goal followed to its result
and, on Ctrl-C, canceled ("Canceling goal..." / "Goal canceled.")."""

from __future__ import annotations

import contextlib
import queue
import threading
import time
from typing import Any

import yaml
from action_msgs.msg import GoalStatus
from rclpy.action import ActionClient

from astiop.robot_programs.emulated_cli.call import Call, Interrupted
from astiop.robot_programs.emulated_cli.dds_fields import (
    load_class,
    message_to_yaml,
    set_message_fields,
)
from astiop.robot_programs.emulated_cli.verb_table import runs
from astiop.transports.rclpy.verbs import STATUS

RUNNING = (GoalStatus.STATUS_ACCEPTED, GoalStatus.STATUS_EXECUTING)


def _done(future: Any, call: Call) -> Any:
    """The future's result once done; Interrupted if the client's Ctrl-C comes first."""
    done = threading.Event()
    future.add_done_callback(lambda _f: done.set())
    while not done.wait(0.05):
        call.wait(0)
    return future.result()


class DdsCalls:
    """`ros2 service call` and `ros2 action send_goal` on one rclpy node: each call's client is
    its own, destroyed when the call ends."""

    def __init__(self, node: Any):
        self.node = node

    @runs("service call")
    def _service_call(self, call: Call, a: dict):
        srv = load_class(a["service_type"], "srv")
        if srv is None:
            raise RuntimeError("The passed service type is invalid")
        if not hasattr(srv, "Request") or not hasattr(srv, "Response"):
            raise RuntimeError("The passed type is not a service")
        text = a.get("stdin_values") if a.get("stdin") else a.get("values", "{}")
        values = yaml.safe_load(text)
        rate = a.get("rate")
        if rate is not None and rate <= 0:
            raise RuntimeError("rate must be greater than zero")
        client = self.node.create_client(srv, a["service_name"])
        try:
            request = srv.Request()
            try:
                set_message_fields(request, values)
            except Exception as exc:  # noqa: BLE001 - whatever rosidl raises, ros2cli says so
                return f"Failed to populate field: {exc}"
            if not client.service_is_ready():
                call.out("waiting for service to become available...\n")
                while not client.wait_for_service(timeout_sec=0.1):
                    call.wait(0)
            while True:
                call.out(f"requester: making request: {request!r}\n\n")
                last = time.time()
                response = _done(client.call_async(request), call)
                call.out(f"response:\n{response!r}\n\n")
                if rate is None:
                    return 0
                call.wait(max(last + 1.0 / rate - time.time(), 0.0))
        finally:
            self.node.destroy_client(client)

    @runs("action send_goal")
    def _action_send_goal(self, call: Call, a: dict):
        action = load_class(a["action_type"], "action")
        if action is None:
            raise RuntimeError("The passed action type is invalid")
        text = a.get("stdin_values") if a.get("stdin") else a.get("goal", "{}")
        values = yaml.safe_load(text)
        client = ActionClient(self.node, action, a["action_name"])
        try:
            return self._send_goal(call, a, client, action, values)
        finally:
            client.destroy()

    def _send_goal(self, call: Call, a: dict, client: Any, action: Any, values: Any):
        goal = action.Goal()
        try:
            set_message_fields(goal, values)
        except Exception as exc:  # noqa: BLE001 - whatever rosidl raises, ros2cli says so
            return f"Failed to populate message fields: {exc!r}"
        call.out("Waiting for an action server to become available...\n")
        while not client.wait_for_server(timeout_sec=0.1):
            call.wait(0)
        call.out(f"Sending goal:\n     {message_to_yaml(goal)}\n")
        feedback: queue.Queue = queue.Queue()
        on_feedback = feedback.put if a.get("feedback") else None
        handle = _done(client.send_goal_async(goal, feedback_callback=on_feedback), call)
        if handle is None:
            raise RuntimeError("Exception while sending goal")
        if not handle.accepted:
            call.out("Goal was rejected.\n")
            return 0
        call.out(f"Goal accepted with ID: {bytes(handle.goal_id.uuid).hex()}\n\n")
        result_future = handle.get_result_async()
        done = threading.Event()
        result_future.add_done_callback(lambda _f: done.set())
        try:
            while not done.wait(0.05):
                call.wait(0)
                while not feedback.empty():  # printed here: one writer per call
                    call.out(f"Feedback:\n    {message_to_yaml(feedback.get().feedback)}\n")
        except Interrupted:
            self._cancel(call, handle)
            raise
        result = result_future.result()
        call.out(f"Result:\n    {message_to_yaml(result.result)}\n")
        call.out(f"Goal finished with status: {STATUS.get(result.status, 'UNKNOWN')}\n")
        return 0

    def _cancel(self, call: Call, handle: Any) -> None:
        """send_goal.py's finally: a goal still running is canceled, and said so."""
        if handle.status not in RUNNING:
            return
        with contextlib.suppress(Interrupted):  # a client gone still has its goal canceled
            call.out("Canceling goal...\n")
        future = handle.cancel_goal_async()
        done = threading.Event()
        future.add_done_callback(lambda _f: done.set())
        if not done.wait(10.0):
            raise RuntimeError("Exception while canceling goal: no answer")
        response = future.result()
        if len(response.goals_canceling) == 0:
            raise RuntimeError("Failed to cancel goal")
        with contextlib.suppress(Interrupted):
            call.out("Goal canceled.\n")
