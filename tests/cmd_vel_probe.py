"""The robot's side of /cmd_vel, in a process of its own: each Twist's arrival as a JSON line.

    python tests/cmd_vel_probe.py

stdout, one JSON object a line, flushed at once:
    {"ready": true}                       subscribed
    {"publishers": N}                     whenever the count of /cmd_vel publishers changes
    {"mono": T, "x": VX, "y": VY, "z": WZ}  a Twist arrived (time.monotonic(), system-wide
                                          on Linux, so another process's clock agrees)
It ends when its stdin closes or on SIGTERM/SIGINT. The caller keeps DDS on the loopback
(ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, ROS_LOCALHOST_ONLY=1, its own ROS_DOMAIN_ID); when
they are not set, this sets the loopback itself.
"""

from __future__ import annotations

import json
import os
import signal
import sys
import threading
import time

os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
os.environ.setdefault("ROS_LOCALHOST_ONLY", "1")


def say(obj: dict) -> None:
    sys.stdout.write(json.dumps(obj) + "\n")
    sys.stdout.flush()


def main() -> None:
    import rclpy
    from geometry_msgs.msg import Twist
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from rclpy.qos import QoSProfile, ReliabilityPolicy

    context = rclpy.Context()
    rclpy.init(context=context)
    node = Node("cmd_vel_probe", context=context, start_parameter_services=False)

    def arrived(msg: Twist) -> None:
        now = time.monotonic()  # first: the rest is the probe's own cost
        say({"mono": now, "x": msg.linear.x, "y": msg.linear.y, "z": msg.angular.z})

    # reliable, keep last 10: what the robot's base subscribes with, and what a default
    # publisher (depth 10) offers
    qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
    sub = node.create_subscription(Twist, "/cmd_vel", arrived, qos)
    publishers = -1

    def count() -> None:
        nonlocal publishers
        n = sub.get_publisher_count()
        if n != publishers:
            publishers = n
            say({"publishers": n})

    node.create_timer(0.02, count)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    halt = threading.Event()

    def stdin_closed() -> None:
        sys.stdin.read()
        halt.set()

    threading.Thread(target=stdin_closed, daemon=True).start()
    for sig in (signal.SIGTERM, signal.SIGINT):
        signal.signal(sig, lambda *_: halt.set())
    say({"ready": True})
    try:
        while not halt.is_set():
            executor.spin_once(timeout_sec=0.05)
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.shutdown(context=context)


if __name__ == "__main__":
    main()
