"""The page's controls: ``build_controls`` returns a dataclass of handles on ``server.gui``, shared
by every tab; ``HOTKEYS`` lists the viser commands once for the commands and the help text."""

from __future__ import annotations

import base64
import re
from dataclasses import dataclass
from pathlib import Path

from app.signs import build_signs
from app.texts import EYES_HELP, STAGE_HELP
from app.words import JOINT_CHOICES, ORIENTATION_CHOICES
from mocap.io.export.formats import FORMATS
from mocap.person import DEFAULT_MODEL, available, install_hint

AUTO = "auto"  # the orientation dropdown's "no entry on this frame"
NO_JOINT = "none"  # the joint dropdown's "clicks place nothing"
LIMBS = ("arm", "leg")  # the pairs the Joints tab swaps (mocap.body.LIMB_JOINTS)
FRAME_STEPS = ("◀ frame", "frame ▶")
KEY_STEPS = ("◀ keyframe", "keyframe ▶")
EDITS = ("↶ undo", "redo ↷")
VIEW_PAIRS = ("frame + 3D", "silhouette + side")  # a phone's two views at a time (app.layout.PAIRS)
DOWNLOADS = {fmt.label: fmt.key for fmt in FORMATS.values()}  # button -> format
METHOD_CHOICES = {"silhouette": "silhouette", "tracking": "track"}  # shown -> annotations'
MARKING_HELP = (
    "The tracking method follows the 16 joints marked on frame 0, over any "
    "background. With the learned eyes on, choosing it places them where the person "
    "model (else the silhouette fit) sees the body: check each, and move a wrong one "
    "with Joints: Place; with nobody on frame 0, **Track** alone lets the person model "
    "mark the body where it first is sure of it. Or "
    "**Mark joints**: it goes to frame 0 and asks for each joint in turn; click where "
    "it is on the video frame. Then press **Track**. Where the review says the body "
    "was lost, go to a frame that shows it and press **Mark joints** again: the 16 "
    "joints marked there start the tracking anew; press **Track**. Click each joint "
    "precisely, the top of the head on the hair's outline: the tracking cuts its blocks "
    "from the marks, and one a few pixels off carries background with it."
)
STATIC = Path(__file__).resolve().parents[1] / "static"
HELP_FILE = STATIC / "help.md"  # the Help folder; its pictures sit beside it
# action -> (label in the command palette, key, modifier). The keys of a video editor's
# J/K/L; viser's own camera keys (W, A, S, D, Q, E, the arrows) are left alone.
HOTKEYS: dict[str, tuple[str, str, str | None]] = {
    "prev_frame": ("Previous frame", "J", None),
    "next_frame": ("Next frame", "L", None),
    "prev_key": ("Previous keyframe", "J", "shift"),
    "next_key": ("Next keyframe", "L", "shift"),
    "keyframe": ("Mark or unmark keyframe", "K", None),
    "doubtful": ("Next doubtful frame", "N", None),
    "undo": ("Undo", "Z", "cmd/ctrl"),
    "redo": ("Redo", "Z", "cmd/ctrl+shift"),
    "play": ("Play or pause the animation", "P", None),
}


HELP = "  \n".join(f"**{'+'.join(filter(None, [mod, key]))}** {label.lower()}" for label, key, mod in HOTKEYS.values())


def help_markdown(path: Path = HELP_FILE) -> str:
    """The help page's markdown with its SVG pictures inlined as data URLs (viser reads
    raster images from ``image_root`` itself, but not SVG)."""

    def inline(match: re.Match) -> str:
        picture = path.parent / match.group(2)
        if picture.suffix != ".svg" or not picture.is_file():
            return match.group(0)
        data = base64.b64encode(picture.read_bytes()).decode()
        return f"![{match.group(1)}](data:image/svg+xml;base64,{data})"

    return re.sub(r"!\[([^]]*)\]\(([^)]*)\)", inline, path.read_text(encoding="utf-8"))


@dataclass(frozen=True)
class Controls:
    """Handles of every control on the page."""

    progress: object
    status: object
    views: object
    method: object
    frame: object
    frame_steps: object
    key_steps: object
    keyframe: object
    frame_info: object
    orientation: object
    orientation_note: object
    segments: dict
    joint: object
    clear_override: object
    swaps: dict
    overrides: object
    edits: object
    doubtful: object
    review: object
    play: object
    downloads: object
    commands: dict
    help_page: object
    track_info: object
    mark: object
    marks_from_fit: object
    track: object
    stage: object
    use_stage: object
    stage_info: object
    learned_eyes: object
    show_landmarks: object
    foot_lock: object


def build_controls(gui, n_frames: int) -> Controls:
    """Lay out the control panel: the frame and the undo history always in view, the rest on tabs."""
    gui.configure_theme(control_width="medium", show_share_button=False)
    gui.main_panel.dock_right()
    progress = gui.add_progress_bar(0.0, animated=True)
    status = gui.add_markdown("Preprocessing…")
    views = gui.add_button_group("Views", VIEW_PAIRS, visible=False)
    method = gui.add_dropdown(
        "Method",
        tuple(METHOD_CHOICES),
        initial_value="silhouette",
        hint="silhouette: static camera and background, nothing to mark; tracking: follows joints marked on frame 0",
    )
    frame = gui.add_slider("Frame", 0, max(n_frames - 1, 0), 1, 0)
    frame_steps = gui.add_button_group("Step", FRAME_STEPS)
    key_steps = gui.add_button_group("Jump", KEY_STEPS)
    play = gui.add_button("Play", icon="player-play", disabled=True)
    keyframe = gui.add_button("Unmark keyframe", icon="key")
    frame_info = gui.add_markdown("")
    edits = gui.add_button_group("Edit", EDITS)
    # folders, not tabs, above them so that they show without scrolling: used once, at the end,
    # or seldom (a sixth tab would wrap the tabs)
    with gui.add_folder("Export", expand_by_default=False):
        foot_lock = gui.add_checkbox(
            "Foot lock",
            initial_value=False,
            hint="keep each planted foot in place through its contact in the files downloaded",
        )
        downloads = {
            f.label: gui.add_button(f.label, icon="download", disabled=True, hint=None if f.available() else f.needs)
            for f in FORMATS.values()
        }
        gui.add_markdown(
            "*HTML page*: the playback page, one HTML file that plays the "
            "body in any browser, from disk, with no server."
        )
    with gui.add_folder("Help", expand_by_default=False):
        gui.add_markdown(HELP)
        help_page = gui.add_markdown(help_markdown(), image_root=STATIC)
    tabs = gui.add_tab_group()
    with tabs.add_tab("Body"):
        orientation = gui.add_dropdown(
            "Facing",
            (AUTO, *ORIENTATION_CHOICES),
            initial_value=AUTO,
            hint="which way the performer faces, from this frame on",
        )
        orientation_note = gui.add_markdown("")
        segments = build_signs(gui)
    with tabs.add_tab("Joints"):
        joint = gui.add_dropdown(
            "Place",
            (NO_JOINT, *JOINT_CHOICES),
            initial_value=NO_JOINT,
            hint="choose a joint, then click where it is on the video frame",
        )
        gui.add_markdown("Choose a joint, then click where it is on the video frame.")
        clear_override = gui.add_button(
            "Clear override", icon="eraser", hint="the chosen joint's, or every one on this frame"
        )
        swaps = {
            limb: gui.add_button(
                f"Swap {limb}s", icon="arrows-exchange", hint=f"left and right {limb}s exchanged on this frame"
            )
            for limb in LIMBS
        }
        overrides = gui.add_markdown("")
    with tabs.add_tab("Tracking"):
        mark, marks_from_fit, track, track_info = _tracking_tab(gui)
    with tabs.add_tab("Review"):
        doubtful = gui.add_button("Next doubtful frame", icon="alert-triangle")
        review = gui.add_markdown("")
    with tabs.add_tab("Stage"):
        stage, use_stage, stage_info = _stage_tab(gui)
        learned_eyes, show_landmarks = _eyes_controls(gui)
    commands = {
        action: gui.add_command(label, hotkey=key, modifier=mod) for action, (label, key, mod) in HOTKEYS.items()
    }
    return Controls(
        progress,
        status,
        views,
        method,
        frame,
        frame_steps,
        key_steps,
        keyframe,
        frame_info,
        orientation,
        orientation_note,
        segments,
        joint,
        clear_override,
        swaps,
        overrides,
        edits,
        doubtful,
        review,
        play,
        downloads,
        commands,
        help_page,
        track_info,
        mark,
        marks_from_fit,
        track,
        stage,
        use_stage,
        stage_info,
        learned_eyes,
        show_landmarks,
        foot_lock,
    )


def _tracking_tab(gui) -> tuple[object, object, object, object]:
    """The Tracking tab's controls: marking, marks from the fit, Track, what it says."""
    gui.add_markdown(MARKING_HELP)
    mark = gui.add_button(
        "Mark joints",
        icon="pointer",
        hint="go to frame 0 and place each joint not yet marked; once all are, "
        "mark the body again on this frame (where the tracking lost it)",
    )
    marks_from_fit = gui.add_button(
        "Marks from the silhouette fit", icon="wand", hint="place all 16 marks where frame 0's fit has them"
    )
    track = gui.add_button("Track", icon="player-track-next", hint="track the marked joints through the video")
    return mark, marks_from_fit, track, gui.add_markdown("")


def _stage_tab(gui) -> tuple[object, object, object]:
    """The Stage tab's controls: the empty stage's source, the button that uses it, what it says."""
    gui.add_markdown(STAGE_HELP)
    stage = gui.add_text(
        "Empty stage",
        initial_value="",
        hint="frames A-B of this video, or a photo or video file of the empty "
        "stage beside the annotation file; empty: estimated from the clip",
    )
    use_stage = gui.add_button(
        "Use as the empty stage", icon="photo-check", hint="find the silhouettes again against it and refit"
    )
    return stage, use_stage, gui.add_markdown("")


def _eyes_controls(gui) -> tuple[object, object]:
    """The learned eyes: the person model on or off (a refit) and whether its joints are shown."""
    gui.add_markdown(EYES_HELP)
    installed = available(DEFAULT_MODEL)
    learned_eyes = gui.add_checkbox(
        "Learned eyes (person model)",
        initial_value=False,
        disabled=True,
        hint="find the silhouettes again with the person model (on) or by the difference from the "
        "empty stage alone (off), and refit"
        if installed
        else install_hint(DEFAULT_MODEL),
    )
    show_landmarks = gui.add_checkbox(
        "Show the person model's joints", initial_value=True, hint="its joints as magenta dots on the silhouette panel"
    )
    return learned_eyes, show_landmarks


# -- what the controls say about a frame ------------------------------------------------
