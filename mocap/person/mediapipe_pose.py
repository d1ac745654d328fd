"""MediaPipe Pose (BlazePose GHUM, the legacy ``solutions.pose`` graph) as a person model:
``model_complexity=1``, whose model files ship in the mediapipe 0.10.14 wheel (it runs offline), in video mode,
with its segmentation mask; its 33 landmarks map onto the contract's 16 joints (``to_joints``)."""

from __future__ import annotations

import contextlib
import os
import threading
import warnings

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
    """MediaPipe Pose over one video's frames in order (``PersonModel``); ``filtered``: its landmarks smoothed
    by its own one-way filter, ``masked``: with its segmentation mask (mocap.person.open_person_model)."""

    name = "mediapipe"
    with_mirror = False

    def __init__(self, filtered: bool = True, masked: bool = True):
        self.filtered, self.masked = filtered, masked
        NativeLogFilter.hold()
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # protobuf's deprecation notes on mediapipe's generated code
                from mediapipe.python.solutions import pose

                self._pose = pose.Pose(
                    static_image_mode=False,
                    model_complexity=1,
                    smooth_landmarks=filtered,
                    enable_segmentation=masked,
                    smooth_segmentation=masked,
                )
        except ImportError as error:  # installed, but a package it needs is not
            NativeLogFilter.release()
            raise MocapError(
                f"mediapipe does not load ({error}): {MODELS['mediapipe'].install} "
                "and the packages mocap lists, or --person-model none"
            ) from None

    def observe(self, frame: np.ndarray) -> PersonView | None:
        """Its view of the video's next BGR frame, None if it sees nobody."""
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # protobuf's, on every call of mediapipe's graph
            result = self._pose.process(np.ascontiguousarray(frame[:, :, ::-1]))
        if result.pose_landmarks is None or (self.masked and result.segmentation_mask is None):
            return None
        h, w = frame.shape[:2]
        image = np.array([(p.x * w - 0.5, p.y * h - 0.5, p.visibility) for p in result.pose_landmarks.landmark])
        world = np.array([(p.x, -p.y, -p.z) for p in result.pose_world_landmarks.landmark])
        joints2d, confidence = to_joints(image[:, :2], image[:, 2])
        world16, _ = to_joints(world, image[:, 2])
        return PersonView(
            np.asarray(result.segmentation_mask, np.float32) if self.masked else None,
            Landmarks(joints2d, confidence, world16 - world16[JOINT_INDEX["pelvis"]]),
        )

    def close(self) -> None:
        self._pose.close()
        NativeLogFilter.release()


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


NATIVE_NOISE = (b"INFO: Created TensorFlow Lite", b"I0000 ", b"W0000 ", b"WARNING: All log messages before absl")


class NativeLogFilter:
    """Standard error passed through a pipe that drops MediaPipe's and TensorFlow Lite's set-up log lines
    (NATIVE_NOISE), which their threads write at any time while a model runs and which would break the
    command line's one-line messages; everything else, Python's or native, goes through. One filter for the
    process, held while any model is open (``hold``, ``release``)."""

    _lock = threading.Lock()
    _users = 0
    _saved = -1
    _thread: threading.Thread | None = None

    @classmethod
    def hold(cls) -> None:
        with cls._lock:
            if cls._users == 0:
                cls._saved = os.dup(2)
                read, write = os.pipe()
                os.dup2(write, 2)
                os.close(write)
                cls._thread = threading.Thread(target=cls._forward, args=(read, cls._saved), daemon=True)
                cls._thread.start()
            cls._users += 1

    @classmethod
    def release(cls) -> None:
        with cls._lock:
            cls._users -= 1
            if cls._users == 0:
                os.dup2(cls._saved, 2)  # the pipe's last writer gone: the thread reads to its end
                cls._thread.join(timeout=1.0)
                os.close(cls._saved)

    @staticmethod
    def _forward(read: int, out: int) -> None:
        pending = b""  # a line's start that may become noise (the logs write a line in pieces)
        with contextlib.suppress(OSError):
            while chunk := os.read(read, 65536):
                *lines, last = (pending + chunk).splitlines(keepends=True)
                if last.endswith((b"\n", b"\r")):
                    lines, last = [*lines, last], b""
                noise = any(n.startswith(last) or last.startswith(n) for n in NATIVE_NOISE)
                pending = last if noise else b""
                kept = b"".join(line for line in lines if not line.startswith(NATIVE_NOISE))
                if kept or not noise:
                    os.write(out, kept + (b"" if noise else last))
        os.close(read)
