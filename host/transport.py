"""Byte transports under the link: a serial device path (real board, pty, simulator) or the in-process core."""
from __future__ import annotations

import ctypes
import time
from typing import Protocol

import serial

from mantaray.paths import native_artifact


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

    One per process (the core's HAL state is global, as a board's hardware is).
    """

    def __init__(self, simulated_clock: bool = True) -> None:
        self._lib = ctypes.CDLL(str(native_artifact("libmantaray_capi.so")))
        self._lib.mr_vmcu_write.argtypes = [ctypes.c_char_p, ctypes.c_size_t]
        self._lib.mr_vmcu_read.argtypes = [ctypes.c_char_p, ctypes.c_size_t]
        self._lib.mr_vmcu_read.restype = ctypes.c_size_t
        self._lib.mr_vmcu_boot(1 if simulated_clock else 0)
        self._buf = ctypes.create_string_buffer(4096)

    def write(self, data: bytes) -> None:
        self._lib.mr_vmcu_write(data, len(data))

    def read(self, timeout_s: float) -> bytes:
        n = self._lib.mr_vmcu_read(self._buf, len(self._buf))
        if n == 0 and timeout_s > 0:
            time.sleep(min(timeout_s, 0.001))  # a wall-clock core may owe periodic telemetry later
            self._lib.mr_vmcu_write(b"", 0)
            n = self._lib.mr_vmcu_read(self._buf, len(self._buf))
        return self._buf.raw[:n]

    def close(self) -> None:
        pass
