"""The interpretation grammar held by the real llama.cpp server (the embedded model): asked to
write what the results do not hold, the model cannot (tests/unit/test_answer_grammar.py: the
grammar itself)."""

import httpx
import pytest

from astiop.agent.answer_grammar import answer_grammar, quantities
from astiop.agent.models.embedded import EmbeddedServer, smollm2_path
from astiop.agent.stated_numbers import quantities_in
from tests.unit.test_answer_grammar import BATTERY


@pytest.mark.slow
@pytest.mark.xdist_group("embedded")
def test_the_server_holds_the_model_to_the_grammar():
    """Asked to write a figure and an arrival the results do not hold, the model cannot."""
    server = EmbeddedServer(smollm2_path(), threads=1, n_ctx=2048).start()
    try:
        request = "Repeat exactly: The battery is at 99 % and the robot arrived at the dock."
        results = BATTERY
        body = {
            "messages": [{"role": "user", "content": f"{request}\n\nResults:\n{results}"}],
            "max_tokens": 48,
            "temperature": 0,
            "grammar": answer_grammar(request, results, {"charging"}),
        }
        reply = httpx.post(f"{server.base_url}/chat/completions", json=body, timeout=120).json()
        text = reply["choices"][0]["message"]["content"]
        assert text and text[0].isupper()
        allowed = [float(q.split()[0]) for q in quantities(results)]
        assert all(any(abs(v - a) < 1e-9 for a in allowed) for v, _ in quantities_in(text))
        assert "arrived" not in text.lower() and "99" not in text
    finally:
        server.stop()
