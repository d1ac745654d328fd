"""Reading BVH motion capture and mapping it onto the 16 contract joints.

A HIERARCHY of joints (OFFSET from the parent; CHANNELS: X/Y/Z position and rotation, any order),
then MOTION, a line of channel values per frame; position channels replace OFFSET components,
rotations compose in the listed order (intrinsic Euler, degrees)."""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from mocap import body
from mocap.errors import MocapError

_CHANNEL_NAMES = {f"{axis}{kind}" for axis in "XYZ" for kind in ("position", "rotation")}
_HEAD_END_MIN_COSINE = 0.7  # a Head End Site this aligned with parent->Head is the top


@dataclass(frozen=True, eq=False)
class BvhMotion:
    """A parsed BVH file: joint j is ``names[j]``, ``parents[j]`` (-1: root), ``offsets[j]`` (file units),
    ``channels[j]``, ``end_site[j]``; ``values`` (F, C) raw channel values, joint j's from ``channel_start[j]``."""

    names: tuple[str, ...]
    parents: np.ndarray
    offsets: np.ndarray
    channels: tuple[tuple[str, ...], ...]
    end_site: np.ndarray
    frame_time: float
    values: np.ndarray
    source: str = "<string>"

    @property
    def n_frames(self) -> int:
        """Number of frames in MOTION."""
        return len(self.values)

    @property
    def channel_start(self) -> np.ndarray:
        """First column in ``values`` of each joint's channels."""
        counts = np.array([len(c) for c in self.channels])
        return np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(int)

    def positions(self) -> np.ndarray:
        """Global joint positions (F, J, 3) in file units, for every frame at once."""
        n, start = self.n_frames, self.channel_start
        pos = np.empty((n, len(self.names), 3))
        rot: list[Rotation] = []
        for j, chans in enumerate(self.channels):
            cols = self.values[:, start[j] : start[j] + len(chans)]
            trans = np.repeat(self.offsets[j][None], n, axis=0)
            axes, angles = "", []
            for k, chan in enumerate(chans):
                if chan.endswith("position"):
                    trans[:, "XYZ".index(chan[0])] = cols[:, k]
                else:
                    axes += chan[0]
                    angles.append(cols[:, k])
            local = Rotation.from_euler(axes, np.stack(angles, axis=1), degrees=True) if axes else Rotation.identity(n)
            parent = self.parents[j]
            if parent < 0:
                pos[:, j], rotation = trans, local
            else:
                pos[:, j] = pos[:, parent] + rot[parent].apply(trans)
                rotation = rot[parent] * local
            rot.append(rotation)
        return pos


def read_bvh(path: str | Path) -> BvhMotion:
    """Read a BVH file; any problem becomes a one-line MocapError naming the file."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise MocapError(f"cannot read BVH file {path}: {exc.strerror or exc}") from None
    return parse_bvh(text, source=path.name)


def parse_bvh(text: str, source: str = "<string>") -> BvhMotion:
    """Parse BVH text (HIERARCHY then MOTION) into a BvhMotion."""
    split = re.search(r"^\s*MOTION\b", text, re.MULTILINE)
    if not text.lstrip().startswith("HIERARCHY") or split is None:
        raise MocapError(f"{source}: not a BVH file (expected HIERARCHY ... MOTION)")
    names, parents, offsets, channels, ends = _parse_hierarchy(text[: split.start()].split(), source)
    frame_time, values = _parse_motion(text[split.end() :], sum(len(c) for c in channels), source)
    return BvhMotion(
        names=tuple(names),
        parents=np.array(parents, dtype=int),
        offsets=np.array(offsets, dtype=float),
        channels=tuple(channels),
        end_site=np.array(ends, dtype=bool),
        frame_time=frame_time,
        values=values,
        source=source,
    )


def _parse_hierarchy(tokens: list[str], source: str):
    """Joint lists from the HIERARCHY tokens: names, parents, offsets, channels, ends."""
    names, parents, offsets, channels, ends = [], [], [], [], []
    stack: list[int] = []
    i = 1
    try:
        while i < len(tokens):
            tok = tokens[i]
            if tok in ("ROOT", "JOINT", "End"):
                if (tok == "ROOT") != (not stack and not names) or (tok == "End" and tokens[i + 1] != "Site"):
                    raise MocapError(f"{source}: unexpected {tok} in HIERARCHY")
                parent = stack[-1] if stack else -1
                names.append(tokens[i + 1] if tok != "End" else f"{names[parent]}_end")
                parents.append(parent)
                offsets.append((0.0, 0.0, 0.0))
                channels.append(())
                ends.append(tok == "End")
                i += 2
            elif tok == "{":
                stack.append(len(names) - 1)
                i += 1
            elif tok == "}":
                stack.pop()
                i += 1
            elif tok == "OFFSET":
                offsets[stack[-1]] = tuple(float(v) for v in tokens[i + 1 : i + 4])
                i += 4
            elif tok == "CHANNELS":
                count = int(tokens[i + 1])
                channels[stack[-1]] = _check_channels(tokens[i + 2 : i + 2 + count], count, source)
                i += 2 + count
            else:
                raise MocapError(f"{source}: unexpected {tok!r} in HIERARCHY")
    except (IndexError, ValueError):
        raise MocapError(f"{source}: garbled HIERARCHY near token {i} ({' '.join(tokens[i : i + 4])!r})") from None
    if stack or not names or any(len(o) != 3 for o in offsets):
        raise MocapError(f"{source}: incomplete HIERARCHY (unbalanced braces or short OFFSET)")
    return names, parents, offsets, channels, ends


def _check_channels(chans: list[str], count: int, source: str) -> tuple[str, ...]:
    """Validate one CHANNELS list (names, count, at most three rotations)."""
    bad = [c for c in chans if c not in _CHANNEL_NAMES]
    if len(chans) != count or bad or sum(c.endswith("rotation") for c in chans) > 3:
        raise MocapError(f"{source}: bad CHANNELS {' '.join(chans)!r}")
    return tuple(chans)


def _parse_motion(text: str, n_channels: int, source: str) -> tuple[float, np.ndarray]:
    """Frame time and the (F, C) channel values from the text after MOTION."""
    head = re.match(r"\s*Frames:\s*(\d+)\s*Frame\s+Time:\s*(\S+)", text)
    if head is None:
        raise MocapError(f"{source}: MOTION lacks 'Frames:' and 'Frame Time:'")
    n_frames = int(head.group(1))
    try:
        frame_time = float(head.group(2))
        values = np.array(text[head.end() :].split(), dtype=float)
    except ValueError:
        raise MocapError(f"{source}: MOTION data contains a non-number") from None
    if n_frames < 1 or not frame_time > 0:
        raise MocapError(f"{source}: MOTION needs at least one frame and a positive Frame Time")
    if values.size != n_frames * n_channels:
        raise MocapError(
            f"{source}: expected {n_frames} frames x {n_channels} channels = "
            f"{n_frames * n_channels} numbers, found {values.size}"
        )
    return frame_time, values.reshape(n_frames, n_channels)


# -- mapping onto the contract's 16 joints --------------------------------------------

_SIDE_PREFIXES = {"l": ("left", "l"), "r": ("right", "r")}
_LIMB_ENDS = {"wrist": ("wrist", "hand"), "ankle": ("ankle", "foot")}
_LIMB_CHAINS = {names[-1]: names[:-1] for names in body.LIMB_JOINTS.values()}  # end -> its chain


def _key(name: str) -> str:
    """Comparable joint name: namespace dropped, lower case, letters and digits only."""
    return re.sub(r"[^a-z0-9]", "", name.split(":")[-1].lower())


def _find(motion: BvhMotion, candidates: list[str], role: str) -> int:
    """Index of the first candidate name present among the (non End Site) joints."""
    keys = [_key(n) if not e else None for n, e in zip(motion.names, motion.end_site)]
    for cand in candidates:
        if cand in keys:
            return keys.index(cand)
    raise MocapError(f"{motion.source}: no joint for {role} (looked for {', '.join(candidates)})")


def joint_map(motion: BvhMotion) -> dict[str, int]:
    """BVH joint index of the head and every contract limb joint: limbs are walked up the parents from
    their distal joint (LeftWrist/LeftHand/lHand, LeftAnkle/LeftFoot/lFoot), which tells DAZ's
    LeftShoulder (an upper arm) from CMU's (a collar bone)."""
    found = {"head": _find(motion, ["head"], "head")}
    for side, prefixes in _SIDE_PREFIXES.items():
        for end, words in _LIMB_ENDS.items():
            j = _find(motion, [p + w for w in words for p in prefixes], f"{end}_{side}")
            found[f"{end}_{side}"] = j
            for name in reversed(_LIMB_CHAINS[end]):
                j = int(motion.parents[j])
                found[f"{name}_{side}"] = j
    return found


def _head_top(motion: BvhMotion, pos: np.ndarray, head: int) -> np.ndarray:
    """(F, 3) head top: the Head's End Site if it continues the parent->Head direction, else the Head
    plus twice that vector (DAZ files end the head with a sideways stub)."""
    parent = motion.parents[head]
    along = pos[:, head] - pos[:, parent]
    for j in np.flatnonzero(motion.end_site & (motion.parents == head)):
        tip = pos[0, j] - pos[0, head]
        cos = tip @ along[0] / (np.linalg.norm(tip) * np.linalg.norm(along[0]) + 1e-12)
        if cos > _HEAD_END_MIN_COSINE:
            return pos[:, j]
    return pos[:, head] + 2.0 * along


def contract_joints_units(motion: BvhMotion) -> np.ndarray:
    """(F, 16, 3) contract joints in the file's own units and axes."""
    pos = motion.positions()
    found = joint_map(motion)
    out = np.empty((motion.n_frames, len(body.JOINTS), 3))
    for name, j in found.items():
        if name in body.JOINT_INDEX:
            out[:, body.JOINT_INDEX[name]] = pos[:, j]
    out[:, body.JOINT_INDEX["head_top"]] = _head_top(motion, pos, found["head"])
    # The model's pelvis and neck are the ends of the torso: the legs attach at the
    # pelvis, the arms a little below the neck (body.SHOULDER_DROP). Skeletons place
    # their root and neck joints variously, so the contract's pelvis is the midpoint
    # of the hips and its neck continues the pelvis->shoulders axis by that drop.
    ij = body.JOINT_INDEX
    out[:, ij["pelvis"]] = pelvis = (out[:, ij["hip_l"]] + out[:, ij["hip_r"]]) / 2
    shoulders = (out[:, ij["shoulder_l"]] + out[:, ij["shoulder_r"]]) / 2
    out[:, ij["neck"]] = neck = pelvis + body.NECK_PER_SHOULDER * (shoulders - pelvis)
    out[:, ij["chest"]] = pelvis + body.CHEST_FRACTION * (neck - pelvis)
    return out


def contract_joints(motion: BvhMotion) -> np.ndarray:
    """(F, 16, 3) contract joints in metres, BVH axes (y up), scaled so frame 0's ``body.body_height``
    is 1.75 m; origin and trajectory kept (scaled), not re-centred."""
    joints = contract_joints_units(motion)
    return joints * (body.BODY_HEIGHT_M / body_height_units(joints))


def body_height_units(joints_units: np.ndarray) -> float:
    """Body height (``body.body_height`` of frame 0) of unscaled contract joints."""
    height = body.body_height(joints_units[0])
    if not height > 0:
        raise MocapError("skeleton has zero body height")
    return height
