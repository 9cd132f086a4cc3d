"""A user's text file, read with bounds: a regular file, a size limit, UTF-8.

Every file fieldtwin reads because a user named it in a command (a CSV signal, a
program named by the console's ``prog load FILE``) goes through ``read_text``:

* only a regular file is read: a FIFO, a device (``/dev/zero``), a socket or a
  directory is refused before anything is read from it, so nothing blocks and
  nothing grows without end;
* at most ``limit`` bytes: a larger file is refused (by its size, then by what
  is actually read, should it grow meanwhile);
* UTF-8 (a byte order mark is dropped); anything else is refused naming the line.

Every refusal is a ConfigError naming the file and what is allowed; none quotes
the file's content (docs/control.md, "Security").
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from fieldtwin.errors import ConfigError

MiB = 1024 * 1024

# Opened without waiting (a FIFO with no writer would block the open), never as a
# controlling terminal, never inherited by a child process.
_FLAGS = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0)
_FLAGS |= getattr(os, "O_CLOEXEC", 0)


def size_text(limit: int) -> str:
    """``16 MiB``, ``1 MiB``, or a number of bytes."""
    return f"{limit // MiB} MiB" if limit % MiB == 0 else f"{limit} bytes"


def _kind(mode: int) -> str:
    kinds = (
        (stat.S_ISDIR, "a directory"),
        (stat.S_ISFIFO, "a FIFO"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISSOCK, "a socket"),
    )
    return next((name for test, name in kinds if test(mode)), "not a regular file")


def read_text(path: str | Path, limit: int, what: str) -> str:
    """The text of the regular file ``path`` (at most ``limit`` bytes of UTF-8).

    ``what`` names the file in messages (``"signal file"``, ``"PL7 program"``).
    """
    name = str(path)
    allowed = f"allowed: a regular {what} of at most {size_text(limit)}, UTF-8"

    def refused(state: str) -> ConfigError:
        return ConfigError(f"{name}: {state} ({allowed})")

    try:
        mode = os.stat(path).st_mode  # a device is never opened
        if not stat.S_ISREG(mode):
            raise refused(f"{_kind(mode)}, not a regular file")
        fd = os.open(path, _FLAGS)
    except OSError as exc:
        raise ConfigError(f"{name}: cannot read the {what} ({exc.strerror or exc})") from None
    try:
        with os.fdopen(fd, "rb") as file:
            info = os.fstat(file.fileno())  # what was opened, should the name have moved
            if not stat.S_ISREG(info.st_mode):
                raise refused(f"{_kind(info.st_mode)}, not a regular file")
            if info.st_size > limit:
                raise refused(f"larger than {size_text(limit)}")
            data = file.read(limit + 1)
    except OSError as exc:
        raise ConfigError(f"{name}: cannot read the {what} ({exc.strerror or exc})") from None
    if len(data) > limit:
        raise refused(f"larger than {size_text(limit)}")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        raise ConfigError(
            f"{name}:{line}: not a UTF-8 text file (byte {exc.start}; {allowed})"
        ) from None


__all__ = ["MiB", "read_text", "size_text"]
