"""Benchmark: where a physics step's time goes at each fidelity, by MuJoCo's own stage timers.

Run: python3 benchmarks/speed/step_profile.py [--configs 17:0.001,21:0.00025] [--plant paper] [--object sphere]
     [--set fabric.stretch=threads --set contact.model=kernel] [--seconds 0.5]
Each config (a named fidelity of sim/model/rig.py, or RESOLUTION:TIMESTEP) loads the model as a trial does, drops the
object at (5, 2) cm, tilts the sheet a little (a0..a3 = 2, -1, 0, 1 cm) and steps --seconds of simulated time,
timing every stage with mjcb_time. Prints per config: the wall time per step and simulated seconds per wall second,
each stage's time per step and share of the step (position: kinematics, inertia, collision, making and projecting
the constraints; velocity: passive forces, the kernel contact's plugin among them; constraint: the solver), and the
constraint rows by kind with the solver's iterations per step. Times are comparable within one run only.
"""

from __future__ import annotations

import argparse
import collections
import sys
import time

import mujoco

from mantaray.sim.evaluation.fidelity import parse_fidelity
from mantaray.sim.model import model as M
from mantaray.sim.model.parameters import ParameterError, plant_names
from mantaray.sim.model.plant import Plant, parse_setting

STAGES = (  # (timer, label, is it inside another stage listed here)
    ("mjTIMER_POSITION", "position", False),
    ("mjTIMER_POS_KINEMATICS", "  kinematics", True),
    ("mjTIMER_POS_INERTIA", "  inertia", True),
    ("mjTIMER_POS_COLLISION", "  collision", True),
    ("mjTIMER_POS_MAKE", "  make constraints", True),
    ("mjTIMER_POS_PROJECT", "  project constraints", True),
    ("mjTIMER_VELOCITY", "velocity (passive, plugin)", False),
    ("mjTIMER_ACTUATION", "actuation", False),
    ("mjTIMER_CONSTRAINT", "constraint solver", False),
    ("mjTIMER_ADVANCE", "integration", False),
)
COMMANDS_M = (0.02, -0.01, 0.0, 0.01)  # [m] a0..a3: a small tilt, so the object rolls and the sheet moves
DROP_M = (0.05, 0.02)  # [m]


def profile(plant: Plant, object_name: str, fidelity, seconds: float) -> dict:
    """One config's stage times [us per step], its step's wall time and the constraint rows by kind."""
    rig = plant.rig(resolution=fidelity.resolution, timestep_s=fidelity.timestep_s, object_name=object_name)
    model, data = M.load(rig)
    M.place_object(model, data, *DROP_M)
    M.set_commands(model, data, COMMANDS_M)
    for timer in data.timer:
        timer.duration, timer.number = 0.0, 0
    steps = max(1, round(seconds / model.opt.timestep))
    rows, iterations = collections.Counter(), 0
    for _ in range(steps):
        mujoco.mj_step(model, data)
        rows.update(mujoco.mjtConstraint(int(k)).name.removeprefix("mjCNSTR_").lower() for k in data.efc_type)
        iterations += int(data.solver_niter[0])
    stages = {label: data.timer[int(getattr(mujoco.mjtTimer, name))].duration / steps for name, label, _ in STAGES}
    step_us = data.timer[int(mujoco.mjtTimer.mjTIMER_STEP)].duration / steps
    return {
        "step_us": step_us,
        "sim_per_wall": model.opt.timestep / (step_us * 1e-6),  # by the step timer: the row counting left out
        "stages": stages,
        "rows": {k: v / steps for k, v in rows.most_common()},
        "iterations": iterations / steps,
        "dofs": model.nv,
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--configs", default="17:0.001,21:0.00025")
    parser.add_argument("--plant", default="paper", choices=plant_names())
    parser.add_argument("--object", default="sphere")
    parser.add_argument("--set", action="append", default=[], type=parse_setting, metavar="KEY=VALUE")
    parser.add_argument("--seconds", type=float, default=0.5, help="simulated seconds per config [s]")
    args = parser.parse_args()
    try:
        fidelities = [parse_fidelity(c) for c in args.configs.split(",")]
        plant = Plant(args.plant).set(dict(args.set))
    except (ValueError, ParameterError) as exc:
        parser.error(str(exc))
    if not args.seconds > 0:
        parser.error(f"--seconds must be > 0, got {args.seconds:g}")
    mujoco.set_mjcb_time(lambda: time.perf_counter() * 1e6)  # [us] MuJoCo's timers read this clock
    try:
        fixed = ", ".join(f"{k}={v}" for k, v in args.set) or "as declared"
        print(f"{args.object} on {args.plant} ({fixed}), {args.seconds:g} simulated s per config", flush=True)
        for fidelity in fidelities:
            p = profile(plant, args.object, fidelity, args.seconds)
            print(
                f"{fidelity.resolution} x {fidelity.resolution}, {fidelity.timestep_s * 1e3:g} ms: {p['dofs']} dofs, "
                f"{p['step_us']:.0f} us a step, {p['sim_per_wall']:.2f} simulated s per wall s"
            )
            for (_, label, _), us in zip(STAGES, p["stages"].values(), strict=True):
                print(f"  {label:28s} {us:8.0f} us  {us / p['step_us']:5.1%}")
            rows = ", ".join(f"{k} {v:.0f}" for k, v in p["rows"].items())
            print(f"  constraint rows a step: {rows}; solver iterations a step: {p['iterations']:.2f}", flush=True)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130
    finally:
        mujoco.set_mjcb_time(None)
    return 0


if __name__ == "__main__":
    sys.exit(main())
