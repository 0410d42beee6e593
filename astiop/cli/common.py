"""What every subcommand shares: the resolved settings, the store, one-line errors."""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, NoReturn

import typer

from astiop.bounded import one_line
from astiop.config import ConfigError, Settings, default_db_path, load_settings

if TYPE_CHECKING:
    from astiop.store import Store

USER_ERROR = 2


class Ending:
    """Whether the command has written and closed all it had: then the executable ends at once,
    without Python's teardown of the loaded modules (0.1-0.2 s of a cold `astiop chat`)."""

    at_once = False


def fail(message: str, code: int = USER_ERROR) -> NoReturn:
    typer.echo(f"astiop: {one_line(message, 1000)}", err=True)
    raise typer.Exit(code)


def interactive() -> bool:
    """Whether a person can answer a y/n prompt (stdin may be closed: `<&-`)."""
    try:
        return sys.stdin is not None and sys.stdin.isatty()
    except (ValueError, OSError):  # closed or detached
        return False


def print_json(data: Any) -> None:
    typer.echo(json.dumps(data, indent=2, default=str))


@dataclass
class CliState:
    overrides: dict[str, Any] = field(default_factory=dict)
    robot_name: str | None = None  # --robot-name: one robot of the fleet
    take: bool = False  # --take: control of a shared robot taken over
    _settings: Settings | None = None
    _store: Store | None = None

    @property
    def fleet_settings(self) -> Settings:
        """The settings as read, before --robot-name picks one robot of the fleet."""
        try:
            return load_settings(self.overrides)
        except ConfigError as exc:
            fail(str(exc))

    def address(self, robot_name: str) -> None:
        """From now on, the fleet's robot `robot_name` (as --robot-name would): its settings
        are read again."""
        self.robot_name, self._settings = robot_name, None

    @property
    def settings(self) -> Settings:
        if self._settings is None:
            try:
                self._settings = load_settings(self.overrides)
            except ConfigError as exc:
                fail(str(exc))
            if self.robot_name is not None:
                from astiop.robot.fleet import FleetError, robot_settings

                try:
                    self._settings = robot_settings(self._settings, self.robot_name)
                except FleetError as exc:
                    fail(str(exc))
            if not self._settings.robot.confirm_actuation:
                typer.echo(
                    "astiop: warning: robot.confirm_actuation is false: actuating commands run "
                    "without asking",
                    err=True,
                )
        return self._settings

    @property
    def db_path(self):
        return self.settings.db or default_db_path()

    @property
    def store(self) -> Store:
        if self._store is None:
            from astiop.store import Store, StoreError  # sqlite-utils: not for every command

            try:
                self._store = Store(self.db_path)
            except StoreError as exc:
                fail(str(exc))
            except OSError as exc:
                fail(f"cannot open database {self.db_path}: {exc.strerror or exc}")
        return self._store


def take_control(gateway, st: CliState) -> None:
    """Control of a shared robot for this command (its lease; --take: from whoever holds it).
    Refused, the command still reads; its motion commands are refused, saying who controls."""
    refused = gateway.take_control(force=st.take)
    if refused:
        typer.echo(f"astiop: {refused}: nothing will move it from here (--take)", err=True)


def state(ctx: typer.Context) -> CliState:
    obj = ctx.find_root().obj
    if not isinstance(obj, CliState):  # called outside the root callback (tests)
        obj = CliState()
        ctx.find_root().obj = obj
    return obj
