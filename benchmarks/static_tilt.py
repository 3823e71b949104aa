"""Benchmark: how an object answers a held tilt on each plant, open loop: when it starts to slide, and how far it goes.

Run: python3 benchmarks/static_tilt.py [--plants paper,polyester] [--object cube] [--starts 0,0.1]
     [--tilts 10,20,26.565,35] [--hold 4]
For each plant, start x [m] (y = 0) and tilt θ [deg]: the object is placed and left to settle, then the four
corners are commanded at once to the plane of a pure x-tilt θ (a_i = x_i tan θ, PROTOCOL.md §5; clipped to the
actuators' range, so beyond 26.6° the edges alone set the slope) and held for --hold s of simulated time. No
controller runs: this separates what the plant lets an object do (its actuators' speed, the sheet's slope, the
friction) from what a controller asks of it. Prints, per row, the carriages' top speed [m/s], the sheet's slope
at the end [deg] (measured 12 cm beside the object's row, off its dent), when the object had first moved 2 cm [s
after the command], how far it moved [cm] and whether it fell off.
"""
from __future__ import annotations

import argparse
import math
import sys

import numpy as np

import mantaray.sim  # noqa: F401  (headless GL before mujoco)
from mantaray.sim import model as M
from mantaray.sim.objects import OBJECTS
from mantaray.sim.parameters import plant_names
from mantaray.sim.plant import Plant

MOVED_M = 0.02          # [m] a move this long counts as the object set going (the protocol's ε)
SLOPE_ROW_M = 0.12      # [m] the slope is measured along y = this, beside the object's dent
SLOPE_SPAN_M = 0.15     # [m] between x = -this and +this


def sheet_slope_deg(model, data) -> float:
    """[deg] The sheet's slope along x (+ = lower at +x) between ±SLOPE_SPAN_M on the row y = SLOPE_ROW_M."""
    rise_m = (M.fabric_height(model, data, -SLOPE_SPAN_M, SLOPE_ROW_M)
              - M.fabric_height(model, data, SLOPE_SPAN_M, SLOPE_ROW_M))
    return math.degrees(math.atan(rise_m / (2 * SLOPE_SPAN_M)))


def hold_tilt(model, data, rig, x0_m: float, tilt_deg: float, hold_s: float) -> dict:
    """Place the object at (x0, 0), command the x-tilt and hold it; what the object did."""
    M.place_object(model, data, x0_m, 0.0, rule=rig.fall)
    t0_s = data.time
    half_x_m = rig.frame.size_x_m / 2
    M.set_commands(model, data, [math.tan(math.radians(tilt_deg)) * (half_x_m if i & 1 else -half_x_m)
                                 for i in range(4)])
    start = M.object_xy(model, data).copy()
    set_going_s, fell = None, False
    while data.time < t0_s + hold_s and not fell:
        M.step_until(model, data, data.time + 0.01)
        moved_m = float(np.hypot(*(M.object_xy(model, data) - start)))
        if set_going_s is None and moved_m > MOVED_M:
            set_going_s = data.time - t0_s
        fell = M.fell_off(model, data, rig.fall)
    return {"slope_deg": sheet_slope_deg(model, data), "set_going_s": set_going_s, "moved_m": moved_m, "fell": fell}


def floats(text: str) -> list[float]:
    try:
        return [float(v) for v in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"need comma-separated numbers, got {text!r}") from None


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--plants", default="paper,polyester", help="comma-separated, of: " + ", ".join(plant_names()))
    parser.add_argument("--object", choices=sorted(OBJECTS), default="cube")
    parser.add_argument("--starts", type=floats, default=[0.0, 0.1], help="start x [m], y = 0; within ±0.2 m")
    parser.add_argument("--tilts", type=floats, default=[10.0, 20.0, 26.565, 35.0], help="x-tilts θ [deg], 0..60")
    parser.add_argument("--hold", type=float, default=4.0, help="how long each tilt is held [s, simulated], 0.1..30")
    args = parser.parse_args()
    plants = args.plants.split(",")
    unknown = [p for p in plants if p not in plant_names()]
    if unknown:
        parser.error(f"unknown plant(s) {', '.join(unknown)}; known: {', '.join(plant_names())}")
    if not all(abs(x) <= 0.2 for x in args.starts):
        parser.error("--starts must be within ±0.2 m, where the object rests on the sheet")
    if not all(0.0 <= t <= 60.0 for t in args.tilts):
        parser.error("--tilts must be within 0..60 deg")
    if not 0.1 <= args.hold <= 30.0:
        parser.error("--hold must be 0.1..30 s")
    for plant in plants:
        rig = Plant(plant).rig(args.object)
        model, data = M.load(rig)
        print(f"{plant}: carriages at most {rig.actuators.speed_m_per_s:.3f} m/s", flush=True)
        for x0_m in args.starts:
            for tilt_deg in args.tilts:
                try:
                    r = hold_tilt(model, data, rig, x0_m, tilt_deg, args.hold)
                except M.ObjectNotSettled as exc:
                    print(f"  {args.object} from x = {x0_m:+.2f} m: not placed ({exc})", flush=True)
                    continue
                going = f"{r['set_going_s']:.2f} s" if r["set_going_s"] is not None else "never"
                print(f"  {args.object} from x = {x0_m:+.2f} m, tilt {tilt_deg:5.1f} deg: sheet {r['slope_deg']:5.1f} deg,"
                      f" moved 2 cm at {going}, {r['moved_m'] * 100:5.1f} cm in all"
                      f"{', fell off' if r['fell'] else ''}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
