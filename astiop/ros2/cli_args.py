"""ros2cli's argument parsers for the verbs astiop uses, per distro: astiop's grammar, and the emulated `ros2`'s.

Read from ros2/ros2cli on the `humble` and `jazzy` branches: ros2topic/verb/{list,info,type,
echo,hz,pub}.py, ros2service/verb/{list,type,call}.py, ros2action/verb/{list,info,send_goal}.py,
ros2node/verb/{list,info}.py, ros2interface/verb/{list,show}.py, ros2param/verb/{list,get,set}.py,
ros2cli/node/{strategy,direct}.py and ros2topic/api add_qos_arguments. Stdlib only: this runs
at every emulated `ros2` call.
"""

from __future__ import annotations

import argparse

from astiop.distro import DISTROS  # noqa: F401 - the emulated ros2 reads it here


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


def _strategy(p) -> None:
    p.add_argument("--spin-time", type=float)
    p.add_argument("-s", "--use-sim-time", action="store_true")
    p.add_argument("--no-daemon", action="store_true")


def _qos(p, distro: str) -> None:
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


def _values_or_stdin(p, distro: str, dest: str, required_on_humble: bool = False) -> None:
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


def build_parser(distro: str, parser_class=argparse.ArgumentParser) -> argparse.ArgumentParser:
    root = parser_class(prog="ros2")
    verbs = root.add_subparsers(dest="command", required=True)

    topic = verbs.add_parser("topic").add_subparsers(dest="verb", required=True)
    p = topic.add_parser("list")
    p.add_argument("-t", "--show-types", action="store_true")
    p.add_argument("-c", "--count-topics", action="store_true")
    p.add_argument("--include-hidden-topics", action="store_true")
    p.add_argument("-v", "--verbose", action="store_true")
    _strategy(p)
    p = topic.add_parser("info")
    p.add_argument("topic_name")
    p.add_argument("--verbose", "-v", action="store_true")
    _strategy(p)
    p = topic.add_parser("type")
    p.add_argument("topic_name")
    _strategy(p)
    p = topic.add_parser("echo")
    p.add_argument("topic_name")
    p.add_argument("message_type", nargs="?")
    _qos(p, distro)
    p.add_argument("--csv", action="store_true")
    p.add_argument("--field")
    p.add_argument("--full-length", "-f", action="store_true")
    p.add_argument("--truncate-length", "-l", type=nonnegative_int, default=128)
    p.add_argument("--no-arr", action="store_true")
    p.add_argument("--no-str", action="store_true")
    p.add_argument("--flow-style", action="store_true")
    p.add_argument("--no-lost-messages", action="store_true")
    p.add_argument("--raw", action="store_true")
    p.add_argument("--filter", dest="filter_expr")
    p.add_argument("--once", action="store_true")
    if distro == "humble":
        p.add_argument("--lost-messages", action="store_true")
    else:
        p.add_argument("--timeout", type=positive_float)
        p.add_argument("--include-message-info", "-i", action="store_true")
    _strategy(p)
    p = topic.add_parser("hz")
    p.add_argument("topic_name")
    p.add_argument("--window", "-w", dest="window_size", type=positive_int, default=10000)
    p.add_argument("--filter", dest="filter_expr")
    p.add_argument("--wall-time", dest="use_wtime", action="store_true")
    _strategy(p)
    p = topic.add_parser("pub")
    p.add_argument("topic_name")
    p.add_argument("message_type")
    _values_or_stdin(p, distro, "values")
    p.add_argument("-r", "--rate", type=positive_float, default=1.0)
    p.add_argument("-p", "--print", type=int, default=1)
    g = p.add_mutually_exclusive_group()
    g.add_argument("-1", "--once", action="store_true")
    g.add_argument("-t", "--times", type=nonnegative_int, default=0)
    p.add_argument("-w", "--wait-matching-subscriptions", type=nonnegative_int)
    if distro != "humble":
        p.add_argument("--max-wait-time-secs", type=positive_float)
    p.add_argument("--keep-alive", type=positive_float, default=0.1)
    p.add_argument("-n", "--node-name")
    _qos(p, distro)
    p.add_argument("--use-sim-time", action="store_true")

    service = verbs.add_parser("service").add_subparsers(dest="verb", required=True)
    p = service.add_parser("list")
    p.add_argument("-t", "--show-types", action="store_true")
    p.add_argument("-c", "--count-services", action="store_true")
    p.add_argument("--include-hidden-services", action="store_true")
    _strategy(p)
    p = service.add_parser("type")
    p.add_argument("service_name")
    _strategy(p)
    p = service.add_parser("call")
    p.add_argument("service_name")
    p.add_argument("service_type")
    _values_or_stdin(p, distro, "values")
    p.add_argument("-r", "--rate", type=float)

    action = verbs.add_parser("action").add_subparsers(dest="verb", required=True)
    p = action.add_parser("list")
    p.add_argument("-t", "--show-types", action="store_true")
    p.add_argument("-c", "--count-actions", action="store_true")
    p = action.add_parser("info")
    p.add_argument("action_name")
    p.add_argument("-t", "--show-types", action="store_true")
    p.add_argument("-c", "--count", action="store_true")
    p = action.add_parser("send_goal")
    p.add_argument("action_name")
    p.add_argument("action_type")
    _values_or_stdin(p, distro, "goal", required_on_humble=True)
    p.add_argument("-f", "--feedback", action="store_true")

    node = verbs.add_parser("node").add_subparsers(dest="verb", required=True)
    p = node.add_parser("list")
    p.add_argument("-a", "--all", action="store_true")
    p.add_argument("-c", "--count-nodes", action="store_true")
    _strategy(p)
    p = node.add_parser("info")
    p.add_argument("node_name")
    p.add_argument("--include-hidden", action="store_true")
    _strategy(p)

    interface = verbs.add_parser("interface").add_subparsers(dest="verb", required=True)
    p = interface.add_parser("list")
    p.add_argument("-m", "--only-msgs", action="store_true")
    p.add_argument("-s", "--only-srvs", action="store_true")
    p.add_argument("-a", "--only-actions", action="store_true")
    p = interface.add_parser("show")
    p.add_argument("type")
    p.add_argument("--all-comments", action="store_true")
    p.add_argument("--no-comments", action="store_true")

    param = verbs.add_parser("param").add_subparsers(dest="verb", required=True)
    p = param.add_parser("list")
    p.add_argument("node_name", nargs="?")
    p.add_argument("--filter")
    p.add_argument("--include-hidden-nodes", action="store_true")
    p.add_argument("--param-prefixes", nargs="+", default=[])
    p.add_argument("--param-type", action="store_true")
    _strategy(p)
    for sub in ("get", "set"):
        p = param.add_parser(sub)
        p.add_argument("node_name")
        p.add_argument("--include-hidden-nodes", action="store_true")
        p.add_argument("parameter_name")
        if sub == "get":
            p.add_argument("--hide-type", action="store_true")
        else:
            p.add_argument("value")
        if distro != "humble":
            p.add_argument("--timeout", type=int, default=1)
        _strategy(p)

    daemon = verbs.add_parser("daemon").add_subparsers(dest="verb", required=True)
    for sub in ("start", "stop", "status"):
        daemon.add_parser(sub)
    return root
