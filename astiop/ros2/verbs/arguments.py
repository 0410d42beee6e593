"""The argument definitions ros2cli's verbs share (ros2cli/node/strategy.py and direct.py,
ros2topic/api add_qos_arguments, the values-or---stdin pair of pub, call and send_goal since
Jazzy). Stdlib only."""

from __future__ import annotations


def positive_float(text: str) -> float:
    value = float(text)
    if not (0 < value < float("inf")):  # NaN fails both comparisons; astiop wants it finite
        raise ValueError("must be positive")
    return value


def nonnegative_int(text: str) -> int:
    value = int(text)
    if value < 0:
        raise ValueError("must be positive or zero")
    return value


def positive_int(text: str) -> int:
    value = int(text)
    if value <= 0:
        raise ValueError("must be positive")
    return value


def strategy(p) -> None:
    p.add_argument("--spin-time", type=float)
    p.add_argument("-s", "--use-sim-time", action="store_true")
    p.add_argument("--no-daemon", action="store_true")


def qos(p, distro: str) -> None:
    p.add_argument(
        "--qos-profile",
        choices=[
            "system_default",
            "sensor_data",
            "services_default",
            "parameters",
            "parameter_events",
            "action_status_default",
            "default",
        ],
    )
    p.add_argument("--qos-depth", type=int)
    p.add_argument("--qos-history", choices=["system_default", "keep_last", "keep_all", "unknown"])
    p.add_argument(
        "--qos-reliability", choices=["system_default", "reliable", "best_effort", "unknown"]
    )
    p.add_argument(
        "--qos-durability", choices=["system_default", "transient_local", "volatile", "unknown"]
    )
    if distro != "humble":
        p.add_argument("--qos-liveliness")
        p.add_argument("--qos-liveliness-lease-duration-seconds", type=float)


def values_or_stdin(p, distro: str, dest: str, required_on_humble: bool = False) -> None:
    """The YAML values, or (since Jazzy) --stdin instead: a mutually exclusive pair."""
    if distro == "humble":
        if required_on_humble:
            p.add_argument(dest)
        else:
            p.add_argument(dest, nargs="?", default="{}")
        return
    g = p.add_mutually_exclusive_group()
    g.add_argument(dest, nargs="?", default="{}")
    g.add_argument("--stdin", action="store_true")
