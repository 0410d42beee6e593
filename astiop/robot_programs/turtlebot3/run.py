"""`astiop sim node --robot turtlebot3`: check what it needs, say where it serves and what it
cannot serve here, serve until a signal."""

from __future__ import annotations

from collections.abc import Callable

from astiop.robot_programs.serving import (
    check_imports,
    refuse_a_taken_graph,
    serve_until_signal,
    where,
)


def serve(
    *,
    seed: int,
    speed: float,
    distro: str,
    model: str,
    namespace: str,
    say: Callable[[str], None],
    join: bool = False,
) -> None:
    check_imports()
    refuse_a_taken_graph([f"{namespace.rstrip('/')}/cmd_vel"], join)
    from astiop.robot_programs.turtlebot3.node import TurtleBot3Nodes

    robot = TurtleBot3Nodes(seed=seed, speed=speed, distro=distro, model=model, namespace=namespace)

    def started() -> str:
        if robot.skipped:
            by_type: dict[str, list[str]] = {}
            for name, type_ in robot.skipped:
                by_type.setdefault(type_, []).append(name)
            said = "; ".join(
                f"{t}: {', '.join(sorted(set(n)))}" for t, n in sorted(by_type.items())
            )
            count = len(robot.skipped)
            say(f"not served: {count} of upstream's names, their types not built here: {said}")
        ns = robot.namespace or "no namespace"
        return (
            f"TurtleBot3 {model} under Nav2 ({distro} names, {ns}) up as ROS 2 nodes "
            f"({len(robot.nodes)} nodes) on {where()}; Ctrl-C stops it"
        )

    serve_until_signal(robot, started, say)
