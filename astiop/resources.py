"""Where the shipped `data/` and `prompts/` folders are, installed or in a checkout."""

from __future__ import annotations

from pathlib import Path

_PACKAGE = Path(__file__).resolve().parent


def resource_dir(name: str) -> Path:
    # A wheel carries them inside the package; an editable checkout has them at the top.
    for candidate in (_PACKAGE / name, _PACKAGE.parent / name):
        if candidate.is_dir():
            return candidate
    raise FileNotFoundError(f"astiop's {name}/ folder is missing from the installation")


def data_path(*parts: str) -> Path:
    return resource_dir("data").joinpath(*parts)


def prompts_path(*parts: str) -> Path:
    return resource_dir("prompts").joinpath(*parts)
