"""Benchmark: simulated seconds per wall second for each object, firmware in the loop over the pty, in lock-step.

Run: python3 benchmarks/speed/sim_speed.py [--duration 10] [--objects sphere,cube]
One process, one core: each object runs one trial of the paper's kind (Manhattan, alpha as in the paper
for the irregular objects) and prints its speed and how the wall time splits between MuJoCo stepping,
the protocol exchange with the firmware, and the rest (Python bookkeeping, fall checks). Figures move
with the machine's load: compare rows of one run, not runs.
"""

from __future__ import annotations

import argparse
import sys

from mantaray.host.link import Link
from mantaray.host.transport import SerialTransport
from mantaray.host.vmcu import VirtualMcu
from mantaray.sim.model.objects import OBJECTS
from mantaray.sim.model.rig import Rig
from mantaray.sim.trial.bridge import Bridge, TrialSpec

ALPHA_M = {"cube": 0.1, "bunny": 0.05, "disk": 0.05, "cylinder": 0.1, "apple": 0.05, "egg": 0.01}  # paper, Fig. 3


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--duration", type=float, default=10.0, help="trial length [s]")
    parser.add_argument("--objects", default=",".join(OBJECTS), help="comma-separated object names")
    args = parser.parse_args()
    print(f"{'object':9s} {'sim s/wall s':>12s} {'physics':>8s} {'link':>6s} {'other':>6s}  outcome")
    with VirtualMcu(clock="sim") as vmcu:
        link = Link(SerialTransport(vmcu.path))
        for name in args.objects.split(","):
            bridge = Bridge(link, Rig().with_object(name))
            r = bridge.run(
                TrialSpec((0.05, -0.05), (-0.05, 0.05), duration_s=args.duration, alpha_m=ALPHA_M.get(name, 0.0))
            )
            other = 1 - r.physics_share - r.link_wall_s / r.wall_time_s
            outcome = "fell off" if r.fell_off else f"final error {r.final_error_m * 100:.1f} cm"
            print(
                f"{name:9s} {r.sim_time_s / r.wall_time_s:12.2f} {r.physics_share:8.1%} "
                f"{r.link_wall_s / r.wall_time_s:6.1%} {other:6.1%}  {outcome}",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
