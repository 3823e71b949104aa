"""Starts an Arduino ELF in simavr (mantaray-simavr, or a rig's) with its UART on a pty; reads its timing report on exit."""

from __future__ import annotations

import json
import os
import select
import subprocess
import tempfile
import time
from pathlib import Path

from mantaray.paths import native_artifact
from mantaray.protocol.rig import default

from .avr_image import elf_path
from .processes import DIE_WITH_PARENT, end

DEFAULT_ELF = elf_path(default())  # the Uno image


def end_of_data(elf: Path) -> int:
    """Address of _end (first byte above .data and .bss) in the ELF, from avr-nm: where the stack paint starts."""
    out = subprocess.run(["avr-nm", str(elf)], capture_output=True, text=True, check=True).stdout
    for line in out.splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[2] == "_end":
            return int(parts[0], 16) & 0xFFFF  # data addresses carry avr-gcc's 0x800000 offset
    raise RuntimeError(f"{elf} has no _end symbol")


class SimulatedUno:
    """The Uno firmware running cycle-accurately in simavr; a context manager. `path` is its serial device path.
    harness names the rig's simavr build (mantaray-simavr-array_2x2 plays the Mega 2560 and the array's hardware)
    for another rig's ELF (build/avr-mega_array_2x2/firmware.elf).

    bench=True holds the bench pin low (external actuators, simulated clock: lock-step with the MuJoCo
    rig); bench=False is the rig, whose motors and multiplexed encoders the harness models. realtime=True
    keeps simulated time from running ahead of the wall clock (simavr is faster than the Uno), which a
    wall-clock firmware needs to keep the host's time. run_for_s stops the simulation by itself after
    that much simulated time (wait() for it). After close(),
    `stats` holds the probe timings in cycles and the RAM the stack never reached.
    """

    def __init__(
        self,
        elf: Path = DEFAULT_ELF,
        bench: bool = True,
        realtime: bool = False,
        run_for_s: float | None = None,
        start_timeout_s: float = 10.0,
        harness: str = "mantaray-simavr",
    ) -> None:
        self.elf = Path(elf)
        if not self.elf.exists():
            raise FileNotFoundError(f"{self.elf} does not exist; build it first: python3 scripts/avr_build.py")
        self._dir = tempfile.TemporaryDirectory(prefix="mantaray-simavr-")
        self._stats_path = Path(self._dir.name) / "stats.json"
        self.stats: dict | None = None
        command = (
            [
                str(native_artifact(harness)),
                str(self.elf),
                "--stats",
                str(self._stats_path),
                "--paint-from",
                hex(end_of_data(self.elf)),
            ]
            + (["--bench"] if bench else [])
            + (["--realtime"] if realtime else [])
            + (["--run-for", str(run_for_s)] if run_for_s is not None else [])
        )
        self.process = subprocess.Popen(
            command,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            preexec_fn=DIE_WITH_PARENT,
        )
        self.path = self._read_pty(start_timeout_s)

    def _read_pty(self, timeout_s: float) -> str:
        """The path from the harness's "pty PATH" line (read unbuffered: the line may share a read with others)."""
        assert self.process.stdout is not None and self.process.stderr is not None  # Popen(stdout=PIPE, stderr=PIPE)
        fd, seen = self.process.stdout.fileno(), b""
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            ready, _, _ = select.select([fd], [], [], 0.1)
            chunk = os.read(fd, 4096) if ready else b""
            seen += chunk
            for line in seen.decode(errors="replace").splitlines():
                if line.startswith("pty ") and seen.endswith(b"\n"):
                    return line.split()[1]
            if ready and not chunk:  # end of file: the harness exited
                break
        err = self.process.stderr.read() if self.process.poll() is not None else b""
        self.close()
        raise RuntimeError(
            f"mantaray-simavr did not report its pty within {timeout_s} s: {err.decode(errors='replace').strip()}"
        )

    def wait(self, timeout_s: float) -> None:
        """Waits for a run_for_s simulation to end by itself, then closes."""
        self.process.wait(timeout=timeout_s)
        self.close()

    def close(self) -> None:
        end(self.process, timeout_s=10)  # it writes its statistics on SIGTERM
        if self._stats_path.exists():
            self.stats = json.loads(self._stats_path.read_text())
        for stream in (self.process.stdout, self.process.stderr):
            if stream is not None:
                stream.close()
        self._dir.cleanup()

    def __enter__(self) -> SimulatedUno:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
