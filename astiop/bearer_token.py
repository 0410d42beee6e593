"""Where a server of astiop's (`astiop mcp --http`, `astiop serve`) gets its token: a file only
its owner can read, or the environment; never the command line, which every user on the machine
sees in `ps`."""

from __future__ import annotations

import os
import re
import stat
from collections.abc import Mapping
from pathlib import Path

MCP_TOKEN = "ASTIOP_MCP_TOKEN"
SERVE_TOKEN = "ASTIOP_SERVE_TOKEN"
METRICS_TOKEN = "ASTIOP_METRICS_TOKEN"
MIN_CHARS = 16
MAX_CHARS = 1024
MAX_FILE_BYTES = 4096
# what an HTTP header carries as is: visible ASCII, no spaces
TOKEN_RE = re.compile(rf"^[\x21-\x7e]{{{MIN_CHARS},{MAX_CHARS}}}$")


def where(variable: str, flag: str = "--token-file") -> str:
    return f"{flag} F (mode 600) or {variable}"


class TokenError(Exception):
    """The token cannot be used; the message is one line that says why and what to do."""


def check(token: str, source: str) -> str:
    if not token:
        raise TokenError(f"{source} is empty")
    if len(token) < MIN_CHARS:
        raise TokenError(f"{source}: the token is {len(token)} characters; it needs {MIN_CHARS}")
    if not TOKEN_RE.match(token):
        raise TokenError(
            f"{source}: the token must be printable ASCII with no spaces, at most {MAX_CHARS} "
            "characters"
        )
    return token


def read_token_file(path: Path, flag: str = "--token-file") -> str:
    """The token in `path`: its one line, without the newline. Refused, as ssh refuses an
    unprotected private key, when others may read or write the file."""
    source = f"{flag} {path}"
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOCTTY | os.O_NONBLOCK)
    except OSError as exc:
        raise TokenError(f"{source}: cannot read: {exc.strerror or exc}") from None
    try:
        info = os.fstat(fd)  # the file opened, not the name: no swap in between
        if stat.S_ISDIR(info.st_mode):
            raise TokenError(f"{source} is a folder, not a file")
        if stat.S_ISREG(info.st_mode) and info.st_mode & 0o077:
            raise TokenError(
                f"{source} may be read or changed by other users "
                f"(mode {stat.S_IMODE(info.st_mode):04o}): chmod 600 {path}"
            )
        os.set_blocking(fd, True)  # a pipe (<(...)) is read to its end
        with os.fdopen(os.dup(fd), "rb") as f:
            data = f.read(MAX_FILE_BYTES + 1)
    except OSError as exc:
        raise TokenError(f"{source}: cannot read: {exc.strerror or exc}") from None
    finally:
        os.close(fd)
    if len(data) > MAX_FILE_BYTES:
        raise TokenError(f"{source} is larger than {MAX_FILE_BYTES} bytes; a token is one line")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise TokenError(f"{source} is not text") from None
    token = text.rstrip("\r\n")
    if "\n" in token or "\r" in token:
        raise TokenError(f"{source} holds more than one line; put the token alone in it")
    return check(token, source)


def token_from(
    token_file: Path | None, env: Mapping[str, str], variable: str, flag: str = "--token-file"
) -> str | None:
    """The token to require: the file's if one is given, else the variable's; None if neither."""
    if token_file is not None:
        return read_token_file(token_file, flag)
    if variable in env:
        return check(env[variable], variable)
    return None
