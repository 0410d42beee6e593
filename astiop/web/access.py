"""Who may open a console: a token checked before any console process starts (then a session
cookie), pages of this server only (the Origin), and wrong tokens slowed down, per address."""

from __future__ import annotations

import hmac
import ipaddress
import secrets
import time
from collections import OrderedDict
from collections.abc import Callable

COOKIE = "astiop_session"
SESSION_S = 12 * 3600.0
FREE_TRIES = 3  # wrong tokens from one address before each answer is delayed
MAX_DELAY_S = 30.0
FORGET_S = 600.0  # an address's wrong tokens are forgotten after this long without one
MAX_TRACKED = 4096  # addresses and sessions kept: a flood cannot grow them without bound


def loopback_host(host: str) -> bool:
    """`host` (a Host header's name, without the port) names this machine."""
    host = host.strip("[]").lower()
    if host == "localhost" or host.endswith(".localhost"):
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def host_name(host_header: str) -> str:
    """The name in a Host header, without its port ('[::1]:8765' -> '::1')."""
    if host_header.startswith("["):
        return host_header[1 : host_header.find("]")] if "]" in host_header else host_header
    return host_header.rsplit(":", 1)[0] if host_header.count(":") == 1 else host_header


class Access:
    """The token (None: no token, loopback only), the sessions it opened, the wrong tries."""

    def __init__(self, token: str | None, clock: Callable[[], float] = time.monotonic):
        self.token = token
        self._clock = clock
        self._sessions: OrderedDict[str, float] = OrderedDict()  # id -> expiry
        self._wrong: OrderedDict[str, tuple[int, float]] = OrderedDict()  # address -> (n, last)

    def token_matches(self, given: str) -> bool:
        if self.token is None:
            return True
        return hmac.compare_digest(given.encode("utf-8", "replace"), self.token.encode())

    def open_session(self) -> str:
        session = secrets.token_urlsafe(32)
        self._sessions[session] = self._clock() + SESSION_S
        while len(self._sessions) > MAX_TRACKED:
            self._sessions.popitem(last=False)
        return session

    def admitted(self, cookie: str | None) -> bool:
        if self.token is None:
            return True
        expiry = self._sessions.get(cookie or "")
        if expiry is None:
            return False
        if expiry < self._clock():
            del self._sessions[cookie]
            return False
        return True

    def delay_s(self, address: str) -> float:
        """How long to wait before answering `address`'s next try: 0 for its first few wrong
        tokens, then doubling, at most MAX_DELAY_S."""
        wrong, last = self._wrong.get(address, (0, 0.0))
        if self._clock() - last > FORGET_S:
            return 0.0
        extra = wrong - FREE_TRIES
        return 0.0 if extra < 0 else min(MAX_DELAY_S, 2.0**extra)

    def wrong_token(self, address: str) -> None:
        wrong, last = self._wrong.pop(address, (0, 0.0))
        if self._clock() - last > FORGET_S:
            wrong = 0
        self._wrong[address] = (wrong + 1, self._clock())
        while len(self._wrong) > MAX_TRACKED:
            self._wrong.popitem(last=False)

    def right_token(self, address: str) -> None:
        self._wrong.pop(address, None)
