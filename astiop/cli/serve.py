"""`astiop serve`: the console in a browser tab, each tab a console process of its own."""

from __future__ import annotations

import logging
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import typer

from astiop.cli import metrics_option
from astiop.cli.common import CliState, fail, state
from astiop.cli.mcp import loopback
from astiop.cli.serve_watcher import Watcher


def _global_args(st: CliState) -> list[str]:
    """The options every tab's console and the E-STOP button run with: this command's own, and
    the database resolved now (so a tab never opens another one)."""
    args = ["--db", str(Path(st.db_path).expanduser().resolve())]
    overrides = st.overrides
    if "model" in overrides.get("llm", {}):
        args += ["--model", overrides["llm"]["model"]]
    robot = overrides.get("robot", {})
    if "backend" in robot:
        args += ["--robot", robot["backend"]]
    if "ros2_transport" in robot:
        args += ["--ros2-transport", robot["ros2_transport"]]
    return args


def _robot_said(st: CliState) -> str:
    robot = st.settings.robot
    if robot.backend == "sim":
        return "simulator (one per tab)"
    return f"ros2 ({robot.ros2_transport} transport)"


def _loopback() -> dict[str, str]:
    """The shared simulator is this server's own robot: its DDS traffic stays on this machine
    (Humble knows ROS_LOCALHOST_ONLY; Jazzy on takes the discovery range and calls it
    deprecated)."""
    if os.environ.get("ROS_DISTRO", "").lower() == "humble":
        return {"ROS_LOCALHOST_ONLY": "1"}
    return {"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}


NODE_START_S = 60.0


# The shared simulator's own domain: never the robot's graph (a real base may listen on this
# machine's domain). Among Linux's safe domain ids (0-101), the first of 99 down to 89 with no
# robot on it (the top two are left to `astiop sim node --domains` fleets).
SIM_DOMAINS = range(99, 88, -1)


def _shared_simulator(st: CliState, mode: str) -> tuple[subprocess.Popen, int] | None:
    """With `--robot sim`, one simulated robot for every tab: `astiop sim node` (real ROS 2 nodes,
    on the loopback, on a domain of its own where no robot is) and the tabs on `--robot ros2
    --ros2-transport rclpy` there. None: each tab simulates its own (`--sim per-tab`, or auto
    where ROS 2 is not installed)."""
    if st.settings.robot.backend != "sim" or mode == "per-tab":
        return None
    from astiop.robot_programs.ros2_node.run import NodeSetupError, check_imports

    try:
        check_imports()
    except NodeSetupError as exc:
        if mode == "shared":
            fail(f"--sim shared: {exc}")
        typer.echo(f"astiop serve: each tab simulates its own robot ({exc})", err=True)
        return None
    said: list[str] = []
    for domain in SIM_DOMAINS:
        node = _start_node(st, domain, said)
        if node is not None:
            return node, domain
        if not said or "already on" not in said[-1]:
            break  # not a robot in its way: it did not start
    fail("the shared simulator did not start: " + (said[-1] if said else "no output"))


def _start_node(st: CliState, domain: int, said: list[str]) -> subprocess.Popen | None:
    sim = st.settings.sim
    argv = [sys.executable, "-m", "astiop", "sim", "node", "--seed", str(sim.seed)]
    node = subprocess.Popen(
        [*argv, "--speed", str(min(sim.speed, 20.0))],
        env={**os.environ, **_loopback(), "ROS_DOMAIN_ID": str(domain)},
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,  # Ctrl-C reaches the server, which ends the robot last
        preexec_fn=_ends_with_its_parent,
    )
    said.clear()
    up = threading.Event()
    drain = threading.Thread(target=_drain, args=(node, said, up), daemon=True)
    drain.start()
    t0 = time.monotonic()
    while not up.wait(0.1) and node.poll() is None and time.monotonic() - t0 < NODE_START_S:
        pass
    if up.is_set() and node.poll() is None:
        return node
    _end_process(node)
    drain.join(5)  # its last lines, to say why
    return None


def _button_stops(st: CliState, env: dict[str, str]):
    """The page's E-STOP button, from this process: a gateway to the tabs' robot made now and
    kept warm, so a click sends the zero velocity at once (None: not reached this way; the
    button starts `astiop estop`)."""
    from astiop.robot.factory import make_robot_gateway, ros2_transport
    from astiop.transports.base import BackendError

    settings = st.settings
    if env:  # the shared simulator: the tabs reach it over rclpy
        settings = settings.model_copy(
            update={"robot": settings.robot.model_copy(update={"backend": "ros2",
                                                               "ros2_transport": "rclpy"})}
        )  # fmt: skip
    if settings.robot.backend != "ros2":
        return None, None
    saved = {name: os.environ.get(name) for name in env}
    os.environ.update(env)  # the shared simulator's domain, read as rclpy starts here
    try:
        if ros2_transport(settings)[0] != "rclpy":
            return None, None
        gateway = make_robot_gateway(settings, None, who="serve", discover=False)
    except BackendError as exc:
        typer.echo(f"astiop serve: the E-STOP button runs astiop estop ({exc})", err=True)
        return None, None
    finally:  # this process's environment as it was (a caller in the same process goes on)
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value
    gateway.warm_estop()

    def stop(who: str) -> list[str]:
        return gateway.estop(who=who)

    return stop, gateway


def _ends_with_its_parent() -> None:
    """A server killed outright (SIGKILL, OOM) takes its simulator with it (Linux)."""
    if sys.platform.startswith("linux"):
        import ctypes
        import signal

        ctypes.CDLL(None).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG


def _drain(node: subprocess.Popen, said: list[str], up: threading.Event) -> None:
    """The simulator's lines: kept until it says it is up, then passed on to the server's."""
    for line in node.stderr:
        if up.is_set():
            print(f"astiop serve: simulator: {line.rstrip()}", file=sys.stderr)
            continue
        said.append(line.rstrip())
        if "up as ROS 2 nodes" in line:
            up.set()


def _end_process(node: subprocess.Popen) -> None:
    if node.poll() is None:
        node.terminate()
        try:
            node.wait(10)
        except subprocess.TimeoutExpired:
            node.kill()
            node.wait(5)


def _start_watcher(base: list[str], env: dict[str, str]) -> subprocess.Popen:
    """`astiop watch run` on the tabs' robot (cli/serve_watcher.py)."""
    return subprocess.Popen(
        [*base, "watch", "run", "--json"],
        env={**os.environ, **env},
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,  # its alerts are in the database: the bell, F8, astiop alerts
        start_new_session=True,  # Ctrl-C reaches the server, which ends it
        preexec_fn=_ends_with_its_parent,
    )


def serve(
    ctx: typer.Context,
    host: str = typer.Option("127.0.0.1", "--host", help="Address to listen on."),
    port: int = typer.Option(8765, "--port", min=1, max=65535, help="Port to listen on."),
    token_file: Path | None = typer.Option(
        None,
        "--token-file",
        metavar="F",
        help="Ask for the token in F's one line (mode 600) before any console starts; or set "
        "ASTIOP_SERVE_TOKEN. Needed off the loopback.",
    ),
    token_given: str | None = typer.Option(None, "--token", hidden=True),
    sim_mode: str = typer.Option(
        "auto",
        "--sim",
        metavar="auto|shared|per-tab",
        help="With --robot sim: one simulated robot for every tab (`astiop sim node`, needs "
        "ROS 2), or one per tab; auto: shared where ROS 2 is installed.",
    ),
    max_consoles: int = typer.Option(
        4,
        "--max-consoles",
        min=1,
        max=64,
        help="Tabs open at once (each is a console process, ~430 MB with the embedded model).",
    ),
    warm: bool = typer.Option(
        True,
        "--warm/--no-warm",
        help="Keep one console process started ahead (its imports done, idle) for the next tab.",
    ),
    watch: bool = typer.Option(
        True,
        "--watch/--no-watch",
        help="Evaluate the robot's watches and built-in alerts with no tab open (an `astiop "
        "watch run` of its own; not where each tab simulates its own robot).",
    ),
    metrics: str | None = metrics_option.ADDRESS,
    metrics_token_file: Path | None = metrics_option.TOKEN_FILE,
) -> None:
    """Serve the console to a web browser: every screen, key and dialog, one console process per
    tab on these settings, database and robot, with an E-STOP button on every page."""
    from astiop.bearer_token import SERVE_TOKEN, TokenError, token_from, where

    if token_given is not None:
        fail(f"--token would show the token to every user in `ps`: give it as {where(SERVE_TOKEN)}")
    try:
        token = token_from(token_file, os.environ, SERVE_TOKEN)
    except TokenError as exc:
        fail(str(exc))
    os.environ.pop(SERVE_TOKEN, None)  # never handed down to a console or the robot's processes
    if not loopback(host) and not token:
        fail(f"--host {host} (not the loopback) needs a token ({where(SERVE_TOKEN)}): anyone who "
             "reaches it would get a console that drives the robot")  # fmt: skip
    if sim_mode not in ("auto", "shared", "per-tab"):
        fail(f"--sim must be auto, shared or per-tab, not {sim_mode!r}")
    st = state(ctx)
    st.settings  # a bad settings file fails here, not in every tab  # noqa: B018
    st.store  # the database opens (and is made) once, before any tab  # noqa: B018
    buttons: list = []  # the button's gateway, made once the port is open
    from astiop.metrics import figures_of

    exporter = metrics_option.start_metrics(
        st, metrics, metrics_token_file,
        lambda: [figures_of(b, st.robot_name or "") for b in buttons if b is not None],
    )  # fmt: skip

    from astiop.web.access import proxy_networks
    from astiop.web.server import ServeConfig, serve_until_stopped

    base = [sys.executable, "-m", "astiop", *_global_args(st)]
    robot, env = _robot_said(st), {}
    shared = _shared_simulator(st, sim_mode)
    node = shared[0] if shared is not None else None
    if shared is not None:
        base += ["--robot", "ros2", "--ros2-transport", "rclpy"]  # the last --robot wins
        robot = f"simulator (shared by every tab; astiop sim node on ROS_DOMAIN_ID={shared[1]})"
        env = {**_loopback(), "ROS_DOMAIN_ID": str(shared[1])}
    config = ServeConfig(
        host=host,
        port=port,
        token=token,
        console_argv=base,
        estop_argv=[*base, "estop"],
        db=Path(st.db_path),
        robot=robot,
        console_env=env,
        max_consoles=max_consoles,
        warm=warm,
        trusted_proxies=proxy_networks(st.settings.serve.trusted_proxies),
    )
    logging.basicConfig(level=logging.INFO, format="astiop serve: %(message)s", stream=sys.stderr)
    access = "the token is asked first" if token else "no token: this machine only"
    if config.trusted_proxies:
        access += ", clients named by " + ", ".join(map(str, config.trusted_proxies))

    def ready(url: str) -> None:
        # the button's own way to the robot, once this server is sure to serve (its rclpy
        # process on the robot's domain: nothing else here speaks ROS 2)
        config.stop_robot, button = _button_stops(st, env)
        if button is not None and exporter is not None:
            button.start()  # its readings too, for the metrics (else it only stops the robot)
        buttons.append(button)
        if host in ("0.0.0.0", "::"):
            url += " (every address of this machine)"
        typer.echo(f"astiop serve: {url} ({access}; robot: {config.robot}); Ctrl-C stops", err=True)

    import asyncio

    watcher = None
    if watch and (shared is not None or st.settings.robot.backend != "sim"):
        watcher = Watcher(lambda: _start_watcher(base, env), _end_process)
        watcher.start()
    try:
        asyncio.run(serve_until_stopped(config, ready))
    except OSError as exc:
        fail(f"cannot listen on {host}:{port}: {exc.strerror or exc}")
    finally:
        if exporter is not None:
            exporter.close()
        for button in buttons:
            if button is not None:
                button.close()
        if watcher is not None:
            watcher.close()
        if node is not None:
            _end_process(node)
