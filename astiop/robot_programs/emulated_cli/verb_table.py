"""Which method runs which ros2 verb in the emulated `ros2`: declared on the method itself,
`@runs("topic hz")`, and looked up by the command's key in a `VerbTable` of the objects that
serve verbs. A verb none of them serves is refused in one line, never an AttributeError."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

VerbKey = tuple[str, str]
Handler = Callable[..., Any]  # (call, args) -> exit status, or a string printed as the error


def runs(*verbs: str) -> Callable[[Handler], Handler]:
    """Mark a method as the one that runs these verbs ("topic hz", "service type", ...)."""
    keys = tuple(tuple(verb.split(" ", 1)) for verb in verbs)

    def mark(method: Handler) -> Handler:
        method.__ros2_verbs__ = keys  # type: ignore[attr-defined]
        return method

    return mark


def marked(cls: type) -> dict[VerbKey, str]:
    """The verbs a class's `@runs` methods run, each with its method's name (a subclass's
    method over its base's)."""
    table: dict[VerbKey, str] = {}
    for klass in reversed(cls.__mro__):
        for name, attr in vars(klass).items():
            for key in getattr(attr, "__ros2_verbs__", ()):
                table[key] = name
    return table


def served(classes: Iterable[type]) -> frozenset[VerbKey]:
    """The verbs objects of these classes run, between them: known without building one."""
    return frozenset(key for cls in classes for key in marked(cls))


class VerbTable:
    """The verbs these objects run, each to the bound method that runs it. Two objects that
    run one verb are a mistake, refused when the table is built."""

    def __init__(self, *servers: object):
        self._handlers: dict[VerbKey, Handler] = {}
        for server in servers:
            for key, name in marked(type(server)).items():
                if key in self._handlers:
                    raise ValueError(f"ros2 {' '.join(key)} is run twice")
                self._handlers[key] = getattr(server, name)

    def handler(self, key: tuple[Any, Any]) -> Handler | None:
        """The method that runs this verb, or None when no object here runs it."""
        return self._handlers.get(key)

    def keys(self) -> frozenset[VerbKey]:
        return frozenset(self._handlers)
