"""The browser app of `mocap serve`: review a fitted video frame by frame, correct it
by clicking, export the animation. Built on viser; imports ``mocap``, never the
other way round (``mocap.cli`` imports this package lazily, inside ``serve``)."""
