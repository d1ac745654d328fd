"""The tracking method's session: the counterpart of the silhouette method's
(mocap.session.silhouette) for a video whose joints the user marked on frame 0
(mocap.track.tracking).

The 2D joints are tracked once; everything the user says afterwards reshapes the 3D
without tracking again: joint overrides replace tracked joints on their frame,
the held orientation tells which way the body is turned (the calibration's two
mirror fits on frame 0, the key triangle's two mirror images on later frames), and
held foreshortening directions fix the depth choices of the
trunk and the limbs (mocap.track.perspective.place_joints) while they hold. The key
joints' depths (Eq. 10-11, the slow part) are kept until the 2D joints change, so a
foreshortening toggle only re-chooses depths.

The same motion file, exports and review as the silhouette method follow from the
Session protocol (mocap.session.base): ``inputs`` holds the tracked joints and what
the 3D shows (orientation and signs read back from it).
"""

from __future__ import annotations

import numpy as np

from mocap.io.annotations import Annotations
from mocap.body import BODY_HEIGHT, JOINT_INDEX, JOINTS, SEGMENT_JOINTS
from mocap.errors import MocapError
from mocap.lift.inputs import Inputs
from mocap.lift.taylor import depth_fractions, orientation_of_yaw, signs_of, yaw_of
from mocap.lift.orientation import NEGLIGIBLE, held_user_signs
from mocap.track.calibration import UNIT_M, calibrate, default_camera
from mocap.track.keydepths import key_joints
from mocap.track.perspective import place_joints, sided_key, steady_depths, to_contract
from mocap.session.base import Session
from mocap.silhouette.passes import SCALE_PERCENTILE
from mocap.track.parts import far_arm
from mocap.track.marks import check_marks
from mocap.track.tracking import (TrackResult, carried_pins, guessed_turn, spread_corrections,
                                  spread_frames, steady_joints, track_video, turn_of)
from mocap.io.video import VideoInfo

MARKS_NEEDED = ("the tracking method needs the 16 joints marked on frame 0 (--annotations "
                'with frames["0"].joints2d, or mark them in the app)')


def marks_of(notes: Annotations) -> dict[str, tuple[float, float]]:
    """Frame 0's joint positions in the annotations: the tracking method's marks."""
    first = notes.frames.get(0)
    if first is None or not first.joints2d:
        raise MocapError(MARKS_NEEDED)
    return dict(first.joints2d)


def remarks_of(notes: Annotations) -> dict[int, dict[str, tuple[float, float]]]:
    """frame -> the joints of every later frame where the annotations place all 16:
    the body marked again, which seeds the tracker anew (mocap.track.reseed)."""
    return {f: dict(n.joints2d) for f, n in sorted(notes.frames.items())
            if f > 0 and n.joints2d and len(n.joints2d) == len(JOINTS)}


def tracked_video(info: VideoInfo, notes: Annotations, progress=None, focal_px: float | None = None) -> TrackResult:
    """The video tracked from the marks of ``notes`` (marks_of; frame 0's orientation)
    and from every frame they mark the body again on (remarks_of)."""
    return track_video(info, marks_of(notes), progress, focal_px=focal_px,
                       orientation=notes.orientations(1)[0], remarks=remarks_of(notes))


def check_tracking_marks(info: VideoInfo, notes: Annotations) -> None:
    """Refuse at once (a MocapError naming the joint) the marks of ``notes`` that the
    tracking cannot start from: a mark missing or outside the frame, or shoulders,
    chest and hips that fit no view of a trunk (the calibration fails)."""
    checked = check_marks(marks_of(notes), info.width, info.height)
    calibrate(checked, default_camera(info.width, info.height), turn_of(notes.orientations(1)[0]))


class TrackSession(Session):
    """A tracked video and the user's annotations; reconstructs on demand."""

    method = "track"
    score_name = "tracking reliability"

    @property
    def review_spacing(self) -> int:
        """A pin carries SPREAD_S to either side (spread_corrections), so the review
        lists one frame of a doubtful stretch that long: the worst."""
        return spread_frames(self.info.fps)

    def __init__(self, info: VideoInfo, tracked: TrackResult,
                 annotations: Annotations | None = None, smooth: float = 0.0):
        super().__init__(info, annotations, smooth)
        self.tracked = tracked
        self.camera = default_camera(info.width, info.height, tracked.focal_px)
        # (steady 2D joints, turns, key joints followed from frame to frame, those on the
        # side the limbs take, their placement free of user signs)
        self._placed: tuple[np.ndarray, list, np.ndarray, np.ndarray, np.ndarray] | None = None
        self._resolution: tuple[Inputs, np.ndarray, np.ndarray] | None = None

    @property
    def scores(self) -> np.ndarray:
        """(F,) each frame's mean joint reliability, NaN where the body was lost."""
        scores = self.tracked.reliability.mean(axis=1).astype(float)
        scores[self.lost] = np.nan
        return scores

    @property
    def lost(self) -> np.ndarray:
        """(F,) bool: the frames the tracking lost the body on (TrackResult.lost)."""
        return self.tracked.lost

    def joint_scores(self) -> np.ndarray:
        """(F, 16) the tracking's confidence in each joint: whether it is still on
        the body (mocap.track.loss.joint_confidence)."""
        return self.tracked.confidence.astype(float)

    def annotate(self, annotations: Annotations) -> None:
        """Take new annotations (marks on frame 0 or the body marked again on another
        frame change the tracking itself: a new session, tracked_video)."""
        super().annotate(annotations)
        self._resolution = None

    def far_arm(self) -> str | None:
        """"l" or "r": the arm farther from the camera on frame 0 (mocap.track.parts.far_arm
        of frame 0's key triangle as the reconstruction finds it: calibrated on the
        marks, turned as frame 0's orientation says or else as the knees tell), None
        for a body facing the camera or away.

        The tracker loses that arm most (benchmarks/bench_track_budget.py: its elbow
        and wrist cost 7.7 of the 10.7 mm that the limbs' gross failures cost); a user
        who pins it alone at the review's stops mends about half of what pinning every
        joint mends, with a third of the pins (64.8 -> 58.7 mm, against 53.5; from the
        held-out views, --yaws 60 120: 76.2 -> 70.6, against 62.9)."""
        self._resolved()
        return far_arm(self._placed[3][0, :, 2])

    @property
    def inputs(self) -> Inputs:
        return self._resolved()[0]

    def pose3d(self, frame: int) -> np.ndarray:
        """(16, 3) the reconstructed joints of a frame (metres, contract frame)."""
        return self._resolved()[1][frame]

    def root(self) -> np.ndarray:
        """(F, 3) the pelvis in the camera's frame (metres, x right, y up, z toward
        the camera): the perspective reconstruction tells its distance (Eq. 10-11)."""
        return self._resolved()[2]

    def held_signs(self) -> np.ndarray:
        return self._resolved()[0].held

    def carried(self, frame: int) -> dict[str, int]:
        """joint -> the frame of the nearest pin that moves it on ``frame``
        (mocap.track.tracking.carried_pins)."""
        return carried_pins(self._annotations.overrides(), frame, self.info.fps)

    def orientation_shown(self, frame: int) -> tuple[str | None, str]:
        """The 3D shows its own facing, turned to the side of the user's held entry;
        on the entry's own frame the page shows the entry."""
        note = self._annotations.frames.get(frame)
        if note is not None and note.orientation is not None:
            return note.orientation, "set here"
        return self.inputs.orientation[frame], "seen in the tracked 3D"

    def _resolved(self) -> tuple[Inputs, np.ndarray, np.ndarray]:
        """The shown inputs, the 3D joints (F, 16, 3, contract frame) and the root
        (F, 3) of the current annotations."""
        if self._resolution is None:
            joints = self._joints2d()
            self._resolution = self._shown(joints, *self._reconstructed(joints))
        return self._resolution

    def _joints2d(self) -> np.ndarray:
        """The tracked joints with the user's overrides put in, each carried to the
        frames around it (mocap.track.tracking.spread_corrections)."""
        return spread_corrections(self.tracked.joints2d, self._annotations.overrides(),
                                  self.info.fps)

    def _reconstructed(self, joints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(F, 16, 3) pinhole-frame joints: each frame's trunk turned to the side of
        its held orientation (frame 0's, where none is said, the knees'), the depth
        choices kept to the held foreshortening while it holds; and (F, 10) the
        user's signs where they hold."""
        notes = self._annotations
        steady = steady_joints(joints, self.info.fps)
        turns = [turn_of(o) for o in notes.orientations(len(joints))]
        turns[0] = turns[0] or guessed_turn(joints, self.info.fps)
        key, free = self._free_placement(steady, turns)
        values, since = notes.held_signs(len(joints))
        fixed = held_user_signs(values, since, depth_fractions(free) <= NEGLIGIBLE)
        return (free if not fixed.any() else self._placed_joints(steady, key, fixed)), fixed

    def _placed_joints(self, steady: np.ndarray, key: np.ndarray,
                       fixed: np.ndarray | None = None) -> np.ndarray:
        """(F, 16, 3) pinhole-frame joints placed from the key joints (place_joints, the
        bones measured where the body was not lost), their depths smoothed along their
        rays (steady_depths)."""
        return steady_depths(place_joints(steady, key, self.camera, fixed=fixed, seen=~self.lost),
                             self.info.fps)

    @staticmethod
    def _shown(joints: np.ndarray, camera: np.ndarray,
               held: np.ndarray) -> tuple[Inputs, np.ndarray, np.ndarray]:
        """What the page and the motion file show: the 2D joints, and the orientation,
        signs and segment lengths read back from the 3D; the 3D pelvis-centred in the
        contract's frame, and the pelvis in the camera's (its root)."""
        joints3d = to_contract(camera)
        root = camera[:, JOINT_INDEX["pelvis"]] * np.array([1.0, -1.0, -1.0])
        n = len(joints)
        yaw = np.array([yaw_of(pose) for pose in joints3d])
        ends = joints3d[:, SEGMENT_JOINTS]
        lengths = np.median(np.linalg.norm(ends[:, :, 1] - ends[:, :, 0], axis=-1), axis=0) / UNIT_M
        inputs = Inputs([orientation_of_yaw(y) for y in yaw], yaw, np.zeros((n, 2), bool), joints,
                        np.full(n, body_px(joints) / BODY_HEIGHT), signs_of(joints3d), lengths, held)
        return inputs, joints3d, root

    def _free_placement(self, steady: np.ndarray, turns: list) -> tuple[np.ndarray, np.ndarray]:
        """The key joints of every frame (Eq. 6-11, on the side the limbs take:
        perspective.sided_key) and every joint placed without the user's signs
        (contract frame): kept while the 2D joints and the turns stay the
        same; after a joint override only the frames it moved are solved again."""
        last = self._placed
        if last is None or last[1] != turns or not np.array_equal(last[0], steady):
            before = (last[0], last[2]) if last is not None and last[1] == turns else None
            followed = key_joints(steady, self.camera, turns, before)
            key = sided_key(steady, followed, self.camera, turns, seen=~self.lost)
            self._placed = (steady, turns, followed, key, self._placed_joints(steady, key))
        return self._placed[3], self._placed[4]


def body_px(joints2d: np.ndarray) -> float:
    """The body's standing height in pixels over a clip: a high percentile of the
    head-top-to-ankles distance (SCALE_PERCENTILE, as the silhouettes' heights)."""
    ankles = joints2d[:, [JOINT_INDEX["ankle_l"], JOINT_INDEX["ankle_r"]]].mean(axis=1)
    heights = np.linalg.norm(joints2d[:, JOINT_INDEX["head_top"]] - ankles, axis=-1)
    return float(np.percentile(heights, SCALE_PERCENTILE))
