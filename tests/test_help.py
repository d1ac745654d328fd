"""The app's Help folder (static/help.md and its picture) and its playback-page download.

The shortcuts are collected from what ``build_controls`` registers with
``gui.add_command`` on a real viser server, so the help cannot drift from the code.
Screenshots go to artifacts/help/ (gitignored)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import viser
from app_helpers import TINY_FRAMES, app, download_export, tiny_video  # noqa: F401
from browser_helpers import SKIP_WITHOUT_CHROMIUM
from helpers import page_data

from app.controls import HELP_FILE, build_controls, help_markdown
from app.words import orientation_label
from mocap.body import ORIENTATIONS

ROOT = Path(__file__).resolve().parents[1]
ARTIFACTS = ROOT / "artifacts" / "help"


class _Recording:
    """A gui that records every add_command call and passes everything on."""

    def __init__(self, gui):
        self._gui, self.commands = gui, []

    def add_command(self, *args, **kwargs):
        self.commands.append(kwargs)
        return self._gui.add_command(*args, **kwargs)

    def __getattr__(self, name):
        return getattr(self._gui, name)


def registered_shortcuts() -> list[str]:
    """'Shift+J', 'Cmd/Ctrl+Z', ...: every hotkey build_controls registers."""
    server = viser.ViserServer(port=0, verbose=False)
    try:
        gui = _Recording(server.gui)
        build_controls(gui, 10)
    finally:
        server.stop()
    combos = []
    for kwargs in gui.commands:
        if kwargs.get("hotkey"):
            mods = [
                {"cmd/ctrl": "Cmd/Ctrl"}.get(m, m.capitalize()) for m in (kwargs.get("modifier") or "").split("+") if m
            ]
            combos.append("+".join([*mods, kwargs["hotkey"].upper()]))
    return combos


def test_commands_are_registered_in_one_place():
    """The shortcut collection below sees them all: build_controls is the only caller."""
    calls = [p for p in (ROOT / "app").glob("*.py") if "add_command(" in p.read_text()]
    assert [p.name for p in calls] == ["controls.py"]


def test_help_mentions_every_shortcut_the_app_registers():
    combos = registered_shortcuts()
    assert len(combos) >= 9 and "Shift+J" in combos and "Cmd/Ctrl+Shift+Z" in combos
    text = HELP_FILE.read_text(encoding="utf-8")
    for combo in combos:
        # whole combination: 'J' must not be satisfied by 'Shift+J'
        assert re.search(rf"(?<![\w+/]){re.escape(combo)}(?![\w+])", text, re.IGNORECASE), combo


def test_help_explains_the_topics_with_a_picture():
    text = HELP_FILE.read_text(encoding="utf-8").lower()
    for topic in (
        "the four panels",
        "orange",
        "blue",
        "green",
        "foreshortening",
        "toward",
        "away",
        "occluded",
        "review",
        "keyboard shortcuts",
    ):
        assert topic in text, topic
    words = " ".join(text.split())
    for orientation in ORIENTATIONS:  # in the Facing list's words, and the annotation file's
        assert orientation_label(orientation).lower() in words and f"`{orientation}`" in words, orientation
    pictures = re.findall(r"!\[[^]]*\]\(([^)]+)\)", HELP_FILE.read_text())
    assert pictures and all((HELP_FILE.parent / p).is_file() for p in pictures)
    assert "data:image/svg+xml;base64," in help_markdown()


@pytest.mark.browser
@SKIP_WITHOUT_CHROMIUM
def test_help_folder_and_playback_download_in_chromium(app, tmp_path, chromium):
    try:
        context = chromium.new_context(viewport={"width": 1280, "height": 800}, accept_downloads=True)
        page = context.new_page()
        page.set_default_timeout(20_000)
        page.goto(f"http://127.0.0.1:{app.server.get_port()}/")
        page.get_by_text(re.compile("frames fitted")).first.wait_for()
        warning = page.get_by_text("Software WebGL rendering detected")
        if warning.count():
            warning.locator("xpath=../..").get_by_role("button").first.click()
        # the help: one click
        page.get_by_text("Help", exact=True).first.click()
        page.get_by_text("Keyboard shortcuts").wait_for()
        picture = page.locator("img[src^='data:image/svg']").first
        picture.scroll_into_view_if_needed()
        page.wait_for_function("img => img.complete && img.naturalWidth > 0", arg=picture.element_handle())
        ARTIFACTS.mkdir(parents=True, exist_ok=True)
        page.wait_for_timeout(300)
        page.screenshot(path=str(ARTIFACTS / "help_folder.png"))
        # the playback page: the export button
        path = download_export(page, "HTML page", tmp_path)
        assert path.name == "walk.html"
        data = page_data(path.read_text())
        assert data["n_frames"] == len(data["frames"]) == TINY_FRAMES
        assert data["name"] == "walk"
    finally:
        context.close()
