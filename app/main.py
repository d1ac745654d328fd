"""`mocap serve`: ``App`` wires the controls (``app.controls``) and scene (``app.scene``) to one
``AppState``; callbacks only call the state, and every change redraws what it changed (``refresh``,
``app.render``)."""

from __future__ import annotations

import threading
from collections.abc import Callable

import viser

from app.controls import (
    DOWNLOADS,
    EDITS,
    FRAME_STEPS,
    KEY_STEPS,
    METHOD_CHOICES,
    NO_JOINT,
    VIEW_PAIRS,
    Controls,
    build_controls,
)
from app.framing import Framing
from app.layout import Layout
from app.player import Player
from app.reel import Reel
from app.render import Rendering
from app.scene import SceneView, side_seen_from
from app.state import AppState
from app.views import FrameCache
from app.words import JOINT_CHOICES, ORIENTATION_CHOICES, chosen, joint_label
from mocap.errors import MocapError
from mocap.person import DEFAULT_MODEL, NONE

FLASH_S = 2.0  # how long a flipped segment flashes


class App(Rendering):
    """One video's app on one viser server."""

    def __init__(self, server: viser.ViserServer, state: AppState):
        self.server, self.state = server, state
        self.frames = FrameCache(state.info, state.scale)
        height, width = self.frames.get(0).shape[:2]
        self.size = (width, height)
        self._render_lock = threading.RLock()
        self.controls: Controls = build_controls(server.gui, state.n_frames)
        self.framing = Framing(server, self.size, self._relayout)
        self.scene = SceneView(
            server.scene,
            self.framing.layout,
            self.size,
            self._image_clicked,
            lambda segment, event: self._run(event.client, self._elsewhere(lambda: self._flip(segment))),
        )
        self.reel = Reel(self.scene, server.scene, state.info.fps, state.n_frames)
        self.player = Player(state, lambda force: self.refresh(force=force), self._pick, self._ahead)
        self._shown: dict[str, object] = {}
        self._notices: dict[int, object] = {}  # client id -> its notification shown
        self._marking = 0  # the frame Mark joints marks the body on
        self._flash: tuple[int, threading.Timer] | None = None  # (frame, its end) of a flipped segment
        self._still_sent = 0.0  # when the panels' own images last changed
        self._wire()
        state.on_change(self.refresh)
        self.refresh()

    @property
    def layout(self) -> Layout:
        """The panels' layout now (the last resized tab's, ``app.framing``)."""
        return self.framing.layout

    @property
    def placing(self) -> str | None:
        """The joint (the contract's name) a click on the video frame places, if any."""
        return chosen(JOINT_CHOICES, self.controls.joint.value)

    def _relayout(self, layout: Layout) -> None:
        with self._render_lock:
            self.scene.place(layout)
            self.controls.views.visible = len(layout.shown) < 4

    # -- events -> state ----------------------------------------------------------

    def _run(self, client, action: Callable[[], object]) -> None:
        """Do a user's action; a refused one is said to that user's tab."""
        try:
            action()
        except MocapError as exc:
            if client is not None:
                self._notify(client, str(exc))

    def _notify(self, client, text: str) -> None:
        """Say ``text`` in the tab's one notification, replacing the last so none stack."""
        with self._render_lock:
            last = self._notices.pop(client.client_id, None)
            if last is not None:
                last.remove()
            self._notices[client.client_id] = client.add_notification(
                "Not done", text, color="red", auto_close_seconds=6.0
            )

    def _on(self, action: Callable[[], object], placing: bool = False) -> Callable:
        """An event callback that runs ``action`` for the event's tab; one not of the Joints tab
        (``placing`` False) ends the joint placing first."""
        return lambda event: self._run(event.client, action if placing else self._elsewhere(action))

    def _elsewhere(self, action: Callable[[], object]) -> Callable[[], object]:
        """``action`` after ending the joint placing (the user has turned to other work)."""

        def run():
            if self.placing is not None:
                self.controls.joint.value = NO_JOINT
                self.refresh()
            return action()

        return run

    def _wire(self) -> None:
        c, state = self.controls, self.state
        actions: dict[str, Callable[[], object]] = {
            "prev_frame": lambda: state.go_to(state.frame - 1),
            "next_frame": lambda: state.go_to(state.frame + 1),
            "prev_key": lambda: self._jump(state.keyframe_after(state.frame, -1), "no keyframe before this frame"),
            "next_key": lambda: self._jump(state.keyframe_after(state.frame, 1), "no keyframe after this frame"),
            "keyframe": self._toggle_keyframe,
            "doubtful": lambda: self._jump(state.next_doubtful(), "no doubtful frame"),
            "undo": lambda: self._jump(state.undo(), "nothing to undo"),
            "redo": lambda: self._jump(state.redo(), "nothing to redo"),
            "play": self.player.toggle,
        }
        for action, command in c.commands.items():  # all but N are beside the tabs: placing goes on
            command.on_trigger(self._on(actions[action], action != "doubtful"))
        for handle, action in ((c.keyframe, "keyframe"), (c.doubtful, "doubtful"), (c.play, "play")):
            handle.on_click(self._on(actions[action], action != "doubtful"))
        for group, options, pair in (
            (c.frame_steps, FRAME_STEPS, ("prev_frame", "next_frame")),
            (c.key_steps, KEY_STEPS, ("prev_key", "next_key")),
            (c.edits, EDITS, ("undo", "redo")),
        ):
            group.on_click(lambda e, o=options, p=pair: self._run(e.client, actions[p[o.index(e.target.value)]]))
        c.views.on_click(lambda e: self.framing.show_pair(VIEW_PAIRS.index(e.target.value)))
        c.frame.on_update(self._from_client(lambda: state.go_to(int(c.frame.value)), placing=True))
        c.orientation.on_update(
            self._from_client(
                lambda: state.set_orientation(state.frame, chosen(ORIENTATION_CHOICES, c.orientation.value))
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
        c.clear_override.on_click(self._on(self._clear_override, placing=True))
        for limb, button in c.swaps.items():
            button.on_click(self._on(lambda limb=limb: state.swap_sides(state.frame, limb)))
        for label, button in c.downloads.items():
            button.on_click(lambda e, key=DOWNLOADS[label]: self._run(e.client, lambda: self._download(e, key)))
        for segment, button in c.segments.items():
            button.on_click(self._on(lambda s=segment: self._flip(s)))

    def _toggle_keyframe(self) -> None:
        """Mark or unmark the frame; refused, as its button is disabled, without a fit there."""
        if self.state.view().joints2d is None:
            raise MocapError(f"frame {self.state.frame} has no fit (not yet, or nobody found) to key")
        self.state.toggle_keyframe(self.state.frame)

    def _from_client(self, action: Callable[[], object], placing: bool = False) -> Callable:
        """An on_update callback that ignores the server's own updates of the control."""
        action = action if placing else self._elsewhere(action)
        return lambda e: self._run(e.client, action) if e.client is not None else None

    def _jump(self, frame: int | None, otherwise: str = "no such frame to go to") -> None:
        if frame is None:
            raise MocapError(otherwise)
        self.state.go_to(frame)

    def _flip(self, segment: str) -> None:
        """Flip a segment's foreshortening, then flash it, the side view turned to its side."""
        frame = self.state.frame
        before = self.state.view().pose3d
        self.state.flip_sign(frame, segment)
        after = self.state.view(frame).pose3d
        with self._render_lock:
            if self._flash is not None:
                self._flash[1].cancel()
            if after is None or self.player.playing:
                return
            self.scene.turn_side(side_seen_from(after, segment))
            self.scene.flash(segment, before)
            timer = threading.Timer(FLASH_S, self._end_flash)
            timer.daemon = True
            self._flash = (frame, timer)
            timer.start()
            self.refresh()

    def _end_flash(self) -> None:
        with self._render_lock:
            self._flash = None
            self.scene.unflash()
            self.refresh()

    def _image_clicked(self, event) -> None:
        joint = self.placing

        def place() -> None:
            if joint is None:
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
        self.controls.joint.value = joint_label(missing[0]) if missing else NO_JOINT
        self.refresh()

    def _learned_eyes(self, on: bool) -> None:
        """Fit with the person model (on) or without (off), unless the fit does already."""
        try:
            if on != (self.state.person_model != NONE):
                self.state.set_person_model(DEFAULT_MODEL if on else NONE)
        finally:
            self.refresh()  # a refused switch shows the checkbox as the fit has it again

    def _clear_override(self) -> None:
        self.state.clear_overrides(self.state.frame, self.placing)

    def _download(self, event, key: str) -> None:
        name, data = self.state.export(key, self.controls.foot_lock.value)
        event.client.send_file_download(name, data, save_immediately=True)

    # -- playing ------------------------------------------------------------------

    def _pick(self, frame: int) -> int:
        """The frame to show when the clock says ``frame``: its own once the reel has it in the
        page, else the latest of the two before it the reel has (frames are dropped, not late)."""
        return self.reel.latest_ready(frame)

    def _ahead(self, frame: int, until: float) -> None:
        """Load the reel with the frames after ``frame`` until the monotonic time ``until``."""
        self.reel.load_ahead(frame, until, self._reel_images)
