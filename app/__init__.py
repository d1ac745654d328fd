"""The browser app of `mocap serve` (viser): review a fitted video, correct it by clicking, export.
Imports ``mocap``, never the other way round (``mocap.cli`` imports it lazily, inside ``serve``)."""
