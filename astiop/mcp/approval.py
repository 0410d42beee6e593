"""Whether an outside agent's command may run: the E-STOP, validation and safety, then a person.

An actuation runs only when the operator started the server with --approve-actuation, or a
console open on the same database approves it within the bound. Nothing here sends anything.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from astiop.robot.estop_latch import ESTOP_REASON
from astiop.robot.gateway import RobotGateway
from astiop.robot.safety import Review, always_allowed, releases_a_stop
from astiop.ros2.render import sent_text
from astiop.store import Store

POLL_S = 0.2
NO_CONSOLE = (
    "no console is open to approve it; start `astiop mcp --approve-actuation` to allow "
    "actuation without one"
)


@dataclass(frozen=True)
class Policy:
    approve_actuation: bool = False  # the operator allowed actuation without a console
    timeout_s: float = 60.0  # how long a console has to answer


@dataclass(frozen=True)
class Clearance:
    review: Review
    refusal: str = ""  # why it may not run ('' when it may)
    approved_by: str = ""  # 'operator (--approve-actuation)', 'console', or '' for a read

    @property
    def cleared(self) -> bool:
        return not self.refusal


def needs_approval(review: Review) -> bool:
    checked = review.checked
    return checked.kind == "actuate" and not always_allowed(checked)


def clear(
    gateway: RobotGateway,
    store: Store,
    policy: Policy,
    text: str,
    client: str,
    what: str,
    robot: str = "",
) -> Clearance:
    """Review `text` and, for an actuation, obtain its approval; `what` is the tool call as
    the person will see it."""
    review = gateway.review(text)
    checked = review.checked
    if needs_approval(review) and gateway.e_stopped:
        return Clearance(review, ESTOP_REASON)
    if not checked.valid:
        return Clearance(review, checked.reason or "not a valid command")
    own = gateway.profile.name("release")
    # a held robot is let go by a person, never an agent
    if checked.command is not None and releases_a_stop(checked, own):
        said = f"{checked.command.name} releases a held robot: a person does, with ctrl+r or astiop estop --release"
        return Clearance(review, said)
    if not review.allowed:
        return Clearance(review, review.reason)
    if not needs_approval(review):
        return Clearance(review)
    if policy.approve_actuation:
        return Clearance(review, approved_by="operator (--approve-actuation)")
    if not store.console_open():
        return Clearance(review, NO_CONSOLE)
    detail = f"MCP client '{client}' asks: {what}"
    if checked.notes:
        detail += "\n" + "\n".join(f"note: {n}" for n in checked.notes)
    request = store.request_approval(
        client, sent_text(checked), detail, policy.timeout_s, robot=robot
    )
    status = wait_for_decision(store, request, policy.timeout_s)
    if status == "approved":
        return Clearance(review, approved_by="console")
    if status == "denied":
        return Clearance(review, "denied by the operator")
    return Clearance(review, f"no answer from the operator within {policy.timeout_s:g} s")


def wait_for_decision(store: Store, request: int, timeout_s: float) -> str:
    """Poll the request until a console decides it or the bound passes (then it expires)."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        row = store.approval(request)
        if row is None:
            return "expired"
        if row["status"] != "pending":
            return str(row["status"])
        time.sleep(POLL_S)
    if store.expire_approval(request):
        return "expired"
    row = store.approval(request)  # answered in the last instant
    return str(row["status"]) if row else "expired"
