"""`astiop sim`: the simulator without the console."""

from __future__ import annotations

import math

import typer

from astiop.cli.common import fail, print_json, state

app = typer.Typer(
    help="Run the warehouse simulator headless: benchmark it, drive it.", no_args_is_help=True
)


@app.command("bench")
def bench(
    seed: int = typer.Option(0, min=0, max=2**32 - 1, help="Seed of the run (lidar noise)."),
    as_json: bool = typer.Option(False, "--json", help="Print the figures as JSON."),
) -> None:
    """Run a seeded mission (undock, three stations, dock) as fast as possible; print figures."""
    from astiop.sim.mission import MISSION, run_mission

    def progress(step: str, leg: dict) -> None:
        if not as_json:
            typer.echo(
                f"  {step:<18} {leg['status']:<10} {leg['sim_s']:7.1f} s sim  "
                f"error {leg['error_m']} m",
                err=True,
            )

    if not as_json:
        typer.echo(f"mission: {' -> '.join(MISSION)}", err=True)
    figures = run_mission(seed, progress)
    data = figures.as_json()
    if as_json:
        data.pop("legs")
        print_json(data)
        return
    typer.echo(
        f"real-time factor  {data['real_time_factor']:8.1f}x   (target >= 1000)\n"
        f"lidar per scan    {data['lidar_ms_mean']:8.3f} ms  (target <= 0.25)\n"
        f"plan mean / max   {data['plan_ms_mean']:8.2f} / {data['plan_ms_max']:.2f} ms "
        f"(target <= 10)\n"
        f"mission           {data['mission_sim_s']:8.1f} s sim in {data['mission_wall_s']:.2f} s\n"
        f"max penetration   {data['max_penetration_m'] * 100:8.2f} cm  (target < 1)\n"
        f"reached all       {data['reached_all']}"
    )
    if not data["reached_all"]:
        raise typer.Exit(1)


def _parse_target(ctx: typer.Context, text: str) -> tuple[float, float, float, str]:
    if "," in text:
        try:
            parts = [float(p) for p in text.split(",")]
        except ValueError:
            fail(f"'{text}' is neither a location name nor X,Y[,THETA_DEG]")
        if len(parts) not in (2, 3):
            fail(f"'{text}': coordinates are X,Y or X,Y,THETA_DEG")
        theta = math.radians(parts[2]) if len(parts) == 3 else 0.0
        return parts[0], parts[1], theta, text
    from astiop.store import LocationError

    try:
        loc = state(ctx).store.require_location(text)
    except LocationError as exc:
        fail(str(exc))
    return loc.x, loc.y, loc.theta, loc.name


@app.command("goto")
def goto(
    ctx: typer.Context,
    target: str = typer.Argument(..., help="A named location, or X,Y[,THETA_DEG] in metres."),
    start: str = typer.Option("", "--from", help="Start at this named location (default: docked)."),
    seed: int = typer.Option(0, min=0, max=2**32 - 1),
    as_json: bool = typer.Option(False, "--json"),
) -> None:
    """Drive from the dock (or --from) to TARGET in fast mode and report how it went."""
    from astiop.sim.geometry import path_length
    from astiop.sim.simulator import GoalError, Simulator

    x, y, theta, label = _parse_target(ctx, target)
    try:
        if start:
            sx, sy, sth, _ = _parse_target(ctx, start)
            sim = Simulator(seed=seed, start=(sx, sy, sth))
            sim.check_goal(sx, sy, sth)
        else:
            sim = Simulator(seed=seed)
        sim.goto(x, y, theta, label)
    except GoalError as exc:
        fail(str(exc))
    plan_length = path_length(sim.plan)
    result = sim.run_goal(900.0)
    px, py, pth = sim.pose
    data = {
        "reached": result is not None and result.status == "succeeded",
        "final_pose": {
            "x": round(px, 4),
            "y": round(py, 4),
            "theta_deg": round(math.degrees(pth), 2),
        },
        "error_m": round(result.error_m, 4) if result else None,
        "sim_s": round(sim.t, 2),
        "path_length_m": round(plan_length, 3),
    }
    if as_json:
        print_json(data)
    else:
        word = "reached" if data["reached"] else f"did not reach ({result.message})"
        typer.echo(
            f"{word} {label}: ({px:.2f}, {py:.2f}, {math.degrees(pth):.1f}°), error "
            f"{data['error_m']} m, path {plan_length:.1f} m, {sim.t:.1f} s sim"
        )
    if not data["reached"]:
        raise typer.Exit(1)


ROBOTS = ("astibot", "turtlebot3")
MAX_ROBOTS = 50  # a dock each along the warehouse's walls (sim/fleet.py)
MAX_DOMAIN_ID = 232  # the highest Fast DDS maps to UDP ports (ROS 2's domain ID docs)


@app.command("node")
def node(
    seed: int = typer.Option(0, min=0, max=2**32 - 1, help="Seed of the simulator."),
    speed: float = typer.Option(
        1.0, "--speed", min=0.1, max=20.0, help="Real-time factor of the robot (tests: > 1)."
    ),
    robot: str = typer.Option(
        "astibot", "--robot", help="astibot, or turtlebot3 (a TurtleBot3 under Nav2)."
    ),
    model: str = typer.Option("burger", "--model", help="TurtleBot3 model: burger or waffle."),
    namespace: str = typer.Option(
        "", "--namespace", help="TurtleBot3: serve every name under this namespace (/tb3_1)."
    ),
    distro: str = typer.Option(
        "jazzy",
        "--distro",
        help="TurtleBot3: whose names and types, jazzy (/cmd_vel TwistStamped) or humble (Twist).",
    ),
    robots: int = typer.Option(
        1, "--robots", min=1, max=MAX_ROBOTS, help="ASTIbots in one warehouse, one per namespace."
    ),
    prefix: str = typer.Option(
        None, "--prefix", help="The robots' names and namespaces: PREFIX1, PREFIX2, … (astibot_)."
    ),
    domains: bool = typer.Option(
        False,
        "--domains",
        help="Each robot un-namespaced on a domain of its own: ROS_DOMAIN_ID, then +1, +2, ….",
    ),
    join: bool = typer.Option(
        False,
        "--join",
        help="Start even where a robot of the same names is already on the domain (by default "
        "it refuses: a simulator never speaks to a real base).",
    ),
) -> None:
    """Run a simulated robot as real ROS 2 nodes on this machine's ROS domain, until Ctrl-C or
    SIGTERM: the ASTIbot (or a fleet of them in one warehouse, --robots N), or a TurtleBot3
    under Nav2. It respects the ROS environment (ROS_DOMAIN_ID, ROS_AUTOMATIC_DISCOVERY_RANGE)."""
    from astiop.robot_programs.serving import NodeSetupError

    say = lambda line: typer.echo(line, err=True)  # noqa: E731
    if robot not in ROBOTS:
        fail(f"--robot must be {' or '.join(ROBOTS)}, not '{robot}'")
    try:
        if robot == "astibot":
            given = [f"--{n}" for n, v in (("namespace", namespace), ("model", model != "burger"),
                     ("distro", distro != "jazzy")) if v]  # fmt: skip
            if given:
                fail(f"{', '.join(given)}: only for --robot turtlebot3")
            if robots > 1 or prefix is not None or domains:
                _serve_fleet(robots, prefix, domains, seed, speed, say, join)
                return
            from astiop.robot_programs.ros2_node.run import serve

            serve(seed, speed, say, join)
            return
        if robots > 1 or prefix is not None or domains:
            fail("--robots, --prefix and --domains: only for --robot astibot")
        from astiop.robot_programs.turtlebot3.graph import DISTROS, MODELS

        if model not in MODELS:
            fail(f"--model must be {' or '.join(MODELS)}, not '{model}'")
        if distro not in DISTROS:
            fail(f"--distro must be {' or '.join(DISTROS)}, not '{distro}'")
        if namespace and not _valid_namespace(namespace):
            fail(f"--namespace '{namespace}' is not a ROS name like /tb3_1")
        from astiop.robot_programs.turtlebot3.run import serve as serve_tb3

        serve_tb3(
            seed=seed, speed=speed, distro=distro, model=model, namespace=namespace, say=say,
            join=join,
        )  # fmt: skip
    except NodeSetupError as exc:
        fail(str(exc))


def _serve_fleet(
    robots: int, prefix, domains: bool, seed: int, speed: float, say, join: bool
) -> None:
    import os
    import re

    from astiop.robot_programs.ros2_node.run import serve_fleet

    prefix = "astibot_" if prefix is None else prefix
    if not re.fullmatch(r"[A-Za-z][A-Za-z0-9_]*", prefix):
        fail(f"--prefix '{prefix}' must start a ROS name: a letter, then letters, digits or '_'")
    names = [f"{prefix}{i}" for i in range(1, robots + 1)]
    placed = None
    if domains:
        base = os.environ.get("ROS_DOMAIN_ID", "0") or "0"
        if not base.isdigit():
            fail(f"ROS_DOMAIN_ID must be a number, not '{base}'")
        placed = [int(base) + i for i in range(robots)]
        if placed[-1] > MAX_DOMAIN_ID:
            fail(f"--domains: robot {robots} would be on domain {placed[-1]} (at most "
                 f"{MAX_DOMAIN_ID}): lower ROS_DOMAIN_ID or --robots")  # fmt: skip
    serve_fleet(names, seed=seed, speed=speed, domains=placed, say=say, join=join)


def _valid_namespace(text: str) -> bool:
    import re

    return re.fullmatch(r"/?[A-Za-z][A-Za-z0-9_]*(/[A-Za-z][A-Za-z0-9_]*)*", text) is not None
