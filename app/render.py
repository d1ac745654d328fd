"""The state -> page half of ``App`` (a mixin): ``refresh`` shows the current frame in every panel and
control, sending only what changed. While playing, the images come from the reel (``app.reel``) in
the same update as the 3D pose."""

from __future__ import annotations

import threading
import time

import numpy as np

from app.controls import AUTO, METHOD_CHOICES
from app.enabling import control_states
from app.reel import LEAD_S
from app.state import FrameView
from app.texts import eyes_text, frame_text, orientation_text, review_text, stage_text, track_prompt, tracking_text
from app.views import caption_image, silhouette_image, tracked_image, video_image
from app.words import joint_label, orientation_label
from mocap.body import JOINT_INDEX
from mocap.person import NONE


class Rendering:
    """App's drawing of the state (the App provides state, scene, controls, reel, player, frames)."""

    def refresh(self, force: bool = False) -> None:
        """Show the current state: only what changed since the last time is sent."""
        with self._render_lock:
            if force:
                self._shown.clear()
            view = self.state.view()
            if self._flash is not None and self._flash[0] != view.index:  # a flash is of its frame
                self._flash[1].cancel()
                self._flash = None
                self.scene.unflash()
            playing = self.player.playing and view.progress.ready  # (a new fit stops it)
            self.reel.key = (*self.state.made_from, self.placing, self.controls.show_landmarks.value, view.method)
            with self.server.atomic():  # the images of a frame arrive with its 3D
                if playing:  # from the reel (a picture sent now would only show after playing)
                    self.reel.show(view.index, keep=True)
                    self._shown.pop("video", None)
                    self._shown.pop("silhouette", None)
                else:
                    if self._show_images(view):
                        self._still_sent = time.monotonic()
                    if not self._settling():
                        self.reel.show(None)
                self._show_captions(view)
                if playing:
                    self._show_animation(view.index)
                else:
                    self._show_pose(view)
                self.scene.show_playhead(view.index, view.n_frames)
                self._show_controls(view)

    def _settling(self) -> bool:
        """Whether the reel's slot stays on view while the panels' own images, just sent, are decoded
        (a Pause shows no older frame meanwhile); a refresh follows."""
        if self.reel.shown_frame is None or time.monotonic() - self._still_sent >= LEAD_S:
            return False
        timer = threading.Timer(LEAD_S, self.refresh)
        timer.daemon = True
        timer.start()
        return True

    def _changed(self, part: str, key: object) -> bool:
        if self._shown.get(part) == key:
            return False
        self._shown[part] = key
        return True

    def _marks(self, view: FrameView) -> dict[str, tuple[float, float]]:
        """Joints ringed on the video frame: the overrides, and the joint being placed."""
        marks = dict(view.overrides)
        joint = self.placing
        if joint is not None and joint not in marks and view.joints2d is not None:
            marks[joint] = tuple(view.joints2d[JOINT_INDEX[joint]])
        return marks

    def _reel_images(self, frame: int) -> tuple[np.ndarray, np.ndarray]:
        """The video and silhouette images of ``frame`` as the panels show them."""
        view = self.state.view(frame)
        return video_image(self.frames.get(frame), self._marks(view), self.state.scale), self._silhouette_image(view)

    def _show_images(self, view: FrameView) -> bool:
        """Send the frame's video and silhouette images that changed; whether any did."""
        marks = self._marks(view)
        sent = self._changed("video", (view.index, sorted(marks.items())))
        if sent:
            self.scene.show_video(video_image(self.frames.get(view.index), marks, self.state.scale))
        joints = None if view.joints2d is None else view.joints2d.tobytes()
        # the silhouette's object: a refit (new stage, learned eyes) brings new ones
        if self._changed(
            "silhouette",
            (
                view.index,
                view.method,
                view.silhouette_ready,
                joints,
                view.sides_known,
                sorted(view.overrides.items()),
                id(view.silhouette),
                self.state.person_model,
                self.controls.show_landmarks.value,
            ),
        ):
            self.scene.show_silhouette(self._silhouette_image(view))
            sent = True
        return sent

    def _show_captions(self, view: FrameView) -> None:
        joint = self.placing
        self.scene.caption("video", f"frame {view.index}" if joint is None else f"click: {joint_label(joint)}")
        if view.method == "track":
            self.scene.caption(
                "silhouette", "tracked" + (f" · reliability {view.score:.2f}" if view.score is not None else "")
            )
        else:
            self.scene.caption(
                "silhouette", "silhouette" + (f" · S = {view.score:.2f}" if view.score is not None else "")
            )

    def _silhouette_image(self, view: FrameView) -> np.ndarray:
        if view.method == "track":
            if view.joints2d is None:
                return caption_image(self.size, "not tracked yet")
            return tracked_image(self.frames.get(view.index), view.joints2d, view.overrides, self.state.scale)
        if not view.silhouette_ready:
            return caption_image(self.size, "silhouette not found yet")
        if view.silhouette is None:
            return caption_image(self.size, "nobody found on this frame")
        return silhouette_image(
            view.silhouette,
            view.joints2d,
            view.sides_known,
            view.overrides,
            self.state.scale,
            self.size,
            self.controls.show_landmarks.value,
            self.state.person_model != NONE,
        )

    def _side_caption(self) -> str:
        """Which side the side view shows the body from (it turns to a flipped segment's)."""
        return "3D · side view from the " + ("left" if self.scene.side_from > 0 else "right")

    def _show_pose(self, view: FrameView) -> None:
        if self._changed("pose", None if view.pose3d is None else view.pose3d.tobytes()):
            self.scene.show_pose(view.pose3d)
        if view.pose3d is not None:
            note = " · flipped" if self.scene.flashing else ""
        elif not view.progress.ready:
            note = " · not yet" if view.progress.error is None else " · none"
        else:
            note = " · nobody found"
        self.scene.caption("front", "3D · camera's view" + note)
        self.scene.caption("side", self._side_caption() + ("" if note == " · flipped" else note))

    def _show_animation(self, frame: int) -> None:
        """Pose the 3D bodies as the playing animation has them on ``frame``."""
        self.scene.show_pose(self.player.pose(frame))
        self._shown.pop("pose", None)
        self.scene.caption("front", f"3D · playing frame {frame}")
        self.scene.caption("side", self._side_caption())

    def _show_controls(self, view: FrameView) -> None:
        c = self.controls
        self._show_progress(view)
        _set(c.frame, value=view.index)
        _set(c.frame_info, content=frame_text(view))
        facing = view.orientation if view.orientation_note == "set here" else None
        _set(c.orientation, value=AUTO if facing is None else orientation_label(facing))
        _set(c.orientation_note, content=orientation_text(view))
        for handle, props in control_states(c, self.state, view):
            _set(handle, **props)
        _set(
            c.overrides,
            content="  \n".join(f"**{joint_label(j)}** at ({x:.0f}, {y:.0f})" for j, (x, y) in view.overrides.items())
            or "No override on this frame.",
        )
        _set(
            c.play,
            disabled=not view.progress.ready,
            label="Pause" if self.player.playing else "Play",
            icon="player-pause" if self.player.playing else "player-play",
        )
        _set(c.review, content=review_text(self.state))
        _set(c.method, value=next(k for k, v in METHOD_CHOICES.items() if v == view.method))
        _set(c.track_info, content=tracking_text(self.state))
        _set(c.stage_info, content=stage_text(self.state))
        _set(c.learned_eyes, value=self.state.person_model != NONE)

    def _show_progress(self, view: FrameView) -> None:
        p, c = view.progress, self.controls
        # a stopped run's bar stays where it stopped, red and still, beside its error
        _set(
            c.progress,
            value=100.0 * p.done / max(p.total, 1),
            visible=not p.ready,
            animated=p.error is None,
            color=None if p.error is None else "red",
        )
        done = "tracked" if view.method == "track" else "fitted"
        eyes = "" if view.method == "track" else f"  \n{eyes_text(self.state)}"
        if p.error is not None:
            text = f"**Stopped:** {p.error}{eyes}"
        elif p.ready:
            text = (
                f"{view.n_frames} frames {done}. Edits are saved to `{self.state.path.name}`.{eyes}"
                + ("  \n" if eyes else " ")
                + next_step(bool(self.state.review_stops(at_once=True)))
            )
            if view.method != "track" and self.state.background_warning:
                text += f"  \n**Warning:** {self.state.background_warning} (Stage tab)."
        elif view.method == "track" and not self.state.tracking:
            text = track_prompt(self.state)
        else:
            work = "Tracking" if view.method == "track" else "Preprocessing"
            text = f"{work}: {p.stage}… {100 * p.done // max(p.total, 1)}%{eyes}"
        _set(c.status, content=text)


def next_step(doubtful: bool) -> str:
    """What a user who has the whole clip fitted does next."""
    return "Next: check the doubtful frames (Review tab, key N), then Export." if doubtful else "Next: Export."


def _set(handle, **props) -> None:
    """Assign the props of a handle that differ (each assignment is a message)."""
    for name, value in props.items():
        if getattr(handle, name) != value:
            setattr(handle, name, value)
