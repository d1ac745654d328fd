"""Shared fixtures: rendered walks fitted once per test session.

The suite runs the paper's classical path unless a test asks for the person model
(``--person-model mediapipe``, tests/test_person*.py): the rendered clips' faceless
bodies are not what a person model is for, and its own tests measure it on real
motion capture."""

from __future__ import annotations

import os

os.environ.setdefault("MOCAP_PERSON_MODEL", "none")

from dataclasses import dataclass
from pathlib import Path

import pytest
from browser_helpers import browser, chromium  # noqa: F401 (the browser fixtures, for every test module)
from helpers import render_walk

from mocap.cli import main
from mocap.synth.truth import Truth


@dataclass(frozen=True)
class FittedClip:
    video: Path
    motion: Path
    truth: Truth


@pytest.fixture(scope="session")
def fitted_walk(tmp_path_factory):
    """fitted_walk(view) -> FittedClip: the walk of helpers.render_walk seen from
    `view`, fitted by `mocap fit` (each view rendered and fitted once)."""
    cache: dict[str, FittedClip] = {}

    def get(view: str = "side") -> FittedClip:
        if view not in cache:
            folder = tmp_path_factory.mktemp(f"walk-{view}")
            video, motion = folder / "walk.mp4", folder / "walk.motion.json"
            truth = render_walk(video, view=view)
            assert main(["fit", str(video), "--out", str(motion), "--quiet"]) == 0
            cache[view] = FittedClip(video, motion, truth)
        return cache[view]

    return get
