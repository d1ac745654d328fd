"""The one place where exports touch the disk: atomic, with a one-line error."""

from __future__ import annotations

import os
from pathlib import Path

from mocap.errors import MocapError
from mocap.io.fileio import atomic_write_bytes


def write_export(path: str | os.PathLike, data: bytes, kind: str) -> Path:
    """Write an export atomically; an unwritable path becomes a MocapError."""
    try:
        return atomic_write_bytes(path, data)
    except OSError as exc:
        raise MocapError(f"cannot write {kind} file {path}: {exc.strerror or exc}") from None
