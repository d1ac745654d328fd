"""The session: one protocol (mocap.session.base.Session) for both methods, what the
command line and the app work through; ``mocap.pipeline.open_session`` opens one.
FORMATS: the export formats a session writes (``Session.export``)."""

from mocap.io.export.formats import FORMATS
from mocap.session.base import Session
from mocap.session.silhouette import SilhouetteSession
from mocap.session.tracking import MARKS_NEEDED, TrackSession, marks_of

__all__ = ["FORMATS", "MARKS_NEEDED", "Session", "SilhouetteSession", "TrackSession", "marks_of"]
