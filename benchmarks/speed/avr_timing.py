"""Benchmark: the Uno firmware's timing in simavr (cycle-accurate, 16 MHz), from its probe pins and stack paint.

Run: python3 benchmarks/speed/avr_timing.py [--seconds 60] [--controller NAME | --settings FILE] [--plant NAME]
Two runs of the same ELF, each for --seconds of simulated time:
  - bench side, in lock-step with the MuJoCo rig of --plant: a trial of the controller (Manhattan with the paper's
    gains as that plant reads them, or the one --settings sets up, as mantaray sim tune writes them for a plant),
    so every camera frame runs it;
    the D13 probe's longest pulses are the object_position frames (controller step, plane transform, reply);
  - rig side, with the harness's modelled motors and I2C encoders: the carriages jogged back and forth, so the
    four position loops (D10 probe) read their encoders over I2C and drive their motors.
Prints cycles (and microseconds) for each, the longest main-loop pass against the 5.6 ms the Uno's 64-byte
receive buffer lasts at 115200 baud, and the RAM the stack never reached. Writes them to --out as JSON.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

from mantaray.arguments import add_controller_arguments, controller_settings
from mantaray.host.link import Link, LinkError
from mantaray.host.simavr import DEFAULT_ELF, SimulatedUno
from mantaray.host.transport import SerialTransport
from mantaray.paths import REPO
from mantaray.protocol import messages as m
from mantaray.sim.bridge import Bridge, TrialSpec
from mantaray.sim.experiment import controller_gains
from mantaray.sim.parameters import plant_names
from mantaray.sim.plant import DEFAULT_PLANT, Plant, plant_for

F_CPU = 16_000_000  # [Hz]
RX_BUFFER_US = 64 * 10 / 115_200 * 1e6  # [us] 64 bytes of 10 bits at 115200 baud


def us(cycles: float) -> str:
    return f"{cycles:>9,.0f} cycles {cycles / F_CPU * 1e6:>8,.0f} us"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="simulated seconds of each run")
    parser.add_argument("--out", default="out/bench/avr_timing.json")
    parser.add_argument(
        "--plant",
        choices=plant_names(),
        help=f"the plant of the bench-side trial (sim/plant.toml) (default: the one --settings was "
        f"tuned for, else {DEFAULT_PLANT})",
    )
    add_controller_arguments(parser)
    args = parser.parse_args()
    settings = controller_settings(parser, args)
    try:
        args.plant = plant_for(settings, args.plant)
    except ValueError as exc:
        parser.error(str(exc))
    plant = Plant(args.plant)
    build = subprocess.run([sys.executable, str(REPO / "scripts" / "avr_build.py")], capture_output=True, text=True)
    if build.returncode != 0:
        print(build.stderr, file=sys.stderr)
        return 1

    with SimulatedUno(DEFAULT_ELF, bench=True) as uno:
        bridge = Bridge(Link(SerialTransport(uno.path)), plant.rig(), plant.tracking())
        result = bridge.run(
            TrialSpec(
                (0.08, -0.06),
                (-0.05, 0.05),
                duration_s=args.seconds,
                controller=settings.controller,
                settings=settings.values,
                gains=controller_gains(settings.controller, None, plant.gain_scale),
            )
        )
        bridge.link.close()
    bench = uno.stats

    uno = SimulatedUno(DEFAULT_ELF, bench=False, run_for_s=args.seconds)
    link = Link(SerialTransport(uno.path), ack_timeout_s=2.0)
    link.identify()
    link.command(m.Configure(telemetry_period=100))
    sign = 1.0
    try:
        while uno.process.poll() is None:  # jog the carriages back and forth until the run ends
            for i in range(4):
                link.command(m.Jog(actuator=i, position=sign * 0.05 * (1 + i % 2)))
            sign = -sign
            time.sleep(0.5)
    except (LinkError, OSError):  # the simulation ended under a command
        pass
    link.close()
    uno.wait(timeout_s=600)
    rig = uno.stats

    report = {
        "bench": bench,
        "rig": rig,
        "trial": result.summary(),
        "controller": settings.controller,
        "settings": dict(settings.values),
        "plant": args.plant,
    }
    frame, loops = bench["byte_handling"], rig["actuator_loops"]
    worst = max(bench["main_loop_pass"]["max_cycles"], rig["main_loop_pass"]["max_cycles"])
    print(f"simavr, ATmega328P at 16 MHz, {args.seconds:g} s simulated per run")
    print(
        f"object_position frame ({settings.controller} step + reply), longest of {frame['count']} bytes handled: "
        f"{us(frame['max_cycles'])}"
    )
    print(
        f"four actuator loops (4 I2C reads, 4 PIDs, 4 PWM writes), {loops['count']} runs: "
        f"mean {us(loops['mean_cycles'])}, max {us(loops['max_cycles'])} (period 4,000 us)"
    )
    print(f"longest main-loop pass: {us(worst)} (the 64-byte RX buffer lasts {RX_BUFFER_US:,.0f} us)")
    print(
        f"RAM the stack never reached: bench {bench['never_used_ram_bytes']} B, rig {rig['never_used_ram_bytes']} B "
        f"of 2,048 B"
    )
    print(f"closed-loop trial on the bench side ({args.plant} plant): {result.summary()}")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(report, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
