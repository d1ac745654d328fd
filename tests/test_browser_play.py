"""Play in a real browser, for a 4:3, a 16:9 and a 9:16 clip: the slider, the video
frame, the silhouette with its fit and the 3D bodies advance together at the video's
frame rate, and playing stops at the last frame. Each screenshot's panels are told
apart by which frame they show (the frame whose image the panel's pixels match best),
so one screenshot proves the panels show one frame, the one the slider reads.
Screenshots go to artifacts/browser/play_*.png."""

from __future__ import annotations

import time

import cv2
import numpy as np
import pytest
from app_helpers import SHAPES, started_app
from browser_helpers import (
    ARTIFACTS,
    SKIP_WITHOUT_CHROMIUM,
    fitted_camera,
    open_page,
    panel_boxes,
    shot,
)
from helpers import render_walk

from app.views import video_image

pytestmark = [pytest.mark.browser, SKIP_WITHOUT_CHROMIUM]
FPS, FRAMES = 10.0, 30  # a 3 s clip: frames 100 ms apart, screenshots in between
WINDOW = {"width": 1280, "height": 720}
# frames the canvas may show behind the slider read just before the screenshot: a
# loaded machine's software WebGL redraws the panels later than the page's controls
LATE = int(FPS)


@pytest.fixture(scope="module", params=list(SHAPES))
def shaped_app(request, tmp_path_factory):
    """(shape, app): a preprocessed app on a FRAMES-long walk of the shape."""
    folder = tmp_path_factory.mktemp(request.param)
    render_walk(folder / "walk.mp4", size=SHAPES[request.param], fps=FPS, seconds=FRAMES / FPS)
    app = started_app(folder / "walk.mp4")
    yield request.param, app
    app.server.stop()


def slider(page) -> int:
    return int(page.locator("[role=slider]").first.get_attribute("aria-valuenow"))


def crop(image: np.ndarray, box) -> np.ndarray:
    """The grey pixels inside ``box`` (page pixels), a little inset from its edges."""
    x0, y0, x1, y1 = box
    dx, dy = 0.03 * (x1 - x0), 0.03 * (y1 - y0)
    return cv2.cvtColor(
        image[round(y0 + dy) : round(y1 - dy), round(x0 + dx) : round(x1 - dx)], cv2.COLOR_BGR2GRAY
    ).astype(np.float32)


def references(app, panel: str, box) -> np.ndarray:
    """(F, h, w): what ``panel`` shows of every frame, cropped as ``crop`` does."""
    x0, y0, x1, y1 = box
    images = []
    for k in range(app.state.n_frames):
        rgb = (
            video_image(app.frames.get(k), {}, app.state.scale)
            if panel == "video"
            else app._silhouette_image(app.state.view(k))
        )
        page = cv2.resize(
            cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR), (round(x1 - x0), round(y1 - y0)), interpolation=cv2.INTER_AREA
        )
        images.append(crop(page, (0, 0, x1 - x0, y1 - y0)))
    return np.stack(images)


def shown_frame(image: np.ndarray, box, refs: np.ndarray) -> tuple[int, float]:
    """The frame whose reference matches the panel's pixels best, and how much better
    than the second best (mean absolute grey difference where the frames differ)."""
    seen = crop(image, box)
    h, w = min(seen.shape[0], refs.shape[1]), min(seen.shape[1], refs.shape[2])
    refs, seen = refs[:, :h, :w], seen[:h, :w]
    moving = refs.std(axis=0) > 8.0  # where the performer passes: the rest is alike
    errors = np.abs(refs[:, moving] - seen[None, moving]).mean(axis=1)
    best, second = np.sort(errors)[:2]
    return int(np.argmin(errors)), float(second - best)


def sample(page) -> tuple[int, np.ndarray, int, float]:
    """(slider before, screenshot, slider after, seconds) while playing."""
    before, t = slider(page), time.monotonic()
    image = cv2.imdecode(np.frombuffer(page.screenshot(), np.uint8), cv2.IMREAD_COLOR)
    return before, image, slider(page), t


def shown_frames(page, boxes, refs) -> dict[str, int]:
    """panel -> the frame it shows now (a screenshot)."""
    image = cv2.imdecode(np.frombuffer(page.screenshot(), np.uint8), cv2.IMREAD_COLOR)
    return {name: shown_frame(image, boxes[name], refs[name])[0] for name in refs}


def settles_on(page, boxes, refs, frame: int) -> bool:
    """Whether the video and silhouette panels come to show ``frame`` (the canvas
    redraws a moment after the slider moves)."""
    end = time.monotonic() + 10.0
    while time.monotonic() < end:
        if set(shown_frames(page, boxes, refs).values()) == {frame}:
            return True
    return False


def test_play_moves_every_panel_and_the_slider_together(chromium, shaped_app):  # noqa: F811
    shape, app = shaped_app
    context = chromium.new_context(viewport=WINDOW)
    try:
        before = set(app.server.get_clients())
        page = open_page(context, app.server.get_port())
        fitted_camera(app, page, before)
        boxes = panel_boxes(page, app, caption=False)
        refs = {name: references(app, name, boxes[name]) for name in ("video", "silhouette")}
        start = time.monotonic()
        page.get_by_role("button", name="Play").click()
        page.get_by_role("button", name="Pause").wait_for()
        samples = []
        for _ in range(2):
            page.wait_for_timeout(500)
            samples.append(sample(page))
        shown = []
        for low, image, high, _ in samples:
            frames = {name: shown_frame(image, boxes[name], refs[name]) for name in refs}
            for name, (frame, margin) in frames.items():
                assert margin > 0.5, f"{shape}: the {name} panel matches no frame clearly"
                assert low - LATE <= frame <= high + 1, (shape, name, frame, low, high)
            shown.append(min(frame for frame, _ in frames.values()))
        (_, first, _, _), (_, second, high, t2) = samples
        assert shown[1] > shown[0], f"{shape}: the panels did not advance ({shown})"
        for name in ("front", "side"):  # the 3D bodies moved with them
            change = np.abs(crop(first, boxes[name]) - crop(second, boxes[name])).mean()
            assert change > 0.2, f"{shape}: the {name} 3D panel did not move ({change:.2f})"
        # paced by the clock: never far behind it (frames are dropped, not slowed)
        assert high >= 0.5 * FPS * (t2 - start), (shape, high, t2 - start)
        ARTIFACTS.mkdir(parents=True, exist_ok=True)
        cv2.imwrite(str(ARTIFACTS / f"play_{shape}.png"), second)
        # it stops at the last frame, every panel on it
        page.get_by_role("button", name="Play").wait_for(timeout=2000 * FRAMES / FPS)
        assert slider(page) == app.state.frame == FRAMES - 1 and not app.player.playing
        assert settles_on(page, boxes, refs, FRAMES - 1), f"{shape}: the panels left behind"
        # Play at the end starts again from the first frame; Pause holds every panel still
        page.get_by_role("button", name="Play").click()
        page.get_by_role("button", name="Pause").click()
        page.get_by_role("button", name="Play").wait_for()
        paused = slider(page)
        assert paused < FRAMES - 1 and app.state.frame == paused and not app.player.playing
        assert settles_on(page, boxes, refs, paused), f"{shape}: the panels left behind the pause"
        shot(page, f"play_{shape}_paused")
    finally:
        context.close()
