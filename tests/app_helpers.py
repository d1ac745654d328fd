"""A tiny rendered clip and a running app on it: fixtures of the app's tests
(import them by name into a test module)."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from helpers import CLIP, render_walk

from mocap.body import SEGMENT_NAMES
from mocap.lift.taylor import depth_fractions

TINY_FRAMES = 20  # 320x240 at 15 fps: fitted in about half a second
SHAPES = {"4x3": (320, 240), "16x9": (384, 216), "9x16": (216, 384)}  # the usual videos'


@pytest.fixture(scope="module")
def tiny_video(tmp_path_factory) -> Path:
    """The walk of helpers.render_walk, TINY_FRAMES long, rendered once per module."""
    path = tmp_path_factory.mktemp("tiny") / "walk.mp4"
    render_walk(path, seconds=TINY_FRAMES / CLIP["fps"])
    return path


@pytest.fixture
def app(tiny_video, tmp_path):
    """A preprocessed app on port 0 on a fresh copy of the tiny clip (no annotations)."""
    app = started_app(fresh_copy(tiny_video, tmp_path))
    yield app
    if app.player.playing:
        app.player.stop()
    app.server.stop()


@pytest.fixture(scope="module", params=list(SHAPES))
def shaped_app(request, tmp_path_factory):
    """(shape, app): a preprocessed app on a 12-frame walk of each of SHAPES."""
    folder = tmp_path_factory.mktemp(request.param)
    render_walk(folder / "walk.mp4", size=SHAPES[request.param], seconds=12 / 15)
    app = started_app(folder / "walk.mp4")
    yield request.param, app
    app.server.stop()


def fresh_copy(video: Path, folder: Path) -> Path:
    """The video copied into ``folder``, so that its annotations start empty there."""
    return Path(shutil.copy(video, folder / video.name))


def started_app(video: Path, timeout: float = 60.0):
    """``app.serve.create`` on port 0, preprocessed; the caller stops ``app.server``."""
    from app.serve import create

    app = create(video, port=0)
    app.state.start()
    assert app.state.ready.wait(timeout), "preprocessing did not finish"
    assert app.state.progress.error is None, app.state.progress.error
    return app


def deepest_segment(state, frame: int | None = None) -> str:
    """The segment of a frame (default: the current one) farthest out of the image
    plane: flipping its foreshortening moves the 3D pose most."""
    return SEGMENT_NAMES[int(np.argmax(depth_fractions(state.view(frame).pose3d)))]


def download_export(page, button: str, folder: Path) -> Path:
    """Open the app page's Export folder, click a button and save the file it sends."""
    page.get_by_text("Export", exact=True).first.click()
    export = page.get_by_role("button", name=button)
    export.wait_for()
    with page.expect_download(timeout=60_000) as download:  # the file is made on the click
        export.click()
    path = folder / download.value.suggested_filename
    download.value.save_as(path)
    return path


@pytest.fixture(scope="module")
def panning_clip(tmp_path_factory):
    """(path, truth): the walk turned toward the camera, through a perspective camera
    over a panning cluttered background (the tracking method's case), TINY_FRAMES long."""
    path = tmp_path_factory.mktemp("panning") / "walk.mp4"
    truth = render_walk(
        path, yaw=45.0, perspective=400.0, moving_background=True, seed=3, seconds=TINY_FRAMES / CLIP["fps"]
    )
    return path, truth


def hold_fitting(monkeypatch, at: int, gate, held=None) -> None:
    """Make the pipeline wait for ``gate`` before it reports frame ``at``'s fit (the
    fits before it reported); ``held`` is set when it starts waiting."""
    from mocap.silhouette.passes import FitStream

    def hold(fits):
        for fit in fits:
            if fit.index == at:
                if held is not None:
                    held.set()
                gate.wait(60)
            yield fit

    class Held(FitStream):
        def push(self, sil):
            return hold(super().push(sil))

        def finish(self):
            return hold(super().finish())

    monkeypatch.setattr("mocap.silhouette.FitStream", Held)
