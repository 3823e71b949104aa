"""Benchmark: what the run's view costs a `sim run` in wall time: no view, the recording only, and the live view.

Run: python3 benchmarks/speed/view_overhead.py [--duration 10] [--repeats 3] [--live-port 9190]
One process, one Bridge at the reference fidelity (sphere, Manhattan, the paper's 12 Hz camera), the same trial run
round-robin under the three set-ups, repeats times each; it prints each one's median wall time, its ratio to no view,
the live view's ratio to the recording alone (what a `sim run` without --live does: the issue's budget is 1.10 on that
one), the recording's size per simulated minute, and the time the view's
parts take per camera frame. The live view's server runs as it does for `--live`, with no browser connected: a
browser is another process (measure it apart). Figures move with the machine's load: compare rows of one run.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

from mantaray.host.link import Link
from mantaray.host.transport import SerialTransport
from mantaray.host.view import REPORTED_ACTUATORS, LiveOptions, LiveServer, RunView
from mantaray.host.vmcu import VirtualMcu
from mantaray.sim.model.rig import Rig
from mantaray.sim.trial.bridge import Bridge, TrialSpec
from mantaray.sim.trial.trial_view import TrialView

SETUPS = ("no view", "recording", "live view")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--duration", type=float, default=10.0, help="trial length [s]")
    parser.add_argument("--repeats", type=int, default=3, help="runs of each set-up")
    parser.add_argument("--live-port", type=int, default=9190, help="the live view's web port (and the next)")
    args = parser.parse_args()
    rig = Rig()
    spec = TrialSpec((0.05, -0.05), (-0.05, 0.05), duration_s=args.duration)
    walls: dict[str, list[float]] = {s: [] for s in SETUPS}
    sizes: list[float] = []
    parts: dict[str, float] = {}
    live = LiveServer(LiveOptions(web_port=args.live_port), lambda text: print(text, file=sys.stderr))
    try:
        with VirtualMcu(clock="sim") as vmcu, tempfile.TemporaryDirectory() as tmp:
            link = Link(SerialTransport(vmcu.path))
            bridge = Bridge(link, rig)
            for k in range(args.repeats):
                for setup in SETUPS:
                    path = Path(tmp) / f"{k}_{setup.replace(' ', '_')}.rrd"
                    view = None
                    if setup != "no view":
                        view = RunView(
                            "mantaray_view_overhead",
                            path,
                            live.options.grpc_url if setup == "live view" else None,
                            {"setup": setup},
                            REPORTED_ACTUATORS,
                            (rig.module.size_x_m, rig.module.size_y_m),
                            print,
                        )
                        bridge.view = _Timed(TrialView(view, bridge.model, bridge.data, rig, link), parts)
                    t = time.perf_counter()
                    result = bridge.run(spec)
                    walls[setup].append(time.perf_counter() - t)
                    if view is not None:
                        bridge.view.close()
                        sizes.append(path.stat().st_size / (result.sim_time_s / 60))
                    bridge.view = None
                    print(f"  {setup:10s} run {k + 1}: {walls[setup][-1]:.2f} s wall", file=sys.stderr, flush=True)
    finally:
        live.close()
    base = statistics.median(walls["no view"])
    frames = args.repeats * 2 * (round(args.duration * 12) + 1)
    print(f"{args.duration:g} s trials, {args.repeats} runs each, round-robin; median wall time and ratio to no view")
    for setup in SETUPS:
        median = statistics.median(walls[setup])
        print(f"  {setup:10s} {median:7.2f} s  {median / base:5.2f}x")
    paired = [live / recorded for live, recorded in zip(walls["live view"], walls["recording"], strict=True)]
    print(
        "the live view against a sim run without it (which records: the issue's budget 1.10), median of the "
        f"round-robin pairs: {statistics.median(paired):.2f}x (each: {', '.join(f'{r:.2f}' for r in paired)})"
    )
    print(f"recording: {statistics.median(sizes) / 1e6:.1f} MB per simulated minute (budget: 50 MB per 60 s run)")
    print("the view's parts per camera frame:", ", ".join(f"{k} {v / frames * 1000:.1f} ms" for k, v in parts.items()))
    return 0


class _Timed:
    """A TrialView whose frame() adds its wall time [s] to parts["view"]."""

    def __init__(self, view: TrialView, parts: dict[str, float]) -> None:
        self.view, self.parts = view, parts

    def start(self, tolerance_m: float) -> None:
        self.view.start(tolerance_m)

    def close(self) -> None:
        self.view.close()

    def frame(self, frame, telemetry) -> None:
        t = time.perf_counter()
        self.view.frame(frame, telemetry)
        self.parts["view"] = self.parts.get("view", 0.0) + time.perf_counter() - t


if __name__ == "__main__":
    sys.exit(main())
