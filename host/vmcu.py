"""Starts the native virtual MCU on a fresh pty and hands back the device path the host opens."""

from __future__ import annotations

import subprocess
import tempfile
import time
from pathlib import Path

from mantaray.paths import native_artifact

from .processes import DIE_WITH_PARENT, end


class VirtualMcu:
    """A `mantaray-vmcu --pty LINK` process; use as a context manager. `path` is the serial device path."""

    def __init__(
        self, clock: str = "sim", start_timeout_s: float = 5.0, path: str | None = None, program: str = "mantaray-vmcu"
    ) -> None:
        """path: where to put the serial device's symlink (default: a fresh temporary directory); a new
        virtual MCU on the path of one that exited plays a board that reset or was plugged back in. program: the
        rig's build (mantaray-vmcu-array_2x2 is the 2 x 2 array's)."""
        self._dir = tempfile.TemporaryDirectory(prefix="mantaray-vmcu-")
        self.path = path or str(Path(self._dir.name) / "tty")
        self.clock = clock
        self.process = subprocess.Popen(
            [str(native_artifact(program)), "--pty", self.path, "--clock", clock],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            preexec_fn=DIE_WITH_PARENT,
        )
        deadline = time.monotonic() + start_timeout_s
        while not Path(self.path).exists():
            if self.process.poll() is not None:
                assert self.process.stderr is not None  # Popen(stderr=PIPE)
                raise RuntimeError(f"virtual MCU exited: {self.process.stderr.read().decode().strip()}")
            if time.monotonic() > deadline:
                self.close()
                raise RuntimeError(f"virtual MCU did not create {self.path} within {start_timeout_s} s")
            time.sleep(0.005)

    def close(self) -> None:
        end(self.process)
        if self.process.stderr is not None:
            self.process.stderr.close()
        self._dir.cleanup()

    def __enter__(self) -> VirtualMcu:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
