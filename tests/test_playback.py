"""The playback page (mocap.io.export.html, static/playback.html): written from a motion
file by `mocap export --html`, opened from file:// in headless chromium, where it
draws the body and plays. The screenshot goes to artifacts/playback/ (gitignored)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from browser_helpers import SKIP_WITHOUT_CHROMIUM
from helpers import page_data

from mocap.cli import main as cli
from mocap.io.export.html import DATA_SLOT, TEMPLATE, motion_html
from mocap.io.export.marks import facing_marks
from mocap.io.export.motion_json import write_motion
from mocap.lift.motion import build_motion
from mocap.synth.walk import walk_cycle

N_FRAMES, FPS = 100, 25.0
GONE = 50  # a frame without a pose
ARTIFACTS = Path(__file__).resolve().parents[1] / "artifacts" / "playback"


@pytest.fixture(scope="module")
def page_file(tmp_path_factory) -> Path:
    """A 100-frame walk's motion file exported as a page by the command line."""
    folder = tmp_path_factory.mktemp("playback")
    joints = walk_cycle(N_FRAMES / FPS, FPS)
    frames = [{"index": i, "keyframe": True, "person": True, "joints3d": joints[i]} for i in range(N_FRAMES)]
    frames[GONE] = {"index": GONE, "keyframe": False, "person": False}
    video = {"path": "clips/walk <side>.mp4", "width": 320, "height": 240, "fps": FPS, "frame_count": N_FRAMES}
    write_motion(folder / "walk.motion.json", video, frames)
    out = folder / "walk.html"
    assert cli(["export", str(folder / "walk.motion.json"), "--html", str(out)]) in (0, None)
    return out


def test_page_is_small_self_contained_and_counts_the_frames(page_file):
    text = page_file.read_text(encoding="utf-8")
    assert len(text.encode()) < 2_000_000, "a 100-frame page should be well under a few MB"
    data = page_data(text)
    assert data["n_frames"] == N_FRAMES == len(data["frames"])
    assert data["fps"] == FPS and data["name"] == "walk <side>"
    assert [i for i, f in enumerate(data["frames"]) if f is None] == [GONE]
    assert "walk &lt;side&gt;" in text and "<side>" not in text  # escaped in the HTML and the JSON
    # nothing fetched: no external script, stylesheet, image or fetch call
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:)?//|fetch\(|import\s""", text)
    assert DATA_SLOT in TEMPLATE.read_text()


def test_page_of_a_motion_uses_the_world_joints():
    joints = walk_cycle(1.0, FPS)
    motion = build_motion(dict(enumerate(joints)), len(joints), FPS, root=np.tile([0.5, 0.0, 0.0], (len(joints), 1)))
    data = page_data(motion_html(motion, "clip"))
    assert data["n_frames"] == motion.n_frames
    np.testing.assert_allclose(data["frames"][3], motion.world_joints[3], atol=1e-3)


def test_page_of_a_fitted_motion_file_follows_its_root(fitted_walk, tmp_path):
    """`mocap fit` writes each frame's root; the page of the file moves the body along it."""
    clip = fitted_walk("side")
    out = tmp_path / "walk.html"
    assert cli(["export", str(clip.motion), "--html", str(out)]) in (0, None)
    frames = [f for f in page_data(out.read_text(encoding="utf-8"))["frames"] if f is not None]
    pelvis_x = np.array([f[3][0] for f in frames])
    assert np.ptp(pelvis_x) > 0.5, "a walk across the frame travels over half a metre"


@pytest.mark.browser
@SKIP_WITHOUT_CHROMIUM
def test_page_plays_from_disk_in_chromium(page_file, chromium):
    try:
        context = chromium.new_context(viewport={"width": 900, "height": 640}, offline=True)
        requests = []
        context.on("request", lambda r: requests.append(r.url))
        page = context.new_page()
        errors = []
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.goto(page_file.as_uri())
        counter = page.locator("#counter")
        counter.wait_for()
        page.wait_for_function("document.getElementById('counter').textContent.length > 0")
        first = counter.text_content()
        page.wait_for_function(f"document.getElementById('counter').textContent !== {first!r}", timeout=5000)
        assert re.fullmatch(rf"frame \d+ of 0–{N_FRAMES - 1}", counter.text_content())
        assert page.get_by_text(f"{N_FRAMES} frames · 25 fps").is_visible()
        assert page.locator("h1").text_content() == "walk <side>"
        # pause on a frame with a pose, then sample the canvas: the body's colours are there
        page.locator("#play").click()
        page.locator("#timeline").fill("10")
        shown = page.evaluate("""() => {
            const c = document.getElementById('view');
            const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
            let body = 0, other = 0;
            for (let i = 0; i < d.length; i += 16) {
                const [r, g, b] = [d[i], d[i + 1], d[i + 2]];
                if (Math.abs(r - 0xf4) + Math.abs(g - 0xf5) + Math.abs(b - 0xf7) > 60) body++;
                else other++;
            }
            return body / (body + other);
        }""")
        assert 0.005 < shown < 0.5, f"{shown:.3%} of the canvas drawn"
        assert counter.text_content() == f"frame 10 of 0–{N_FRAMES - 1}"  # 0-based, as the files
        # the nose and the chest's mark drawn where mocap.body puts them (facing shows)
        pose = page.evaluate("() => DATA.frames[10]")
        drawn = np.array(page.evaluate("() => facingMarks(DATA.frames[10]).map(m => [m[0], m[1]])"))
        marks = facing_marks(np.array(pose))
        np.testing.assert_allclose(drawn[:, 0], marks[:, 0], atol=1e-3)
        np.testing.assert_allclose(drawn[:, 1], marks[:, 0] + marks[:, 1] * marks[:, 2, :1], atol=1e-3)
        page.locator("#play").click()
        page.wait_for_timeout(300)
        ARTIFACTS.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(ARTIFACTS / "playback.png"))
        assert not errors, errors
        assert all(u.startswith("file://") for u in requests), requests
    finally:
        context.close()
