"""`mocap serve`: ``App`` wires the controls (``app.controls``) and scene (``app.views``) to one
``AppState``; callbacks only call the state, and every change redraws what it changed (``refresh``)."""

from __future__ import annotations

import threading
from collections.abc import Callable

import numpy as np
import viser

from app.controls import (
    AUTO,
    DOWNLOADS,
    EDITS,
    FRAME_STEPS,
    KEY_STEPS,
    METHOD_CHOICES,
    NO_JOINT,
    Controls,
    build_controls,
)
from app.enabling import control_states
from app.layout import Layout, place_cameras
from app.player import Player
from app.state import AppState, FrameView
from app.texts import eyes_text, frame_text, orientation_text, review_text, stage_text, tracking_text
from app.views import FrameCache, SceneView, caption_image, silhouette_image, tracked_image, video_image
from mocap.body import JOINT_INDEX
from mocap.errors import MocapError
from mocap.person import DEFAULT_MODEL, NONE


class App:
    """One video's app on one viser server."""

    def __init__(self, server: viser.ViserServer, state: AppState):
        self.server, self.state = server, state
        self.frames = FrameCache(state.info, state.scale)
        height, width = self.frames.get(0).shape[:2]
        self.size = (width, height)
        self.layout = Layout.for_video(width, height)
        self.scene = SceneView(
            server.scene,
            self.layout,
            self.size,
            self._image_clicked,
            lambda segment, event: self._run(event.client, lambda: self._flip(segment)),
        )
        self.controls: Controls = build_controls(server.gui, state.n_frames)
        self.player = Player(state, lambda force: self.refresh(force=force))
        self._render_lock = threading.RLock()
        self._shown: dict[str, object] = {}
        self._notices: dict[int, object] = {}  # client id -> its notification shown
        self._marking = 0  # the frame Mark joints marks the body on
        self._wire()
        place_cameras(server, self.layout)
        state.on_change(self.refresh)
        self.refresh()

    # -- events -> state ----------------------------------------------------------

    def _run(self, client, action: Callable[[], object]) -> None:
        """Do a user's action; a refused one is said to that user's tab."""
        try:
            action()
        except MocapError as exc:
            if client is not None:
                self._notify(client, str(exc))

    def _notify(self, client, text: str) -> None:
        """Say ``text`` in the tab's one notification, replacing the last so none stack out of their band."""
        with self._render_lock:
            last = self._notices.pop(client.client_id, None)
            if last is not None:
                last.remove()
            self._notices[client.client_id] = client.add_notification(
                "Not done", text, color="red", auto_close_seconds=6.0
            )

    def _on(self, action: Callable[[], object]) -> Callable:
        """An event callback that runs ``action`` for the event's tab."""
        return lambda event: self._run(event.client, action)

    def _wire(self) -> None:
        c, state = self.controls, self.state
        actions: dict[str, Callable[[], object]] = {
            "prev_frame": lambda: state.go_to(state.frame - 1),
            "next_frame": lambda: state.go_to(state.frame + 1),
            "prev_key": lambda: self._jump(state.keyframe_after(state.frame, -1)),
            "next_key": lambda: self._jump(state.keyframe_after(state.frame, 1)),
            "keyframe": self._toggle_keyframe,
            "doubtful": lambda: self._jump(state.next_doubtful(), "no doubtful frame"),
            "undo": lambda: self._jump(state.undo(), "nothing to undo"),
            "redo": lambda: self._jump(state.redo(), "nothing to redo"),
            "play": self.player.toggle,
        }
        for action, command in c.commands.items():
            command.on_trigger(self._on(actions[action]))
        for handle, action in ((c.keyframe, "keyframe"), (c.doubtful, "doubtful"), (c.play, "play")):
            handle.on_click(self._on(actions[action]))
        for group, options, pair in (
            (c.frame_steps, FRAME_STEPS, ("prev_frame", "next_frame")),
            (c.key_steps, KEY_STEPS, ("prev_key", "next_key")),
            (c.edits, EDITS, ("undo", "redo")),
        ):
            group.on_click(lambda e, o=options, p=pair: self._run(e.client, actions[p[o.index(e.target.value)]]))
        c.frame.on_update(self._from_client(lambda: state.go_to(int(c.frame.value))))
        c.orientation.on_update(
            self._from_client(
                lambda: state.set_orientation(state.frame, None if c.orientation.value == AUTO else c.orientation.value)
            )
        )
        c.joint.on_update(lambda _e: self.refresh())  # the ring shown, Clear override's state
        c.method.on_update(self._from_client(lambda: state.set_method(METHOD_CHOICES[c.method.value])))
        c.mark.on_click(self._on(self._start_marking))
        c.marks_from_fit.on_click(self._on(state.marks_from_fit))
        c.track.on_click(self._on(state.start_tracking))
        c.use_stage.on_click(self._on(lambda: state.set_background(c.stage.value)))
        c.learned_eyes.on_update(self._from_client(lambda: self._learned_eyes(c.learned_eyes.value)))
        c.show_landmarks.on_update(lambda _e: self.refresh())
        c.clear_override.on_click(self._on(self._clear_override))
        for label, button in c.downloads.items():
            button.on_click(lambda e, key=DOWNLOADS[label]: self._run(e.client, lambda: self._download(e, key)))
        for segment, button in c.segments.items():
            button.on_click(self._on(lambda s=segment: self._flip(s)))

    def _toggle_keyframe(self) -> None:
        """Mark or unmark the frame; refused, as its button is disabled, without a fit there."""
        if self.state.view().joints2d is None:
            raise MocapError(f"frame {self.state.frame} has no fit (not yet, or nobody found) to key")
        self.state.toggle_keyframe(self.state.frame)

    def _from_client(self, action: Callable[[], object]) -> Callable:
        """An on_update callback that ignores the server's own updates of the control."""
        return lambda e: self._run(e.client, action) if e.client is not None else None

    def _jump(self, frame: int | None, otherwise: str = "no such frame to go to") -> None:
        if frame is None:
            raise MocapError(otherwise)
        self.state.go_to(frame)

    def _flip(self, segment: str) -> None:
        self.state.flip_sign(self.state.frame, segment)

    def _image_clicked(self, event) -> None:
        joint = self.controls.joint.value

        def place() -> None:
            if joint == NO_JOINT:
                raise MocapError(
                    "choose a joint under Joints > Place first (or press Mark joints "
                    "on the Tracking tab), then click where it is"
                )
            at = self.layout.video_pixel(event.ray_origin, event.ray_direction, self.size)
            if at is not None:
                xy = (at[0] / self.state.scale - 0.5, at[1] / self.state.scale - 0.5)
                self.state.set_override(self.state.frame, joint, xy)
                if self.state.frame == self._marking and self.state.method == "track":
                    self._next_mark()

        self._run(event.client, place)

    def _start_marking(self) -> None:
        """Go to the marking frame (AppState.marking_frame) and ask for its first unmarked joint."""
        self._marking = self.state.marking_frame()
        if not self.state.unmarked(self._marking):
            raise MocapError(
                f"all 16 joints are marked on frame {self._marking}; to move one, choose "
                "it under Joints > Place and click on the frame"
            )
        self.state.go_to(self._marking)
        self._next_mark()

    def _next_mark(self) -> None:
        """Ask for the next joint not marked on the marking frame (none once all are)."""
        missing = self.state.unmarked(self._marking)
        self.controls.joint.value = missing[0] if missing else NO_JOINT
        self.refresh()

    def _learned_eyes(self, on: bool) -> None:
        """Fit with the person model (on) or without (off), unless the fit does already."""
        try:
            if on != (self.state.person_model != NONE):
                self.state.set_person_model(DEFAULT_MODEL if on else NONE)
        finally:
            self.refresh()  # a refused switch shows the checkbox as the fit has it again

    def _clear_override(self) -> None:
        joint = self.controls.joint.value
        self.state.clear_overrides(self.state.frame, None if joint == NO_JOINT else joint)

    def _download(self, event, key: str) -> None:
        name, data = self.state.export(key, self.controls.foot_lock.value)
        event.client.send_file_download(name, data, save_immediately=True)

    # -- state -> page ------------------------------------------------------------

    def refresh(self, force: bool = False) -> None:
        """Show the current state: only what changed since the last time is sent."""
        with self._render_lock:
            if force:
                self._shown.clear()
            view = self.state.view()
            self._show_images(view)
            if self.player.playing and view.progress.ready:  # (a new fit stops it)
                self._show_animation(view.index)
            else:
                self._show_pose(view)
            self._show_controls(view)

    def _changed(self, part: str, key: object) -> bool:
        if self._shown.get(part) == key:
            return False
        self._shown[part] = key
        return True

    def _marks(self, view: FrameView) -> dict[str, tuple[float, float]]:
        """Joints ringed on the video frame: the overrides, and the joint being placed."""
        marks = dict(view.overrides)
        joint = self.controls.joint.value
        if joint != NO_JOINT and joint not in marks and view.joints2d is not None:
            marks[joint] = tuple(view.joints2d[JOINT_INDEX[joint]])
        return marks

    def _show_images(self, view: FrameView) -> None:
        marks = self._marks(view)
        if self._changed("video", (view.index, sorted(marks.items()))):
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
        joint = self.controls.joint.value
        self.scene.caption("video", f"frame {view.index}" + (f" · click: {joint}" if joint != NO_JOINT else ""))
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

    def _show_pose(self, view: FrameView) -> None:
        if self._changed("pose", None if view.pose3d is None else view.pose3d.tobytes()):
            self.scene.show_pose(view.pose3d)
        if view.pose3d is not None:
            note = ""
        elif not view.progress.ready:
            note = " · not yet" if view.progress.error is None else " · none"
        else:
            note = " · nobody found"
        self.scene.caption("front", "3D · camera's view" + note)
        self.scene.caption("side", "3D · side view" + note)

    def _show_animation(self, frame: int) -> None:
        """Pose the 3D bodies as the playing animation has them on ``frame``."""
        self.scene.show_pose(self.player.pose(frame))
        self._shown.pop("pose", None)
        self.scene.caption("front", f"3D · playing frame {frame}")
        self.scene.caption("side", "3D · side view")

    def _show_controls(self, view: FrameView) -> None:
        c = self.controls
        self._show_progress(view)
        _set(c.frame, value=view.index)
        _set(c.frame_info, content=frame_text(view))
        _set(c.orientation, value=view.orientation if view.orientation_note == "set here" else AUTO)
        _set(c.orientation_note, content=orientation_text(view))
        for handle, props in control_states(c, self.state, view):
            _set(handle, **props)
        _set(
            c.overrides,
            content="  \n".join(f"**{j}** at ({x:.0f}, {y:.0f})" for j, (x, y) in view.overrides.items())
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
                + next_step(bool(self.state.review_stops()))
            )
            if view.method != "track" and self.state.background_warning:
                text += f"  \n**Warning:** {self.state.background_warning} (Stage tab)."
        elif view.method == "track" and not self.state.tracking:
            missing = len(self.state.unmarked())
            text = (
                "Tracking: all 16 joints are marked on frame 0; press Track (Tracking tab)."
                if not missing
                else f"Tracking: mark the 16 joints on frame 0 ({missing} to go; Tracking tab), then press Track."
            )
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
