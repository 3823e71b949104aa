"""Benchmark: round-trip time from an object_position frame to the telemetry that answers it, over the pty.

Run: python3 benchmarks/speed/link_rtt.py [--frames N] [--view-frames N]
Prints the frame sizes, the telemetry rate 115200 baud allows, and RTT percentiles for the virtual MCU
on both clocks; then, paced as a 30 Hz camera, the rig's frame-to-command time without and with the run's view
(host/view.py: a recording and the live server, fed a 1280 x 720 frame each time as `mantaray rig --live` does).
Times are wall-clock on this machine: compare them only within one run.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from mantaray.host.link import Link
from mantaray.host.transport import SerialTransport
from mantaray.host.view import LiveOptions, LiveServer, RunView
from mantaray.host.vmcu import VirtualMcu
from mantaray.protocol import messages as m
from mantaray.protocol.framing import encode_frame

BAUD_BYTES_PER_S = 115200 / 10  # 8N1: 10 bits per byte
CAMERA_HZ = 30.0  # [Hz] the pace of the view rows: a webcam's
VIEW_PORT = 9290  # the live view's web port in the view row (and the next)


def measure(clock: str, frames: int, view: RunView | None = None, pace_hz: float | None = None) -> list[float]:
    """RTTs [s] of `frames` position frames while running, one at a time; paced at pace_hz (None: back to back);
    with a view, each answered frame then goes to it as the rig's run gives it (the camera image deferred)."""
    image = np.random.default_rng(0).integers(0, 255, (720, 1280, 3), dtype=np.uint8)
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
            telemetry = link.position(msg, timeout_s=1.0)
            rtts.append(time.perf_counter() - t0)
            if view is not None:
                t_s = capture_us / 1e6
                view.frame(t_s, (msg.x, msg.y), (0.1, -0.05), 0.02, telemetry, link)
                view.defer(t_s, lambda t_s=t_s: view.camera(t_s, image, None, (0.1, -0.05), 0.02, (640.0, 360.0)))
            if pace_hz is not None:
                time.sleep(max(0.0, 1 / pace_hz - (time.perf_counter() - t0)))
        link.close()
    return rtts


def _line(what: str, rtts: list[float]) -> str:
    rtts = sorted(rtts)

    def q(p: float) -> float:  # [us] the p-quantile
        return rtts[min(len(rtts) - 1, int(p * len(rtts)))] * 1e6

    return (
        f"{what}, {len(rtts)} frames: median {statistics.median(rtts) * 1e6:.0f} us, "
        f"p90 {q(0.9):.0f} us, p99 {q(0.99):.0f} us, max {rtts[-1] * 1e6:.0f} us"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--frames", type=int, default=2000, help="position frames per clock (default 2000)")
    parser.add_argument("--view-frames", type=int, default=600, help="frames of each view row (default 600: 20 s)")
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
        print(_line(f"pty RTT, {clock} clock", measure(clock, args.frames)))
    print(_line(f"rig path at {CAMERA_HZ:g} Hz, no view", measure("wall", args.view_frames, pace_hz=CAMERA_HZ)))
    live = LiveServer(LiveOptions(web_port=VIEW_PORT), print)
    try:
        with tempfile.TemporaryDirectory() as tmp:
            view = RunView("mantaray_link_rtt", Path(tmp) / "rtt.rrd", live.options.grpc_url, {}, 4, (0.5, 0.5), print)
            rtts = measure("wall", args.view_frames, view, pace_hz=CAMERA_HZ)
            view.close()
    finally:
        live.close()
    print(_line(f"rig path at {CAMERA_HZ:g} Hz, live view and recording", rtts))


if __name__ == "__main__":
    main()
