"""The tracking's lost body in a real browser (Debian's chromium driven by Python
playwright): the review lists the lost stretch first, the user goes to a frame that
shows the performer again, marks the 16 joints there by clicking, presses Track, and
the frames that were lost are answered. Screenshots go to artifacts/browser/."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from app_helpers import started_app
from browser_helpers import SKIP_WITHOUT_CHROMIUM, browser, open_page, shot, wait_until  # noqa: F401
from helpers import render_walk_with_exit
from test_browser import mark_by_clicking, to_tracking

from mocap.body import JOINTS

pytestmark = [pytest.mark.browser, SKIP_WITHOUT_CHROMIUM]
sync_api = pytest.importorskip("playwright.sync_api")

GONE = slice(10, 24)  # frames the performer is out of the picture
BACK = GONE.stop + 2  # a frame that shows them again, where they are marked again


def test_the_review_leads_to_the_lost_body_and_a_remark_by_clicks_finds_it(browser, tmp_path):
    video = tmp_path / "exit.mp4"
    # after the exit the colours change (a cut to a camera graded otherwise): the
    # tracker cannot find the marked colours again by itself
    truth = render_walk_with_exit(
        video, GONE, regraded=True, seed=3, yaw=45.0, perspective=400.0, moving_background=True
    )
    marks = dict(zip(JOINTS, truth.joints2d[0].tolist()))
    video.with_suffix(".annotations.json").write_text(
        json.dumps(
            {
                "format": "mocap-annotations",
                "version": 1,
                "frames": {"0": {"orientation": "forward_right", "joints2d": marks}},
            }
        )
    )
    n = len(truth.joints2d)
    app = started_app(video)
    try:
        page = open_page(browser, app.server.get_port())
        to_tracking(page, "all 16 joints are marked on frame 0")
        page.get_by_role("button", name="Track", exact=True).click()
        wait_until(lambda: app.state.progress.ready and not app.state.tracking, timeout=120)
        page.get_by_role("tab", name="Review").click()
        lost = page.get_by_text(re.compile(r"body lost on frames \d+-29: mark the body here"))
        lost.wait_for()
        first = app.state.review_stops()[0]
        assert first.reasons[0].startswith("body lost") and GONE.start <= first.frame <= GONE.start + 2
        assert not np.isfinite(app.state.view(BACK).score)
        shot(page, "remark_review")
        page.get_by_role("button", name="Next doubtful").click()
        wait_until(lambda: app.state.frame == first.frame)
        for frame in range(first.frame + 1, BACK + 1):
            page.get_by_role("button", name="frame ▶", exact=True).click()
            wait_until(lambda f=frame: app.state.frame == f)
        page.get_by_role("tab", name="Tracking").click()
        mark_by_clicking(page, app, truth.joints2d[BACK])
        page.get_by_text(f"All 16 joints marked again on frame {BACK}.").wait_for()
        assert app.state.frame == BACK
        page.get_by_role("button", name="Track", exact=True).click()
        wait_until(
            lambda: app.state.progress.ready and not app.state.tracking and not app.state.marks_changed, timeout=120
        )
        page.get_by_text(f"{n} frames tracked.").first.wait_for()
        views = [app.state.view(frame) for frame in range(GONE.stop, n)]
        assert all(np.isfinite(view.score) for view in views)
        err = (
            np.array([np.linalg.norm(view.joints2d - truth.joints2d[view.index], axis=-1).mean() for view in views])
            / truth.body_height_px
        )
        assert err.mean() < 0.04 and err.max() < 0.07
        assert all(d.frame < GONE.stop for d in app.state.review_stops() if d.reasons[0].startswith("body lost"))
        shot(page, "remark_tracked")
    finally:
        app.server.stop()
