"""The page's layout in a real browser, for the usual video shapes (4:3, 16:9, and a
phone's 9:16 portrait) in a 1280x720 and a 1920x1080 window: the four panels with
their captions all inside the 3D canvas, none over another nor under the control
panel or a notification, all of one size; the tabs on one line. Screenshots go to
artifacts/browser/layout_*.png."""

from __future__ import annotations

import numpy as np
import pytest
from app_helpers import shaped_app  # noqa: F401
from browser_helpers import (
    SKIP_WITHOUT_CHROMIUM,
    box_of,
    fitted_camera,
    open_page,
    panel_boxes,
    shot,
    wait_until,
)

from app.layout import CAPTION_CHARS

pytestmark = [pytest.mark.browser, SKIP_WITHOUT_CHROMIUM]
WINDOWS = ((1280, 720), (1920, 1080))


def overlap(a, b) -> bool:
    return a[0] < b[2] - 0.5 and b[0] < a[2] - 0.5 and a[1] < b[3] - 0.5 and b[1] < a[3] - 0.5


def refusal_box(page, video) -> tuple[float, float, float, float]:
    """The box of the notification a click on the video panel brings (no joint chosen to
    place: refused); clicked again where a slow page only saw it as it closed."""
    notice = page.locator(".mantine-Notification-root").last
    for _ in range(3):
        page.mouse.click((video[0] + video[2]) / 2, (video[1] + video[3]) / 2)
        notice.wait_for(state="visible")
        if (box := notice.bounding_box()) is not None:
            return box["x"], box["y"], box["x"] + box["width"], box["y"] + box["height"]
    raise AssertionError("the refusal's notification never stayed to be measured")


@pytest.mark.parametrize("window", WINDOWS, ids=lambda w: f"{w[0]}x{w[1]}")
def test_panels_visible_apart_and_of_one_size(chromium, shaped_app, window):  # noqa: F811
    shape, app = shaped_app
    context = chromium.new_context(viewport={"width": window[0], "height": window[1]})
    try:
        before = set(app.server.get_clients())
        page = open_page(context, app.server.get_port())
        fitted_camera(app, page, before)
        canvas = box_of(page.locator("canvas[data-engine]"))
        controls = box_of(page.get_by_role("tablist"))
        assert canvas[2] <= controls[0], "the 3D canvas runs under the control panel"
        boxes = panel_boxes(page, app)
        for name, box in boxes.items():
            assert canvas[0] <= box[0] and box[2] <= canvas[2], f"{name} cut off at the sides"
            assert canvas[1] <= box[1] and box[3] <= canvas[3], f"{name} cut off at the top or bottom"
        names = list(boxes)
        for i, a in enumerate(names):
            for b in names[i + 1 :]:
                assert not overlap(boxes[a], boxes[b]), f"{a} and {b} overlap"
        sizes = np.array([(b[2] - b[0], b[3] - b[1]) for b in boxes.values()])
        np.testing.assert_allclose(sizes, np.broadcast_to(sizes[0], sizes.shape), rtol=0.02)
        assert sizes[0].min() > 0.15 * min(window), f"panels of {sizes[0]} px are too small"
        captions = [c.text for c in app.scene.captions.values()]
        assert max(map(len, captions)) <= CAPTION_CHARS, captions  # each fits its panel
        # once the panel has settled (it may be narrower for a moment while it docks)
        wait_until(lambda: len({round(box_of(t)[1]) for t in page.get_by_role("tab").all()}) == 1)
        shown = refusal_box(page, boxes["video"])
        for name, box in boxes.items():
            assert not overlap(shown, box), f"the notification covers {name}"
        shot(page, f"layout_{shape}_{window[0]}x{window[1]}")
    finally:
        context.close()
