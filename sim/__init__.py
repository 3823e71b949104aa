"""MuJoCo model of the MANTA-RAY rig: its description, the paper's objects, MJCF generation and scene helpers."""
