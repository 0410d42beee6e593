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
DOUBLINGS = 5  # 2 ** 5 > MAX_DELAY_S: no power is ever computed past it (2.0 ** 1024 overflows)
MAX_COUNTED = 1_000_000  # an address's wrong tries counted up to this


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


Network = ipaddress.IPv4Network | ipaddress.IPv6Network


def proxy_networks(entries: list[str]) -> tuple[Network, ...]:
    """'127.0.0.1', '10.0.0.0/8', '::1' as networks (ValueError names a bad one)."""
    return tuple(ipaddress.ip_network(entry.strip(), strict=False) for entry in entries)


def _ip(text: str) -> ipaddress.IPv4Address | ipaddress.IPv6Address | None:
    try:
        return ipaddress.ip_address(text.strip().strip("[]"))
    except ValueError:
        return None


def client_address(peer: str | None, forwarded_for: list[str], trusted: tuple[Network, ...]) -> str:
    """Who a request comes from: its peer; when the peer is a trusted proxy, the nearest address
    in X-Forwarded-For that is not one (a client forges only the entries left of its own, which
    its proxy appends). A header from anyone else is not read."""
    address = peer or "?"
    hops = [hop for header in forwarded_for for hop in header.split(",")][-64:]
    while (ip := _ip(address)) is not None and any(ip in net for net in trusted) and hops:
        if _ip(hops[-1]) is None:
            break  # not an address: the proxy's peer is the last one we can name
        address = str(_ip(hops.pop()))
    return address


def _bucket(address: str) -> str:
    """Wrong tries are counted per address, per /64 for IPv6 (one host holds a whole /64)."""
    ip = _ip(address)
    if isinstance(ip, ipaddress.IPv6Address) and ip.ipv4_mapped is None and not ip.is_loopback:
        return str(ipaddress.IPv6Network(f"{ip}/64", strict=False))
    return address


class Access:
    """The token (None: no token, loopback only), the sessions it opened, the wrong tries."""

    def __init__(self, token: str | None, clock: Callable[[], float] = time.monotonic):
        self.token = token
        self._clock = clock
        self._sessions: OrderedDict[str, float] = OrderedDict()  # id -> expiry
        # address -> (wrong tries, the last one's time, when the last one waiting is answered)
        self._wrong: OrderedDict[str, tuple[int, float, float]] = OrderedDict()

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

    def wrong_try(self, address: str) -> float | None:
        """Count a wrong token from `address` (before anything awaits, so parallel tries are
        counted one by one) and say how long its answer waits: its turn after the address's
        earlier wrong tries, each delayed 0 s for the first FREE_TRIES, then 1, 2, 4 ... at most
        MAX_DELAY_S. None: its turn is more than MAX_DELAY_S away (a flood): refused at once."""
        now, address = self._clock(), _bucket(address)
        wrong, last, turn = self._wrong.pop(address, (0, 0.0, 0.0))
        if now - last > FORGET_S:
            wrong, turn = 0, 0.0
        wrong = min(wrong + 1, MAX_COUNTED)
        extra = wrong - 1 - FREE_TRIES  # the delay grows with the tries before this one
        delay = (
            0.0
            if extra < 0
            else MAX_DELAY_S
            if extra >= DOUBLINGS
            else min(MAX_DELAY_S, 2.0**extra)
        )
        answer_at = max(now, turn) + delay
        flood = answer_at - now > MAX_DELAY_S
        self._wrong[address] = (wrong, now, turn if flood else answer_at)
        while len(self._wrong) > MAX_TRACKED:
            self._wrong.popitem(last=False)
        return None if flood else answer_at - now

    def right_token(self, address: str) -> None:
        """The address's wrong tries are forgotten, unless some are still waiting for their
        answer (a guesser behind the same address as the operator keeps its penalty)."""
        address = _bucket(address)
        _wrong, _last, turn = self._wrong.get(address, (0, 0.0, 0.0))
        if turn <= self._clock():
            self._wrong.pop(address, None)
