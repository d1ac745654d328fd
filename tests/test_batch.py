"""`mocap batch` on real Dask clusters: a local one of 2 worker processes, and a
`dask scheduler` with a `dask worker` started as processes of their own; three tiny
rendered walks and one broken file. Then what a second run skips, what a run killed
after its first video leaves and how the next run finishes it, how a review's
annotations feed the next batch, and the library's page in chromium."""

from __future__ import annotations

import contextlib
import io
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest
from browser_helpers import ARTIFACTS, SKIP_WITHOUT_CHROMIUM
from helpers import frame_joints, render_walk, text_mp4

from mocap.batch import Tally, find_videos, library_names
from mocap.batch.library import ANNOTATIONS, FAILED, RECORD, is_finished, read_record, review_target
from mocap.batch.task import Outcome
from mocap.body import JOINTS
from mocap.cli import main
from mocap.io.annotations import Annotations, save_annotations

pytest.importorskip("dask.distributed")
GOOD = ("walk_a", "walk_b", "walk_c")
DEADLINE_S = 120  # for the cluster's processes to start and a video to finish


@pytest.fixture(scope="module")
def videos(tmp_path_factory) -> Path:
    """Three walks (walk_a as the session's fitted_walk("side")) and a broken file."""
    folder = tmp_path_factory.mktemp("videos")
    for seed, name in enumerate(GOOD, start=1):
        render_walk(folder / f"{name}.mp4", seed=seed)
    text_mp4(folder)
    return folder


@pytest.fixture(scope="module")
def library(videos, tmp_path_factory):
    """The four videos done on a local cluster of 2 workers: (DIR, exit code, output)."""
    out = tmp_path_factory.mktemp("library") / "lib"
    code, said = run_cli(["batch", str(videos), "--out", str(out), "--workers", "2"])
    return out, code, said


def run_cli(argv: list[str]) -> tuple[int, str]:
    """`mocap ARGV` in this process: exit code and what it printed (both streams)."""
    text = io.StringIO()
    with contextlib.redirect_stdout(text), contextlib.redirect_stderr(text):
        code = main(argv)
    return code, text.getvalue()


def assert_library(out: Path, failed: str = "notes") -> None:
    """Three finished walks (motion file, exports, masks, sheet) and one failure."""
    for name in GOOD:
        record = read_record(out / name)
        assert record is not None, name
        motion = json.loads((out / name / "motion.json").read_text())
        assert [f["mask"] for f in motion["frames"]] == [f"masks/{i:06d}.png" for i in range(30)]
        assert sorted(record["files"]) == ["bvh", "csv", "glb", "masks", "motion", "playback", "sheet", "thumb"]
        assert all((out / name / f).exists() for f in record["files"].values())
        assert record["summary"]["frames"] == 30 and 0.5 < record["summary"]["mean_score"] <= 1
    error = json.loads((out / failed / FAILED).read_text())["error"]
    assert "not a video file" in error and "\n" not in error
    assert not (out / failed / RECORD).exists()


def test_local_cluster_does_the_good_videos_and_reports_the_broken_one(library, fitted_walk):
    out, code, said = library
    assert code == 1  # some failed
    assert "FAILED notes:" in said and "not a video file" in said
    assert "dashboard: " in said and "4 videos, 0 already done, 4 to do" in said
    assert_library(out)
    # the same fit as `mocap fit` on the same video
    fitted = json.loads(fitted_walk("side").motion.read_text())
    batch = json.loads((out / "walk_a" / "motion.json").read_text())
    np.testing.assert_allclose(frame_joints(batch), frame_joints(fitted), atol=1e-3)


def test_masks_are_the_silhouettes_at_video_size(library):
    out, _, _ = library
    masks = sorted((out / "walk_a" / "masks").glob("*.png"))
    assert [m.name for m in masks] == [f"{i:06d}.png" for i in range(30)]
    motion = json.loads((out / "walk_a" / "motion.json").read_text())
    for frame, path in zip(motion["frames"], masks):
        mask = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
        assert mask.shape == (240, 320) and set(np.unique(mask)) <= {0, 255}
        x, y = np.round(frame["joints2d"][3]).astype(int)  # the pelvis lies on the performer
        assert mask[y, x] == 255


def test_index_lists_every_video(library):
    out, _, _ = library
    lines = (out / "index.csv").read_text().splitlines()
    assert lines[0].startswith("name,video,status,method,frames,fitted,fps,mean_score,doubtful")
    status = {line.split(",")[0]: line.split(",")[2] for line in lines[1:]}
    assert status == {"notes": "failed", "walk_a": "done", "walk_b": "done", "walk_c": "done"}
    page = (out / "index.html").read_text()
    assert all(f'href="{n}/motion.html"' in page for n in GOOD) and "not a video file" in page


def test_second_run_skips_and_a_review_redoes_only_its_video(library, videos, tmp_path):
    out = tmp_path / "lib"
    shutil.copytree(library[0], out)  # the times kept: still finished
    before = {n: (out / n / RECORD).stat().st_mtime_ns for n in GOOD}
    code, said = run_cli(["batch", str(videos), "--out", str(out), "--workers", "1"])
    assert code == 1 and "4 videos, 3 already done, 1 to do" in said and "FAILED notes" in said
    assert {n: (out / n / RECORD).stat().st_mtime_ns for n in GOOD} == before
    # a review in `mocap serve DIR/walk_b` saves its edits there; the next batch takes them
    video, notes_path = review_target(out / "walk_b")
    assert video == str(videos / "walk_b.mp4") and notes_path == out / "walk_b" / "annotations.json"
    save_annotations(notes_path, Annotations(keyframes=(0, 10, 20, 29)))
    good = [str(videos / f"{n}.mp4") for n in GOOD]
    code, said = run_cli(["batch", *good, "--out", str(out), "--workers", "1", "--annotations-from", str(out)])
    assert code == 0 and "3 videos, 2 already done, 1 to do" in said and "done walk_b" in said
    frames = json.loads((out / "walk_b" / "motion.json").read_text())["frames"]
    assert [f["index"] for f in frames if f["keyframe"]] == [0, 10, 20, 29]
    assert read_record(out / "walk_b")["annotations"] == str(notes_path)
    assert {n: (out / n / RECORD).stat().st_mtime_ns for n in ("walk_a", "walk_c")} == {
        n: before[n] for n in ("walk_a", "walk_c")
    }


def test_a_finished_folder_is_done_again_when_its_video_or_settings_change(library, videos):
    out = library[0]
    record = read_record(out / "walk_c")
    folder, video = out / "walk_c", str(videos / "walk_c.mp4")
    assert is_finished(folder, video, record["settings"])
    assert not is_finished(folder, video, {**record["settings"], "exports": ["bvh"]})
    assert not is_finished(folder, str(videos / "walk_b.mp4"), record["settings"])
    stamp = (folder / RECORD).stat().st_mtime
    os.utime(video, (stamp + 10, stamp + 10))  # the video replaced after the run
    try:
        assert not is_finished(folder, video, record["settings"])
    finally:
        os.utime(video, (stamp - 10, stamp - 10))


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start(argv: list[str], log: Path) -> subprocess.Popen:
    """A process in a session of its own (so that it and its children end together)."""
    with open(log, "wb") as out:
        return subprocess.Popen(argv, stdout=out, stderr=subprocess.STDOUT, start_new_session=True)


def stop(process: subprocess.Popen, sig: int = signal.SIGTERM) -> None:
    """End a process started by ``start`` and every process of its session."""
    try:
        os.killpg(process.pid, sig)
        process.wait(timeout=20)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        process.wait(timeout=20)
    except ProcessLookupError:
        pass


@pytest.fixture
def dask_cluster(tmp_path):
    """A `dask scheduler` and one `dask worker` (one thread) on 127.0.0.1, each a
    process of its own; yields the scheduler's address."""
    from dask.distributed import Client

    address = f"tcp://127.0.0.1:{free_port()}"
    dask = [sys.executable, "-m", "dask"]
    scheduler = start(
        [*dask, "scheduler", "--host", "127.0.0.1", "--port", address.rsplit(":", 1)[1], "--no-dashboard"],
        tmp_path / "scheduler.log",
    )
    worker = start(
        [
            *dask,
            "worker",
            address,
            "--nthreads",
            "1",
            "--nworkers",
            "1",
            "--no-dashboard",
            "--local-directory",
            str(tmp_path / "worker"),
        ],
        tmp_path / "worker.log",
    )
    try:
        with Client(address, timeout=f"{DEADLINE_S}s") as client:
            client.wait_for_workers(1, timeout=DEADLINE_S)
        yield address
    finally:
        stop(worker)
        stop(scheduler)


def test_existing_cluster_by_scheduler_address(dask_cluster, videos, tmp_path):
    out = tmp_path / "lib"
    code, said = run_cli(["batch", str(videos / "*.mp4"), "--out", str(out), "--scheduler", dask_cluster])
    assert code == 1 and "FAILED notes:" in said
    assert_library(out)


def test_a_killed_batch_is_finished_by_the_next_run(videos, tmp_path):
    out = tmp_path / "lib"
    good = [str(videos / f"{n}.mp4") for n in GOOD]
    batch = start(
        [sys.executable, "-m", "mocap.cli", "batch", *good, "--out", str(out), "--workers", "1"], tmp_path / "batch.log"
    )
    try:
        deadline = time.monotonic() + DEADLINE_S
        while not any((out / n / RECORD).exists() for n in GOOD):
            assert batch.poll() is None and time.monotonic() < deadline, (tmp_path / "batch.log").read_text()
            time.sleep(0.05)
    finally:
        stop(batch, signal.SIGKILL)  # no chance to clean up
    first = [n for n in GOOD if (out / n / RECORD).exists()]
    assert len(first) == 1
    stamp = (out / first[0] / RECORD).stat().st_mtime_ns
    for name in set(GOOD) - set(first):  # nothing half-written looks finished
        assert read_record(out / name) is None
        for path in (out / name).glob("*.json") if (out / name).exists() else ():
            json.loads(path.read_text())
    code, said = run_cli(["batch", *good, "--out", str(out), "--workers", "1"])
    assert code == 0 and "3 videos, 1 already done, 2 to do" in said
    assert (out / first[0] / RECORD).stat().st_mtime_ns == stamp
    assert all(read_record(out / n) is not None for n in GOOD)


def test_inputs_and_names(tmp_path):
    for sub in ("a", "b"):
        (tmp_path / sub).mkdir()
        for suffix in (".mp4", ".avi", ".txt"):
            (tmp_path / sub / f"video{suffix}").write_bytes(b"x")
    found = find_videos([str(tmp_path)])
    assert [p.relative_to(tmp_path).as_posix() for p in found] == [
        "a/video.avi",
        "a/video.mp4",
        "b/video.avi",
        "b/video.mp4",
    ]
    assert find_videos([str(tmp_path / "*" / "*.mp4"), str(tmp_path / "a" / "video.mp4")]) == [
        tmp_path / "a" / "video.mp4",
        tmp_path / "b" / "video.mp4",
    ]
    assert library_names(found) == ["a-video.avi", "a-video.mp4", "b-video.avi", "b-video.mp4"]
    assert library_names([tmp_path / "a" / "x.mp4", tmp_path / "b" / "y.mp4"]) == ["x", "y"]


@pytest.mark.parametrize(
    "args, message",
    [
        (["nowhere/*.mp4"], "nowhere/*.mp4: no file matches"),
        (["missing.mp4"], "missing.mp4: no such file or folder"),
        (["{videos}", "--exports", "bvh,obj"], "--exports: unknown format 'obj'"),
        (["{videos}", "--workers", "0"], "--workers must be 1 or more"),
        (["{videos}", "--annotations-from", "nowhere"], "--annotations-from nowhere: no such folder"),
    ],
)
def test_bad_input_is_one_line(args, message, videos, tmp_path, capsys):
    argv = ["batch", *(a.format(videos=videos) for a in args), "--out", str(tmp_path / "lib")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("mocap: error: ") and message in err and err.count("\n") == 1


@pytest.mark.browser
@SKIP_WITHOUT_CHROMIUM
def test_index_page_opens_in_chromium_and_its_links_resolve(library, chromium):
    out = library[0]
    context = chromium.new_context()
    try:
        page = context.new_page()
        page.goto((out / "index.html").as_uri())
        assert page.locator("tbody tr, table tr").count() == 5  # the header and 4 videos
        images = page.eval_on_selector_all("img", "els => els.map(e => e.naturalWidth)")
        assert len(images) == 3 and min(images) == 480  # every thumbnail decoded
        ARTIFACTS.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(ARTIFACTS / "library.png"), full_page=True)
        links = page.eval_on_selector_all("a", "els => els.map(e => e.href)")
        paths = [Path(sync_api_path(u)) for u in links]
        assert len(paths) == 3 * 8 and all(p.exists() for p in paths)
        page.get_by_role("link", name="walk_b", exact=True).click()
        page.wait_for_load_state()
        assert page.title() == "walk_b · mocap playback"
        assert page.locator("#timeline").get_attribute("max") == "29"
    finally:
        context.close()


def sync_api_path(url: str) -> str:
    """The file a file:// link points at."""
    from urllib.parse import unquote, urlparse

    assert url.startswith("file://"), url
    return unquote(urlparse(url).path)


def test_tracking_annotations_beside_the_videos_make_a_tracked_video(tmp_path):
    """`--annotations-from` with the app's own file name beside a video: the tracking
    method from frame 0's marks; its masks still come from the silhouettes."""
    truth = render_walk(tmp_path / "walk_c.mp4", view="three-quarter", seed=4)
    marks = {j: truth.joints2d[0, i].tolist() for i, j in enumerate(JOINTS)}
    notes = Annotations(method="track").with_orientation(0, "forward_right")
    for joint, xy in marks.items():
        notes = notes.with_joint(0, joint, tuple(xy))
    (tmp_path / "notes").mkdir()
    save_annotations(tmp_path / "notes" / "walk_c.annotations.json", notes)
    out = tmp_path / "lib"
    code, said = run_cli(
        [
            "batch",
            str(tmp_path / "walk_c.mp4"),
            "--out",
            str(out),
            "--workers",
            "1",
            "--annotations-from",
            str(tmp_path / "notes"),
        ]
    )
    assert code == 0, said
    record = read_record(out / "walk_c")
    assert record["summary"]["method"] == "track" and record["summary"]["fitted"] == 30
    motion = json.loads((out / "walk_c" / "motion.json").read_text())
    err = np.linalg.norm(frame_joints(motion) - truth.joints2d, axis=-1) / truth.body_height_px
    assert np.median(err) < 0.05  # followed, as `mocap fit --method track`
    assert len(list((out / "walk_c" / "masks").glob("*.png"))) == 30


def test_frames_per_second_counts_running_videos_until_they_end():
    tally = Tally(2)
    tally.start -= 10.0  # ten seconds in
    tally.running_frames((0.0, {"name": "a", "frames": 40}))
    tally.running_frames((0.0, {"name": "b", "frames": 20}))
    assert tally.fps == pytest.approx(6.0, rel=0.01)
    tally.add(Outcome("a", frames=100, seconds=9.0))
    tally.running_frames((0.0, {"name": "a", "frames": 90}))  # a late report of a done video
    assert tally.fps == pytest.approx(12.0, rel=0.01) and tally.running == {"b": 20}


def test_serve_takes_a_library_folder_or_a_file_in_it(library, videos, tmp_path, capsys):
    out = library[0]
    video, notes = review_target(out / "walk_a" / "motion.json")
    assert video == str(videos / "walk_a.mp4") and notes == out / "walk_a" / ANNOTATIONS
    assert review_target(videos / "walk_a.mp4") is None  # a video: served as before
    assert main(["serve", str(tmp_path)]) == 2  # a folder of something else
    assert f"{tmp_path}: is a folder, not a video nor a video's folder of a `mocap batch`" in (capsys.readouterr().err)
