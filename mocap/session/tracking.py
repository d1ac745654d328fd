"""The tracking method's session (mocap.track.tracking): frame 0's 16 marks are tracked once; later
annotations reshape the 3D without tracking again (overrides replace tracked joints; held orientation
and foreshortening pick the trunk's mirror fit and the depth choices: perspective.place_joints). The
key joints' depths (Eq. 10-11, the slow part) are kept until the 2D joints change."""

from __future__ import annotations

import numpy as np

from mocap.body import BODY_HEIGHT, JOINT_INDEX, JOINTS, SEGMENT_JOINTS, STANDING_PERCENTILE
from mocap.camera import FLIP_YZ, default_camera
from mocap.errors import MocapError
from mocap.io.annotations import Annotations
from mocap.io.video import VideoInfo
from mocap.lift.inputs import Inputs
from mocap.lift.orientation import held_user_signs
from mocap.lift.taylor import orientation_of_yaw, signs_of, yaw_of
from mocap.person import NONE, opened_model
from mocap.session.base import Session
from mocap.session.silhouette import SilhouetteSession
from mocap.track.calibration import UNIT_M, calibrate
from mocap.track.keydepths import key_joints
from mocap.track.landmarks import released, seed_marks
from mocap.track.marks import check_marks, shoulders_as_hips
from mocap.track.parts import far_arm
from mocap.track.perspective import place_joints, sided_key, steady_depths, to_contract
from mocap.track.tracking import (
    TrackResult,
    carried_pins,
    guessed_turn,
    head_to_ankles,
    spread_corrections,
    spread_frames,
    steady_joints,
    track_clip,
    turn_of,
)

USUAL_FIT = 0.75  # of the clip's median S: a fit of a frame this good shows the body (fit_shows_body)
MARKS_NEEDED = (
    "the tracking method needs the 16 joints marked on frame 0 (--annotations "
    'with frames["0"].joints2d, or mark them in the app) or a person model to propose them (--person-model)'
)


def marks_of(notes: Annotations) -> dict[str, tuple[float, float]]:
    """Frame 0's joint positions in the annotations: the tracking method's marks."""
    first = notes.frames.get(0)
    if first is None or not first.joints2d:
        raise MocapError(MARKS_NEEDED)
    return dict(first.joints2d)


def remarks_of(notes: Annotations) -> dict[int, dict[str, tuple[float, float]]]:
    """frame -> the joints of every later frame where the annotations place all 16:
    the body marked again, which seeds the tracker anew (mocap.track.reseed)."""
    return {
        f: dict(n.joints2d)
        for f, n in sorted(notes.frames.items())
        if f > 0 and n.joints2d and len(n.joints2d) == len(JOINTS)
    }


def tracked_video(
    info: VideoInfo, notes: Annotations, progress=None, focal_px: float | None = None, person: str = NONE
) -> TrackResult:
    """The video tracked from the marks of ``notes`` (marks_of, frame 0's orientation) and remarks_of, looking
    through the ``person`` model named (mocap.person), whose landmarks stand in for frame 0's marks if none."""
    marks = marks_of(notes) if person == NONE or notes.frames.get(0) and notes.frames[0].joints2d else None
    with opened_model(person, apart=True) as model:  # in its own process, looking ahead of the tracker
        return track_clip(
            info,
            marks,
            progress,
            focal_px=focal_px,
            orientation=notes.orientations(1)[0],
            remarks=remarks_of(notes),
            person=model,
        )


def marks_from_fit(fitted: Session) -> dict[str, tuple[float, float]]:
    """Frame 0's 16 joints of a silhouette method's session as tracking marks to 0.1 px
    (sides resolved, overrides kept, shoulders in the hips' order: shoulders_as_hips):
    a start for the user to correct."""
    if not fitted.person[0]:
        raise MocapError("frame 0 has no silhouette fit to take the marks from")
    return as_marks(shoulders_as_hips(fitted.inputs.joints2d[0]))


def proposed_marks(fitted: SilhouetteSession, fit_too: bool = False) -> dict[str, tuple[float, float]] | None:
    """Frame 0's 16 joints as tracking marks to 0.1 px, to correct: as the person model the silhouette fit looked
    through saw them where it is sure of the trunk (mocap.track.landmarks.seed_marks); else, with ``fit_too``, the
    fit's own (``marks_from_fit``) where it shows the body (``fit_shows_body``: a figure the model does not read);
    None otherwise."""
    seen = fitted.fits[0].landmarks if fitted.fits else None
    marks = seed_marks(seen, (fitted.info.height, fitted.info.width))
    if marks is None:
        return marks_from_fit(fitted) if fit_too and fit_shows_body(fitted, 0) else None
    return as_marks(marks)


def as_marks(joints: np.ndarray) -> dict[str, tuple[float, float]]:
    """Joints (16, 2) as marks, joint -> (x, y) to 0.1 px (as the annotations keep them)."""
    return {name: (round(float(x), 1), round(float(y), 1)) for name, (x, y) in zip(JOINTS, joints)}


def fit_shows_body(fitted: SilhouetteSession, frame: int) -> bool:
    """Whether the silhouette fit of ``frame`` explains its silhouette (S, Eq. 3) at least USUAL_FIT as well as the
    clip's median fit: one fitted to what background subtraction makes of an empty scene explains far less."""
    scores = fitted.scores
    return bool(fitted.person[frame] and scores[frame] >= USUAL_FIT * np.nanmedian(scores))


def check_tracking_marks(info: VideoInfo, notes: Annotations) -> None:
    """Raise a MocapError naming the joint if tracking cannot start from the marks of ``notes``: a mark
    missing or outside the frame, or a trunk that fits no view (the calibration fails)."""
    checked = check_marks(marks_of(notes), info.width, info.height)
    calibrate(checked, default_camera(info.width, info.height), turn_of(notes.orientations(1)[0]))


class TrackSession(Session):
    """A tracked video and the user's annotations; reconstructs on demand."""

    method = "track"
    score_name = "tracking reliability"

    @property
    def review_spacing(self) -> int:
        """A pin's reach to either side (spread_corrections): the review lists one frame per stretch."""
        return spread_frames(self.info.fps)

    def __init__(
        self, info: VideoInfo, tracked: TrackResult, annotations: Annotations | None = None, smooth: float = 0.0
    ):
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

    def annotate(self, annotations: Annotations, focus: int | None = None) -> None:
        """Take new annotations; new marks (frame 0 or a re-mark) need a new session (tracked_video)."""
        super().annotate(annotations, focus)
        self._resolution = None

    def far_arm(self) -> str | None:
        """ "l" or "r": the arm farther from the camera in frame 0's reconstructed key triangle
        (mocap.track.parts.far_arm), None facing the camera or away; the tracker loses it most."""
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
        """joint -> frame of the nearest pin that moves it on ``frame`` (track.tracking.carried_pins)."""
        return carried_pins(self._annotations.overrides(), frame, self.info.fps)

    def orientation_shown(self, frame: int) -> tuple[str | None, str]:
        """The 3D's own facing, turned to the side of the user's held entry; on its own frame, the entry."""
        note = self._annotations.frames.get(frame)
        if note is not None and note.orientation is not None:
            return note.orientation, "set here"
        return self.inputs.orientation[frame], "seen in the tracked 3D"

    def _resolved(self) -> tuple[Inputs, np.ndarray, np.ndarray]:
        """(shown inputs, (F, 16, 3) contract-frame joints, (F, 3) root) of the current annotations."""
        if self._resolution is None:
            joints = self._joints2d()
            self._resolution = self._shown(joints, *self._reconstructed(joints))
        return self._resolution

    def _joints2d(self) -> np.ndarray:
        """Tracked joints with the user's overrides put in and carried around them (spread_corrections)."""
        return spread_corrections(self.tracked.joints2d, self._annotations.overrides(), self.info.fps)

    def _reconstructed(self, joints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """((F, 16, 3) pinhole-frame joints, (F, 10) user signs where held): each trunk turned to its
        held orientation (frame 0's default: the knees') until the person model sees the body turn
        (landmarks.released), depth choices kept to held foreshortening."""
        notes = self._annotations
        steady = steady_joints(joints, self.info.fps)
        starts = sorted(f for f, note in notes.frames.items() if note.orientation is not None)
        turns = released([turn_of(o) for o in notes.orientations(len(joints))], starts, self.tracked.facing)
        turns[0] = turns[0] or guessed_turn(joints, self.info.fps)
        key, free = self._free_placement(steady, turns)
        values, since = notes.held_signs(len(joints))
        fixed = held_user_signs(values, since)
        return (free if not fixed.any() else self._placed_joints(steady, key, fixed)), fixed

    def _placed_joints(self, steady: np.ndarray, key: np.ndarray, fixed: np.ndarray | None = None) -> np.ndarray:
        """(F, 16, 3) pinhole-frame joints placed from the key joints (place_joints, bones measured where
        the body was not lost), depths smoothed along their rays (steady_depths)."""
        return steady_depths(place_joints(steady, key, self.camera, fixed=fixed, seen=~self.lost), self.info.fps)

    @staticmethod
    def _shown(joints: np.ndarray, camera: np.ndarray, held: np.ndarray) -> tuple[Inputs, np.ndarray, np.ndarray]:
        """(inputs with orientation, signs and lengths read back from the 3D; joints pelvis-centred in
        the contract frame; the pelvis in the camera frame, the root)."""
        joints3d = to_contract(camera)
        root = camera[:, JOINT_INDEX["pelvis"]] * FLIP_YZ
        n = len(joints)
        yaw = np.array([yaw_of(pose) for pose in joints3d])
        ends = joints3d[:, SEGMENT_JOINTS]
        lengths = np.median(np.linalg.norm(ends[:, :, 1] - ends[:, :, 0], axis=-1), axis=0) / UNIT_M
        inputs = Inputs(
            [orientation_of_yaw(y) for y in yaw],
            yaw,
            np.zeros((n, 2), bool),
            joints,
            np.full(n, body_px(joints) / BODY_HEIGHT),
            signs_of(joints3d),
            lengths,
            held,
        )
        return inputs, joints3d, root

    def _free_placement(self, steady: np.ndarray, turns: list) -> tuple[np.ndarray, np.ndarray]:
        """(key joints (Eq. 6-11, sided: perspective.sided_key), joints placed without user signs), kept
        while the 2D joints and turns stay; after an override only the frames it moved are re-solved."""
        last = self._placed
        if last is None or last[1] != turns or not np.array_equal(last[0], steady):
            before = (last[0], last[2]) if last is not None and last[1] == turns else None
            followed = key_joints(steady, self.camera, turns, before)
            key = sided_key(steady, followed, self.camera, turns, seen=~self.lost)
            self._placed = (steady, turns, followed, key, self._placed_joints(steady, key))
        return self._placed[3], self._placed[4]


def body_px(joints2d: np.ndarray) -> float:
    """Standing height in pixels over a clip: the STANDING_PERCENTILE of head-top-to-ankles distances."""
    return float(np.percentile(head_to_ankles(joints2d), STANDING_PERCENTILE))
