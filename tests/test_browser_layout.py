"""The page's layout in a real browser, for the usual video shapes (4:3, 16:9, and a
phone's 9:16 portrait) in landscape windows (1024x768, 1280x720, 1600x900) and a phone's
portrait one (540x960, where viser puts the controls in a sheet along the bottom): the
panels shown with their captions all inside the 3D canvas, none over another nor under the
controls or a notification, all of one size, as large as the canvas allows (filling its
width or its height); on the phone each at least 40 % of the window's width, two at a time
where four would be smaller (the Views buttons switch the pair); the tabs on one line.
Screenshots go to artifacts/browser/layout_*.png."""

from __future__ import annotations

import numpy as np
import pytest
from app_helpers import shaped_app  # noqa: F401
from browser_helpers import (
    SKIP_WITHOUT_CHROMIUM,
    box_of,
    controls_box,
    fitted_camera,
    open_page,
    panel_boxes,
    shot,
    wait_until,
)

from app.layout import CAPTION_CHARS, MARGIN_PX, MIN_SHARE, PAIRS, is_phone

pytestmark = [pytest.mark.browser, SKIP_WITHOUT_CHROMIUM]
WINDOWS = ((1024, 768), (1280, 720), (1600, 900), (540, 960))


def overlap(a, b) -> bool:
    return a[0] < b[2] - 0.5 and b[0] < a[2] - 0.5 and a[1] < b[3] - 0.5 and b[1] < a[3] - 0.5


def refusal_box(page, video) -> tuple[float, float, float, float]:
    """The box of the notification a click on the video panel brings (no joint chosen to
    place: refused), once it has slid into place; clicked again where a slow page only saw
    it as it closed."""
    notice = page.locator(".mantine-Notification-root").last
    for _ in range(3):
        page.mouse.click((video[0] + video[2]) / 2, (video[1] + video[3]) / 2)
        notice.wait_for(state="visible")
        boxes = [None]
        for _ in range(20):
            page.wait_for_timeout(100)
            boxes.append(notice.bounding_box())
            if boxes[-1] is None or boxes[-1] == boxes[-2]:
                break
        if (box := boxes[-1]) is not None:
            return box["x"], box["y"], box["x"] + box["width"], box["y"] + box["height"]
    raise AssertionError("the refusal's notification never stayed to be measured")


def check_panels(page, app, window) -> dict[str, tuple[float, float, float, float]]:
    """Check the panels shown against the canvas and the controls; their boxes."""
    canvas = box_of(page.locator("canvas[data-engine]"))
    controls = controls_box(page)
    phone = is_phone(*window)
    if not phone:
        assert canvas[2] <= controls[0] + 0.5, "the 3D canvas runs under the control panel"
    boxes = panel_boxes(page, app)
    for name, box in boxes.items():
        assert canvas[0] <= box[0] and box[2] <= canvas[2], f"{name} cut off at the sides"
        assert canvas[1] <= box[1] and box[3] <= canvas[3], f"{name} cut off at the top or bottom"
        assert not overlap(box, controls), f"the controls cover {name}: {box} {controls}"
    names = list(boxes)
    for i, a in enumerate(names):
        for b in names[i + 1 :]:
            assert not overlap(boxes[a], boxes[b]), f"{a} and {b} overlap"
    sizes = np.array([(b[2] - b[0], b[3] - b[1]) for b in boxes.values()])
    np.testing.assert_allclose(sizes, np.broadcast_to(sizes[0], sizes.shape), rtol=0.02)
    assert sizes[0].min() > 0.15 * min(window), f"panels of {sizes[0]} px are too small"
    # as large as the canvas allows: the panels span its width, or its height (a phone's: above the sheet)
    spans = np.array(list(boxes.values()))
    free_w = canvas[2] - canvas[0] - 2 * MARGIN_PX
    free_h = (controls[1] if phone else canvas[3]) - canvas[1] - 2 * MARGIN_PX
    used = max((spans[:, 2].max() - spans[:, 0].min()) / free_w, (spans[:, 3].max() - spans[:, 1].min()) / free_h)
    assert used > 0.97, f"the panels leave room to grow ({used:.2f} of the canvas)"
    if window[1] > window[0]:  # portrait: every view at least MIN_SHARE of the window's width
        assert sizes[:, 0].min() >= MIN_SHARE * window[0], (sizes[:, 0], window)
    return boxes


@pytest.mark.parametrize("window", WINDOWS, ids=lambda w: f"{w[0]}x{w[1]}")
def test_panels_visible_apart_and_of_one_size(chromium, shaped_app, window):  # noqa: F811
    shape, app = shaped_app
    context = chromium.new_context(viewport={"width": window[0], "height": window[1]})
    try:
        before = set(app.server.get_clients())
        page = open_page(context, app.server.get_port())
        fitted_camera(app, page, before)
        # once the panel has settled (it may be narrower for a moment while it docks, and a
        # phone's sheet moves below the views when the server has its canvas's size)
        wait_until(lambda: len({round(box_of(t)[1]) for t in page.get_by_role("tab").all()}) == 1)
        if is_phone(*window):
            wait_until(lambda: controls_box(page)[1] >= panel_boxes(page, app)["video"][3] - 0.5)
        boxes = check_panels(page, app, window)
        captions = [c.text for c in app.scene.captions.values()]
        assert max(map(len, captions)) <= CAPTION_CHARS, captions  # each fits its panel
        shown = refusal_box(page, boxes["video"])
        for name, box in boxes.items():
            assert not overlap(shown, box), f"the notification covers {name}"
        shot(page, f"layout_{shape}_{window[0]}x{window[1]}")
        if len(app.layout.shown) < 4:  # two at a time: the other two on a click
            page.get_by_role("button", name="silhouette + side").click()
            wait_until(lambda: app.layout.shown == PAIRS[1])
            fitted_camera(app, page, set())
            check_panels(page, app, window)
            shot(page, f"layout_{shape}_{window[0]}x{window[1]}_other_pair")
            page.get_by_role("button", name="frame + 3D").click()
            wait_until(lambda: app.layout.shown == PAIRS[0])
    finally:
        context.close()
