"""MediaPipe Pose (BlazePose GHUM, the legacy ``solutions.pose`` graph) as a person model:
``model_complexity=1``, whose model files ship in the mediapipe 0.10.14 wheel (it runs offline), in video mode,
with its segmentation mask; its 33 landmarks map onto the contract's 16 joints (``to_joints``)."""

from __future__ import annotations

import contextlib
import os

import numpy as np

from mocap.body import CHEST_FRACTION, JOINT_INDEX, JOINTS
from mocap.errors import MocapError
from mocap.person import MODELS, Landmarks, PersonView

# Heights above the floor in a 1.75 m body (anthropometric tables): shoulders
# (acromion) 1.44 m, ears (tragion) 1.62 m, the neck's base 1.50 m, the head's top
# 1.75 m. Along shoulders-middle -> ears-middle, as fractions of that line:
NECK_ALONG = (1.50 - 1.44) / (1.62 - 1.44)
HEAD_TOP_ALONG = (1.75 - 1.44) / (1.62 - 1.44)

# MediaPipe's landmark numbers of the joints it has itself (BlazePose's 33 points)
_OWN = {
    "shoulder_l": 11,
    "shoulder_r": 12,
    "elbow_l": 13,
    "elbow_r": 14,
    "wrist_l": 15,
    "wrist_r": 16,
    "hip_l": 23,
    "hip_r": 24,
    "knee_l": 25,
    "knee_r": 26,
    "ankle_l": 27,
    "ankle_r": 28,
}
_EARS, _SHOULDERS, _HIPS = (7, 8), (11, 12), (23, 24)


class Model:
    """MediaPipe Pose over one video's frames in order (``PersonModel``)."""

    name = "mediapipe"

    def __init__(self):
        try:
            with _quiet_native_logs():
                from mediapipe.python.solutions import pose

                self._pose = pose.Pose(
                    static_image_mode=False,
                    model_complexity=1,
                    smooth_landmarks=True,
                    enable_segmentation=True,
                    smooth_segmentation=True,
                )
            self._first = True
        except ImportError as error:  # installed, but a package it needs is not
            raise MocapError(
                f"mediapipe does not load ({error}): {MODELS['mediapipe'].install} "
                "and the packages mocap lists, or --person-model none"
            ) from None

    def observe(self, frame: np.ndarray) -> PersonView | None:
        """Its view of the video's next BGR frame, None if it sees nobody."""
        rgb = np.ascontiguousarray(frame[:, :, ::-1])
        if self._first:  # its first inference logs how it set itself up
            with _quiet_native_logs():
                result = self._pose.process(rgb)
            self._first = False
        else:
            result = self._pose.process(rgb)
        if result.pose_landmarks is None or result.segmentation_mask is None:
            return None
        h, w = frame.shape[:2]
        image = np.array([(p.x * w - 0.5, p.y * h - 0.5, p.visibility) for p in result.pose_landmarks.landmark])
        world = np.array([(p.x, -p.y, -p.z) for p in result.pose_world_landmarks.landmark])
        joints2d, confidence = to_joints(image[:, :2], image[:, 2])
        world16, _ = to_joints(world, image[:, 2])
        return PersonView(
            np.asarray(result.segmentation_mask, np.float32),
            Landmarks(joints2d, confidence, world16 - world16[JOINT_INDEX["pelvis"]]),
        )

    def close(self) -> None:
        self._pose.close()


def to_joints(points: np.ndarray, visibility: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """BlazePose's 33 points (33, D) and visibilities -> the contract's 16 joints (16, D) and confidences: pelvis
    the hips' middle, neck and head top along shoulders -> ears (NECK_ALONG, HEAD_TOP_ALONG), chest at
    CHEST_FRACTION; a derived joint's confidence is the least of its points'."""
    out = np.zeros((len(JOINTS), points.shape[1]))
    conf = np.zeros(len(JOINTS))
    for name, k in _OWN.items():
        out[JOINT_INDEX[name]], conf[JOINT_INDEX[name]] = points[k], visibility[k]
    shoulders, ears, hips = (points[list(p)].mean(axis=0) for p in (_SHOULDERS, _EARS, _HIPS))
    neck = shoulders + NECK_ALONG * (ears - shoulders)
    derived = {
        "pelvis": (hips, _HIPS),
        "neck": (neck, _SHOULDERS + _EARS),
        "head_top": (shoulders + HEAD_TOP_ALONG * (ears - shoulders), _SHOULDERS + _EARS),
        "chest": (hips + CHEST_FRACTION * (neck - hips), _HIPS + _SHOULDERS + _EARS),
    }
    for name, (point, made_of) in derived.items():
        out[JOINT_INDEX[name]], conf[JOINT_INDEX[name]] = point, visibility[list(made_of)].min()
    return out, np.clip(conf, 0.0, 1.0)


@contextlib.contextmanager
def _quiet_native_logs():
    """Standard error closed while the model is built and runs its first frame (MediaPipe's C++ set-up logs would
    break the one-line messages); no longer, since the descriptor is the whole process's."""
    try:
        saved = os.dup(2)
    except OSError:
        yield
        return
    with open(os.devnull, "wb") as null:
        os.dup2(null.fileno(), 2)
        try:
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)
