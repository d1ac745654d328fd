"""Which controls can act on the frame shown; the others are disabled. Button groups cannot be
disabled in viser: the tab's notification says what they refuse."""

from __future__ import annotations

from functools import cache

from app.controls import DOWNLOADS, NO_JOINT, Controls
from app.signs import sign_button
from app.state import AppState, FrameView
from mocap.io.export.formats import FORMATS
from mocap.person import DEFAULT_MODEL, available


@cache
def writable(label: str) -> bool:
    """Whether this installation writes a download button's format (FBX needs Blender)."""
    return FORMATS[DOWNLOADS[label]].available()


@cache
def person_model_installed() -> bool:
    """Whether the default person model's package is installed (the learned eyes' switch)."""
    return available(DEFAULT_MODEL)


def control_states(c: Controls, state: AppState, view: FrameView) -> list[tuple[object, dict]]:
    """(handle, props) of every control whose state depends on the frame or the work done."""
    joint = c.joint.value
    lifted = view.progress.ready and view.progress.error is None
    keys = state.annotations.keyframe_indices(state.n_frames)
    out = [(c.segments[s], sign_button(s, view)) for s in c.segments]
    out += [(button, {"disabled": not lifted or not writable(label)}) for label, button in c.downloads.items()]
    out += [
        # a frame not fitted, or without anybody, lifts nothing; the last keyframe stays
        (
            c.keyframe,
            {
                "label": "Unmark keyframe" if view.keyframe else "Mark as keyframe",
                "disabled": view.joints2d is None or (view.keyframe and len(keys) == 1),
            },
        ),
        (c.clear_override, {"disabled": not view.overrides or (joint != NO_JOINT and joint not in view.overrides)}),
        *((button, {"disabled": not view.sides_known}) for button in c.swaps.values()),
        (c.doubtful, {"disabled": not lifted or not state.review_stops(at_once=True)}),
        (c.foot_lock, {"disabled": not lifted}),
        (c.mark, {"disabled": not state.unmarked(state.marking_frame())}),
        (c.marks_from_fit, {"disabled": not state.silhouette_fitted}),
        (c.track, {"disabled": state.tracking or bool(state.unmarked()) and not state.tracks_unmarked}),
        # switched as a new empty stage is set: once the fit is done, refitting
        (c.learned_eyes, {"disabled": not state.ready.is_set() or not person_model_installed()}),
    ]
    return out
