"""The Body tab's foreshortening sign buttons, grouped by limb; a click flips the sign, as in 3D. Each
shows its state by icon and word (circle-dot "toward": the far end points at the camera; circle-x
"away") and its source; the colour repeats the icon in a colour-blind-safe pair."""

from __future__ import annotations

from app.state import FrameView
from mocap.body import AWAY, SEGMENT_INDEX, SEGMENT_NAMES, SIDES, TOWARD, limb, segment_label

# sign -> (word, icon, colour)
SIGN_LOOK = {TOWARD: ("toward", "circle-dot", (94, 60, 153)), AWAY: ("away", "circle-x", (240, 200, 60))}
FLAT = 0.05  # |dZ| / length below which a segment lies in the image plane
SIDE_NAMES = {"l": "Left", "r": "Right"}
LEGEND = (
    "Each segment's far end **⊙ toward** the camera or **⊗ away**, and who says so. "
    "Click to flip, or click the segment in 3D."
)


def sign_groups() -> tuple[tuple[str, tuple[str, ...]], ...]:
    """(heading, segments) of the sign list: the torso and head, then each arm, then each leg."""
    centre = tuple(s for s in SEGMENT_NAMES if not s.endswith(tuple(f"_{side}" for side in SIDES)))
    return (("Torso and head", centre),) + tuple(
        (f"{SIDE_NAMES[side]} {kind}", limb(kind, side).segments) for kind in ("arm", "leg") for side in SIDES
    )


def build_signs(gui) -> dict:
    """The legend, then a heading and a button per segment for each group: segment -> button."""
    gui.add_markdown(LEGEND)
    buttons = {}
    for heading, segments in sign_groups():
        gui.add_markdown(f"**{heading}**")
        for segment in segments:
            buttons[segment] = gui.add_button(f"{segment_label(segment)}: –", icon="circle-dashed", disabled=True)
    return buttons


def sign_button(segment: str, view: FrameView) -> dict:
    """Label, icon, colour and state of a segment's button on a frame: disabled without a 3D pose."""
    if view.signs is None:
        return {"label": f"{segment_label(segment)}: –", "icon": "circle-dashed", "color": None, "disabled": True}
    k = SEGMENT_INDEX[segment]
    word, icon, colour = SIGN_LOOK[view.signs[k]]
    flat = " · flat" if view.depths[k] < FLAT else ""  # in the image plane: either will do
    return {
        "label": f"{segment_label(segment)}: {word} · {view.sign_notes[k]}{flat}",
        "icon": icon,
        "color": colour,
        "disabled": False,
    }
