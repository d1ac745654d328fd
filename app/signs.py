"""The Body tab's foreshortening signs, grouped by limb: the torso and the head, then the
performer's left arm, right arm, left leg and right leg (mocap.body's limbs), a button
per segment; a click flips the segment's sign, as a click on it in 3D does.

Each button says its state with an icon and a word (circle-dot, "toward": the segment's
far end points at the camera, as an arrow's tip seen head-on; circle-x, "away": its
tail) and where the state comes from (set here, held from frame K, guessed). Its colour
only repeats the icon, in a pair that colour-blind eyes tell apart (purple and yellow,
apart from the orange and blue the views give the left and right limbs).
"""

from __future__ import annotations

from app.state import FrameView
from mocap.body import AWAY, SEGMENT_INDEX, SEGMENT_NAMES, SIDES, TOWARD, limb, segment_label

# sign -> (word, icon, colour)
SIGN_LOOK = {TOWARD: ("toward", "circle-dot", (94, 60, 153)),
             AWAY: ("away", "circle-x", (240, 200, 60))}
FLAT = 0.05                         # |dZ| / length below which a segment lies in the image plane
SIDE_NAMES = {"l": "Left", "r": "Right"}
LEGEND = ("Each segment's far end **⊙ toward** the camera or **⊗ away**, and who says so. "
          "Click to flip, or click the segment in 3D.")


def sign_groups() -> tuple[tuple[str, tuple[str, ...]], ...]:
    """(heading, segments) of the sign list: the torso and head, then each arm, then each leg."""
    centre = tuple(s for s in SEGMENT_NAMES if not s.endswith(tuple(f"_{side}" for side in SIDES)))
    return (("Torso and head", centre),) + tuple(
        (f"{SIDE_NAMES[side]} {kind}", limb(kind, side).segments) for kind in ("arm", "leg") for side in SIDES)


def build_signs(gui) -> dict:
    """The legend, then a heading and a button per segment for each group: segment -> button."""
    gui.add_markdown(LEGEND)
    buttons = {}
    for heading, segments in sign_groups():
        gui.add_markdown(f"**{heading}**")
        for segment in segments:
            buttons[segment] = gui.add_button(f"{segment_label(segment)}: –", icon="circle-dashed",
                                              disabled=True)
    return buttons


def sign_button(segment: str, view: FrameView) -> dict:
    """Label, icon, colour and state of a segment's button on a frame: disabled without
    a 3D pose (not lifted yet, or nobody found)."""
    if view.signs is None:
        return {"label": f"{segment_label(segment)}: –", "icon": "circle-dashed", "color": None,
                "disabled": True}
    k = SEGMENT_INDEX[segment]
    word, icon, colour = SIGN_LOOK[view.signs[k]]
    flat = " · flat" if view.depths[k] < FLAT else ""       # in the image plane: either will do
    return {"label": f"{segment_label(segment)}: {word} · {view.sign_notes[k]}{flat}", "icon": icon,
            "color": colour, "disabled": False}
