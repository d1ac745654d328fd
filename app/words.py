"""The page's plain words for the contract's names: joints ("wrist_l" -> "left wrist") and orientations
("forward_left" -> "front, turned to image left"; segments: mocap.body.segment_label, which the review's reasons
share); the dropdowns show these and map the choice back (``chosen``)."""

from __future__ import annotations

from mocap.body import JOINTS, ORIENTATIONS, sided_label

JOINT_WORDS = {"head_top": "top of the head"}
ORIENTATION_WORDS = {
    "left": "side-on, facing image left",
    "right": "side-on, facing image right",
    "forward_left": "front, turned to image left",
    "forward_right": "front, turned to image right",
    "backward_left": "back, turned to image left",
    "backward_right": "back, turned to image right",
}


def joint_label(joint: str) -> str:
    """A joint's name for people: 'wrist_l' -> 'left wrist' (the performer's left)."""
    return JOINT_WORDS.get(joint) or sided_label(joint)


def orientation_label(orientation: str) -> str:
    """An orientation's name for people: 'backward_right' -> 'back, turned to image right'."""
    return ORIENTATION_WORDS[orientation]


JOINT_CHOICES = {joint_label(j): j for j in JOINTS}  # shown -> the contract's
ORIENTATION_CHOICES = {orientation_label(o): o for o in ORIENTATIONS}


def chosen(choices: dict[str, str], shown: str) -> str | None:
    """The contract's name of a dropdown's shown choice (None: one of the page's own, "none", "auto")."""
    return choices.get(shown)
