"""Benchmark: round-trip time from an object_position frame to the telemetry that answers it, over the pty.

Run: python3 benchmarks/link_rtt.py [--frames N]
Prints the frame sizes, the telemetry rate 115200 baud allows, and RTT percentiles for the virtual MCU
on both clocks. Times are wall-clock on this machine: compare them only within one run.
"""

from __future__ import annotations

import argparse
import statistics
import time

from mantaray.host.link import Link
from mantaray.host.transport import SerialTransport
from mantaray.host.vmcu import VirtualMcu
from mantaray.protocol import messages as m
from mantaray.protocol.framing import encode_frame

BAUD_BYTES_PER_S = 115200 / 10  # 8N1: 10 bits per byte


def measure(clock: str, frames: int) -> list[float]:
    """RTTs [s] of `frames` position frames while running, one at a time."""
    with VirtualMcu(clock=clock) as vmcu:
        link = Link(SerialTransport(vmcu.path))
        link.identify()
        link.command(m.Configure(deadman=60000, telemetry_period=0))
        link.command(m.SetTarget(x=0.1, y=-0.05))
        link.command(m.Start())
        rtts = []
        for i in range(1, frames + 1):
            capture_us = i * 83_333  # 12 Hz camera
            if clock == "sim":
                link.command(m.SimClock(now=capture_us))
            msg = m.ObjectPosition(frame=i & 0xFFFF, capture_time=capture_us, x=0.001 * (i % 50), y=0.0)
            t0 = time.perf_counter()
            link.position(msg, timeout_s=1.0)
            rtts.append(time.perf_counter() - t0)
        link.close()
    return rtts


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--frames", type=int, default=2000, help="position frames per clock (default 2000)")
    args = parser.parse_args()

    telemetry = len(encode_frame(m.Telemetry(), 0))
    position = len(encode_frame(m.ObjectPosition(), 0))
    print(f"telemetry frame: {telemetry} bytes on the wire ({m.Telemetry.SIZE}-byte payload)")
    print(f"object_position frame: {position} bytes on the wire")
    print(
        f"highest telemetry rate at 115200 baud 8N1: {BAUD_BYTES_PER_S / telemetry:.1f} frames/s "
        f"({telemetry / BAUD_BYTES_PER_S * 1e3:.2f} ms per frame)"
    )
    print(
        f"UART time of position + telemetry on a real 115200 link: "
        f"{(telemetry + position) / BAUD_BYTES_PER_S * 1e3:.2f} ms"
    )
    for clock in ("wall", "sim"):
        rtts = sorted(measure(clock, args.frames))

        def q(p: float, rtts: list[float] = rtts) -> float:  # [us] the p-quantile
            return rtts[min(len(rtts) - 1, int(p * len(rtts)))] * 1e6

        print(
            f"pty RTT, {clock} clock, {len(rtts)} frames: median {statistics.median(rtts) * 1e6:.0f} us, "
            f"p90 {q(0.9):.0f} us, p99 {q(0.99):.0f} us, max {rtts[-1] * 1e6:.0f} us"
        )


if __name__ == "__main__":
    main()
