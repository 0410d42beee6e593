"""The embedded model's KV cache of its fixed prompts, kept on disk so a new process starts warm.

Each kind of call (planning, interpretation) begins with the same system prompt and examples
on every request. The embedded server keeps one slot per kind (the client sends `id_slot`, so
one kind never evicts the other); after a call whose prefix is not on disk yet, the slot is cut
back to that prefix (the messages before the request) and saved (llama.cpp's
`POST /slots/{id}?action=save`), and at the next start each file is restored into its slot
(`action=restore`) before the first request.

Why a restore does not change a reply: llama.cpp keeps the tokens with their K and V, and on
the next request reuses only the longest common prefix of those tokens and the request's (a
causal model's K and V at a position depend on the tokens up to it alone); the rest is
evaluated as usual. A changed prompt therefore reuses only what is still the same, and its
next call saves the slot anew. The numbers are the same as a cold prefill's only with
`EmbeddedServer`'s settings (a KV cache per slot, flash attention off), and only while part of
the prompt is left to evaluate: a prompt found whole in the slot (the same call again) has its
last token evaluated alone, which rounds differently. Hence a file holds the prefix only, and a
call that repeats the slot's last one starts from that file. What else the numbers depend on (the model file's sha256, xllamacpp's version
and build, the context and cache layout) names the files' build; each file is named for the
sha256 of its content too, checked before a restore. A file that is missing, damaged or of
another build is skipped (and replaced after the next call), never an error. Files and the
index are written under a temporary name and renamed, so two processes at once can only miss
each other's cache, never read half of one.
"""

from __future__ import annotations

import asyncio
import contextlib
import hashlib
import json
import os
import re
import secrets
import threading
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import platformdirs

from astiop.config import APP_NAME

if TYPE_CHECKING:
    import httpx

    from astiop.agent.models.llm import Messages

FORMAT = 1  # of the index and of what a build is named for
SLOTS = 2  # planning and interpretation, each in its own slot
MAX_INDEX_BYTES = 64 * 1024
ORPHAN_AFTER_S = 60.0  # a file no index names, this old, is no other process's either
STALE_AFTER_S = 7 * 24 * 3600.0  # a build not used for a week (an old model or xllamacpp)
_STATE_FILE = re.compile(r"^[0-9a-f]{16}-[0-9a-f]{32}\.bin$")


def default_cache_dir() -> Path:
    """Under the user's cache folder ($XDG_CACHE_HOME/astiop on Linux): safe to delete."""
    return platformdirs.user_cache_path(APP_NAME) / "prompt-cache"


def _client(base_url: str) -> httpx.Client:
    import httpx

    from astiop.agent.models.llm import tls_for

    return httpx.Client(timeout=30.0, verify=tls_for(base_url))


def _sha256(data: str) -> str:
    return hashlib.sha256(data.encode("utf-8")).hexdigest()


def file_sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with path.open("rb") as fh:
        while chunk := fh.read(1 << 20):
            digest.update(chunk)
    return digest.hexdigest()


_INTACT: dict[tuple[str, int, int, int], bool] = {}  # a file's version -> whether intact


def intact(path: Path, digest: str) -> bool:
    """Whether the file's sha256 begins with `digest`: hashed once per version of the file (its
    size, mtime and inode) in this process, not at each restore."""
    st = path.stat()
    key = (str(path), st.st_size, st.st_mtime_ns, st.st_ino)
    if key not in _INTACT:
        _INTACT[key] = file_sha256(path).startswith(digest)
    return _INTACT[key]


def check_files(directory: Path) -> None:
    """Hashes the files the indexes name, e.g. while the model loads, so a restore need not."""
    for index in Path(directory).glob("slots-*.json"):
        for raw in _slots_of(_read_json(index)):
            name = raw.get("file") if isinstance(raw, dict) else None
            if isinstance(name, str) and _STATE_FILE.match(name):
                with contextlib.suppress(OSError):
                    intact(Path(directory) / name, name[17:49])


def _slots_of(index: Any) -> list:
    """An index's list of slots, or none when it is not one."""
    slots = index.get("slots") if isinstance(index, dict) else None
    return slots if isinstance(slots, list) else []


def _read_json(path: Path) -> Any:
    """The file's JSON, or None when it is missing, too big or not JSON."""
    try:
        if path.stat().st_size > MAX_INDEX_BYTES:
            return None
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError, RecursionError):
        return None


def _write_json(path: Path, data: Any) -> None:
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp")
    try:
        tmp.write_text(json.dumps(data, indent=1), encoding="utf-8")
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def model_sha256(path: Path, directory: Path) -> str:
    """The model file's sha256, remembered for its size, mtime and inode (hashing ~100 MB
    takes 0.15 s, once per model file)."""
    st = path.stat()
    key, stamp = str(path.resolve()), [st.st_size, st.st_mtime_ns, st.st_ino]
    memo_path = directory / "models.json"
    memo = _read_json(memo_path)
    memo = memo if isinstance(memo, dict) else {}
    seen = memo.get(key)
    if (
        isinstance(seen, dict)
        and seen.get("stamp") == stamp
        and isinstance(seen.get("sha256"), str)
    ):
        return seen["sha256"]
    digest = file_sha256(path)
    memo[key] = {"stamp": stamp, "sha256": digest}
    try:
        directory.mkdir(parents=True, exist_ok=True)
        _write_json(memo_path, memo)
    except OSError:
        pass  # hashed again next time
    return digest


def system_of(messages: Messages) -> str | None:
    """What kind of call this is: the sha256 of its system prompt (None without one)."""
    if messages and messages[0].get("role") == "system":
        return _sha256(str(messages[0].get("content", "")))
    return None


def prefix_of(messages: Messages, n: int) -> str:
    return _sha256(json.dumps(messages[:n], sort_keys=True, ensure_ascii=False))


@dataclass
class SlotFile:
    """What one slot holds on disk: the kind of call, the messages before its request, the file."""

    system: str
    prefix: str  # sha256 of the first `n` messages
    n: int
    file: str

    @classmethod
    def parse(cls, raw: Any, build: str) -> SlotFile | None:
        if not isinstance(raw, dict):
            return None
        try:
            entry = cls(str(raw["system"]), str(raw["prefix"]), int(raw["n"]), str(raw["file"]))
        except (KeyError, TypeError, ValueError):
            return None
        ok = _STATE_FILE.match(entry.file) and entry.file.startswith(build) and entry.n >= 1
        return entry if ok else None  # a name is never a path: no '/' or '..' reaches the server


@dataclass
class _Slot:
    system: str
    saved: SlotFile | None  # None: what the slot holds is not on disk
    used: float
    last: str = ""  # sha256 of the messages of the slot's last call


class PromptCache:
    """The slots of one embedded server and their files under `directory`."""

    def __init__(self, directory: Path, identity: dict[str, Any], slots: int = SLOTS):
        self.directory = Path(directory)
        self.build = _sha256(json.dumps({"format": FORMAT, **identity}, sort_keys=True))[:16]
        self._slots: list[_Slot | None] = [None] * slots
        self._lock = threading.Lock()
        self._base = ""
        self.restored: list[tuple[int, int]] = []  # (slot, tokens) restored at start
        self.saves = 0

    @property
    def index_path(self) -> Path:
        return self.directory / f"slots-{self.build}.json"

    # -- at start ------------------------------------------------------------------------
    def restore(self, base_url: str) -> None:
        """Each slot's file into its slot, before the first request; what fails is skipped."""
        import httpx  # ~0.1 s to import: not before the model's process is launched

        self._base = base_url
        entries = self._read_index()
        if not any(entries):
            return
        try:
            with _client(base_url) as client:
                for slot, entry in enumerate(entries):
                    if entry is not None:
                        self._restore_one(client, slot, entry)
            os.utime(self.index_path)  # in use: not stale
        except (OSError, httpx.HTTPError):
            pass

    def _restore_one(self, client: httpx.Client, slot: int, entry: SlotFile) -> None:
        tokens = self._load(client, slot, entry)
        if tokens is None:
            return
        with self._lock:
            self._slots[slot] = _Slot(entry.system, entry, time.monotonic())
        self.restored.append((slot, tokens))

    def _load(self, client: httpx.Client, slot: int, entry: SlotFile) -> int | None:
        """The file into the slot, if intact; the tokens it held, or None."""
        path = self.directory / entry.file
        try:
            ok = intact(path, entry.file[17:49])
        except OSError:
            return None
        if not ok:
            path.unlink(missing_ok=True)  # damaged: the next call writes it anew
            return None
        resp = client.post(
            f"{self._base}/slots/{slot}?action=restore", json={"filename": entry.file}
        )
        if resp.status_code != 200:
            return None  # e.g. it no longer fits the context: the slot is left as it was
        try:
            return int(resp.json().get("n_restored", 0))
        except (ValueError, AttributeError, TypeError):
            return 0

    # -- around each call (the client's SlotRouter) --------------------------------------
    async def slot_for(self, messages: Messages) -> int | None:
        """The slot of this kind of call; a new kind takes a free slot, else the least recently
        used one. None (the server chooses) for a call without a system prompt."""
        system = system_of(messages)
        if system is None:
            return None
        with self._lock:
            slot, again = self._assign(system, _sha256(json.dumps(messages, sort_keys=True)))
        if again:  # the slot holds this very prompt: start from the prefix, as a new process
            await asyncio.to_thread(self._reset, slot)
        return slot

    def _assign(self, system: str, call: str) -> tuple[int, bool]:
        now = time.monotonic()
        for i, held in enumerate(self._slots):
            if held is not None and held.system == system:
                held.used = now
                return i, held.last == call
        free = [i for i, held in enumerate(self._slots) if held is None]
        i = free[0] if free else min(range(len(self._slots)), key=self._last_used)
        self._slots[i] = _Slot(system, None, now)
        return i, False

    def _reset(self, slot: int) -> None:
        """The slot back to its saved prefix; without one, emptied (a cold prefill follows)."""
        import httpx

        with self._lock:
            held = self._slots[slot]
            saved = held.saved if held is not None else None
        try:
            with _client(self._base) as client:
                if saved is None or self._load(client, slot, saved) is None:
                    client.post(f"{self._base}/slots/{slot}?action=erase")
        except (OSError, httpx.HTTPError):
            pass

    def _last_used(self, i: int) -> float:
        held = self._slots[i]
        return held.used if held is not None else 0.0

    async def kept(self, slot: int, messages: Messages) -> None:
        """After a call in `slot`: save its prefix unless the slot's file already begins it."""
        n = len(messages) - 1
        with self._lock:
            held = self._slots[slot] if 0 <= slot < len(self._slots) else None
            if held is None or held.system != system_of(messages):
                return
            held.last = _sha256(json.dumps(messages, sort_keys=True))
            if n < 1 or not self._base or not messages[n].get("content"):
                return
            saved = held.saved
            if saved is not None and saved.n <= n and prefix_of(messages, saved.n) == saved.prefix:
                return  # the common case: nothing to do
            entry = SlotFile(held.system, prefix_of(messages, n), n, "")
        cut = [*messages[:n], {"role": messages[n].get("role", "user"), "content": ""}]
        await asyncio.to_thread(self._save, slot, cut, entry)

    def _save(self, slot: int, cut: Messages, entry: SlotFile) -> None:
        import httpx

        tmp = self.directory / f"tmp-{os.getpid()}-{secrets.token_hex(6)}.bin"
        try:
            self.directory.mkdir(parents=True, exist_ok=True)
            with _client(self._base) as client:
                # The slot cut back to the prefix: the call with its request emptied (one
                # token generated, not kept). The prompt parts where the request began, so only
                # the tokens after that are evaluated: the prefix keeps the call's numbers.
                resp = client.post(
                    f"{self._base}/v1/chat/completions",
                    json={
                        "messages": cut,
                        "max_tokens": 1,
                        "temperature": 0.0,
                        "id_slot": slot,
                        "cache_prompt": True,
                    },
                )
                if resp.status_code != 200:
                    return
                resp = client.post(
                    f"{self._base}/slots/{slot}?action=save", json={"filename": tmp.name}
                )
            if resp.status_code != 200:
                return
            entry.file = f"{self.build}-{file_sha256(tmp)[:32]}.bin"
            os.replace(tmp, self.directory / entry.file)
            with self._lock:
                held = self._slots[slot]
                if held is not None and held.system == entry.system:
                    held.saved, held.last = entry, ""
            self._write_index(slot, entry)
            self.saves += 1
            self._prune()
        except (OSError, httpx.HTTPError):
            pass  # no cache this time; never the turn's failure
        finally:
            tmp.unlink(missing_ok=True)

    # -- the index -----------------------------------------------------------------------
    def _read_index(self) -> list[SlotFile | None]:
        raw = _slots_of(_read_json(self.index_path))
        entries = [SlotFile.parse(r, self.build) for r in raw[: len(self._slots)]]
        return entries + [None] * (len(self._slots) - len(entries))

    def _write_index(self, slot: int, entry: SlotFile) -> None:
        entries = self._read_index()  # another process's other slot stays as it wrote it
        entries[slot] = entry
        slots = [asdict(e) if e else None for e in entries]
        _write_json(self.index_path, {"format": FORMAT, "slots": slots})

    def _prune(self) -> None:
        """Files no index names (replaced, or left by a process that died), and builds not used
        for a week."""
        now, named = time.time(), set()
        for index in self.directory.glob("slots-*.json"):
            try:
                if now - index.stat().st_mtime > STALE_AFTER_S:
                    index.unlink()
                    continue
            except OSError:
                continue
            for raw in _slots_of(_read_json(index)):
                if isinstance(raw, dict) and isinstance(raw.get("file"), str):
                    named.add(raw["file"])
        for path in self.directory.glob("*.bin"):
            try:
                if path.name not in named and now - path.stat().st_mtime > ORPHAN_AFTER_S:
                    path.unlink()
            except OSError:
                pass
