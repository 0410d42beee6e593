"""The rules baseline on a table of operator phrasings."""

import pytest

from astiop.agent.rules import plan

LOCS = [
    "charging_dock",
    "assembly_station",
    "cps_storage",
    "shipping",
    "inspection_zone_a",
    "inspection_zone_b",
]
GOTO = "ros2 service call /goto_position astiop_msgs/srv/GotoPosition"

CASES = [
    ("What is the battery level?", ["ros2 topic echo /battery_status --once"]),
    ("how much charge is left", ["ros2 topic echo /battery_status --once"]),
    ("Where is the robot right now?", ["ros2 topic echo /robot_pose --once"]),
    ("give me its coordinates", ["ros2 topic echo /robot_pose --once"]),
    ("What is the robot status?", ["ros2 topic echo /robot_status --once"]),
    ("Is anything blocking it?", ["ros2 topic echo /obstacles --once"]),
    ("any obstacles around the robot?", ["ros2 topic echo /obstacles --once"]),
    ("show the lidar scan", ["ros2 topic echo /scan --once"]),
    ("run diagnostics", ["ros2 topic echo /diagnostics --once"]),
    ("what does the conveyor say", ["ros2 topic echo /conveyor/status --once"]),
    ("Send the robot to the assembly station", [f"{GOTO} \"{{name: 'assembly_station'}}\""]),
    ("go to cps storage", [f"{GOTO} \"{{name: 'cps_storage'}}\""]),
    ("drive to shiping", [f"{GOTO} \"{{name: 'shipping'}}\""]),
    ("go to x 12 y 4", [f'{GOTO} "{{x: 12.000, y: 4.000, theta: 0.0000}}"']),
    ("move to (20, 12.25) facing 90", [f'{GOTO} "{{x: 20.000, y: 12.250, theta: 1.5708}}"']),
    ("STOP", ["ros2 service call /stop std_srvs/srv/Trigger"]),
    ("go charge", ["ros2 service call /dock std_srvs/srv/Trigger"]),
    ("undock", ["ros2 service call /undock std_srvs/srv/Trigger"]),
    ("load the pallet", ["ros2 service call /conveyor/load std_srvs/srv/Trigger"]),
    ("unload it", ["ros2 service call /conveyor/unload std_srvs/srv/Trigger"]),
    ("list the locations", ["ros2 service call /list_locations astiop_msgs/srv/ListLocations"]),
    (
        "inspect zone B and report obstacles",
        [f"{GOTO} \"{{name: 'inspection_zone_b'}}\"", "ros2 topic echo /obstacles --once"],
    ),
    (
        "go to shipping then unload",
        [
            f"{GOTO} \"{{name: 'shipping'}}\"",
            "ros2 service call /conveyor/unload std_srvs/srv/Trigger",
        ],
    ),
    ("tell me a joke", []),
]


@pytest.mark.parametrize("request_text,expected", CASES)
def test_rules_plan(request_text, expected):
    assert plan(request_text, LOCS) == expected
