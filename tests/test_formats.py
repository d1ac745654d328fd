"""Every export format from both faces: `mocap fit` writes each (--out, --bvh, --glb,
--csv, --html) and the app's state offers each for download (AppState.export), the
same bytes from the same video, each file read back by its own reader."""

from __future__ import annotations

import csv
import io
import json

import numpy as np
import pytest
import trimesh
from app_helpers import TINY_FRAMES, fresh_copy, tiny_video  # noqa: F401
from helpers import page_data

from app.controls import DOWNLOADS
from app.state import AppState
from mocap.cli import main
from mocap.io.bvh import read_bvh
from mocap.io.export.formats import FORMATS


@pytest.fixture(scope="module")
def both(tiny_video, tmp_path_factory):
    """{format key: (the file `mocap fit` wrote, the app's (name, bytes))}."""
    folder = tmp_path_factory.mktemp("formats")
    video = fresh_copy(tiny_video, folder)
    paths = {key: folder / f"cli{fmt.suffix}" for key, fmt in FORMATS.items()}
    flags = [a for key, path in paths.items() for a in ("--out" if key == "json" else f"--{key}", path)]
    assert main(["fit", str(video), "--quiet", *map(str, flags)]) == 0
    state = AppState(video)
    state.start()
    assert state.ready.wait(60) and state.progress.error is None
    return {key: (paths[key], state.export(key)) for key in FORMATS}


def read_back(key: str, data: bytes, path) -> int:
    """The number of frames a file holds, read by its format's reader."""
    if key == "json":
        return len(json.loads(data)["frames"])
    if key == "bvh":
        return read_bvh(path).values.shape[0]
    if key == "glb":
        scene = trimesh.load(io.BytesIO(data), file_type="glb")
        assert len(scene.geometry) == 10
        return TINY_FRAMES          # the frame count is the animation's, which trimesh skips
    if key == "csv":
        return len(list(csv.reader(io.StringIO(data.decode())))) - 1
    return page_data(data.decode())["n_frames"]


@pytest.mark.parametrize("key", list(FORMATS))
def test_every_format_from_the_command_line_and_the_app(both, key):
    path, (name, data) = both[key]
    assert data == path.read_bytes(), f"{key}: the app's file differs from the command line's"
    assert name == "walk" + FORMATS[key].suffix
    assert read_back(key, data, path) == TINY_FRAMES


def test_the_app_offers_every_format():
    assert sorted(DOWNLOADS.values()) == sorted(FORMATS)


def test_the_csv_holds_the_world_joints_of_the_motion_file(both):
    frames = json.loads(both["json"][1][1])["frames"]
    rows = np.array(list(csv.reader(io.StringIO(both["csv"][1][1].decode())))[1:], float)
    world = np.array([np.add(f["joints3d"], f["root"]) for f in frames])
    assert np.abs(rows[:, 2:].reshape(world.shape) - world).max() < 2e-3
