"""mocap: one person, one fixed camera, a 3D animation out."""
