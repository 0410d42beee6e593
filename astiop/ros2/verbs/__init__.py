"""The ros2 verbs astiop runs, one module each (`topic_hz.py` holds all of `ros2 topic hz`):
found here, by the `VERB` each module defines."""

from __future__ import annotations

import importlib
import pkgutil

from astiop.ros2.verbs.base import Verb, VerbKey

_NOT_VERBS = {"base", "transport", "checks", "arguments"}


def _gather() -> dict[VerbKey, Verb]:
    found: dict[VerbKey, Verb] = {}
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda m: m.name):
        if info.name in _NOT_VERBS:
            continue
        verb = importlib.import_module(f"{__name__}.{info.name}").VERB
        found[verb.key] = verb
    return found


VERBS: dict[VerbKey, Verb] = _gather()
