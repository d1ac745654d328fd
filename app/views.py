"""What the scene shows of a frame in the panels ``app.layout`` places: the video frame, the silhouette
with the fitted model, and the 3D cylinder body from the camera and the side (OpenCV, viser handles)."""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Callable, Iterator

import cv2
import numpy as np
import trimesh
from scipy.spatial.transform import Rotation

from app.layout import Layout
from mocap.body import BODY_HEIGHT_M, JOINT_INDEX, SEGMENT_JOINTS, SEGMENT_NAMES, left_direction, semi_axes
from mocap.image.draw import LANDMARK_BGR, LEARNED_BGR, draw_landmarks, draw_skeleton, segment_colour, silhouette_view
from mocap.io.export.marks import FACING_MARKS, facing_marks
from mocap.io.video import VideoInfo, iter_frames
from mocap.session import Silhouette

DISPLAY_HEIGHT = 480  # px: smaller frames are shown enlarged to this height
CENTRE_RGB = (150, 150, 160)  # torso and head in 3D (the scene is white)
MARK_RGB = (40, 40, 48)  # the nose and the chest's mark (mocap.silhouette.facing)
CONE = trimesh.creation.cone(radius=1.0, height=1.0, sections=16)  # base at z = 0, tip at z = 1
MARK_BGR = (0, 230, 255)  # joint overrides and the joint being placed
UNSIDED_BGR = (90, 200, 90)  # the 2D model before left and right are known
UNSEEN_BGR = (170, 170, 170)  # the legend's line where the person model saw nobody
AMBIENT = 1.2  # ambient light intensity beside the default lights
UPRIGHT = (0.0, 1.0, 0.0, 0.0)  # half turn about x: viser images put row 0 at -y
SIDE = tuple(Rotation.from_euler("y", 90, degrees=True).as_quat(scalar_first=True))
_J = JOINT_INDEX


def segment_transforms(joints3d: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centres (10, 3), orientations (10, 4; w, x, y, z) and lengths (10,) of the
    cylinders of a pose: each one's local z runs proximal -> distal, its local x
    toward the body's left (the torso's ellipse lies across the shoulders)."""
    ends = np.asarray(joints3d, float)[SEGMENT_JOINTS]
    axis = ends[:, 1] - ends[:, 0]
    length = np.linalg.norm(axis, axis=-1)
    z = np.where(length[:, None] > 1e-9, axis / np.maximum(length, 1e-9)[:, None], [0.0, 1.0, 0.0])
    j = np.asarray(joints3d, float)
    left = left_direction(j)
    x = left[None] - (z @ left)[:, None] * z
    # a segment along the body's left-right line: any direction across it will do
    across = np.cross(z, np.eye(3)[np.argmin(np.abs(z), axis=1)])
    x = np.where(np.linalg.norm(x, axis=-1, keepdims=True) > 1e-6, x, across)
    x /= np.linalg.norm(x, axis=-1, keepdims=True)
    frames = np.stack([x, np.cross(z, x), z], axis=-1)
    wxyz = Rotation.from_matrix(frames).as_quat(scalar_first=True)
    return (ends[:, 0] + ends[:, 1]) / 2, wxyz, length


def segment_rgb(segment: str) -> tuple[int, int, int]:
    """The 3D colour of a segment: the overlay's left/right colours, grey in the middle."""
    if not segment.endswith(("_l", "_r")):
        return CENTRE_RGB
    b, g, r = segment_colour(segment)
    return r, g, b


def display_factor(height: int) -> float:
    """How much an image ``height`` px tall is enlarged for display (up to DISPLAY_HEIGHT), so that
    rings, names and skeleton lines stay thin against the body."""
    return max(1.0, DISPLAY_HEIGHT / height)


def for_display(image: np.ndarray, scale: float) -> tuple[np.ndarray, float]:
    """A copy of ``image`` to draw on and show, enlarged by ``display_factor``, and
    ``scale`` (video pixels to the image's) to draw with."""
    factor = display_factor(image.shape[0])
    if factor == 1.0:
        return image.copy(), scale
    return cv2.resize(image, None, fx=factor, fy=factor, interpolation=cv2.INTER_LINEAR), scale * factor


def caption_image(size: tuple[int, int], text: str) -> np.ndarray:
    """A grey RGB image of ``size`` (width, height), enlarged by ``display_factor``, saying ``text``."""
    factor = display_factor(size[1])
    size = (round(size[0] * factor), round(size[1] * factor))
    image = np.full((size[1], size[0], 3), 60, np.uint8)
    scale = size[1] / 400
    (tw, th), _ = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, scale, 2)
    cv2.putText(
        image,
        text,
        ((size[0] - tw) // 2, (size[1] + th) // 2),
        cv2.FONT_HERSHEY_SIMPLEX,
        scale,
        (230, 230, 230),
        2,
        cv2.LINE_AA,
    )
    return image


def mark_joints(image: np.ndarray, points: dict[str, tuple[float, float]], scale: float) -> np.ndarray:
    """Ring and name each joint of ``points`` (video pixels) on a BGR image at ``scale``."""
    radius = max(4, image.shape[0] // 60)
    for name, (x, y) in points.items():
        centre = (int(round(x * scale)), int(round(y * scale)))
        cv2.circle(image, centre, radius, MARK_BGR, 2, cv2.LINE_AA)
        cv2.putText(
            image,
            name,
            (centre[0] + radius + 2, centre[1] - radius),
            cv2.FONT_HERSHEY_SIMPLEX,
            image.shape[0] / 800,
            MARK_BGR,
            1,
            cv2.LINE_AA,
        )
    return image


def video_image(frame_bgr: np.ndarray, marks: dict[str, tuple[float, float]], scale: float) -> np.ndarray:
    """The video frame (RGB, ``for_display``) with the joints of ``marks`` ringed."""
    image, scale = for_display(frame_bgr, scale)
    return cv2.cvtColor(mark_joints(image, marks, scale), cv2.COLOR_BGR2RGB)


def silhouette_image(
    silhouette: Silhouette | None,
    joints2d: np.ndarray | None,
    sides_known: bool,
    overrides: dict[str, tuple[float, float]],
    scale: float,
    size: tuple[int, int],
    landmarks: bool = True,
    eyes: bool = False,
) -> np.ndarray:
    """The silhouette in grey with the fitted model over it (RGB, ``for_display``; ``size``: processed
    (w, h)); limbs in one colour until sides are known. With ``eyes``, the person model's mask-only
    pixels teal, its joints magenta dots (``landmarks``), and a legend."""
    mask = np.zeros((size[1], size[0]), np.uint8)
    learned = None
    if silhouette is not None:
        x0, y0, x1, y1 = silhouette.box
        mask[y0:y1, x0:x1] = silhouette.mask()
        only = silhouette.learned_mask()
        if only is not None:
            learned = np.zeros_like(mask)
            learned[y0:y1, x0:x1] = only
    view, scale = for_display(silhouette_view(mask, None, learned), scale)
    factor = view.shape[0] / size[1]  # processing pixels to the image's
    if joints2d is not None:
        thickness = max(2, view.shape[0] // 240)
        draw_skeleton(view, joints2d * scale, thickness, None if sides_known else UNSIDED_BGR)
    seen = silhouette is not None and silhouette.landmarks is not None
    if landmarks and seen:
        marks = silhouette.landmarks.scaled(factor)
        draw_landmarks(view, marks.joints2d, marks.confidence, max(2.0, view.shape[0] / 160))
    if joints2d is not None:
        mark_joints(view, overrides, scale)
    if eyes and silhouette is not None:
        if not seen:
            legend(view, [("person model saw nobody here", UNSEEN_BGR, None)])
        else:
            legend(
                view,
                [("person model's mask only", LEARNED_BGR, "box")]
                + ([("person model's joints", LANDMARK_BGR, "dot")] if landmarks else []),
            )
    return cv2.cvtColor(view, cv2.COLOR_BGR2RGB)


def legend(image: np.ndarray, entries: list[tuple[str, tuple[int, int, int], str | None]]) -> np.ndarray:
    """Lines of (text, BGR colour, swatch: "box", "dot" or None) at the image's top
    left, each text in its colour outlined in black (drawn in place, returned)."""
    font = image.shape[0] / 700
    line = max(12, round(image.shape[0] / 28))
    for k, (text, colour, swatch) in enumerate(entries):
        y = line * (k + 1)
        x = round(line * 0.4)
        if swatch == "box":
            cv2.rectangle(image, (x, y - line * 2 // 3), (x + line * 2 // 3, y), colour, -1)
        elif swatch == "dot":
            cv2.circle(image, (x + line // 3, y - line // 3), max(2, line // 5), colour, -1, cv2.LINE_AA)
        x += line if swatch else 0
        cv2.putText(image, text, (x, y), cv2.FONT_HERSHEY_SIMPLEX, font, (0, 0, 0), 3, cv2.LINE_AA)
        cv2.putText(image, text, (x, y), cv2.FONT_HERSHEY_SIMPLEX, font, colour, 1, cv2.LINE_AA)
    return image


def tracked_image(
    frame_bgr: np.ndarray, joints2d: np.ndarray, overrides: dict[str, tuple[float, float]], scale: float
) -> np.ndarray:
    """The video frame dimmed, the tracked joints (anatomical sides) over it (RGB, ``for_display``)."""
    view, scale = for_display((frame_bgr * 0.55).astype(np.uint8), scale)
    draw_skeleton(view, joints2d * scale, max(2, view.shape[0] // 240))
    return cv2.cvtColor(mark_joints(view, overrides, scale), cv2.COLOR_BGR2RGB)


class FrameCache:
    """Recent decoded video frames at the processing scale; the frame after the last read is decoded
    on rather than sought (a seek decodes from the keyframe before it)."""

    def __init__(self, info: VideoInfo, scale: float, size: int = 48):
        self.info, self.scale, self.size = info, scale, size
        self._frames: OrderedDict[int, np.ndarray] = OrderedDict()
        self._lock = threading.Lock()
        self._reader: Iterator[tuple[int, np.ndarray]] | None = None
        self._next = -1  # the frame the reader decodes next

    def get(self, index: int) -> np.ndarray:
        with self._lock:
            if index not in self._frames:
                self._frames[index] = self._read(index)
                if len(self._frames) > self.size:
                    self._frames.popitem(last=False)
            self._frames.move_to_end(index)
            return self._frames[index]

    def _read(self, index: int) -> np.ndarray:
        if index != self._next or self._reader is None:
            self._reader = iter_frames(self.info, start=index, scale=self.scale)
        self._next = index + 1
        return next(self._reader)[1]


class SceneView:
    """The scene's panels and the handles that update them."""

    def __init__(
        self,
        scene,
        layout: Layout,
        image_size: tuple[int, int],
        on_image_click: Callable[[object], None],
        on_segment_click: Callable[[str, object], None],
    ):
        self.layout, self.size = layout, image_size
        scene.set_up_direction("+y")
        # plain lights: the default image-based lighting is slow in software WebGL
        scene.configure_environment_map(None)
        scene.configure_default_lights(cast_shadow=False)
        scene.add_light_ambient("/ambient", intensity=AMBIENT)
        blank = caption_image(image_size, "loading")
        self.video = self._image(scene, "/video", blank, layout.video)
        self.silhouette = self._image(scene, "/silhouette", blank, layout.silhouette)
        self.video.on_click(on_image_click)
        self.captions = {
            name: scene.add_label(
                f"/captions/{name}",
                "",
                anchor="bottom-left",
                font_size_mode="scene",
                font_scene_height=layout.caption_height,
                position=(at[0] - layout.width / 2, at[1] + layout.height / 2 + 0.02, 0.0),
            )
            for name, at in (
                ("video", layout.video),
                ("silhouette", layout.silhouette),
                ("front", layout.front),
                ("side", layout.side),
            )
        }
        self.radii = semi_axes(BODY_HEIGHT_M)
        views = (("front", layout.front, (1.0, 0.0, 0.0, 0.0)), ("side", layout.side, SIDE))
        self.bodies = [self._body(scene, name, at, wxyz, on_segment_click) for name, at, wxyz in views]
        self.marks = [self._marks(scene, name, on_segment_click) for name, _, _ in views]

    def _image(self, scene, name: str, image: np.ndarray, at: tuple[float, float]):
        return scene.add_image(
            name,
            image,
            self.layout.width,
            self.layout.height,
            jpeg_quality=85,
            wxyz=UPRIGHT,
            position=(at[0], at[1], 0.0),
            cast_shadow=False,
            receive_shadow=False,
        )

    @staticmethod
    def _body(scene, name: str, at: tuple[float, float], wxyz, on_click: Callable[[str, object], None]) -> list:
        scene.add_frame(f"/body/{name}", show_axes=False, wxyz=wxyz, position=(at[0], at[1], 0.0))
        handles = []
        for segment in SEGMENT_NAMES:
            handle = scene.add_cylinder(
                f"/body/{name}/{segment}",
                radius=1.0,
                height=1.0,
                color=segment_rgb(segment),
                radial_segments=20,
                cast_shadow=False,
                receive_shadow=False,
                visible=False,
            )
            handle.on_click(lambda event, s=segment: on_click(s, event))
            handles.append(handle)
        return handles

    @staticmethod
    def _marks(scene, name: str, on_click: Callable[[str, object], None]) -> list:
        """The facing marks of a body (cones): a click on one is a click on its segment."""
        handles = []
        for mark, (segment, *_) in FACING_MARKS.items():
            handle = scene.add_mesh_simple(
                f"/body/{name}/{mark}",
                CONE.vertices,
                CONE.faces,
                color=MARK_RGB,
                flat_shading=True,
                cast_shadow=False,
                receive_shadow=False,
                visible=False,
            )
            handle.on_click(lambda event, s=segment: on_click(s, event))
            handles.append(handle)
        return handles

    def show_video(self, image: np.ndarray) -> None:
        self.video.image = image

    def show_silhouette(self, image: np.ndarray) -> None:
        self.silhouette.image = image

    def show_pose(self, joints3d: np.ndarray | None) -> None:
        """Pose both 3D bodies (pelvis at their panel's centre), or hide them."""
        if joints3d is None:
            for handle in (h for body in self.bodies + self.marks for h in body):
                handle.visible = False
            return
        joints3d = joints3d - joints3d[_J["pelvis"]]
        centres, wxyz, lengths = segment_transforms(joints3d)
        marks = facing_marks(joints3d)
        turns = [Rotation.align_vectors([m[1]], [[0.0, 0.0, 1.0]])[0] for m in marks]  # cone's z out
        for body, cones in zip(self.bodies, self.marks):
            for k, handle in enumerate(body):
                handle.position, handle.wxyz = centres[k], wxyz[k]
                handle.scale = (float(self.radii[k, 0]), float(self.radii[k, 1]), float(lengths[k]))
                handle.visible = True
            for (base, _, (length, radius, _)), turn, handle in zip(marks, turns, cones):
                handle.position, handle.wxyz = base, turn.as_quat(scalar_first=True)
                handle.scale = (float(radius), float(radius), float(length))
                handle.visible = True

    def caption(self, name: str, text: str) -> None:
        if self.captions[name].text != text:
            self.captions[name].text = text
