"""Every export format from both faces: `mocap fit` writes each (--out, --bvh, --glb,
--csv, --html) and the app's state offers each for download (AppState.export), the
same bytes from the same video and annotations (the keyframes the app proposed, saved), each
file read back by its own reader."""

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
from mocap import body
from mocap.cli import main
from mocap.io.bvh_reader import read_bvh
from mocap.io.export.formats import FORMATS
from mocap.io.export.html import motion_file_html


@pytest.fixture(scope="module")
def both(tiny_video, tmp_path_factory):
    """{format key: (the file `mocap fit` wrote, the app's (name, bytes))}."""
    folder = tmp_path_factory.mktemp("formats")
    video = fresh_copy(tiny_video, folder)
    state = AppState(video)
    state.start()
    assert state.ready.wait(60) and state.progress.error is None
    notes = ["--annotations", str(state.path)]  # the keyframes the app proposed, saved
    paths = {key: folder / f"cli{fmt.suffix}" for key, fmt in FORMATS.items() if fmt.available()}
    flags = [a for key, path in paths.items() for a in ("--out" if key == "json" else f"--{key}", path)]
    assert main(["fit", str(video), "--quiet", *notes, *map(str, flags)]) == 0
    locked = folder / "locked.motion.json"
    assert main(["fit", str(video), "--quiet", *notes, "--foot-lock", "--out", str(locked)]) == 0
    return {key: (paths[key], state.export(key)) for key in paths} | {
        "foot lock": (locked, state.export("json", foot_lock=True))
    }


def read_back(key: str, data: bytes, path) -> int:
    """The number of frames a file holds, read by its format's reader."""
    if key == "json":
        return len(json.loads(data)["frames"])
    if key == "bvh":
        return read_bvh(path).values.shape[0]
    if key == "glb":
        scene = trimesh.load(io.BytesIO(data), file_type="glb")
        assert list(scene.geometry) == ["body"]
        return TINY_FRAMES  # the frame count is the animation's, which trimesh skips
    if key == "csv":
        return len(list(csv.reader(io.StringIO(data.decode())))) - 1
    if key == "fbx":
        return TINY_FRAMES  # Blender reads it back: test_blender.py
    return page_data(data.decode())["n_frames"]


@pytest.mark.parametrize("key", list(FORMATS))
def test_every_format_from_the_command_line_and_the_app(both, key):
    if key not in both:
        pytest.skip(f"{key}: not available here ({FORMATS[key].holds})")
    path, (name, data) = both[key]
    if key == "fbx":  # Blender stamps the FBX with the time it wrote it
        assert data[:18] == path.read_bytes()[:18] == b"Kaydara FBX Binary"
    else:
        assert data == path.read_bytes(), f"{key}: the app's file differs from the command line's"
    assert name == "walk" + FORMATS[key].suffix
    assert read_back(key, data, path) == TINY_FRAMES


def test_the_foot_lock_from_both_faces(both):
    """`mocap fit --foot-lock` and the app's Foot lock write the same motion, which keeps
    the bones of the plain one and moves only legs."""
    path, (_, data) = both["foot lock"]
    assert data == path.read_bytes()
    plain, locked = (json.loads(both["json"][1][1]), json.loads(data))
    joints = [np.array([f["joints3d"] for f in d["frames"] if "joints3d" in f]) for d in (plain, locked)]
    moved = np.abs(joints[1] - joints[0]).max(axis=(0, 2)) > 1e-3
    legs = [body.JOINT_INDEX[f"{j}_{s}"] for j in ("knee", "ankle") for s in "lr"]
    assert not moved[np.setdiff1d(np.arange(16), legs)].any()


def test_the_page_of_the_motion_file_is_the_fits_page(both):
    """`mocap export --html` of the motion file shows what `mocap fit --html` does (the
    exports' world: the file's origin taken off)."""
    motion_path, html_path = both["json"][0], both["html"][0]
    mine = page_data(motion_file_html(motion_path))["frames"]
    fits = page_data(html_path.read_text(encoding="utf-8"))["frames"]
    assert np.abs(np.array(mine, float) - np.array(fits, float)).max() < 1.5e-3  # pages keep mm


def test_the_app_offers_every_format():
    assert sorted(DOWNLOADS.values()) == sorted(FORMATS)


def test_the_csv_holds_the_world_joints_of_the_motion_file(both):
    data = json.loads(both["json"][1][1])
    rows = list(csv.reader(io.StringIO(both["csv"][1][1].decode())))
    first = rows[0].index("head_top_x_right_m")
    values = np.array([row[first : first + 48] for row in rows[1:]], float)
    world = np.array([np.add(f["joints3d"], f["root"]) - data["origin"] for f in data["frames"]])
    assert np.abs(values.reshape(world.shape) - world).max() < 2e-4
