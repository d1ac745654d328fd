"""The command line on a new user's mistakes and broken files: each ends with exit code 2
and one line, `mocap: error: ...`, that names the file (or port) and the problem, never a
traceback; and the annotation and motion loaders fuzzed."""

from __future__ import annotations

import copy
import json
import socket
from pathlib import Path

import pytest
from helpers import assert_one_line_error, render_walk
from helpers import run_cli as run
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mocap.errors import MocapError
from mocap.io.export.html import motion_file_html


@pytest.fixture(scope="module")
def walk(tmp_path_factory):
    video = tmp_path_factory.mktemp("walk") / "walk.avi"
    render_walk(video, seconds=1.0)
    return video


# -- mocap serve ----------------------------------------------------------------------


def test_serve_on_a_taken_port_is_an_error_naming_it(walk, capsys):
    pytest.importorskip("viser")
    with socket.socket() as other:
        other.bind(("127.0.0.1", 0))
        other.listen()
        port = other.getsockname()[1]
        code, err = run(capsys, "serve", walk, "--port", port)
    assert code == 2
    assert_one_line_error(err, f"port {port}", "taken", "--port 0")


def test_serve_on_port_0_takes_any_free_one(walk):
    create = pytest.importorskip("app.serve").create
    app = create(walk, port=0)
    try:
        assert app.server.get_port() > 0
    finally:
        app.server.stop()


# -- outputs that cannot be written: refused before the fit --------------------------


def _unwritable(tmp_path: Path, name: str) -> tuple[Path, str]:
    """Paths whose folder takes no file, even for root (who ignores permission bits)."""
    regular = tmp_path / "notes.txt"
    regular.write_text("a file, not a folder")
    return {
        "missing": (tmp_path / "no" / "such" / name, "does not exist"),
        "under a file": (regular / name, "is a file, not a folder"),
        "/proc": (Path("/proc") / name, "cannot write in folder /proc"),
    }


@pytest.mark.parametrize("case", ["missing", "under a file", "/proc"])
@pytest.mark.parametrize("option", ["--out", "--bvh"])
def test_fit_refuses_an_unwritable_output_before_fitting(walk, tmp_path, capsys, case, option):
    out, problem = _unwritable(tmp_path, "walk.out")[case]
    args = [option, out] if option == "--out" else ["--out", tmp_path / "m.json", option, out]
    code, err = run(capsys, "fit", walk, *args, "--quiet")
    assert code == 2
    assert_one_line_error(err, str(out), problem)
    assert not (tmp_path / "m.json").exists()


@pytest.mark.parametrize("case", ["missing", "under a file", "/proc"])
def test_sheet_refuses_an_unwritable_output(fitted_walk, tmp_path, capsys, case):
    clip = fitted_walk("side")
    out, problem = _unwritable(tmp_path, "sheet.png")[case]
    code, err = run(capsys, "sheet", clip.video, clip.motion, "--out", out)
    assert code == 2
    assert_one_line_error(err, str(out), problem)


@pytest.mark.parametrize("case", ["missing", "under a file", "/proc"])
def test_synth_refuses_an_unwritable_output(tmp_path, capsys, case):
    out, problem = _unwritable(tmp_path, "a.mp4")[case]
    code, err = run(capsys, "synth", "walk-cycle", out, "--seconds", "0.5")
    assert code == 2
    assert_one_line_error(err, str(out), problem)


@pytest.mark.parametrize("case", ["missing", "under a file", "/proc"])
def test_fit_refuses_a_masks_folder_it_cannot_make_before_fitting(walk, tmp_path, capsys, case):
    masks, problem = _unwritable(tmp_path, "masks")[case]
    out = tmp_path / "m.json"
    code, err = run(capsys, "fit", walk, "--out", out, "--masks", masks, "--quiet")
    assert code == 2
    assert_one_line_error(err, str(masks), problem)
    assert not out.exists() and not masks.exists()


def test_fit_refuses_masks_named_like_a_file(walk, tmp_path, capsys):
    masks = tmp_path / "masks"
    masks.write_text("a file, not a folder")
    code, err = run(capsys, "fit", walk, "--out", tmp_path / "m.json", "--masks", masks, "--quiet")
    assert code == 2
    assert_one_line_error(err, f"{masks}: is a file, not a folder")


def test_masks_with_the_tracking_method_are_refused_before_tracking(walk, tmp_path, capsys):
    """Refused for the masks, not after a tracking for the marks it lacks."""
    code, err = run(capsys, "fit", walk, "--method", "track", "--masks", tmp_path / "masks", "--quiet")
    assert code == 2
    assert_one_line_error(err, "--masks needs the silhouette method")


@pytest.mark.parametrize(
    "option, name, problem",
    [
        ("--glb", "walk.bvh", "the GLB would go into a file named like a BVH (.bvh); name it .glb"),
        ("--bvh", "walk.glb", "the BVH would go into a file named like a GLB (.glb); name it .bvh"),
        ("--out", "walk.csv", "the motion JSON would go into a file named like a CSV (.csv)"),
    ],
)
def test_fit_refuses_an_output_named_like_another_format(walk, tmp_path, capsys, option, name, problem):
    out = tmp_path / name
    code, err = run(capsys, "fit", walk, option, out, "--quiet")
    assert code == 2
    assert_one_line_error(err, f"{out}: {problem}")
    assert not out.exists()


@pytest.mark.parametrize(
    "option, problem",
    [
        ("--annotations", "is a folder, not an annotation file"),
        ("--background", "is a folder, not a background image or video"),
    ],
)
def test_fit_refuses_a_folder_for_an_input_file(walk, tmp_path, capsys, option, problem):
    code, err = run(capsys, "fit", walk, option, tmp_path, "--out", tmp_path / "m.json", "--quiet")
    assert code == 2
    assert_one_line_error(err, f"{tmp_path}: {problem}")


def test_a_motion_file_given_as_annotations_is_told_by_its_format(fitted_walk, walk, tmp_path, capsys):
    motion = fitted_walk("side").motion
    code, err = run(capsys, "fit", walk, "--annotations", motion, "--out", tmp_path / "m.json", "--quiet")
    assert code == 2
    assert_one_line_error(err, f'{motion}: format: expected "mocap-annotations", got "mocap-motion"')


# -- Ctrl+C: one line, exit 130, nothing written and the annotations as they were ----


def test_ctrl_c_while_starting_up_is_one_line(monkeypatch, capsys):
    """The parser imports the commands' modules: a Ctrl+C there is no traceback either."""
    import mocap.cli

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(mocap.cli, "build_parser", interrupted)
    assert run(capsys, "fit", "any.mp4") == (130, ["mocap: interrupted"])


def test_ctrl_c_during_a_fit_writes_nothing_and_keeps_the_annotations(walk, tmp_path, capsys, monkeypatch):
    import mocap.pipeline

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    notes = tmp_path / "walk.annotations.json"
    notes.write_text(
        json.dumps({"format": "mocap-annotations", "version": 1, "frames": {"3": {"orientation": "left"}}})
    )
    before = notes.read_bytes()
    monkeypatch.setattr(mocap.pipeline, "silhouette_passes", interrupted)
    out = tmp_path / "m.json"
    code, err = run(capsys, "fit", walk, "--annotations", notes, "--out", out, "--masks", tmp_path / "masks")
    assert (code, err) == (130, ["mocap: interrupted"])
    assert notes.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["walk.annotations.json"]


# -- broken motion files --------------------------------------------------------------


@pytest.mark.parametrize(
    "key, damage, place, problem",
    [
        ("joints3d", lambda j: j[:3], "frames[4].joints3d", "expected 16 joints, got a list of 3"),
        (
            "joints3d",
            lambda j: [j[0], [0.1, "oops", 0.2]] + j[2:],
            "frames[4].joints3d[1][1]",
            'expected a number, got the string "oops"',
        ),
        ("joints2d", lambda j: j[:-1], "frames[4].joints2d", "expected 16 joints, got a list of 15"),
    ],
)
def test_export_refuses_a_damaged_motion_file(fitted_walk, tmp_path, capsys, key, damage, place, problem):
    doc = json.loads(fitted_walk("side").motion.read_text())
    doc["frames"][4][key] = damage(doc["frames"][4][key])
    motion, page = tmp_path / "damaged.motion.json", tmp_path / "page.html"
    motion.write_text(json.dumps(doc))
    code, err = run(capsys, "export", motion, "--html", page)
    assert code == 2
    assert_one_line_error(err, f"{motion}: {place}: {problem}")
    assert not page.exists()


# -- annotations ----------------------------------------------------------------------


def test_frames_that_are_no_object_are_explained(walk, tmp_path, capsys):
    notes = tmp_path / "walk.annotations.json"
    notes.write_text(json.dumps({"format": "mocap-annotations", "version": 1, "frames": "oops"}))
    code, err = run(capsys, "fit", walk, "--annotations", notes, "--out", tmp_path / "m.json")
    assert code == 2
    assert_one_line_error(
        err,
        f"{notes}: frames: expected an object of notes by frame index",
        '{"12": {"orientation": "left"}}',
        'got the string "oops"',
    )


# -- fuzzing the motion loader: a motion file or one MocapError, and a page from it ----

_value = st.recursive(
    st.none() | st.booleans() | st.integers(-2, 20) | st.floats() | st.text(max_size=6),
    lambda inner: st.lists(inner, max_size=17) | st.dictionaries(st.text(max_size=6), inner, max_size=3),
    max_leaves=40,
)
_FIELDS = ["index", "keyframe", "person", "score", "joints2d", "joints3d", "root", "confidence"]


@st.composite
def _damaged(draw, valid: dict) -> dict:
    """A valid motion document with a few fields replaced, cut or dropped."""
    doc = copy.deepcopy(valid)
    for _ in range(draw(st.integers(1, 3))):
        where = draw(st.sampled_from(["top", "video", "frame", "row"]))
        frames = doc["frames"] if isinstance(doc["frames"], list) and doc["frames"] else [{}]
        frame = frames[draw(st.integers(0, len(frames) - 1))]
        if where == "top":
            doc[draw(st.sampled_from(["video", "frames", "joints"]))] = draw(_value)
        elif where == "video" and isinstance(doc.get("video"), dict):
            doc["video"][draw(st.sampled_from(["fps", "width", "frame_count", "path"]))] = draw(_value)
        elif where == "frame" and isinstance(frame, dict):
            frame[draw(st.sampled_from(_FIELDS))] = draw(_value)
        elif isinstance(frame, dict) and isinstance(frame.get("joints3d"), list) and frame["joints3d"]:
            rows = frame["joints3d"]
            rows[draw(st.integers(0, len(rows) - 1))] = draw(_value)
    return doc


@pytest.fixture(scope="module")
def valid_motion(fitted_walk) -> dict:
    doc = json.loads(fitted_walk("side").motion.read_text())
    doc["frames"] = doc["frames"][:3]
    return doc


@settings(
    max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture]
)
@given(data=st.data())
def test_the_motion_loader_only_ever_raises_mocap_errors(valid_motion, tmp_path_factory, data):
    path = tmp_path_factory.getbasetemp() / "fuzzed.motion.json"
    path.write_text(json.dumps(data.draw(_damaged(valid_motion))))
    try:
        page = motion_file_html(path)
    except MocapError as exc:
        assert str(exc).startswith(f"{path}: ") and "\n" not in str(exc)
    else:
        assert page.startswith("<!")
