"""A fault-injecting transport between the link and any other: dropped bytes, bit flips and noise bursts, both ways."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .transport import Transport


@dataclass
class FaultCounts:
    dropped: int = 0
    flipped: int = 0
    burst_bytes: int = 0


@dataclass
class FaultInjector:
    """Wraps a transport; every byte either way is dropped with p_drop, gets one bit flipped with p_flip, and
    with p_burst per write or read a burst of 1..burst_max random bytes is inserted. Seeded: reproducible."""

    inner: Transport
    p_drop: float = 0.0
    p_flip: float = 0.0
    p_burst: float = 0.0
    burst_max: int = 16
    seed: int = 1
    counts: FaultCounts = field(default_factory=FaultCounts)

    def __post_init__(self) -> None:
        self._rng = np.random.default_rng(self.seed)

    def _mangle(self, data: bytes) -> bytes:
        out = bytearray()
        for byte in data:
            if self._rng.random() < self.p_drop:
                self.counts.dropped += 1
                continue
            if self._rng.random() < self.p_flip:
                byte ^= 1 << int(self._rng.integers(8))
                self.counts.flipped += 1
            out.append(byte)
        if data and self._rng.random() < self.p_burst:
            burst = self._rng.integers(0, 256, int(self._rng.integers(1, self.burst_max + 1)), dtype=np.uint8)
            at = int(self._rng.integers(len(out) + 1))
            out[at:at] = burst.tobytes()
            self.counts.burst_bytes += len(burst)
        return bytes(out)

    def write(self, data: bytes) -> None:
        self.inner.write(self._mangle(data))

    def read(self, timeout_s: float) -> bytes:
        return self._mangle(self.inner.read(timeout_s))

    def close(self) -> None:
        self.inner.close()
