"""The simulated TurtleBot3's services: turtlebot3_node's (motor_power: SetBool, reset: Trigger
— devices/motor_power.cpp, devices/reset.cpp), diff_drive_controller's reset_odometry (Trigger,
odometry.cpp), map_server's map (GetMap), amcl's Empty services, the lifecycle managers'
is_active and each Nav2 server's lifecycle services (every server is active once the managers
have brought them up with autostart: true)."""

from __future__ import annotations

from typing import Any

from astiop.ros2.message_objects import to_message
from astiop.sim import messages as sm

# lifecycle_msgs/msg/State ids
INACTIVE, ACTIVE = 2, 3
STATES = ((0, "unknown"), (1, "unconfigured"), (2, "inactive"), (3, "active"), (4, "finalized"))
ACTIVE_TRANSITIONS = ((4, "deactivate", ACTIVE, INACTIVE), (7, "shutdown", ACTIVE, 4))


class ServiceHandlers:
    def __init__(self, robot: Any):
        self.robot = robot

    def handler(self, name: str, type_: str):
        verb = name.rsplit("/", 1)[-1]
        special = {
            "/motor_power": self._motor_power,
            "/reset": self._reset,
            "/reset_odometry": self._reset_odometry,
            "/map_server/map": self._map,
            "/reinitialize_global_localization": self._empty,
            "/request_nomotion_update": self._nomotion_update,
        }
        if name in special:
            return special[name]
        if verb == "is_active":
            return self._is_active
        return {
            "get_state": self._get_state,
            "get_available_states": self._get_available_states,
            "get_available_transitions": self._get_available_transitions,
            "get_transition_graph": self._get_available_transitions,
            "change_state": self._change_state,
        }[verb]

    def _motor_power(self, request: Any, response: Any) -> Any:
        self.robot.set_motor_power(bool(request.data))
        response.success, response.message = True, ""
        return response

    def _reset(self, _request: Any, response: Any) -> Any:
        self.robot.reset_odometry()  # the gyro's calibration is instant here
        response.success, response.message = True, "Calibration End, Odom reset requested"
        return response

    def _reset_odometry(self, _request: Any, response: Any) -> Any:
        self.robot.reset_odometry()
        response.success, response.message = True, "Odometry reset"
        return response

    def _map(self, _request: Any, response: Any) -> Any:
        response.map = to_message(type(response.map), sm.occupancy_grid(self.robot.sim.map))
        return response

    def _empty(self, _request: Any, response: Any) -> Any:
        return response

    def _nomotion_update(self, _request: Any, response: Any) -> Any:
        self.robot.publish_amcl_pose()
        return response

    def _is_active(self, _request: Any, response: Any) -> Any:
        response.success = True
        return response

    def _get_state(self, _request: Any, response: Any) -> Any:
        response.current_state.id, response.current_state.label = ACTIVE, "active"
        return response

    def _get_available_states(self, _request: Any, response: Any) -> Any:
        cls = _state_class()
        response.available_states = [_state(cls, i, label) for i, label in STATES]
        return response

    def _get_available_transitions(self, _request: Any, response: Any) -> Any:
        from lifecycle_msgs.msg import Transition, TransitionDescription

        cls = _state_class()
        response.available_transitions = [
            TransitionDescription(
                transition=Transition(id=tid, label=label),
                start_state=_state(cls, start, dict(STATES)[start]),
                goal_state=_state(cls, goal, dict(STATES)[goal]),
            )
            for tid, label, start, goal in ACTIVE_TRANSITIONS
        ]
        return response

    def _change_state(self, request: Any, response: Any) -> Any:
        # lifecycle transitions are not simulated: the servers stay active, a request is refused
        response.success = False
        return response


def _state_class():
    from lifecycle_msgs.msg import State

    return State


def _state(cls, state_id: int, label: str):
    return cls(id=state_id, label=label)
