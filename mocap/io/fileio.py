"""Writing files so that a crash never leaves a half-written one (write, flush, rename)."""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path

from mocap.errors import MocapError


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> Path:
    """Write data to path atomically: a temporary file beside it, fsync, rename."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent or ".")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        os.chmod(tmp, path.stat().st_mode & 0o777 if path.exists() else 0o644)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    return path


def atomic_write_json(path: str | os.PathLike, obj) -> Path:
    """Write obj as JSON atomically."""
    return atomic_write_bytes(path, (json.dumps(obj, indent=1) + "\n").encode())


def check_writable(*paths: str | os.PathLike | None) -> None:
    """Refuse, before the long work that ends in writing them, output paths whose
    folder is missing or takes no new file (None: not asked for)."""
    for path in (Path(p) for p in paths if p is not None):
        if path.is_dir():
            raise MocapError(f"{path}: is a folder, not a file")
        _check_folder_takes_files(path)


def check_writable_folder(folder: str | os.PathLike) -> None:
    """Refuse, before the long work, an output folder that cannot be made or replaced (a file of that
    name, or a missing or unwritable parent: the folder is first written beside itself)."""
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise MocapError(f"{folder}: is a file, not a folder")
    _check_folder_takes_files(folder)


def _check_folder_takes_files(path: Path) -> None:
    """Refuse ``path`` unless its folder exists and takes a new file, probed by making and removing one
    (permission bits say nothing to root, nor to read-only mounts or /proc)."""
    folder = path.parent
    if folder.exists() and not folder.is_dir():
        raise MocapError(f"{path}: {folder} is a file, not a folder")
    if not folder.is_dir():
        raise MocapError(f"{path}: folder {folder} does not exist")
    try:
        fd, probe = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise MocapError(f"{path}: cannot write in folder {folder} ({exc.strerror or exc})") from None
