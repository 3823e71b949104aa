"""Benchmark: each controller's longest object_position frame on the board in simavr (cycle-accurate, 16 MHz).

Run: python3 benchmarks/speed/controller_frames.py [--rig protocol/rigs/array_2x2.toml] [--frames 200] [--seed 1]
For each controller the board's image runs bench side (simulated clock) in simavr: configure, a target at the far
corner of the surface, start, then --frames camera frames at 12 Hz at positions drawn from --seed uniformly over 90 %
of the surface (on an array: every module, so the frames route and hand over). The D13 probe times each frame from
its first byte to its reply sent (controller step, plane, telemetry and, on an array, array_commands); the longest
is printed in cycles and milliseconds against the 5 ms an object_position frame may take (the 64-byte receive
buffer lasts 5.6 ms at 115200 baud). The image is built first (scripts/avr_build.py).
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from mantaray.host.avr_image import AvrBuildError, ensure_elf
from mantaray.host.link import Link
from mantaray.host.simavr import SimulatedUno
from mantaray.host.transport import SerialTransport
from mantaray.protocol import messages as m
from mantaray.protocol import rig as rig_description
from mantaray.protocol.rig import rig_file

FRAME_BUDGET_MS = 5.0  # [ms] the longest an object_position frame may take
FRAME_US = 83_333  # [us] 12 Hz


def longest_frame_cycles(elf, harness: str, description, controller: m.Controller, positions: np.ndarray) -> int:
    with SimulatedUno(elf, bench=True, harness=harness) as board:
        link = Link(SerialTransport(board.path), description=description, ack_timeout_s=2.0)
        link.identify()
        link.command(m.Configure(controller=controller))
        now_us = 1_000_000
        link.command(m.SimClock(now=now_us))
        link.command(m.SetTarget(*(0.9 * h for h in description.grid.half_extent_m)))
        link.command(m.Start())
        for frame, (x, y) in enumerate(positions, 1):
            now_us += FRAME_US
            link.command(m.SimClock(now=now_us))
            link.position(m.ObjectPosition(frame=frame, capture_time=now_us, x=float(x), y=float(y)))
        link.close()
    return board.stats["byte_handling"]["max_cycles"]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rig", type=rig_file, default=rig_description.default(), metavar="FILE", help="rig file")
    parser.add_argument("--frames", type=int, default=200, help="camera frames per controller")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    description = args.rig
    if not 1 <= args.frames <= 10_000:
        parser.error("--frames must be 1..10000")
    try:
        elf = ensure_elf(description)
    except AvrBuildError as exc:
        print(exc, file=sys.stderr)
        return 1
    hx, hy = description.grid.half_extent_m
    positions = np.random.default_rng(args.seed).uniform((-0.9 * hx, -0.9 * hy), (0.9 * hx, 0.9 * hy), (args.frames, 2))
    print(f"{description.board.mcu} in simavr ({description.describe()}), {args.frames} frames each, seed {args.seed}")
    worst = 0.0
    for controller in m.Controller:
        cycles = longest_frame_cycles(elf, description.simavr_harness, description, controller, positions)
        ms = cycles / description.board.f_cpu_hz * 1000
        worst = max(worst, ms)
        print(f"{controller.name.lower():10s} longest frame {cycles:>7,} cycles {ms:5.2f} ms", flush=True)
    print(
        f"longest of all: {worst:.2f} ms against {FRAME_BUDGET_MS:g} ms: {'within' if worst < FRAME_BUDGET_MS else 'OVER'}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
