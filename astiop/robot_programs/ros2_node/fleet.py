"""A fleet of simulated ASTIbots as ROS 2 nodes, in one process and one warehouse world: each
robot under its own namespace on one domain (the ROS 2 convention: /astibot_1/cmd_vel), spun
by one executor; or, free_fleet style, each un-namespaced on a domain of its own."""

from __future__ import annotations

import threading
from pathlib import Path

from astiop.robot_programs.ros2_common import RobotNodes
from astiop.robot_programs.ros2_node.node import SimRobotNodes
from astiop.sim.fleet import SimFleet
from astiop.sim.runner import SimRunner


class SimFleetNodes:
    """Robots named `names`; `domains[i]` puts robot i on that domain, un-namespaced."""

    def __init__(
        self,
        names: list[str],
        *,
        seed: int,
        speed: float,
        folder: Path,
        domains: list[int] | None = None,
    ):
        self.names = names
        self.fleet = SimFleet(names, seed=seed)
        self.runner = SimRunner(self.fleet, speed=speed)
        self.host = None if domains else RobotNodes()
        self.robots = [
            SimRobotNodes(
                seed=seed + i,
                speed=speed,
                locations_db=folder / f"{name}.db",
                sim=sim,
                namespace="" if domains else f"/{name}",
                parent=self.host,
                domain_id=domains[i] if domains else None,
            )
            for i, (name, sim) in enumerate(zip(names, self.fleet.robots, strict=True))
        ]
        self.catalog = self.robots[0].catalog

    def start(self) -> None:
        if self.host is not None:
            self.host.init_context()
        for robot in self.robots:
            robot.start()
        self.runner.start()

    def spin(self) -> None:
        threads = [threading.Thread(target=r.spin, daemon=True) for r in self.robots[1:]]
        for t in threads:
            t.start()
        self.robots[0].spin()
        for t in threads:
            t.join(timeout=5)

    def stop(self) -> None:
        for robot in [self.host, *self.robots]:
            if robot is not None:
                robot.stop()

    def close(self) -> None:
        self.runner.stop()
        for robot in self.robots:
            robot.close()
        if self.host is not None:
            self.host.close_nodes()  # the shared context, once every robot's nodes are gone
