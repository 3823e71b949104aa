"""Child processes the host starts (the virtual MCU, the live view's server): ended politely, then firmly."""

from __future__ import annotations

import ctypes
import signal
import subprocess
import sys

END_TIMEOUT_S = 5.0  # [s] how long a child has to end on SIGTERM before it is killed
PR_SET_PDEATHSIG = 1  # prctl option (linux/prctl.h): a signal the child gets when its parent dies


def _die_with_parent() -> None:
    """In the child before exec: get SIGTERM when the parent dies, so no child outlives its host."""
    ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGTERM)


# Popen's preexec_fn for a child that must end with this process (Linux; elsewhere None: end() on close only).
DIE_WITH_PARENT = _die_with_parent if sys.platform.startswith("linux") else None


def end(process: subprocess.Popen, timeout_s: float = END_TIMEOUT_S) -> None:
    """SIGTERM, then SIGKILL if it has not ended within timeout_s [s]; waited for either way (no zombie)."""
    if process.poll() is not None:
        return
    process.terminate()
    try:
        process.wait(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        process.kill()
        process.wait()
