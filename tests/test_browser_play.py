"""Play in a real browser, for a 4:3, a 16:9 and a 9:16 clip: the slider, the video
frame, the silhouette with its fit and the 3D bodies advance together at the video's
frame rate, and playing stops at the last frame. Each screenshot reads the frame every
view shows: the image panels' by the frame whose image their pixels match best, the 3D
views' by the playhead bar above each (filled to the frame, sent with its pose), the
slider's by its thumb: all four views within LATE frames of the slider in the same
screenshot. Screenshots go to artifacts/browser/play_*.png."""

from __future__ import annotations

import time

import cv2
import numpy as np
import pytest
from app_helpers import SHAPES, started_app
from browser_helpers import (
    ARTIFACTS,
    SKIP_WITHOUT_CHROMIUM,
    box_of,
    fitted_camera,
    open_page,
    panel_boxes,
    screen_point,
    shot,
)
from helpers import render_walk

from app.scene import BAR
from app.views import video_image

pytestmark = [pytest.mark.browser, SKIP_WITHOUT_CHROMIUM]
FPS, FRAMES = 10.0, 30  # a 3 s clip: frames 100 ms apart, screenshots in between
WINDOW = {"width": 1280, "height": 720}
LATE = 2  # frames a view may show away from the slider


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


def playhead_frame(image: np.ndarray, page, app, view: str) -> int:
    """The frame a 3D view's playhead bar shows: its dark fill's share of the bar, times the
    frame count, less one."""
    layout = app.layout
    x, y = getattr(layout, view)
    y += layout.height / 2 + 0.02 + BAR / 2
    (x0, row), (x1, _) = (screen_point(page, app, (x + dx * layout.width / 2, y, 0.0)) for dx in (-1, 1))
    grey = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)[round(row), round(x0) : round(x1)].astype(float)
    filled = np.flatnonzero(grey < 140)
    width = (filled.max() + 1) if len(filled) else 0
    return round(width / (x1 - x0) * app.state.n_frames) - 1


def slider_frame(image: np.ndarray, page, n_frames: int) -> int:
    """The frame the frame slider shows in a screenshot: where its thumb is along the track
    (the blue bar from the track's left ends at the thumb's right edge)."""
    x0, y0, x1, y1 = box_of(page.locator(".mantine-Slider-track").first)
    t0, _, t1, _ = box_of(page.locator(".mantine-Slider-thumb").first)
    row = image[round((y0 + y1) / 2), round(x0) : round(x1 + t1 - t0)].astype(int)
    blue = np.flatnonzero((row[:, 0] > 150) & (row[:, 2] < 120))  # BGR
    centre = (blue.max() + 1 if len(blue) else 0) - (t1 - t0) / 2
    return round(centre / (x1 - x0) * (n_frames - 1))


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
        for _ in range(3):
            page.wait_for_timeout(400)
            samples.append(sample(page))
        shown = []
        for low, image, high, _ in samples:
            frames = {name: shown_frame(image, boxes[name], refs[name]) for name in refs}
            for name, (_, margin) in frames.items():
                assert margin > 0.5, f"{shape}: the {name} panel matches no frame clearly"
            seen = {name: frame for name, (frame, _) in frames.items()}
            seen |= {name: playhead_frame(image, page, app, name) for name in ("front", "side")}
            slid = slider_frame(image, page, FRAMES)
            assert low <= slid <= high, (shape, low, slid, high)
            for name, frame in seen.items():  # every view on the slider's frame, give or take LATE
                assert abs(frame - slid) <= LATE, (shape, name, frame, slid, seen)
            shown.append(min(seen.values()))
        (_, first, _, _), *_, (_, second, high, t2) = samples
        assert shown[0] < shown[1] <= shown[2], f"{shape}: the panels did not advance ({shown})"
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
