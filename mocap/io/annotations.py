"""What the user said: the ``mocap-annotations`` file (CONTRACT.md), checked with messages naming the
bad place, resolved sticky (orientation and foreshortening hold until a later entry, joint overrides
on their own frame only) and saved atomically. Held signs meet the first guess in mocap.lift.inputs."""

from __future__ import annotations

import json
import math
import os
import re
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from mocap.body import FORESHORTENING, JOINTS, ORIENTATIONS, SEGMENT_INDEX, SEGMENT_NAMES
from mocap.errors import MocapError
from mocap.io.fileio import atomic_write_json
from mocap.io.jsoncheck import Bad, describe, expect, is_number

FORMAT, VERSION = "mocap-annotations", 1
_FRAME_KEY = re.compile(r"0|[1-9][0-9]*")
_TOP_KEYS = ("format", "version", "method", "background", "keyframes", "frames")
METHODS = ("silhouette", "track")  # the two methods: mocap fit --method
_FRAME_KEYS = ("orientation", "foreshortening", "joints2d")


@dataclass(frozen=True)
class FrameNote:
    """The user's inputs on one frame; empty fields say nothing."""

    orientation: str | None = None
    foreshortening: dict[str, str] = field(default_factory=dict)  # segment -> toward/away
    joints2d: dict[str, tuple[float, float]] = field(default_factory=dict)

    def is_empty(self) -> bool:
        return self.orientation is None and not self.foreshortening and not self.joints2d

    def to_dict(self) -> dict:
        out: dict = {}
        if self.orientation is not None:
            out["orientation"] = self.orientation
        if self.foreshortening:
            out["foreshortening"] = dict(self.foreshortening)
        if self.joints2d:
            out["joints2d"] = {j: [float(x), float(y)] for j, (x, y) in self.joints2d.items()}
        return out


@dataclass(frozen=True)
class Annotations:
    """All the user's inputs: frame -> FrameNote, ``keyframes`` (None: all), and beyond CONTRACT.md
    ``method`` (None: the silhouette method; "track": frame 0's joints2d are the tracking method's marks)
    and ``background``, the empty scene: a photo or video (relative to the annotation file), the clip's
    (first, last) frames showing the stage empty, or None (estimated from the clip)."""

    frames: dict[int, FrameNote] = field(default_factory=dict)
    keyframes: tuple[int, ...] | None = None
    method: str | None = None
    background: str | tuple[int, int] | None = None

    # -- editing (each returns a new, checked Annotations) --------------------------

    def _with_note(self, frame: int, **changes) -> "Annotations":
        note = replace(self.frames.get(frame, FrameNote()), **changes)
        frames = {k: v for k, v in self.frames.items() if k != frame}
        if not note.is_empty():
            frames[frame] = note
        return replace(self, frames=dict(sorted(frames.items())))

    def with_orientation(self, frame: int, orientation: str | None) -> "Annotations":
        """Set (or with None clear) the orientation entry of a frame."""
        if orientation is not None and orientation not in ORIENTATIONS:
            raise MocapError(f"unknown orientation {orientation!r} (choose {', '.join(ORIENTATIONS)})")
        return self._with_note(frame, orientation=orientation)

    def with_foreshortening(self, frame: int, segment: str, value: str | None) -> "Annotations":
        """Set (or with None clear) one segment's foreshortening entry on a frame."""
        if segment not in SEGMENT_INDEX:
            raise MocapError(f"unknown segment {segment!r}")
        if value is not None and value not in FORESHORTENING:
            raise MocapError(f"foreshortening must be 'toward' or 'away', not {value!r}")
        signs = {**self.frames.get(frame, FrameNote()).foreshortening, segment: value}
        return self._with_note(frame, foreshortening={k: v for k, v in signs.items() if v is not None})

    def with_joint(self, frame: int, joint: str, xy: tuple[float, float] | None) -> "Annotations":
        """Set (or with None clear) a joint override on a frame."""
        if joint not in JOINTS:
            raise MocapError(f"unknown joint {joint!r}")
        if xy is not None and not (len(xy) == 2 and all(math.isfinite(float(v)) for v in xy)):
            raise MocapError(f"joint override must be two finite numbers, not {xy!r}")
        joints = {
            **self.frames.get(frame, FrameNote()).joints2d,
            joint: None if xy is None else (float(xy[0]), float(xy[1])),
        }
        return self._with_note(frame, joints2d={k: v for k, v in joints.items() if v is not None})

    def with_method(self, method: str | None) -> "Annotations":
        """Choose the method (METHODS), or with None leave it unsaid."""
        if method is not None and method not in METHODS:
            raise MocapError(f"unknown method {method!r} (choose {', '.join(METHODS)})")
        return replace(self, method=method)

    def with_background(self, background: str | tuple[int, int] | None) -> "Annotations":
        """Give the empty scene (a file name, or first and last frames); None: estimate it from the clip."""
        try:
            checked = (
                None
                if background is None
                else _background(list(background) if isinstance(background, tuple) else background, None)
            )
        except Bad as exc:
            raise MocapError(str(exc)) from None
        return replace(self, background=checked)

    def background_source(self, path: str | os.PathLike | None) -> str | tuple[int, int] | None:
        """The empty scene, a file name made relative to the annotation file ``path`` (None: cwd)."""
        if isinstance(self.background, str) and path is not None:
            return str(Path(path).parent / self.background)
        return self.background

    # -- sticky resolution ----------------------------------------------------------

    def orientations(self, n_frames: int) -> list[str | None]:
        """Each frame's orientation held from the latest entry at or before it."""
        out: list[str | None] = [None] * n_frames
        for frame, note in self.frames.items():
            if note.orientation is not None and frame < n_frames:
                out[frame:] = [note.orientation] * (n_frames - frame)
        return out

    def held_signs(self, n_frames: int) -> tuple[np.ndarray, np.ndarray]:
        """(values, since), both (F, 10): each segment's latest sign at or before each
        frame (+1 toward, -1 away, 0 none) and the frame of that entry (-1 none)."""
        values = np.zeros((n_frames, len(SEGMENT_NAMES)), np.int8)
        since = np.full((n_frames, len(SEGMENT_NAMES)), -1)
        for frame, note in self.frames.items():
            for segment, value in note.foreshortening.items():
                if frame < n_frames:
                    k = SEGMENT_INDEX[segment]
                    values[frame:, k] = 1 if value == "toward" else -1
                    since[frame:, k] = frame
        return values, since

    def overrides(self) -> dict[int, dict[str, tuple[float, float]]]:
        """frame -> {joint: (x, y)} of the joint overrides (own frame only)."""
        return {f: dict(n.joints2d) for f, n in self.frames.items() if n.joints2d}

    def keyframe_indices(self, n_frames: int) -> list[int]:
        """The keyframes, every frame when none were given."""
        return list(range(n_frames)) if self.keyframes is None else [k for k in self.keyframes if k < n_frames]

    def to_dict(self) -> dict:
        out: dict = {"format": FORMAT, "version": VERSION}
        if self.method is not None:
            out["method"] = self.method
        if self.background is not None:
            out["background"] = self.background if isinstance(self.background, str) else list(self.background)
        if self.keyframes is not None:
            out["keyframes"] = list(self.keyframes)
        out["frames"] = {str(k): v.to_dict() for k, v in self.frames.items()}
        return out


# -- reading and checking -------------------------------------------------------------


def _no_constant(name: str):
    raise ValueError(f"{name} is not a JSON number")


def _unique_keys(pairs: list) -> dict:
    keys = [k for k, _ in pairs]
    if len(set(keys)) != len(keys):
        dup = next(k for k in keys if keys.count(k) > 1)
        raise ValueError(f"duplicate key {json.dumps(dup)}")
    return dict(pairs)


def _frame_index(key: str, frame_count: int | None, place: str) -> int:
    if not _FRAME_KEY.fullmatch(key):
        raise Bad(place, f"frame key {json.dumps(key)} is not a frame index (0, 1, 2, ...)")
    index = int(key)
    if frame_count is not None and index >= frame_count:
        raise Bad(place, f"frame {index} is out of range (the video has {frame_count} frames)")
    return index


def _keyframes(value, frame_count: int | None) -> tuple[int, ...]:
    expect(value, list, "keyframes", "a list of frame indices")
    if not value:
        raise Bad("keyframes", "empty list (leave it out for every frame)")
    for i, k in enumerate(value):
        if not isinstance(k, int) or isinstance(k, bool) or k < 0:
            raise Bad(f"keyframes[{i}]", f"expected a frame index, got {json.dumps(k)[:40]}")
        if frame_count is not None and k >= frame_count:
            raise Bad(f"keyframes[{i}]", f"frame {k} is out of range (the video has {frame_count} frames)")
    return tuple(sorted(set(value)))


def _background(value, frame_count: int | None) -> str | tuple[int, int]:
    """The empty scene: a non-empty file name, or [first, last] frames of the clip."""
    if isinstance(value, str):
        if not value.strip():
            raise Bad("background", "empty file name (leave it out to estimate the background)")
        return value
    if not (
        isinstance(value, list)
        and len(value) == 2
        and all(isinstance(v, int) and not isinstance(v, bool) for v in value)
    ):
        got = json.dumps(value)[:40] if isinstance(value, list) else describe(value)
        raise Bad("background", f"expected a file name or [first, last] frames, got {got}")
    first, last = value
    if not 0 <= first <= last:
        raise Bad("background", f"frames {first}..{last} are not a range (0 <= first <= last)")
    if frame_count is not None and last >= frame_count:
        raise Bad("background", f"frame {last} is out of range (the video has {frame_count} frames)")
    return (first, last)


def _note(value, place: str) -> FrameNote:
    expect(value, dict, place, f"an object (keys {', '.join(_FRAME_KEYS)})")
    for key in value:
        if key not in _FRAME_KEYS:
            raise Bad(place, f"unknown key {json.dumps(key)} (expected {', '.join(_FRAME_KEYS)})")
    orientation = value.get("orientation")
    if orientation is not None and orientation not in ORIENTATIONS:
        raise Bad(
            f"{place}.orientation",
            f"unknown orientation {json.dumps(orientation)[:40]} (choose {', '.join(ORIENTATIONS)})",
        )
    signs = expect(value.get("foreshortening", {}), dict, f"{place}.foreshortening", "an object")
    for segment, sign in signs.items():
        if segment not in SEGMENT_INDEX:
            raise Bad(f"{place}.foreshortening", f"unknown segment {json.dumps(segment)[:40]}")
        if sign not in FORESHORTENING:
            raise Bad(f"{place}.foreshortening.{segment}", f'expected "toward" or "away", got {json.dumps(sign)[:40]}')
    joints = expect(value.get("joints2d", {}), dict, f"{place}.joints2d", "an object")
    points = {}
    for joint, xy in joints.items():
        if joint not in JOINTS:
            raise Bad(f"{place}.joints2d", f"unknown joint {json.dumps(joint)[:40]}")
        if not (isinstance(xy, list) and len(xy) == 2 and all(is_number(v) and math.isfinite(v) for v in xy)):
            raise Bad(f"{place}.joints2d.{joint}", f"expected [x, y] in pixels, got {json.dumps(xy)[:40]}")
        points[joint] = (float(xy[0]), float(xy[1]))
    return FrameNote(orientation, dict(signs), points)


def parse_annotations(data, frame_count: int | None = None) -> Annotations:
    """Check a decoded annotation document; raises Bad naming the place."""
    expect(data, dict, "", "a JSON object")
    if data.get("format") != FORMAT:  # first: a motion file is told by its format
        raise Bad("format", f'expected "{FORMAT}", got {json.dumps(data.get("format"))[:40]}')
    for key in data:
        if key not in _TOP_KEYS:
            raise Bad("", f"unknown key {json.dumps(key)[:40]} (expected {', '.join(_TOP_KEYS)})")
    version = data.get("version")
    if not (isinstance(version, int) and not isinstance(version, bool) and version == VERSION):
        raise Bad("version", f"expected {VERSION}, got {json.dumps(version)[:40]}")
    method = data.get("method")
    if method is not None and method not in METHODS:
        raise Bad("method", f"expected one of {', '.join(METHODS)}, got {json.dumps(method)[:40]}")
    background = _background(data["background"], frame_count) if "background" in data else None
    keyframes = _keyframes(data["keyframes"], frame_count) if "keyframes" in data else None
    frames = expect(
        data.get("frames", {}),
        dict,
        "frames",
        'an object of notes by frame index (e.g. {"12": {"orientation": "left"}})',
    )
    notes = {}
    for key, value in frames.items():
        place = f"frames[{json.dumps(key)[:40]}]"
        notes[_frame_index(key, frame_count, place)] = _note(value, place)
    return Annotations({k: v for k, v in sorted(notes.items()) if not v.is_empty()}, keyframes, method, background)


def annotations_from_text(text: str, frame_count: int | None = None, source: str = "annotations") -> Annotations:
    """Decode and check annotation JSON; any problem is one MocapError naming the place."""
    try:
        data = json.loads(text, parse_constant=_no_constant, object_pairs_hook=_unique_keys)
    except (ValueError, RecursionError) as exc:
        raise MocapError(f"{source}: not valid JSON ({exc})") from None
    try:
        return parse_annotations(data, frame_count)
    except Bad as exc:
        raise MocapError(f"{source}: {exc}") from None


def load_annotations(path: str | os.PathLike, frame_count: int | None = None) -> Annotations:
    """Read an annotation file, checked against the video's frame count."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise MocapError(f"{path}: no such annotation file") from None
    except IsADirectoryError:
        raise MocapError(f"{path}: is a folder, not an annotation file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise MocapError(f"{path}: cannot read annotations ({exc})") from None
    return annotations_from_text(text, frame_count, str(path))


def save_annotations(path: str | os.PathLike, annotations: Annotations) -> Path:
    """Write the annotation file atomically (a crash never leaves half a file)."""
    return atomic_write_json(path, annotations.to_dict())
