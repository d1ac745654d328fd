"""What the page says about the frame, the stage, the learned eyes, the orientation, the
review queue and the tracking, in the words of the page (markdown)."""

from __future__ import annotations

from app.state import AppState, FrameView
from app.words import joint_label, orientation_label
from mocap.body import SIDE_WORDS
from mocap.person import NONE

REVIEW_LINES = 8  # doubtful frames listed on the page


def frame_text(view: FrameView) -> str:
    """The frame's markdown: which frame, whether a keyframe, fit quality, doubts."""
    head = f"**Frame {view.index}** of 0–{view.n_frames - 1} · " + (
        "keyframe" if view.keyframe else "not a keyframe (interpolated in the export)"
    )
    if not view.fitted:
        done = "tracked" if view.method == "track" else "fitted"
        body = f"Not {done} yet." if view.progress.error is None else f"Not {done}."
    elif view.score is None:
        body = "Nobody found on this frame."
    else:
        score = "Tracking reliability" if view.method == "track" else "Similarity S ="
        body = f"{score} **{view.score:.2f}**" + "".join(f"  \n⚠ {with_fix(d)}" for d in view.doubts)
        body += "".join(
            f"  \n↔ {', '.join(map(joint_label, joints))} moved by the pin on frame {source}"
            for source, joints in pins_by_frame(view.carried).items()
        )
    return f"{head}  \n{body}"


# a doubt's words -> the page's control that answers it
FIXES = {"hands may have swapped sides": "Joints: Swap arms", "feet may have swapped sides": "Joints: Swap legs"}


def with_fix(doubt: str) -> str:
    """A doubt, with the control that fixes it where one does at a click."""
    fix = next((f for words, f in FIXES.items() if doubt.startswith(words)), None)
    return doubt if fix is None else f"{doubt} ({fix})"


def pins_by_frame(carried: dict[str, int]) -> dict[int, list[str]]:
    """frame -> the joints its pins carry to this frame (FrameView.carried)."""
    out: dict[int, list[str]] = {}
    for joint, source in carried.items():
        out.setdefault(source, []).append(joint)
    return dict(sorted(out.items()))


STAGE_HELP = (
    "The silhouettes are the frame's difference from the empty stage. When the "
    "performer never leaves a spot, the stage there is only guessed: give frames of "
    "this video where the stage is empty (e.g. `0-40`), or a photo or short video of it "
    "filmed from the same place."
)


EYES_HELP = (
    "**Learned eyes**: a person model (MediaPipe Pose) looks at each frame too, and at "
    "its mirror image (its joints are the mean of the two). Where "
    "it sees the performer, its mask is the silhouette, edged by the difference from the "
    "empty stage (teal on the silhouette panel: where only it saw the body, e.g. a part "
    "that never moved), and its joints (magenta dots) guide the fit. Where it sees nobody, "
    "it is shown the figure the difference from the empty stage found, cut out on a plain "
    "ground, and names its joints there. Off: the difference from the empty stage alone, "
    "the paper's classical path."
)
PERSON_MODEL_NAMES = {"mediapipe": "MediaPipe"}  # a person model's name as the page says it


def eyes_text(state) -> str:
    """What the silhouette method looks through, on how many frames the person model saw somebody and on how many
    the silhouettes alone answer."""
    name = state.person_model
    if name == NONE:
        return "Eyes: silhouettes only (the difference from the empty stage)."
    seen, cut_out, done = state.eyes_seen()
    text = f"Eyes: person model ({PERSON_MODEL_NAMES.get(name, name)}) + silhouettes"
    if done:
        text += f"; it saw the performer on {seen} of {done} frames"
        if cut_out:
            text += f" ({cut_out} of them only when shown the silhouette cut out)"
        if seen < done:
            text += f", the silhouettes alone answer the other {done - seen}"
    return text + "."


def stage_text(state) -> str:
    """The empty stage in use and the fit's warning about it."""
    background = state.annotations.background
    used = (
        "estimated from the clip"
        if background is None
        else f"frames {background[0]}-{background[1]}"
        if isinstance(background, tuple)
        else f"`{background}`"
    )
    warning = state.background_warning
    return f"Empty stage: {used}." + (f"  \n**Warning:** {warning}." if warning else "")


def orientation_text(view: FrameView) -> str:
    """Which way the performer faces on the frame, and who said so."""
    if view.orientation is None:
        return "Facing: not known yet."
    return f"Facing **{orientation_label(view.orientation)}** ({view.orientation_note})."


def review_text(state: AppState) -> str:
    """The review queue's head as markdown."""
    queue = state.review_stops(at_once=True)
    if not state.progress.ready:
        return "Ranked once every frame is fitted."
    if not queue:
        return "No doubtful frame."
    lines = [f"- **{d.frame}**: {'; '.join(d.reasons)}" for d in queue[:REVIEW_LINES]]
    head = (
        f"{len(queue)} frames to review, most doubtful first:"
        if len(queue) <= REVIEW_LINES
        else f"{len(queue)} frames to review; the {REVIEW_LINES} most doubtful (Next doubtful frame walks them all):"
    )
    return far_arm_text(state) + head + "\n" + "\n".join(lines)


def far_arm_text(state: AppState) -> str:
    """The tracking's advice to check its far arm first (TrackSession.far_arm)."""
    side = state.far_arm()
    if side is None:
        return ""
    name = SIDE_WORDS[side]
    return (
        f"The tracker loses the **far arm** most: at each stop, check the **{name}** "
        f"elbow and wrist first (the performer's {name}, farther from the camera).\n\n"
    )


UNMARKED_TRACK = "the person model marks the body where it is first sure of it, and the tracking goes back to frame 0"


def track_prompt(state: AppState) -> str:
    """The status line's next step of a tracking not started: mark frame 0, or Track (``tracks_unmarked``)."""
    missing = len(state.unmarked())
    if not missing:
        return "Tracking: all 16 joints are marked on frame 0; press Track (Tracking tab)."
    if state.tracks_unmarked:
        return f"Tracking: press Track ({UNMARKED_TRACK}), or mark the 16 joints on frame 0 first (Tracking tab)."
    return f"Tracking: mark the 16 joints on frame 0 ({missing} to go; Tracking tab), then press Track."


def tracking_text(state: AppState) -> str:
    """The Tracking tab's state: the marks, whether they were tracked, the tracking."""
    missing = state.unmarked()
    if state.tracks_unmarked:
        marks = f"No joints marked on frame 0: with **Track** {UNMARKED_TRACK}; or **Mark joints** first."
    elif missing:
        marks = (
            f"**{16 - len(missing)} of 16** joints marked on frame 0; next: {', '.join(map(joint_label, missing[:4]))}"
            + ("…" if len(missing) > 4 else "")
        )
    else:
        marks = "All 16 joints marked on frame 0."
    again = state.marking_frame()
    left = state.unmarked(again)
    if again and len(left) < 16:
        marks += (
            f"  \n**{16 - len(left)} of 16** joints marked again on frame {again}; next: {joint_label(left[0])}"
            if left
            else f"  \nAll 16 joints marked again on frame {again}."
        )
    if state.method != "track":
        return marks + "  \nChoose *tracking* as the method to see the tracked motion."
    p = state.progress
    if p.error is not None:
        return f"{marks}  \n**Stopped:** {p.error}"
    if not p.ready:
        return marks + (
            f"  \nTracking… {100 * p.done // max(p.total, 1)}%"
            if state.tracking
            else ""
            if state.tracks_unmarked
            else "  \nPress **Track** when the marks are right."
        )
    return (
        marks
        + "  \n"
        + (
            "**The marks changed since the tracking: press Track again.**"
            if state.marks_changed
            else f"{p.total} frames tracked."
        )
    )
