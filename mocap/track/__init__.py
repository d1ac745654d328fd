"""The tracking method (the VBA paper): the joints marked on frame 0 followed by colour
block matching, a perspective camera calibrated from the key triangle, and the 3D
skeleton along the viewing rays; a person model, where given, proposes the marks and
finds the body the colours lose (landmarks, opinion, reseed). ``track_clip`` is its
front door."""

from mocap.track.tracking import TrackResult, track_clip

__all__ = ["TrackResult", "track_clip"]
