"""The progress bar of long work (`mocap fit`, `mocap sheet`): drawn on a terminal,
silent under --quiet and when stderr is a file or a pipe (logs stay clean)."""

from __future__ import annotations

import io
import sys

import pytest
from helpers import render_walk

from mocap.cli import main


class Terminal(io.StringIO):
    """stderr as a terminal: what a user at the keyboard sees."""

    def isatty(self) -> bool:
        return True


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    """A 1 s walk (15 frames: 30 steps of the silhouette method) and its motion file."""
    folder = tmp_path_factory.mktemp("progress")
    video, motion = folder / "walk.avi", folder / "walk.motion.json"
    render_walk(video, seconds=1.0)
    assert main(["fit", str(video), "--out", str(motion), "--quiet"]) == 0
    return video, motion


def _stderr_of(monkeypatch, argv: list, terminal: bool) -> str:
    err = Terminal() if terminal else io.StringIO()
    monkeypatch.setattr(sys, "stderr", err)
    assert main([str(a) for a in argv]) == 0
    return err.getvalue()


def test_fit_draws_a_bar_on_a_terminal_only(fitted, tmp_path, monkeypatch):
    video, _ = fitted
    fit = ["fit", video, "--out", tmp_path / "m.json"]
    drawn = _stderr_of(monkeypatch, fit, terminal=True)
    assert "finding the performer's silhouette" in drawn
    assert "fitting the body model: 100%" in drawn and "30/30" in drawn
    for quiet in (
        _stderr_of(monkeypatch, fit + ["--quiet"], terminal=True),
        _stderr_of(monkeypatch, fit, terminal=False),
    ):
        assert all(line.startswith("mocap: warning: ") for line in quiet.splitlines())  # no bar


def test_sheet_draws_a_bar_on_a_terminal_only(fitted, tmp_path, monkeypatch):
    video, motion = fitted
    sheet = ["sheet", video, motion, "--out", tmp_path / "s.png", "--frames", "6"]
    drawn = _stderr_of(monkeypatch, sheet, terminal=True)
    assert "tiles: 100%" in drawn and "7/7" in drawn  # the background, then 6 tiles
    assert _stderr_of(monkeypatch, sheet + ["--quiet"], terminal=True) == ""
    assert _stderr_of(monkeypatch, sheet, terminal=False) == ""
