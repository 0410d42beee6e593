"""What astiop's stations say of a robot on its own graph, so that it holds between machines on
one ROS 2 domain as the store makes it hold between processes on one machine: the lease on
`<namespace>/astiop_control`, the E-STOP latch on `<namespace>/astiop_estop`; std_msgs/msg/String
holding JSON, reliable and transient-local with depth 1.

Why a transient-local topic: a console that joins later is handed every holder's last word
(each writer keeps its own; see below for when it is not), with no server to ask and none to
fail; a holder that dies
takes its writer, and so its word, with it; anyone can read it (`ros2 topic echo
/astibot_2/astiop_control`). The holder says it again every heartbeat; a word not heard again
for the lease's time is a holder gone.

A late joiner's history is not always handed over: on a loaded machine a station started later
was seen to hear nothing of a writer it had discovered for 12 s and more (Fast DDS, Jazzy). So
every writer answers a newcomer's first word with its own, and a station that has spoken asks
again every `ASK_S` while it settles (its word marked `asking`) until it has heard every writer
it knows of."""

from __future__ import annotations

import contextlib
import json
import threading
import time
from collections.abc import Callable
from typing import Any

from rclpy.duration import Duration
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import String

from astiop.store.leases import LEASE_TTL_S
from astiop.transports.rclpy.graph import full_name
from astiop.transports.rclpy.node import NODE_PREFIX, RosProcess

CONTROL = "astiop_control"  # the lease
ESTOP = "astiop_estop"  # the E-STOP latch
QOS = QoSProfile(
    depth=1,
    history=HistoryPolicy.KEEP_LAST,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)
ASK_S = 0.5  # a settling station asks the writers it has not heard again this often
ANSWER_S = 0.25  # a writer answers one asker at most this often


def _peers_listed(node: Any, me: tuple[str, str]) -> bool:
    """Whether every other astiop node seen has had its writers discovered too (a loaded machine
    may find a node a second or more before its writers: its /rosout at least is listed)."""
    for name, space in node.get_node_names_and_namespaces():
        if (name, space) == me or not name.startswith(NODE_PREFIX):
            continue
        try:
            if not node.get_publisher_names_and_types_by_node(name, space):
                return False
        except Exception:  # noqa: BLE001 - gone meanwhile: nothing of it to wait for
            continue
    return True


class ControlTopic:
    def __init__(
        self,
        proc: RosProcess,
        namespace: str,
        topic: str = CONTROL,
        on_word: Callable[[dict[str, Any]], None] | None = None,
    ):
        self.proc = proc
        self.name = f"{namespace.rstrip('/')}/{topic}"
        self._on_word = on_word  # called on the executor's thread with each word heard
        self._lock = threading.Lock()
        self._heard: dict[str, tuple[float, dict[str, Any]]] = {}  # token -> (when, word)
        self._said: dict[str, Any] | None = None  # this writer's last word: each answer repeats it
        self._answered: dict[str, float] = {}  # token -> when it was last answered
        node = proc.node
        self._me = node.get_fully_qualified_name()  # said in each word: whose it is
        self._pub = node.create_publisher(String, self.name, QOS)
        self._sub = node.create_subscription(String, self.name, self._receive, QOS)

    def settle(self, timeout_s: float = 5.0, least_s: float = 0.5) -> bool:
        """Until every other writer on the topic has been heard (transient-local, or in answer
        to this writer's words: asked again every `ASK_S` meanwhile), every reader known matches
        this writer and every other astiop node seen has its writers listed, at least `least_s`
        after another node of the graph was first seen (a loaded machine may take seconds to
        discover anyone; the others on the domain are found in the same round, their writers a
        moment later), or `timeout_s`: a take must not miss a holder that is there, nor a holder
        miss the take, and a station started later must hear a press. False: `timeout_s` ran
        out."""
        asked = time.monotonic()  # its first word asked already, if it has said one
        deadline = asked + timeout_s
        node = self.proc.node
        me = (node.get_name(), node.get_namespace())
        graph_seen: float | None = None  # when another node was first seen
        while time.monotonic() < deadline:
            now = time.monotonic()
            if graph_seen is None and any(n != me for n in node.get_node_names_and_namespaces()):
                graph_seen = now
            others = node.count_publishers(self.name) - 1
            with self._lock:  # one token per writer: its own is that of its last word
                own = str(self._said.get("token")) if self._said else None
                heard = sum(token != own for token in self._heard)
            readers = node.count_subscribers(self.name)
            matched = self._pub.get_subscription_count() >= readers
            settled = graph_seen is not None and now - graph_seen >= least_s
            if heard >= others and matched and settled and _peers_listed(node, me):
                return True
            if heard < others and now - asked >= ASK_S:
                self._ask()
                asked = now
            time.sleep(0.05)
        return False

    def _ask(self) -> None:
        """This writer's last word again, marked for every writer that hears it to answer."""
        with self._lock:
            said = self._said
        if said is not None:
            self._publish({**said, "asking": True})

    def _publish(self, word: dict[str, Any]) -> None:
        self._pub.publish(String(data=json.dumps(word)))

    def _receive(self, msg: String) -> None:  # the executor's thread
        try:
            word = json.loads(msg.data)
            token = str(word["token"])
        except (ValueError, KeyError, TypeError):
            return  # not ours: nothing to follow
        now = time.monotonic()
        with self._lock:
            newcomer = token not in self._heard
            self._heard[token] = (now, word)
            said = self._said
            answer = (
                said is not None
                and token != str(said.get("token"))
                and (newcomer or bool(word.get("asking")))
                and now - self._answered.get(token, -ANSWER_S) >= ANSWER_S
            )
            if answer:
                self._answered[token] = now
        if answer and said is not None:  # `said` is never None here: for the type checker
            self._publish(said)
        if self._on_word is not None:
            self._on_word(word)

    def announce(self, word: dict[str, Any], acked_s: float = 0.0) -> None:
        """Say it; with `acked_s`, wait that long at most for every reader to have it (a word
        said just before this process ends: a takeover, a release)."""
        said = {**word, "node": self._me}
        with self._lock:
            self._said = said
        self._publish(said)
        if acked_s > 0:  # ros2/rclpy humble rclpy/rclpy/publisher.py: wait_for_all_acked
            self._pub.wait_for_all_acked(Duration(nanoseconds=int(acked_s * 1e9)))

    def words(self) -> list[dict[str, Any]]:
        """The last word of each writer whose node is still on the graph (a word with no node
        named, from an older astiop, counts as still there), however old."""
        node = self.proc.node
        live = {full_name(space, name) for name, space in node.get_node_names_and_namespaces()}
        live.add(self._me)
        with self._lock:
            words = [w for _, w in self._heard.values()]
        return [w for w in words if w.get("node", self._me) in live]

    def holders(self, released: bool = False) -> list[dict[str, Any]]:
        """Every holder heard within the lease's time that has not let go (`released`: and
        those that took it and let go since), latest take first."""
        now = time.monotonic()
        with self._lock:
            live = [w for t, w in self._heard.values() if now - t < LEASE_TTL_S]
        live = [w for w in live if released or not w.get("released")]
        return sorted(live, key=lambda w: (w.get("taken_at", 0.0), w["token"]), reverse=True)

    def close(self) -> None:
        node = self.proc.node
        with contextlib.suppress(Exception):  # the process is ending
            node.destroy_subscription(self._sub)
        with contextlib.suppress(Exception):
            node.destroy_publisher(self._pub)
