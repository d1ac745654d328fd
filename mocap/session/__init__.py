"""The session: one protocol (mocap.session.base.Session) for both methods, what the
command line and the app work through; ``mocap.pipeline.open_session`` opens one.
Beside them, the silhouette method's per-frame products a session hands out."""

from mocap.session.base import Session
from mocap.session.keys import propose_keyframes
from mocap.session.silhouette import SilhouetteSession
from mocap.session.tracking import (
    MARKS_NEEDED,
    TrackSession,
    check_tracking_marks,
    marks_from_fit,
    marks_of,
    remarks_of,
    tracked_video,
)
from mocap.silhouette import FrameFit, Silhouette

__all__ = [
    "MARKS_NEEDED",
    "FrameFit",
    "Session",
    "Silhouette",
    "SilhouetteSession",
    "TrackSession",
    "check_tracking_marks",
    "marks_from_fit",
    "marks_of",
    "propose_keyframes",
    "remarks_of",
    "tracked_video",
]
