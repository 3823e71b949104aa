"""The simulated MANTA-RAY rig (MuJoCo) and its bridge to the firmware; see sim/README.md."""

import os

# MuJoCo picks its OpenGL backend when it is first imported: offscreen EGL where there is no display.
if "DISPLAY" not in os.environ:
    os.environ.setdefault("MUJOCO_GL", "egl")
