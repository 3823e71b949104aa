"""Benchmark: how an object answers a held tilt on each plant, open loop: when it starts to slide, and how far it goes.

Run: python3 benchmarks/experiments/static_tilt.py [--plants paper,polyester] [--object cube] [--starts 0,0.1]
     [--tilts 10,20,26.565,35] [--hold 6] [--resolution 11] [--timestep 0.002] [--integrator discrete]
     [--set KEY=VALUE ...]
For each plant, start x [m] (y = 0) and tilt θ [deg]: the object is placed and left to settle, then the four
corners are commanded at once to the plane of a pure x-tilt θ (a_i = x_i tan θ, PROTOCOL.md §5; every corner stays
in range up to atan(range / (m / 2)) = 45°) and held for --hold s of simulated time. No controller runs: this
separates what the plant lets an object do (its carriages' speed, the sheet's give, the friction) from what a
controller asks of it. The physics is the trials' default fidelity (the reference) unless --resolution and --timestep say
otherwise, under the rig's integrator unless --integrator names another (`discrete` integrates the sheet's bending and
its damping implicitly, Euler explicitly: the step-convergence probe of sim/README.md, Convergence). The contact is
the plant's (`--set contact.model=kernel --set contact.kernel_width_m=0.12` for the kernel contact, sim/README.md,
Convergence 9).
Prints, per row: when the carriages' own positions first came within 1° of the commanded tilt [s after the
command] and their tilt at the end [deg]; the object's slide relative to the sheet under it (along x, + =
downhill; the sheet itself moves as the corners do, carrying the object), when it first exceeded 2 cm and its
value at the end [cm]; and whether and when it fell off.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys

import numpy as np

import mantaray.sim  # noqa: F401  (headless GL before mujoco)
from mantaray.sim.evaluation import experiment as E
from mantaray.sim.model import model as M
from mantaray.sim.model.objects import OBJECTS
from mantaray.sim.model.parameters import plant_names
from mantaray.sim.model.plant import parse_setting
from mantaray.sim.model.rig import Rig

SLID_M = 0.02  # [m] a slide this long counts as the object set going (the protocol's ε)
AT_TILT_DEG = 1.0  # [deg] the carriages count as at the commanded tilt within this
SHEET_VERTICES = 4  # the sheet under the object: the mean of this many vertices nearest it at placement
STEP_S = 0.01  # [s] how often the probe looks


def carriage_tilt_deg(model, data, size_x_m: float) -> float:
    """[deg] The x-tilt the carriages' positions make (+ = +x side lower): atan((a1 - a0) / m), PROTOCOL.md §5."""
    a_m = [data.qpos[model.jnt_qposadr[model.joint(f"lift{i}").id]] for i in (0, 1)]
    return math.degrees(math.atan((a_m[1] - a_m[0]) / size_x_m))


def hold_tilt(model, data, rig, x0_m: float, tilt_deg: float, hold_s: float) -> dict:
    """Place the object at (x0, 0), command the x-tilt and hold it; what the carriages and the object did."""
    M.place_object(model, data, x0_m, 0.0, rule=rig.fall)
    t0_s = data.time
    half_x_m = rig.module.size_x_m / 2
    M.set_commands(
        model, data, [math.tan(math.radians(tilt_deg)) * (half_x_m if i & 1 else -half_x_m) for i in range(4)]
    )
    under = np.argsort(np.hypot(*(M.fabric_vertices(model, data)[:, :2] - M.object_xy(model, data)).T))[:SHEET_VERTICES]

    def offset_x_m() -> float:  # the object's x relative to the sheet under it
        return float(M.object_xy(model, data)[0] - M.fabric_vertices(model, data)[under, 0].mean())

    start_m = offset_x_m()
    out = {"at_tilt_s": None, "slid_s": None, "fell_s": None}
    while data.time < t0_s + hold_s:
        M.step_until(model, data, data.time + STEP_S)
        t_s = data.time - t0_s
        off_deg = abs(carriage_tilt_deg(model, data, rig.module.size_x_m) - tilt_deg)
        if out["at_tilt_s"] is None and off_deg < AT_TILT_DEG:
            out["at_tilt_s"] = t_s
        if out["slid_s"] is None and offset_x_m() - start_m > SLID_M:
            out["slid_s"] = t_s
        if M.fell_off(model, data, rig.fall):
            out["fell_s"] = t_s
            break
    return {**out, "tilt_deg": carriage_tilt_deg(model, data, rig.module.size_x_m), "slid_m": offset_x_m() - start_m}


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
    parser.add_argument(
        "--tilts",
        type=floats,
        default=[10.0, 20.0, 26.565, 35.0],
        help="x-tilts θ [deg], 0 up to where a corner leaves its range (45° on the paper's module)",
    )
    parser.add_argument("--hold", type=float, default=6.0, help="how long each tilt is held [s, simulated], 0.1..30")
    parser.add_argument("--resolution", type=int, default=E.Experiment.resolution, help="fabric vertices per side")
    parser.add_argument("--timestep", type=float, default=E.Experiment.timestep_s, help="physics step [s]")
    parser.add_argument(
        "--integrator",
        choices=("Euler", "discrete"),
        default=None,
        help="MuJoCo's integrator (default: the rig's, sim/model/rig.py Solver)",
    )
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="set a plant parameter over each plant (a key of sim/model/plant.toml, in its range); repeatable",
    )
    args = parser.parse_args()
    try:
        setting = tuple(parse_setting(text) for text in args.set)
    except ValueError as exc:
        parser.error(str(exc))
    plants = args.plants.split(",")
    unknown = [repr(p) for p in plants if p not in plant_names()]
    if unknown:
        parser.error(f"unknown plant(s) {', '.join(unknown)}; known: {', '.join(plant_names())}")
    rig = Rig()
    steepest_deg = math.degrees(math.atan(rig.actuators.range_m / (rig.module.size_x_m / 2)))
    if not all(abs(x) <= 0.2 for x in args.starts):
        parser.error("--starts must be within ±0.2 m, where the object rests on the sheet")
    if not all(0.0 <= t <= steepest_deg for t in args.tilts):
        parser.error(f"--tilts must be within 0..{steepest_deg:g} deg: steeper, a corner leaves its range")
    if not 0.1 <= args.hold <= 30.0:
        parser.error("--hold must be 0.1..30 s")
    for plant in plants:
        try:
            rig = E.Experiment(
                object_name=args.object,
                plant=plant,
                resolution=args.resolution,
                timestep_s=args.timestep,
                plant_set=setting,
            ).rig()
        except ValueError as exc:
            parser.error(str(exc))
        if args.integrator:
            rig = dataclasses.replace(rig, solver=dataclasses.replace(rig.solver, integrator=args.integrator))
        model, data = M.load(rig)
        contact = (
            "the flex's triangles"
            if rig.contact.model == "mesh"
            else f"a kernel of h = {rig.contact.kernel_width_m * 100:g} cm, k = {rig.contact.kernel_stiffness_n_per_m:g} N/m"
        )
        print(
            f"{plant}: carriages at most {rig.actuators.speed_m_per_s:.3f} m/s; fabric {args.resolution} x "
            f"{args.resolution} at {args.timestep:g} s, {rig.solver.integrator}; contact {contact}",
            flush=True,
        )
        for x0_m in args.starts:
            for tilt_deg in args.tilts:
                head = f"  {args.object} from x = {x0_m:+.2f} m, tilt {tilt_deg:5.1f} deg:"
                try:
                    r = hold_tilt(model, data, rig, x0_m, tilt_deg, args.hold)
                except M.ObjectNotSettled as exc:
                    print(f"{head} not placed ({exc})", flush=True)
                    continue
                at_tilt = f"at {r['at_tilt_s']:.2f} s" if r["at_tilt_s"] is not None else "never"
                slid = f"at {r['slid_s']:.2f} s" if r["slid_s"] is not None else "never"
                fell = f", fell off at {r['fell_s']:.2f} s" if r["fell_s"] is not None else ""
                print(
                    f"{head} carriages at the tilt {at_tilt} ({r['tilt_deg']:.1f} deg at the end);"
                    f" slid 2 cm {slid}, {r['slid_m'] * 100:+.1f} cm in all{fell}",
                    flush=True,
                )
    return 0


if __name__ == "__main__":
    sys.exit(main())
