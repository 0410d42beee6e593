"""Does a model endpoint answer, and what does it serve: the one check `models`, `doctor` and
the dashboard share."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

from astiop.agent.models.embedded import EmbeddedModelError, smollm2_path
from astiop.agent.models.llm import LLMError
from astiop.agent.models.specs import LLMEndpoint, SpecError, open_endpoint


@dataclass
class Reach:
    spec: str
    answers: bool = False
    serves: list[str] = field(default_factory=list)
    detail: str = ""

    def as_json(self) -> dict:
        return asdict(self)


async def probe(spec: str | LLMEndpoint) -> Reach:
    """Rules always answer; a local GGUF answers when its file is there (the server starts
    on demand); a server answers when it lists its models within 5 s."""
    try:
        ep = spec if isinstance(spec, LLMEndpoint) else open_endpoint(spec)
    except SpecError as exc:
        return Reach(str(spec), detail=str(exc))
    reach = Reach(ep.spec.raw)
    if ep.is_rules:
        reach.answers, reach.detail = True, "rule-based baseline, no LLM"
    elif ep.local:
        try:
            path = smollm2_path() if ep.spec.kind == "embedded" else ep.spec.path
            reach.answers, reach.serves = True, [path.stem]
            reach.detail = f"started on demand from {path}"
        except EmbeddedModelError as exc:
            reach.detail = str(exc)
    else:
        try:
            found = await ep.client().list_models()
            reach.answers, reach.serves = True, [m.name for m in found]
            reach.detail = f"answers at {ep.spec.url}, serving {len(found)} model(s)"
            if ep.spec.name and ep.spec.name not in reach.serves:
                reach.detail = f"{ep.spec.name} is not among the served models"
        except LLMError as exc:
            reach.detail = str(exc)
    return reach
