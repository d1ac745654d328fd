"""The session: one video, the user's annotations and the 3D they give, whichever the method.

Each method's session supplies ``inputs``, ``pose3d`` and ``root``; the keyframes, the motion (section
3.4's interpolation, ``mocap.lift.motion``) and the motion file's frames (CONTRACT.md) are shared here."""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from pathlib import Path

import numpy as np

from mocap.body import JOINT_INDEX
from mocap.camera import Focal
from mocap.errors import MocapError
from mocap.io.annotations import Annotations, FrameNote
from mocap.io.export.formats import Clip, export_file
from mocap.io.video import VideoInfo
from mocap.lift.contacts import FEET
from mocap.lift.inputs import Inputs, Said, root_track
from mocap.lift.motion import Motion, build_motion
from mocap.lift.taylor import depth_fractions
from mocap.session.review import Doubt, covering, review_queue


class Session(ABC):
    """A video's per-frame results and the user's annotations (checked: mocap.io.annotations); the 3D on demand."""

    method: str  # "silhouette" or "track", as the annotations name it
    score_name: str  # what ``scores`` are, for the page
    review_spacing = 0  # frames around a listed doubtful frame the review skips

    focal: Focal | None = None  # the camera's focal length, where the user gave it

    def __init__(self, info: VideoInfo, annotations: Annotations | None = None, smooth: float = 0.0):
        self.info, self.smooth = info, smooth
        self._annotations = annotations or Annotations()
        self._queue: list[Doubt] | None = None  # for the current annotations, once computed
        self._queue_before: list[Doubt] | None = None  # the last one computed
        self._focus: int | None = None  # the frame the last edit was made on (annotate)

    @property
    def annotations(self) -> Annotations:
        return self._annotations

    @property
    def n_frames(self) -> int:
        return self.info.frame_count

    def annotate(self, annotations: Annotations, focus: int | None = None) -> None:
        """Take new annotations; what they change is resolved again when next needed, around ``focus`` (the
        frame the user looks at) first where the method can, the rest at ``settle``."""
        self._annotations, self._queue, self._focus = annotations, None, focus

    def settle(self, most: int | None = None) -> bool:
        """Finish what an edit left for later (``annotate``'s focus), at most ``most`` pieces of it (None: all);
        whether there was anything."""
        return False

    @property
    @abstractmethod
    def scores(self) -> np.ndarray:
        """(F,) each frame's score in [0, 1], NaN where nobody was found."""

    @property
    def person(self) -> np.ndarray:
        """(F,) bool: the frames that show the performer."""
        return np.isfinite(self.scores)

    @property
    @abstractmethod
    def inputs(self) -> Inputs:
        """The 2D joints (anatomical sides, overrides in), orientation, signs and lengths."""

    @abstractmethod
    def pose3d(self, frame: int) -> np.ndarray | None:
        """(16, 3) joints of a frame (metres, contract frame, pelvis-centred); None without a person."""

    def root(self) -> np.ndarray:
        """(F, 3) pelvis in metres, camera frame (CONTRACT.md's ``root``), NaN without a person;
        here its depth comes from the body's image scale (lift.inputs.root_track) through the camera's focal
        length where it is known (``focal``)."""
        inputs = self.inputs
        size = (self.info.width, self.info.height)
        return root_track(inputs.joints2d, inputs.px_per_unit, size, self.focal and self.focal.pixels(*size))

    def joint_scores(self) -> np.ndarray:
        """(F, 16) what the method knows of each joint in [0, 1]: here the frame's score."""
        return np.repeat(np.nan_to_num(self.scores)[:, None], len(JOINT_INDEX), axis=1)

    def confidence(self) -> np.ndarray:
        """(F, 16) joint confidence in [0, 1] (CONTRACT.md): ``joint_scores``, 1 where the user placed it."""
        conf = np.clip(self.joint_scores(), 0.0, 1.0)
        for i, points in self._annotations.overrides().items():
            if i < self.n_frames:
                conf[i, [JOINT_INDEX[j] for j in points]] = 1.0
        return conf

    @property
    def lost(self) -> np.ndarray:
        """(F,) bool: frames where the method lost the performer (motion file's ``lost``); none here."""
        return np.zeros(self.n_frames, bool)

    def far_arm(self) -> str | None:
        """ "l" or "r": the arm to check first, where the method knows one."""
        return None

    # -- what a frame shows and where it comes from ----------------------------------

    @abstractmethod
    def held_signs(self) -> np.ndarray:
        """(F, 10) the user's signs where they hold (+1 toward, -1 away; an entry holds
        until a later entry changes it: held_user_signs), 0 elsewhere."""

    def sign_sources(self, frame: int) -> tuple[str, ...]:
        """Where each segment's sign on ``frame`` comes from: "set here", "held from frame K" or "guessed"."""
        held = self.held_signs()[frame]
        since = self._annotations.held_signs(self.n_frames)[1][frame]
        return tuple(source_note(int(s), frame) if h else "guessed" for h, s in zip(held, since))

    def orientation_shown(self, frame: int) -> tuple[str | None, str]:
        """(orientation, its source) of ``frame``: the user's held entry, else the first guess."""
        entry = entry_frame(self._annotations, frame, lambda n: n.orientation)
        return self.inputs.orientation[frame], source_note(entry, frame)

    def depths(self, frame: int) -> tuple[float, ...]:
        """Each segment's |dZ| / length on ``frame`` (0: in the image plane); () without a person."""
        pose = self.pose3d(frame)
        return () if pose is None else tuple(float(d) for d in depth_fractions(pose))

    def carried(self, frame: int) -> dict[str, int]:
        """joint -> frame of an override on another frame that moves it on ``frame`` (tracking's pins)."""
        return {}

    def review_queue(self, at_once: bool = False) -> list[Doubt]:
        """Doubtful frames, most doubtful first, and why (mocap.session.review). ``at_once``: the last queue
        computed, where one was and the current annotations' is not yet: what a page shows the moment an edit
        is made, the current queue (``queue_stale`` until then) following off the click's path."""
        if self._queue is None and not (at_once and self._queue_before is not None):
            self._queue = self._queue_before = review_queue(self)
        return self._queue_before if self._queue is None else self._queue

    @property
    def queue_stale(self) -> bool:
        """Whether ``review_queue`` has yet to be computed for the current annotations."""
        return self._queue is None

    def review_stops(self, at_once: bool = False) -> list[Doubt]:
        """The frames a review visits, most doubtful first (``review_queue``'s ``at_once``); where edits reach
        around a frame (``review_spacing``), one frame per stretch they cover (review.covering)."""
        queue = self.review_queue(at_once)
        return covering(queue, self.n_frames, self.review_spacing) if self.review_spacing else queue

    def keyframes(self) -> list[int]:
        """The annotations' keyframes (default every frame) where a person was found."""
        person = self.person
        return [k for k in self._annotations.keyframe_indices(self.n_frames) if person[k]]

    def motion(self) -> Motion:
        """Keyframes' 3D, the frames between interpolated (mocap.lift.motion), every edit settled."""
        self.settle()
        keys = self.keyframes()
        if not keys:
            raise MocapError(f"{self.info.path}: no keyframe shows a person, nothing to lift")
        return build_motion(
            {k: self.pose3d(k) for k in keys}, self.n_frames, self.info.fps, root=self.root(), smooth=self.smooth
        )

    @property
    def silhouette_confidence(self) -> np.ndarray | None:
        """(F,) each frame's silhouette confidence (the silhouette method's), or None."""
        return None

    def sign_margins(self) -> np.ndarray | None:
        """(F, 10) how much the clip solve's cost rises with each sign the other way (the silhouette
        method's, mocap.lift.signpath.sign_margins), or None."""
        return None

    @property
    def background_warning(self) -> str | None:
        """What the user should know about the background (the silhouette method's)."""
        return None

    def motion_frames(self, motion: Motion) -> list[dict]:
        """Motion-file entries (CONTRACT.md): a frame without a person stays ``person: false``, with
        interpolated joints3d between keyframes; a lost frame says ``lost: true`` and has no joints."""
        keys = np.flatnonzero(motion.keyframes)
        person, scores, inputs, lost = self.person, self.scores, self.inputs, self.lost
        contacts, confidence = motion.contacts, self.confidence()
        frames = []
        for i in range(self.n_frames):
            entry: dict = {"index": i, "keyframe": bool(motion.keyframes[i]), "person": bool(person[i])}
            if lost[i]:
                entry["lost"] = True
            if person[i]:
                if entry["keyframe"]:
                    entry["score"] = float(scores[i])
                entry["orientation"] = inputs.orientation[i]
                entry["joints2d"] = inputs.joints2d[i]
                entry["confidence"] = confidence[i]
            if (person[i] or keys[0] < i < keys[-1]) and not lost[i]:
                entry["joints3d"] = motion.joints3d[i]
                entry["root"] = motion.root[i]
                entry["contacts"] = dict(zip(FEET, map(bool, contacts[i])))
            frames.append(entry)
        return frames

    def clip(self, foot_lock: bool = False) -> Clip:
        """The motion and its motion-file frames (every export's source); ``foot_lock``: Motion.foot_locked."""
        motion, info = self.motion(), self.info
        motion = motion.foot_locked() if foot_lock else motion
        video = {
            "path": info.path,
            "width": info.width,
            "height": info.height,
            "fps": info.fps,
            "frame_count": info.frame_count,
        }
        return Clip(Path(info.path).stem, video, self.motion_frames(motion), motion)

    def export(self, key: str, foot_lock: bool = False) -> tuple[str, bytes]:
        """(file name, content) of the animation in a format of mocap.io.export.formats."""
        return export_file(key, self.clip(foot_lock))


def entry_frame(notes: Annotations, frame: int, has: Callable[[FrameNote], object]) -> int | None:
    """The latest frame at or before ``frame`` whose note satisfies ``has`` (sticky entries)."""
    return max((k for k, note in notes.frames.items() if k <= frame and has(note)), default=None)


def source_note(entry: int | None, frame: int) -> str:
    """Where a sticky value of ``frame`` comes from, for the page (``entry`` -1 or None: no entry)."""
    if entry is None or entry < 0:
        return "guessed"
    return "set here" if entry == frame else f"held from frame {entry}"


def said_of(notes: Annotations, n_frames: int) -> Said:
    """The user's annotations as the lift reads them: arrays over ``n_frames``."""
    return Said(notes.orientations(n_frames), notes.overrides(), *notes.held_signs(n_frames))
