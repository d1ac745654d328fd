"""Ground truth of a rendered clip (`mocap-truth` JSON): the camera and the exact
2D and 3D joints of every frame, written and read here."""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from mocap import body
from mocap.errors import MocapError
from mocap.io.fileio import atomic_write_json


@dataclass(frozen=True, eq=False)
class Camera:
    """A fixed camera: ``rotation`` rows are image right, up and toward-camera in world axes;
    ``origin`` the world point at the image centre (orthographic, ``scale`` px/m) or the eye
    (perspective, ``scale`` = focal px)."""

    kind: str
    yaw_deg: float
    pitch_deg: float
    rotation: np.ndarray
    origin: np.ndarray
    scale: float
    cx: float
    cy: float

    def to_camera(self, world: np.ndarray) -> np.ndarray:
        """World points (..., 3) -> camera frame (x right, y up, z toward the camera)."""
        return (np.asarray(world) - self.origin) @ self.rotation.T

    def project_camera(self, cam: np.ndarray) -> np.ndarray:
        """Camera-frame points (..., 3) -> pixels (..., 2), x right, y down."""
        xy = cam[..., :2] * self.scale
        if self.kind == "perspective":
            xy = xy / -cam[..., 2:3]
        return np.stack([self.cx + xy[..., 0], self.cy - xy[..., 1]], axis=-1)

    def to_dict(self) -> dict:
        """JSON form; ``scale`` is named ``focal`` for a perspective camera."""
        d = {k: v.tolist() if isinstance(v, np.ndarray) else v for k, v in asdict(self).items()}
        d["focal" if self.kind == "perspective" else "scale"] = d.pop("scale")
        d["projection"] = (
            "u = cx + s*x, v = cy - s*y" if self.kind == "orthographic" else "u = cx + f*x/(-z), v = cy - f*y/(-z)"
        ) + " with (x, y, z) = rotation @ (world - origin)"
        return d

    @classmethod
    def from_dict(cls, d: dict) -> "Camera":
        """Inverse of ``to_dict``."""
        return cls(
            kind=d["kind"],
            yaw_deg=d["yaw_deg"],
            pitch_deg=d["pitch_deg"],
            rotation=np.array(d["rotation"]),
            origin=np.array(d["origin"]),
            scale=d.get("scale", d.get("focal")),
            cx=d["cx"],
            cy=d["cy"],
        )


@dataclass(frozen=True, eq=False)
class Truth:
    """The exact ground truth of a rendered clip (see ``to_dict`` for the JSON)."""

    source: str
    fps: float
    width: int
    height: int
    camera: Camera
    body_height_m: float
    body_height_px: float
    source_frames: np.ndarray  # (F,) frame of the source motion shown in each frame
    joints2d: np.ndarray  # (F, 16, 2) pixels, anatomical left/right
    joints3d: np.ndarray  # (F, 16, 3) metres, camera-aligned, origin at the pelvis
    pelvis_camera: np.ndarray  # (F, 3) pelvis in the camera frame (re-projection)

    def to_dict(self) -> dict:
        """The ``mocap-truth`` JSON document."""
        frames = [
            {
                "index": i,
                "source_frame": int(s),
                "joints2d": np.round(j2, 3).tolist(),
                "joints3d": np.round(j3, 5).tolist(),
                "pelvis_camera": np.round(p, 5).tolist(),
            }
            for i, (s, j2, j3, p) in enumerate(
                zip(self.source_frames, self.joints2d, self.joints3d, self.pelvis_camera)
            )
        ]
        return {
            "format": "mocap-truth",
            "version": 1,
            "source": self.source,
            "fps": self.fps,
            "width": self.width,
            "height": self.height,
            "camera": self.camera.to_dict(),
            "body_height_m": self.body_height_m,
            "body_height_px": self.body_height_px,
            "joints": list(body.JOINTS),
            "frames": frames,
        }


def save_truth(truth: Truth, path: str | Path) -> None:
    """Write the truth JSON (atomically)."""
    atomic_write_json(path, truth.to_dict())


def load_truth(path: str | Path) -> Truth:
    """Read a truth JSON written by ``save_truth``."""
    try:
        d = json.loads(Path(path).read_text())
        if d.get("format") != "mocap-truth" or d.get("version") != 1:
            raise MocapError(f"{path}: not a mocap-truth version 1 file")
        frames = d["frames"]
        return Truth(
            source=d["source"],
            fps=d["fps"],
            width=d["width"],
            height=d["height"],
            camera=Camera.from_dict(d["camera"]),
            body_height_m=d["body_height_m"],
            body_height_px=d["body_height_px"],
            source_frames=np.array([f["source_frame"] for f in frames], dtype=int),
            joints2d=np.array([f["joints2d"] for f in frames], dtype=float),
            joints3d=np.array([f["joints3d"] for f in frames], dtype=float),
            pelvis_camera=np.array([f["pelvis_camera"] for f in frames], dtype=float),
        )
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as exc:
        raise MocapError(f"cannot read truth file {path}: {exc}") from None
