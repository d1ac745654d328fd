"""The session: one protocol (mocap.session.base.Session) for both methods, what the
command line and the app work through; ``mocap.pipeline.open_session`` opens one.

Beside the sessions, the words a front end needs to speak with them, so that it
reaches the methods through this door alone: the annotations (read, saved, edited),
the export formats a session writes (``Session.export``), the review's doubts, the
video's frames, the silhouette method's per-frame products and their drawing, the
body's facing marks.
"""

from mocap.facing import FACING_MARKS, facing_marks
from mocap.io.annotations import Annotations, load_annotations, save_annotations
from mocap.io.export.formats import FORMATS
from mocap.io.video import VideoInfo, iter_frames, open_video, processing_scale, read_frame
from mocap.overlay import LANDMARK_BGR, LEARNED_BGR, draw_landmarks, draw_skeleton, segment_colour, silhouette_view
from mocap.person import DEFAULT_MODEL, NONE, available, check_name, install_hint
from mocap.review import Doubt
from mocap.session.base import Session
from mocap.session.silhouette import SilhouetteSession
from mocap.session.tracking import (MARKS_NEEDED, TrackSession, check_tracking_marks, marks_of, remarks_of,
                                    tracked_video)
from mocap.silhouette.passes import FrameFit, Silhouette

__all__ = ["DEFAULT_MODEL", "FACING_MARKS", "FORMATS", "LANDMARK_BGR", "LEARNED_BGR", "MARKS_NEEDED", "NONE",
           "Annotations", "Doubt", "FrameFit", "Session", "Silhouette", "SilhouetteSession",
           "TrackSession", "VideoInfo", "available", "check_name", "check_tracking_marks", "draw_landmarks", "draw_skeleton",
           "facing_marks", "install_hint", "iter_frames", "load_annotations", "marks_of", "open_video",
           "processing_scale", "read_frame", "save_annotations", "segment_colour", "silhouette_view",
           "remarks_of", "tracked_video"]
