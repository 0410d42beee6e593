"""The E-STOP latch on the robot's own graph, so that it holds across stations: every astiop
process (a console, `serve`, `mcp`, a one-shot command), whatever its database, on this machine
or another, says on `<namespace>/astiop_estop` what it knows of the robot's E-STOP and follows
what the others say.

What a station says is the newest press and the newest release it knows of, each with who made
it, where (host, process) and when. The E-STOP is engaged while the newest press is newer than
the newest release. Both only ever grow, so the words merge in any order and a late word never
undoes a newer one: a press is never undone by a release made before it, and a release made
after a press is never undone by that press's late steps. A station that joins later is handed
every live writer's last word (transient-local, or in answer to its first word), and every
station that heard a press says it again, so the press outlives the process that made it
while any station lives."""

from __future__ import annotations

import contextlib
import logging
import os
import socket
import threading
import time
import uuid
from collections.abc import Callable
from dataclasses import asdict, dataclass
from typing import Any

log = logging.getLogger("astiop.robot")
LAST_WORD_S = 1.0  # a station's last word: how long it waits for every reader to have it
ECHO_S = 4.0  # a release made here: how long, at most, its station waits at its close for every
# other station to say it back (a loaded machine may take seconds to deliver it)
SAY_AGAIN_S = 0.5
SETTLE_S = 5.0  # a new station waits at most this for the others' words before it actuates
OPENED_S = 2 * SETTLE_S  # a keeper waits at most this for its channel to open, then settle
HEARD_LEAST_S = 1.0  # a writer's endpoint may be discovered a moment after its participant


@dataclass(frozen=True, order=True)
class Act:
    """A press or a release: when, who, where."""

    at: float
    who: str
    host: str
    pid: int

    @classmethod
    def here(cls, who: str, at: float | None = None) -> Act:
        return cls(time.time() if at is None else at, who, socket.gethostname(), os.getpid())

    @classmethod
    def read(cls, word: Any) -> Act | None:
        if not isinstance(word, dict):
            return None
        try:
            return cls(float(word["at"]), str(word["who"]), str(word["host"]), int(word["pid"]))
        except (KeyError, TypeError, ValueError):
            return None

    @property
    def words(self) -> str:
        when = time.strftime("%H:%M:%S", time.localtime(self.at))
        return f"{self.who} on {self.host} (pid {self.pid}) at {when}"

    def is_here(self) -> bool:
        return self.host == socket.gethostname() and self.pid == os.getpid()


def _covers(theirs: Act | None, mine: Act | None) -> bool:
    """Whether a station that says `theirs` knows of `mine` (or of one newer)."""
    return mine is None or (theirs is not None and theirs >= mine)


def _newer(mine: Act | None, theirs: Act | None) -> Act | None:
    if theirs is None:
        return mine
    return theirs if mine is None or theirs > mine else mine


class StationLatch:
    """One robot's E-STOP as the stations on its graph say it. `open_channel(on_word)` opens the
    robot's `astiop_estop` topic (None: this transport cannot: the latch is then the store's
    alone); `follow()` is called, on a thread of this object's own, whenever what the stations
    say changed (the gateway makes its store and its robot follow)."""

    def __init__(
        self,
        open_channel: Callable[[Callable[[dict[str, Any]], None]], Any],
        follow: Callable[[], object],
    ):
        self.token = uuid.uuid4().hex
        self._open_channel = open_channel
        self._follow = follow
        self._lock = threading.Lock()
        self._press: Act | None = None
        self._release: Act | None = None
        self._channel: Any = None
        self._opening: Any = None  # the channel while it settles: words said, none followed
        self._released_here = False  # a release said by this station, not only heard
        self._ready = threading.Event()
        self._changed = threading.Event()
        self._closed = threading.Event()
        self._thread = threading.Thread(target=self._run, name="estop-graph", daemon=True)

    def start(self) -> StationLatch:
        self._thread.start()
        return self

    # -- what the stations say ------------------------------------------------------------
    @property
    def press(self) -> Act | None:
        return self._press

    @property
    def release(self) -> Act | None:
        return self._release

    @property
    def engaged(self) -> bool:
        press, release = self._press, self._release
        return press is not None and (release is None or press > release)

    @property
    def on_graph(self) -> bool:
        """Whether this station hears the robot's graph (False: the store alone holds it)."""
        return self._channel is not None

    def wait_ready(self, timeout_s: float = SETTLE_S) -> bool:
        """Until the words of the stations already on the graph have been heard (a station
        started later refuses from its first command), or `timeout_s`."""
        return self._ready.wait(timeout_s)

    # -- what this station says -----------------------------------------------------------
    def pressed(self, act: Act) -> None:
        """A press made here: said on the graph at once (never raises)."""
        self._merge(act, None)
        self._say()

    def released(self, act: Act) -> None:
        self._released_here = True
        self._merge(None, act)
        self._say()

    def _merge(self, press: Act | None, release: Act | None) -> bool:
        with self._lock:
            before = (self._press, self._release)
            self._press = _newer(self._press, press)
            self._release = _newer(self._release, release)
            return (self._press, self._release) != before

    def _word(self) -> dict[str, Any]:
        press, release = self._press, self._release
        return {
            "token": self.token,
            "press": asdict(press) if press else None,
            "release": asdict(release) if release else None,
        }

    def _say(self) -> None:
        channel = self._channel or self._opening
        if channel is None:
            return
        try:
            channel.announce(self._word())
        except Exception as exc:  # noqa: BLE001 - the store and this process still hold it
            log.error("the E-STOP could not be said on the robot's graph: %s", exc)

    # -- following ------------------------------------------------------------------------
    def _heard(self, word: dict[str, Any]) -> None:
        """A word from the graph (the executor's thread: only merged here)."""
        if word.get("token") == self.token:
            return
        if self._merge(Act.read(word.get("press")), Act.read(word.get("release"))):
            if self._opening is not None:  # settling: said back now, not once settled
                self._say()
            self._changed.set()

    def _run(self) -> None:
        channel = None
        try:
            channel = self._open_channel(self._heard)
            if channel is not None:
                # said at once, before it settles: a station settling meanwhile (a keeper, a
                # station that started with it) hears this one's word instead of waiting it out
                self._opening = channel
                self._say()
                if not channel.settle(SETTLE_S, HEARD_LEAST_S):
                    log.warning(
                        "not every station on the robot's graph was heard within %.0f s: "
                        "an E-STOP pressed there may not hold here yet",
                        SETTLE_S,
                    )
        except Exception as exc:  # noqa: BLE001 - the store still holds the latch here
            if not self._closed.is_set():  # else: the process ended while it opened
                log.error("the E-STOP is not followed on the robot's graph: %s", exc)
            channel = None
        self._opening = None
        if channel is not None and self._closed.is_set():
            with contextlib.suppress(Exception):  # closed while it opened: never said
                channel.close()
            channel = None
        self._channel = channel
        self._ready.set()
        if self._channel is None:
            return
        self._say()  # a press made as it stopped settling, before `_channel` was set
        while not self._closed.is_set():
            if not self._changed.wait(1.0):
                continue
            self._changed.clear()
            if self._closed.is_set():
                break
            self._say()  # a press heard is said again: it outlives the one who made it
            try:
                self._follow()
            except Exception as exc:  # noqa: BLE001 - looked at again at the next word
                log.error("the E-STOP on the robot's graph could not be followed: %s", exc)

    def close(self) -> None:
        """Done with the robot: this station's last word is heard by every station on the graph
        before its writer goes (a one-shot `astiop estop` ends right after its press or
        release, and its word goes with its writer). A release made here is said until each
        station still on the graph that said the press says it back (`ECHO_S` at most): a
        keeper that missed it would hold the robot stopped for good. A press needs no such
        wait: every station that heard it says it again, and a one-shot press's keeper is
        handed it on its command line."""
        if self._press is not None or self._release is not None:
            self._ready.wait(SETTLE_S)  # its channel opened first: the word is said on it
        self._opening = None
        self._closed.set()
        self._changed.set()
        channel, self._channel = self._channel, None
        if channel is None:
            return
        if self._press is not None or self._release is not None:
            with contextlib.suppress(Exception):
                channel.announce(self._word(), LAST_WORD_S)
        if self._released_here:
            self._wait_for_echo(channel)
        with contextlib.suppress(Exception):
            channel.close()

    def _wait_for_echo(self, channel: Any) -> None:
        deadline = time.monotonic() + ECHO_S
        said = time.monotonic()
        while not self._echoed(channel):
            now = time.monotonic()
            if now >= deadline:
                log.warning("the E-STOP's release was not said back by every station that held it")
                return
            if now - said >= SAY_AGAIN_S:
                with contextlib.suppress(Exception):
                    channel.announce(self._word())
                said = now
            time.sleep(0.05)

    def _echoed(self, channel: Any) -> bool:
        """Whether every other station on the graph heard saying a press says this station's
        release (or a newer one): a station that never held the press holds nothing after it
        either."""
        release = self._release
        try:
            words = channel.words()
        except Exception:  # noqa: BLE001 - the process is ending: nothing more to wait for
            return True
        return all(
            _covers(Act.read(word.get("release")), release)
            for word in words
            if word.get("token") != self.token and Act.read(word.get("press")) is not None
        )
