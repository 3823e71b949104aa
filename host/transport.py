"""Byte transports under the link: a serial device path (real board, pty, simulator) or the in-process core."""

from __future__ import annotations

import ctypes
import functools
import time
from typing import Protocol

import serial

from mantaray.paths import native_artifact
from mantaray.protocol.rig import build_of


class Transport(Protocol):
    def write(self, data: bytes) -> None: ...
    def read(self, timeout_s: float) -> bytes: ...
    def close(self) -> None: ...


class SerialTransport:
    """A serial device path, opened raw at 115200 8N1 (pyserial)."""

    def __init__(self, path: str, baud: int = 115200) -> None:
        self.path = path
        self._port = serial.Serial(path, baud, timeout=0)

    def write(self, data: bytes) -> None:
        self._port.write(data)

    def read(self, timeout_s: float) -> bytes:
        """Whatever arrives within timeout_s [s]: returns as soon as any byte is there."""
        self._port.timeout = timeout_s
        first = self._port.read(1)
        if not first:
            return b""
        waiting = self._port.in_waiting
        return first + (self._port.read(waiting) if waiting else b"")

    def close(self) -> None:
        self._port.close()


class InProcessTransport:
    """The native firmware core loaded as a library: the same firmware as the virtual MCU, with no pty.

    Each is one virtual MCU of its own (the core holds no global state), so any number run side by side in one
    process; it is freed with the transport (close() only ends the host's end, as closing a board's port does).
    """

    def __init__(self, simulated_clock: bool = True, build: str = "module") -> None:
        """build: the rig's firmware build (RigDescription.name; "array_2x2" is the 2 x 2 array's)."""
        self._lib = _capi(build)
        self.simulated_clock = simulated_clock
        self._handle = self._lib.mr_vmcu_new(1 if simulated_clock else 0)
        self._buf = ctypes.create_string_buffer(4096)

    def power_cycle(self) -> None:
        """The board restarts as if its power went off and on (idle, defaults, a boot message), on the same clock."""
        self._lib.mr_vmcu_free(self._handle)
        self._handle = self._lib.mr_vmcu_new(1 if self.simulated_clock else 0)

    def write(self, data: bytes) -> None:
        self._lib.mr_vmcu_write(self._handle, data, len(data))

    def read(self, timeout_s: float) -> bytes:
        n = self._lib.mr_vmcu_read(self._handle, self._buf, len(self._buf))
        if n == 0 and timeout_s > 0:
            time.sleep(min(timeout_s, 0.001))  # a wall-clock core may owe periodic telemetry later
            self._lib.mr_vmcu_write(self._handle, b"", 0)
            n = self._lib.mr_vmcu_read(self._handle, self._buf, len(self._buf))
        return self._buf.raw[:n]

    def close(self) -> None:
        """The host's end closes; the board stays (as a board does when its port closes: a reconnect finds it)."""

    def __del__(self) -> None:
        if getattr(self, "_handle", None) is not None:
            self._lib.mr_vmcu_free(self._handle)


@functools.cache
def _capi(build: str) -> ctypes.CDLL:
    """The C library of a rig's virtual MCU, its signatures declared (loaded once per process)."""
    lib = ctypes.CDLL(str(native_artifact(f"{build_of(build, 'libmantaray_capi', '_')}.so")))
    lib.mr_vmcu_new.argtypes, lib.mr_vmcu_new.restype = [ctypes.c_int], ctypes.c_void_p
    lib.mr_vmcu_free.argtypes, lib.mr_vmcu_free.restype = [ctypes.c_void_p], None
    handle_bytes: list = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_size_t]
    lib.mr_vmcu_write.argtypes, lib.mr_vmcu_write.restype = handle_bytes, None
    lib.mr_vmcu_read.argtypes, lib.mr_vmcu_read.restype = handle_bytes, ctypes.c_size_t
    return lib
