"""Where a video's annotations live, and saving them: atomically, before an edit is
applied and shown, so that a page never shows an edit that a crash could lose."""

from __future__ import annotations

import os
from pathlib import Path

from mocap.errors import MocapError
from mocap.io.annotations import Annotations, load_annotations, save_annotations


def annotations_path(video: str | os.PathLike) -> Path:
    """Where a video's annotations live: beside it, VIDEO.annotations.json."""
    return Path(video).with_suffix(".annotations.json")


def load(path: Path, n_frames: int) -> Annotations:
    """The annotations saved at ``path``, none when there is no file yet."""
    return load_annotations(path, n_frames) if path.exists() else Annotations()


def save(path: Path, notes: Annotations) -> None:
    """Save atomically; a failure is a MocapError naming the file."""
    try:
        save_annotations(path, notes)
    except OSError as exc:
        raise MocapError(f"cannot save annotations to {path}: {exc.strerror or exc}") from None
