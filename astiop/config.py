"""Settings (pydantic-settings): a TOML file at the XDG config path, then ASTIOP_* variables
(`__` nests: ASTIOP_LLM__THREADS), then CLI flags, each over the one before."""

from __future__ import annotations

import os
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Annotated, Any, Literal

import platformdirs
import tomli_w
from pydantic import BaseModel, ConfigDict, Field, StrictBool, ValidationError, field_validator
from pydantic._internal._utils import deep_update
from pydantic_settings import (
    BaseSettings,
    EnvSettingsSource,
    NoDecode,
    SettingsConfigDict,
    SettingsError,
    TomlConfigSettingsSource,
)

from astiop.bounded import one_line

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

APP_NAME = "astiop"


class ConfigError(Exception):
    """A settings source is malformed; the message is one line naming source, key and problem."""


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid", validate_assignment=True)


class RobotSettings(_Section):
    backend: Literal["sim", "ros2"] = "sim"
    max_linear_speed: float = Field(
        0.8, gt=0, le=1.4, allow_inf_nan=False, description="m/s, clamp on /cmd_vel"
    )
    max_angular_speed: float = Field(
        1.0, gt=0, le=3.0, allow_inf_nan=False, description="rad/s, clamp on /cmd_vel"
    )
    # a safety switch takes only true or false (not "no", 0 or "off")
    confirm_actuation: StrictBool = True
    ros2_executable: str = "ros2"
    # rclpy in process, or the `ros2` executable; auto: rclpy when it and the robot's message
    # packages import, else the CLI
    ros2_transport: Literal["auto", "rclpy", "cli"] = "auto"
    ros2_timeout_s: float = Field(10.0, gt=0, le=3600, allow_inf_nan=False)
    # which names play which role: auto (matched on the graph), a shipped profile's name
    # (astibot, turtlebot3_burger, turtlebot3_waffle) or a profile file's path
    profile: str = "auto"
    namespace: str = Field("", description="the robot's ROS 2 namespace, e.g. /tb3_1")
    # `astiop estop` leaves a keeper that says its press on the robot's graph until released
    estop_keeper: StrictBool = True


class FleetRobot(_Section):
    """One robot of a fleet: its name (what --robot-name takes) and where it is reached."""

    name: str = Field(pattern=r"^[A-Za-z0-9_-]{1,64}$")
    namespace: str = Field(default="", description="its ROS 2 namespace, e.g. /astibot_2")
    profile: str = Field(default="", description="its profile (robot.profile when empty)")


class FleetSettings(_Section):
    # "auto": every namespace on the domain that holds a velocity command and a pose or
    # odometry, named for its namespace (/tb3_2 is tb3_2); "list": the robots below
    discover: Literal["list", "auto"] = "list"
    robots: list[FleetRobot] = Field(default_factory=list)

    @field_validator("robots")
    @classmethod
    def _unique(cls, robots: list[FleetRobot]) -> list[FleetRobot]:
        for key in ("name", "namespace"):
            seen = [getattr(r, key) for r in robots]
            dup = next((v for v in seen if seen.count(v) > 1), None)
            if dup is not None:
                raise ValueError(f"two robots of the fleet have the {key} '{dup}'")
        return robots


class SimSettings(_Section):
    seed: int = Field(0, ge=0, le=2**32 - 1)
    speed: float = Field(
        1.0, gt=0, le=100, allow_inf_nan=False, description="real-time factor of the console's sim"
    )
    battery: float = Field(
        0.85, ge=0, le=1, allow_inf_nan=False, description="the simulated battery's charge at start"
    )


class WatchSettings(_Section):
    builtins: StrictBool = True  # battery, fault, contact, E-STOP, goal, progress, mission alerts
    # %, None: the robot profile's limits.battery_low, else 20
    battery_low: float | None = Field(default=None, ge=0, le=100, allow_inf_nan=False)
    no_progress_s: float = Field(default=30.0, gt=0, le=3600, allow_inf_nan=False)
    hz: float = Field(default=10.0, gt=0, le=50, allow_inf_nan=False)  # `watch run` samples


class LLMSettings(_Section):
    model: str = "embedded"
    mode: Literal["command", "tool"] = "tool"
    threads: int | None = Field(None, ge=1, le=64)
    context: int = Field(4096, ge=512)
    max_tokens: int = Field(256, ge=16, le=8192)
    timeout_s: float = Field(120.0, gt=0, le=86400, allow_inf_nan=False)
    # `model` takes images (OpenAI `image_url` parts, Ollama `images`): a question about the
    # robot's view is sent the camera's frame; never for embedded, gguf or rules
    vision: StrictBool = False
    endpoints: Annotated[list[str], NoDecode] = Field(
        default_factory=list, description="extra specs for `models`; comma-separated in a variable"
    )

    def marks_vision(self, spec: str) -> bool:
        """Whether `spec` is the model `vision` marks: the one named by `model`, not another
        switched to later (`/model` in the console, `chat -m`)."""
        return self.vision and spec.strip() == self.model.strip()

    @field_validator("endpoints", mode="before")
    @classmethod
    def _comma_separated(cls, value: Any) -> Any:
        if isinstance(value, str):
            return [v.strip() for v in value.split(",") if v.strip()]
        return value


class ServeSettings(_Section):
    # the reverse proxies (addresses or networks) whose X-Forwarded-For names the client: behind
    # one, every visitor's address is the proxy's; comma-separated in a variable
    trusted_proxies: Annotated[list[str], NoDecode] = Field(default_factory=list)

    @field_validator("trusted_proxies", mode="before")
    @classmethod
    def _comma_separated(cls, value: Any) -> Any:
        if isinstance(value, str):
            return [v.strip() for v in value.split(",") if v.strip()]
        return value

    @field_validator("trusted_proxies")
    @classmethod
    def _networks(cls, value: list[str]) -> list[str]:
        import ipaddress

        if len(value) > 64:
            raise ValueError("at most 64 trusted proxies")
        for entry in value:
            try:
                ipaddress.ip_network(entry, strict=False)
            except ValueError:
                raise ValueError(f"{entry!r} is not an address or a network") from None
        return value


class ConsoleSettings(_Section):
    # the camera as real pixels where the terminal draws images (Sixel, kitty's protocol),
    # asked of the terminal as the console starts; "cells": half-block cells everywhere
    camera: Literal["auto", "cells"] = "auto"


class Settings(BaseSettings):
    """`Settings()` reads them as astiop does: flags > ASTIOP_* environment > the TOML file."""

    model_config = SettingsConfigDict(
        env_prefix="ASTIOP_",
        env_nested_delimiter="__",
        case_sensitive=False,
        extra="forbid",
        validate_assignment=True,
    )
    db: Path | None = None
    robot: RobotSettings = Field(default_factory=RobotSettings)
    sim: SimSettings = Field(default_factory=SimSettings)
    llm: LLMSettings = Field(default_factory=LLMSettings)
    fleet: FleetSettings = Field(default_factory=FleetSettings)
    serve: ServeSettings = Field(default_factory=ServeSettings)
    watches: WatchSettings = Field(default_factory=WatchSettings)
    console: ConsoleSettings = Field(default_factory=ConsoleSettings)

    @classmethod
    def settings_customise_sources(
        cls, settings_cls, init_settings, env_settings, dotenv_settings, file_secret_settings
    ):
        file = TomlConfigSettingsSource(settings_cls, toml_file=config_path())
        return (init_settings, _Environment(os.environ), file)


# Variables astiop reads that are not settings: where the settings file is, and a secret that
# must never be shown with the settings (the servers' bearer tokens).
NOT_SETTINGS = {"ASTIOP_CONFIG", "ASTIOP_MCP_TOKEN", "ASTIOP_SERVE_TOKEN", "ASTIOP_METRICS_TOKEN"}

# Short names for the variables an operator sets most; any key is ASTIOP_SECTION__KEY.
_ENV_SHORTCUTS = {
    "ASTIOP_DB": "ASTIOP_DB",
    "ASTIOP_MODEL": "ASTIOP_LLM__MODEL",
    "ASTIOP_ROBOT": "ASTIOP_ROBOT__BACKEND",
}


def config_path(env: Mapping[str, str] | None = None) -> Path:
    env = os.environ if env is None else env
    if env.get("ASTIOP_CONFIG"):
        return Path(env["ASTIOP_CONFIG"]).expanduser()
    return platformdirs.user_config_path(APP_NAME) / "config.toml"


def default_db_path() -> Path:
    return platformdirs.user_data_path(APP_NAME) / "astiop.db"


def _describe(err: ValidationError) -> str:
    first = err.errors()[0]
    key = ".".join(str(p) for p in first["loc"]) or "(top level)"
    return f"{key}: {first['msg']}"


class _Environment(EnvSettingsSource):
    """ASTIOP_* variables read from a given mapping (the process's, unless a test gives one)."""

    def __init__(self, env: Mapping[str, str]):
        self._given = env
        super().__init__(Settings)

    def _load_env_vars(self) -> Mapping[str, str | None]:
        return {_ENV_SHORTCUTS.get(k, k).lower(): v for k, v in self._given.items()}

    def __call__(self) -> dict[str, Any]:
        return _switches(super().__call__(), Settings)


def _switches(data: dict[str, Any], model: Any) -> dict[str, Any]:
    """A switch spelled true or false in a variable is that boolean; any other word is left
    for validation to refuse (a file's switch must be a TOML boolean)."""
    for key, value in data.items():
        field = getattr(model, "model_fields", {}).get(key)
        if field is None:
            continue
        if isinstance(value, dict):
            _switches(value, field.annotation)
        elif field.annotation is bool and str(value).strip().lower() in ("true", "false"):
            data[key] = str(value).strip().lower() == "true"
    return data


def _unknown_variable(env: Mapping[str, str]) -> str | None:
    """The first ASTIOP_* variable that names no setting (a typo must not pass unnoticed)."""
    for name in env:
        if not name.startswith("ASTIOP_") or name in NOT_SETTINGS:
            continue
        model: Any = Settings
        for part in _ENV_SHORTCUTS.get(name, name)[len("ASTIOP_") :].lower().split("__"):
            fields = getattr(model, "model_fields", {})
            if part not in fields:
                return name
            model = fields[part].annotation
    return None


def _file_values(path: Path) -> dict[str, Any]:
    if not path.exists():
        return {}
    try:
        return TomlConfigSettingsSource(Settings, toml_file=path)()
    except RecursionError:
        raise ConfigError(f"{path}: the TOML nests too deeply to read") from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"config error: {path}: invalid TOML: {exc}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"config error: {path}: cannot read: {exc}") from None


def _validated(data: dict[str, Any], source: str) -> Settings:
    try:
        return Settings.model_validate(data)  # validates only: reads no source itself
    except ValidationError as exc:
        raise ConfigError(f"{source}: {_describe(exc)}") from None


def load_settings(
    overrides: Mapping[str, Any] | None = None,
    *,
    env: Mapping[str, str] | None = None,
    path: Path | None = None,
) -> Settings:
    """Flags (`overrides`, nested) over ASTIOP_* variables over the TOML file; an error names
    the source that brought the bad value."""
    env = os.environ if env is None else env
    path = path or config_path(env)
    data = _file_values(path)
    _validated(data, f"config error: {path}")
    if (name := _unknown_variable(env)) is not None:
        raise ConfigError(f"config error: {name} names no setting (see: astiop config show)")
    try:
        data = deep_update(data, _Environment(env)())
    except SettingsError as exc:
        raise ConfigError(f"config error: ASTIOP_* environment: {one_line(exc, 300)}") from None
    settings = _validated(data, "config error: ASTIOP_* environment")
    if overrides:
        settings = _validated(deep_update(settings.model_dump(), dict(overrides)), "bad option")
    return settings


def to_toml(settings: Settings) -> str:
    """The effective settings as a TOML file an operator can save and edit (tomli-w); unset
    keys are listed as comments, since TOML has no null."""
    data = settings.model_dump(mode="json")
    unset = [k for k, v in data.items() if v is None]
    unset += [f"{t}.{k}" for t, vs in data.items() if isinstance(vs, dict)
              for k, v in vs.items() if v is None]  # fmt: skip
    clean = {
        k: ({kk: vv for kk, vv in v.items() if vv is not None} if isinstance(v, dict) else v)
        for k, v in data.items()
        if v is not None
    }
    head = "".join(f"# {key} is unset\n" for key in unset)
    return head + tomli_w.dumps(clean)
