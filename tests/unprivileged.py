"""Commands run as a user whom file modes bind, so a permission test means what it says where the
suite runs as root (CI does): root writes through a read-only file or folder."""

from __future__ import annotations

import contextlib
import functools
import os
import shutil
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest

NOBODY = "65534"  # nobody and its group (nogroup on Debian, nobody on Fedora): numbers travel

# What the user may not do is what the test is about. It keeps one capability,
# CAP_DAC_READ_SEARCH: reading and searching any folder, so it reaches the interpreter (a venv's
# python links into /root/.pyenv, mode 0700) and pytest's tmp_path (0700). Writing is still
# bound by the file modes, and os.access() ignores capabilities for a user other than root.
SETPRIV = (
    f"--reuid={NOBODY}", f"--regid={NOBODY}", "--clear-groups",
    "--inh-caps=+dac_read_search", "--ambient-caps=+dac_read_search",
)  # fmt: skip


@functools.cache
def _prefix() -> tuple[list[str], str]:
    """The argv prefix that runs a command as that user, and why there is none ("" if there is)."""
    if os.geteuid() != 0:
        return [], ""  # this user is bound by file modes already (checked by each test)
    setpriv = shutil.which("setpriv")
    if setpriv is None:
        return [], "running as root without setpriv (util-linux) to become an unprivileged user"
    prefix = [setpriv, *SETPRIV]
    probe = [*prefix, sys.executable, "-c", "import os, astiop; print(os.geteuid())"]
    out = subprocess.run(
        probe, capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL
    )
    if out.returncode != 0 or out.stdout.strip() != NOBODY:
        why = (out.stderr.strip().splitlines() or ["no error"])[-1]
        return [], f"running as root, and setpriv cannot run python as user {NOBODY}: {why}"
    return prefix, ""


def unprivileged_prefix() -> list[str]:
    """Skip where no unprivileged user is at hand, unless CI demands the test
    (REQUIRE_PERMISSION_TESTS=1): then fail."""
    prefix, why = _prefix()
    if why and os.environ.get("REQUIRE_PERMISSION_TESTS") == "1":
        pytest.fail(why)
    if why:
        pytest.skip(why)
    return prefix


def run_unprivileged(*argv: str) -> subprocess.CompletedProcess:
    """`argv` (after the interpreter) run by this interpreter as the unprivileged user."""
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1"}  # the repo is not that user's to write
    cmd = [*unprivileged_prefix(), sys.executable, *argv]
    return subprocess.run(
        cmd, capture_output=True, text=True, timeout=60, stdin=subprocess.DEVNULL, env=env
    )


def astiop_unprivileged(*args: str) -> subprocess.CompletedProcess:
    """`astiop ARGS` as a process of the unprivileged user."""
    return run_unprivileged("-m", "astiop", *args)


@contextlib.contextmanager
def reachable_folder() -> Iterator[Path]:
    """A folder of this user's that the unprivileged one reaches and reads (pytest's tmp_path
    lies under a folder of mode 0700, and click checks a path with os.access, no capability)."""
    folder = Path(tempfile.mkdtemp(prefix="astiop-unprivileged-"))
    try:
        folder.chmod(0o755)
        yield folder
    finally:
        for path in (folder, *folder.rglob("*")):  # a test may leave a mode that bars removal
            if path.is_dir():
                path.chmod(0o755)
        shutil.rmtree(folder)
