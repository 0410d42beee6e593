"""Build the robot gateway the settings ask for: the simulator (default) or the real robot."""

from __future__ import annotations

from astiop.config import Settings
from astiop.robot.gateway import RobotGateway
from astiop.robot.lease import Lease
from astiop.robot.safety import SafetyPolicy
from astiop.ros2.profile_types import Profile, ProfileSpec
from astiop.sim.simulator import Simulator
from astiop.store import Store
from astiop.transports.base import RobotTransport


def make_safety(
    settings: Settings, store: Store | None, profile: Profile | None = None
) -> SafetyPolicy:
    """The settings' limits, lowered to the robot's own where its profile knows them (a
    TurtleBot3 Burger: 0.22 m/s, not the ASTIbot's 0.8). The geofence is the profile's, else
    the robot's map's once the gateway has it (`RobotGateway.use_map`)."""
    bounds = profile.map.geofence if profile is not None else None

    def locate(name: str) -> tuple[float, float] | None:
        loc = store.get_location(name) if store else None
        return (loc.x, loc.y) if loc else None

    linear, angular = settings.robot.max_linear_speed, settings.robot.max_angular_speed
    limits = profile.limits if profile is not None else None
    if limits is not None and limits.max_linear_speed is not None:
        linear = min(linear, limits.max_linear_speed)
    if limits is not None and limits.max_angular_speed is not None:
        angular = min(angular, limits.max_angular_speed)
    return SafetyPolicy(
        max_linear=linear,
        max_angular=angular,
        geofence=bounds,
        confirm_actuation=settings.robot.confirm_actuation,
        locate=locate,
        zones=store.list_zones if store is not None else None,
    )


def make_sim_gateway(
    settings: Settings,
    store: Store | None,
    *,
    realtime: bool = False,
    sim: Simulator | None = None,
    who: str = "astiop",
    restore_latch: bool = True,
) -> RobotGateway:
    from astiop.transports.simulator.backend import SimBackend

    sim = sim or Simulator(
        seed=settings.sim.seed,
        v_max=settings.robot.max_linear_speed,
        battery_soc=settings.sim.battery,
    )
    backend = SimBackend(sim, store, realtime=realtime, speed=settings.sim.speed)
    return RobotGateway(
        backend, make_safety(settings, store), store=store, who=who, restore_latch=restore_latch
    )


def ros2_transport(settings: Settings) -> tuple[str, str]:
    """("rclpy" or "cli", why the CLI when it is the CLI); BackendError if rclpy is asked for
    and cannot run here."""
    from astiop.transports.base import BackendError
    from astiop.transports.rclpy.available import rclpy_missing

    wanted = settings.robot.ros2_transport
    if wanted == "cli":
        return "cli", "as set (robot.ros2_transport)"
    missing = rclpy_missing()
    if wanted == "rclpy" and missing:
        raise BackendError(f"--ros2-transport rclpy: {missing}")
    return ("cli", missing) if missing else ("rclpy", "")


def profile_spec(settings: Settings) -> ProfileSpec:
    """What the settings fix of the robot's profile (robot.profile, robot.namespace);
    BackendError in one line for a profile that cannot be used."""
    from astiop.ros2.profile_file import ProfileError, read_spec
    from astiop.transports.base import BackendError

    try:
        return read_spec(settings.robot.profile, settings.robot.namespace)
    except ProfileError as exc:
        raise BackendError(str(exc)) from None


def make_robot_gateway(
    settings: Settings,
    store: Store | None,
    *,
    realtime: bool = False,
    who: str = "astiop",
    discover: bool = True,
    restore_latch: bool = True,
) -> RobotGateway:
    """`discover=False`: neither wait for a ROS 2 robot's discovery to settle nor read its whole
    graph first (an E-STOP sends as soon as the base is found); `restore_latch`: `RobotGateway`."""
    if settings.robot.backend == "ros2":
        transport, why = ros2_transport(settings)
        fixed = profile_spec(settings)
        backend: RobotTransport
        if transport == "rclpy":
            from astiop.transports.rclpy.backend import RclpyBackend

            backend = RclpyBackend(settings.robot.ros2_timeout_s, discover=discover, fixed=fixed)
        else:
            from astiop.transports.ros2cli.backend import Ros2Backend

            backend = Ros2Backend(
                settings.robot.ros2_executable,
                settings.robot.ros2_timeout_s,
                discover=discover,
                fixed=fixed,
            )
            backend.label = f"ros2 via the CLI: {why}"
        if discover:
            _named_robot_found(settings, backend)
        gateway = RobotGateway(
            backend,
            make_safety(settings, store, backend.catalog.profile),
            settings.robot.ros2_timeout_s,
            store=store,
            who=who,
            restore_latch=restore_latch,
            latch_key=settings.robot.namespace,  # a fleet's robot: a latch of its own
        )
        gateway.follow_stations(settings.robot.namespace)
        if store is not None:  # a robot on the graph is shared: one operator controls it
            ns = settings.robot.namespace
            gateway.lease = robot_lease(ns, store, who, backend)
            # a name under another robot's namespace reaches that robot: its lease is asked
            gateway.lease_of = lambda other: robot_lease(other, store, who, backend)
        return gateway
    return make_sim_gateway(
        settings, store, realtime=realtime, who=who, restore_latch=restore_latch
    )


def _named_robot_found(settings: Settings, backend: RobotTransport) -> None:
    """A fleet found on the graph (--fleet auto): the robot --robot-name names must be on it,
    or nothing is sent, latched or stored for it (BackendError). Heard of until discovery is
    over: a robot's participant may come seconds after another's."""
    import time

    from astiop.ros2.fleet_names import namespaces
    from astiop.transports.base import BackendError

    ns = settings.robot.namespace.rstrip("/")
    if not ns or settings.fleet.discover != "auto":
        return

    def heard_of() -> bool:
        cat = backend.catalog
        return any(n.startswith(ns + "/") for n in (*cat.topics, *cat.services, *cat.nodes))

    while not heard_of() and backend.discovering():
        time.sleep(0.25)
        backend.refresh(settle=False)
    if not heard_of():
        found = ", ".join(n.lstrip("/") for n in namespaces(backend.catalog)) or "none"
        backend.close()
        raise BackendError(
            f"no robot named '{ns.lstrip('/')}' on the ROS 2 domain (its robots: {found})"
        )


def robot_lease(ns: str, store: Store, who: str, backend: RobotTransport) -> Lease:
    """The lease of the ROS 2 robot under namespace `ns` on this process's domain, announced on
    the robot's graph where the transport can."""
    import os

    from astiop.robot.lease import lease_key

    key = lease_key(ns, os.environ.get("ROS_DOMAIN_ID", "0"))
    name = ns.strip("/") or "the robot"
    return Lease(store, key, name, who, channel=lambda: backend.control_channel(ns))


def leave_the_graph(timeout_s: float) -> bool:
    """This process's rclpy node and context closed now, if it has one (a command that ends
    without Python's teardown would leave its endpoints in every peer's graph until its DDS
    lease runs out: a stale /cmd_vel publisher of another type, for 20 s); False if the close
    did not end within `timeout_s`."""
    import sys

    node = sys.modules.get("astiop.transports.rclpy.node")
    if node is None:
        return True
    return node.close_shared(timeout_s)
