"""The scene's panels, where ``app.layout`` places them: the video and silhouette images, a caption
above each, the 3D cylinder body seen from the camera and from the side (viser handles), and above
each 3D view a playhead bar (the frame's place in the clip). A flipped segment flashes (``flash``):
drawn in FLASH_RGB with its place before the flip as a ghost, the rest of the body seen through."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import trimesh
from scipy.spatial.transform import Rotation

from app.layout import PANELS, Layout
from app.views import caption_image
from mocap.body import BODY_HEIGHT_M, JOINT_INDEX, SEGMENT_JOINTS, SEGMENT_NAMES, left_direction, semi_axes
from mocap.image.draw import segment_colour
from mocap.io.export.marks import FACING_MARKS, facing_marks

CENTRE_RGB = (150, 150, 160)  # torso and head in 3D (the scene is white)
MARK_RGB = (40, 40, 48)  # the nose and the chest's mark (mocap.silhouette.facing)
CONE = trimesh.creation.cone(radius=1.0, height=1.0, sections=16)  # base at z = 0, tip at z = 1
AMBIENT = 1.2  # ambient light intensity beside the default lights
UPRIGHT = (0.0, 1.0, 0.0, 0.0)  # half turn about x: viser images put row 0 at -y
FRONT = (1.0, 0.0, 0.0, 0.0)
# the side view seen from the image's left (the camera to the right) or from its right
SIDE = tuple(Rotation.from_euler("y", 90, degrees=True).as_quat(scalar_first=True))
OTHER_SIDE = tuple(Rotation.from_euler("y", -90, degrees=True).as_quat(scalar_first=True))
FLASH_RGB = (235, 20, 140)  # a flipped segment while it flashes, and its ghost
GHOST_OPACITY = 0.45  # the flipped segment's place before the flip
SEE_THROUGH = 0.3  # the rest of the body's opacity while a segment flashes
TRACK_RGB, PLAYHEAD_RGB = (215, 215, 222), (60, 60, 75)
BAR = 0.04  # the playhead bar's height (scene units), below the caption
STRIDE_M = 1.3  # the widest a walking body gets: a narrower panel shows the body smaller
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


def side_seen_from(joints3d: np.ndarray, segment: str) -> int:
    """+1: the side view from the image's left (SIDE), -1: from its right, whichever side the
    segment is on (so that the torso does not hide it)."""
    k = SEGMENT_NAMES.index(segment)
    middle = np.asarray(joints3d, float)[SEGMENT_JOINTS[k]].mean(axis=0)
    return -1 if middle[0] > joints3d[_J["pelvis"]][0] else 1


HIDDEN = {"cast_shadow": False, "receive_shadow": False, "visible": False}  # a body part until a frame poses it


def clicked_as(handle, segment: str, on_click: Callable[[str, object], None]):
    """``handle`` with a click on it reported as a click on ``segment``."""
    handle.on_click(lambda event: on_click(segment, event))
    return handle


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
        self.panels = {name: scene.add_frame(f"/{name}", show_axes=False) for name in PANELS}
        blank = caption_image(image_size, "loading")
        self.video = self.add_image(scene, "/video/image", blank)
        self.silhouette = self.add_image(scene, "/silhouette/image", blank)
        self.video.on_click(on_image_click)
        self.captions = {
            name: scene.add_label(
                f"/{name}/caption",
                "",
                anchor="bottom-left",
                font_size_mode="scene",
                font_scene_height=layout.caption_height,
                position=(-layout.width / 2, layout.height / 2 + 0.02 + (BAR + 0.02) * (name in PANELS[2:]), 0.0),
            )
            for name in PANELS
        }
        self.body_scale = min(1.0, layout.width / STRIDE_M)  # a tall video's panel is narrow
        self.radii = semi_axes(BODY_HEIGHT_M) * self.body_scale
        self.turns = [FRONT, SIDE]  # each 3D view's body frame
        self.side_from = 1  # the side view from the image's left (+1) or right (-1)
        self.frames = [
            scene.add_frame(f"/{name}/body", show_axes=False, wxyz=w) for name, w in zip(PANELS[2:], self.turns)
        ]
        self.bodies = [self._body(scene, name, on_segment_click) for name in PANELS[2:]]
        self.marks = [self._marks(scene, name, on_segment_click) for name in PANELS[2:]]
        self.ghosts = [
            scene.add_cylinder(
                f"/{name}/body/ghost",
                color=FLASH_RGB,
                opacity=GHOST_OPACITY,
                cast_shadow=False,
                receive_shadow=False,
                visible=False,
            )
            for name in PANELS[2:]
        ]
        self.playheads = [self._playhead(scene, name) for name in PANELS[2:]]
        self.flashing: str | None = None
        self.place(layout)

    def add_image(self, scene, name: str, image: np.ndarray, visible: bool = True):
        """An image filling its panel (a child of the panel's frame)."""
        return scene.add_image(
            name,
            image,
            self.layout.width,
            self.layout.height,
            jpeg_quality=85,
            wxyz=UPRIGHT,
            cast_shadow=False,
            receive_shadow=False,
            visible=visible,
        )

    def place(self, layout: Layout) -> None:
        """Move the panels where ``layout`` has them; those it does not show are hidden."""
        self.layout = layout
        for name, (x, y) in zip(PANELS, layout.centres):
            self.panels[name].position = (x, y, 0.0)
            self.panels[name].visible = name in layout.shown

    def _body(self, scene, name: str, on_click: Callable[[str, object], None]) -> list:
        handles = []
        for segment in SEGMENT_NAMES:
            handle = scene.add_cylinder(
                f"/{name}/body/{segment}",
                radius=1.0,
                height=1.0,
                color=segment_rgb(segment),
                radial_segments=20,
                **HIDDEN,
            )
            handles.append(clicked_as(handle, segment, on_click))
        return handles

    @staticmethod
    def _marks(scene, name: str, on_click: Callable[[str, object], None]) -> list:
        """The facing marks of a body (cones): a click on one is a click on its segment."""
        handles = []
        for mark, (segment, *_) in FACING_MARKS.items():
            handle = scene.add_mesh_simple(
                f"/{name}/body/{mark}", CONE.vertices, CONE.faces, color=MARK_RGB, flat_shading=True, **HIDDEN
            )
            handles.append(clicked_as(handle, segment, on_click))
        return handles

    def _playhead(self, scene, name: str) -> tuple[object, object]:
        """A 3D view's bar between its caption and the panel: the track, and its fill up to the frame."""
        y = self.layout.height / 2 + 0.02 + BAR / 2

        def bar(part: str, rgb: tuple[int, int, int], z: float):
            return scene.add_box(
                f"/{name}/{part}",
                color=rgb,
                dimensions=(1.0, BAR, 0.002),
                position=(0.0, y, z),
                scale=(self.layout.width, 1.0, 1.0),
                cast_shadow=False,
                receive_shadow=False,
            )

        return bar("track", TRACK_RGB, 0.0), bar("playhead", PLAYHEAD_RGB, 0.003)

    def show_video(self, image: np.ndarray) -> None:
        self.video.image = image

    def show_silhouette(self, image: np.ndarray) -> None:
        self.silhouette.image = image

    def show_playhead(self, frame: int, n_frames: int) -> None:
        """Fill each 3D view's bar up to ``frame``: (frame + 1) / n_frames of its width."""
        width = self.layout.width * (frame + 1) / max(n_frames, 1)
        for _, fill in self.playheads:
            fill.scale = (width, 1.0, 1.0)
            fill.position = (width / 2 - self.layout.width / 2, *fill.position[1:])

    def show_pose(self, joints3d: np.ndarray | None) -> None:
        """Pose both 3D bodies (pelvis at their panel's centre), or hide them."""
        if joints3d is None:
            for handle in (h for body in self.bodies + self.marks for h in body):
                handle.visible = False
            return
        s = self.body_scale
        joints3d = joints3d - joints3d[_J["pelvis"]]
        centres, wxyz, lengths = segment_transforms(joints3d * s)
        marks = facing_marks(joints3d)
        turns = [Rotation.align_vectors([m[1]], [[0.0, 0.0, 1.0]])[0] for m in marks]  # cone's z out
        for body, cones in zip(self.bodies, self.marks):
            for k, handle in enumerate(body):
                handle.position, handle.wxyz = centres[k], wxyz[k]
                handle.scale = (float(self.radii[k, 0]), float(self.radii[k, 1]), float(lengths[k]))
                handle.visible = True
            for (base, _, (length, radius, _)), turn, handle in zip(marks, turns, cones):
                handle.position, handle.wxyz = np.asarray(base) * s, turn.as_quat(scalar_first=True)
                handle.scale = (float(radius * s), float(radius * s), float(length * s))
                handle.visible = True

    def turn_side(self, seen_from: int) -> None:
        """Show the side view from the image's left (+1) or right (-1)."""
        self.side_from = seen_from
        self.turns[1] = SIDE if seen_from > 0 else OTHER_SIDE
        self.frames[1].wxyz = self.turns[1]

    def flash(self, segment: str, before: np.ndarray | None) -> None:
        """Show ``segment`` flipped: in FLASH_RGB, its place in the pose ``before`` as a ghost, the
        rest of the body see-through (a segment behind the torso shows)."""
        k = SEGMENT_NAMES.index(segment)
        self.flashing = segment
        for body, cones in zip(self.bodies, self.marks):
            for i, handle in enumerate(body):
                handle.color = FLASH_RGB if i == k else segment_rgb(SEGMENT_NAMES[i])
                handle.opacity = None if i == k else SEE_THROUGH
            for handle in cones:
                handle.opacity = SEE_THROUGH
        if before is None:
            return
        centres, wxyz, lengths = segment_transforms((before - before[_J["pelvis"]]) * self.body_scale)
        for ghost in self.ghosts:
            ghost.position, ghost.wxyz = centres[k], wxyz[k]
            ghost.scale = (float(self.radii[k, 0]) * 1.05, float(self.radii[k, 1]) * 1.05, float(lengths[k]))
            ghost.visible = True

    def unflash(self) -> None:
        """End a flash: the body as it was drawn before."""
        if self.flashing is None:
            return
        self.flashing = None
        for body, cones in zip(self.bodies, self.marks):
            for segment, handle in zip(SEGMENT_NAMES, body):
                handle.color, handle.opacity = segment_rgb(segment), None
            for handle in cones:
                handle.opacity = None
        for ghost in self.ghosts:
            ghost.visible = False

    def caption(self, name: str, text: str) -> None:
        if self.captions[name].text != text:
            self.captions[name].text = text
