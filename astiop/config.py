"""Settings: a TOML file at the XDG config path, then ASTIOP_* variables, then CLI flags."""

from __future__ import annotations

import os
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Literal

import platformdirs
import tomli_w
from pydantic import BaseModel, ConfigDict, Field, StrictBool, ValidationError

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
    ros2_timeout_s: float = Field(10.0, gt=0, le=3600, allow_inf_nan=False)


class SimSettings(_Section):
    seed: int = Field(0, ge=0, le=2**32 - 1)
    speed: float = Field(
        1.0, gt=0, le=100, allow_inf_nan=False, description="real-time factor of the console's sim"
    )


class LLMSettings(_Section):
    model: str = "embedded"
    mode: Literal["command", "tool"] = "tool"
    threads: int | None = Field(None, ge=1, le=64)
    context: int = Field(4096, ge=512)
    max_tokens: int = Field(256, ge=16, le=8192)
    timeout_s: float = Field(120.0, gt=0, le=86400, allow_inf_nan=False)
    endpoints: list[str] = Field(default_factory=list, description="extra specs for `models`")


class Settings(_Section):
    db: Path | None = None
    robot: RobotSettings = Field(default_factory=RobotSettings)
    sim: SimSettings = Field(default_factory=SimSettings)
    llm: LLMSettings = Field(default_factory=LLMSettings)


# Short names for the variables an operator sets most; any key is ASTIOP_SECTION__KEY.
_ENV_SHORTCUTS = {
    "ASTIOP_DB": ("db",),
    "ASTIOP_MODEL": ("llm", "model"),
    "ASTIOP_ROBOT": ("robot", "backend"),
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


def _set_nested(data: dict[str, Any], keys: tuple[str, ...], value: Any) -> None:
    for key in keys[:-1]:
        data = data.setdefault(key, {})
        if not isinstance(data, dict):
            raise ConfigError(f"config: {'.'.join(keys)}: parent is not a table")
    data[keys[-1]] = value


def _env_values(env: Mapping[str, str]) -> dict[str, Any]:
    values: dict[str, Any] = {}
    for name, raw in env.items():
        if not name.startswith("ASTIOP_") or name == "ASTIOP_CONFIG":
            continue
        if name in _ENV_SHORTCUTS:
            keys = _ENV_SHORTCUTS[name]
        elif "__" in name:
            keys = tuple(part.lower() for part in name[len("ASTIOP_") :].split("__"))
        else:
            continue
        value: Any = raw
        if raw.strip().lower() in ("true", "false"):  # a TOML boolean, spelled in a variable
            value = raw.strip().lower() == "true"
        if keys[-1] == "endpoints":
            value = [v.strip() for v in raw.split(",") if v.strip()]
        _set_nested(values, keys, value)
    return values


def _merge(base: dict[str, Any], extra: Mapping[str, Any]) -> dict[str, Any]:
    merged = dict(base)
    for key, value in extra.items():
        if isinstance(value, Mapping) and isinstance(merged.get(key), dict):
            merged[key] = _merge(merged[key], value)
        else:
            merged[key] = value
    return merged


def read_config_file(path: Path) -> dict[str, Any]:
    if not path.exists():
        return {}
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except RecursionError:
        raise ConfigError(f"{path}: the TOML nests too deeply to read") from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"config error: {path}: invalid TOML: {exc}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"config error: {path}: cannot read: {exc}") from None


def load_settings(
    overrides: Mapping[str, Any] | None = None,
    *,
    env: Mapping[str, str] | None = None,
    path: Path | None = None,
) -> Settings:
    """File, then environment, then `overrides` (nested dict from CLI flags)."""
    env = os.environ if env is None else env
    path = path or config_path(env)
    file_data = read_config_file(path)
    try:
        Settings.model_validate(file_data)
    except ValidationError as exc:
        raise ConfigError(f"config error: {path}: {_describe(exc)}") from None
    merged = _merge(file_data, _env_values(env))
    try:
        settings = Settings.model_validate(merged)
    except ValidationError as exc:
        raise ConfigError(f"config error: ASTIOP_* environment: {_describe(exc)}") from None
    if overrides:
        try:
            settings = Settings.model_validate(_merge(settings.model_dump(), overrides))
        except ValidationError as exc:
            raise ConfigError(f"bad option: {_describe(exc)}") from None
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
