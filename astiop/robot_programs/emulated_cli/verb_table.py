"""Which method runs which ros2 verb in the emulated `ros2` over DDS: declared on
the method itself, `@runs("topic hz")`, and looked up by the command's key. A verb it does not
serve is refused in one line, never an AttributeError."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, ClassVar

VerbKey = tuple[str, str]


def runs(*verbs: str) -> Callable[[Callable], Callable]:
    """Mark a method as the one that runs these verbs ("topic hz", "service type", ...)."""
    keys = tuple(tuple(verb.split(" ", 1)) for verb in verbs)

    def mark(method: Callable) -> Callable:
        method.__ros2_verbs__ = keys  # type: ignore[attr-defined]
        return method

    return mark


class ServesVerbs:
    """A transport's table of verbs, gathered from its classes' `@runs` once, at class time."""

    VERBS: ClassVar[dict[VerbKey, str]] = {}

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        table: dict[VerbKey, str] = {}
        for klass in reversed(cls.__mro__):
            for name, attr in vars(klass).items():
                for key in getattr(attr, "__ros2_verbs__", ()):
                    table[key] = name
        cls.VERBS = table

    def verb_handler(self, key: VerbKey) -> Callable | None:
        name = self.VERBS.get(key)
        return getattr(self, name) if name is not None else None
