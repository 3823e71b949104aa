"""Benchmark: the firmware's timing in simavr (cycle-accurate, 16 MHz), from its probe pins and stack paint.

Run: python3 benchmarks/speed/avr_timing.py [--seconds 60] [--controller NAME | --settings FILE] [--plant NAME]
     [--rig protocol/rigs/array_2x2.toml] [--fidelity 11:0.002]
--rig picks the board: the Uno for one module (protocol/rig.toml), the Mega 2560 for the 2 x 2 array, whose bench
trial crosses all its modules (from (-0.3, -0.3) to (0.3, 0.3)), so its frames route and hand over. --fidelity is the
bench trial's physics (RESOLUTION:STEP, a module's): it only moves the object; what is measured is the firmware.
Two runs of the same ELF, each for --seconds of simulated time:
  - bench side, in lock-step with the MuJoCo rig of --plant: a trial of the controller (Manhattan with the paper's
    gains as that plant reads them, or the one --settings sets up, as mantaray sim tune writes them for a plant),
    so every camera frame runs it;
    the D13 probe's longest pulses are the object_position frames (controller step, plane transform, reply);
  - rig side, with the harness's modelled motors and I2C encoders: the carriages jogged back and forth, so the
    four position loops (D10 probe) read their encoders over I2C and drive their motors.
Prints cycles (and microseconds) for each, the longest main-loop pass against the time the board's receive buffer
lasts at 115200 baud (64 bytes on the Uno: 5.6 ms; platformio.ini), and the RAM the stack never reached. Writes them to --out as JSON.
"""

from __future__ import annotations

import argparse
import configparser
import json
import re
import sys
import time
from pathlib import Path

from mantaray.host.avr_image import AvrBuildError, ensure_elf
from mantaray.host.cli_controller import add_controller_arguments, controller_settings
from mantaray.host.link import Link, LinkError
from mantaray.host.simavr import SimulatedUno
from mantaray.host.transport import SerialTransport
from mantaray.paths import REPO
from mantaray.protocol import messages as m
from mantaray.protocol import rig as rig_description
from mantaray.protocol.rig import rig_file
from mantaray.sim.evaluation.fidelity import parse_fidelity
from mantaray.sim.model.parameters import plant_names
from mantaray.sim.model.plant import DEFAULT_PLANT, Plant, plant_for
from mantaray.sim.trial.bridge import Bridge, TrialSpec

ARDUINO_RX_BUFFER_BYTES = 64  # HardwareSerial's receive buffer unless an environment sets SERIAL_RX_BUFFER_SIZE


def rx_buffer_bytes(env: str) -> int:
    """The board's serial receive buffer [bytes] as its PlatformIO environment builds it (platformio.ini)."""
    parser = configparser.ConfigParser(inline_comment_prefixes=(";",))
    parser.read(REPO / "platformio.ini")
    found = re.search(r"-DSERIAL_RX_BUFFER_SIZE=(\d+)", parser.get(f"env:{env}", "build_flags", fallback=""))
    return int(found.group(1)) if found else ARDUINO_RX_BUFFER_BYTES


def us(cycles: float, f_cpu_hz: int) -> str:
    return f"{cycles:>9,.0f} cycles {cycles / f_cpu_hz * 1e6:>8,.0f} us"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=60.0, help="simulated seconds of each run")
    parser.add_argument("--out", default="out/bench/avr_timing.json")
    parser.add_argument(
        "--plant",
        choices=plant_names(),
        help=f"the plant of the bench-side trial (sim/model/plant.toml) (default: the one --settings was "
        f"tuned for, else {DEFAULT_PLANT})",
    )
    parser.add_argument("--rig", type=rig_file, default=rig_description.default(), metavar="FILE", help="rig file")
    parser.add_argument("--fidelity", default="11:0.002", help="the bench trial's physics, RESOLUTION:STEP")
    add_controller_arguments(parser)
    args = parser.parse_args()
    try:
        fidelity = parse_fidelity(args.fidelity)
    except ValueError as exc:
        parser.error(f"--fidelity: {exc}")
    description = args.rig
    env, harness = description.pio_env, description.simavr_harness
    one_module = description.module_count == 1
    start, target = ((0.08, -0.06), (-0.05, 0.05)) if one_module else ((-0.3, -0.3), (0.3, 0.3))
    settings = controller_settings(parser, args)
    try:
        args.plant = plant_for(settings, args.plant)
    except ValueError as exc:
        parser.error(str(exc))
    plant = Plant(args.plant)
    try:
        elf = ensure_elf(description)
    except AvrBuildError as exc:
        print(exc, file=sys.stderr)
        return 1
    hz = description.board.f_cpu_hz

    rig = plant.rig(resolution=fidelity.resolution, timestep_s=fidelity.timestep_s).with_description(description)
    with SimulatedUno(elf, bench=True, harness=harness) as uno:
        bridge = Bridge(Link(SerialTransport(uno.path), description=description), rig, plant.tracking())
        result = bridge.run(
            TrialSpec(
                start,
                target,
                duration_s=args.seconds,
                controller=settings.controller,
                settings=settings.values,
                gain_scale=plant.gain_scale,
            )
        )
        bridge.link.close()
    bench = uno.stats

    uno = SimulatedUno(elf, bench=False, run_for_s=args.seconds, harness=harness)
    link = Link(SerialTransport(uno.path), ack_timeout_s=2.0, description=description)
    link.identify()
    link.command(m.Configure(telemetry_period=100))
    sign = 1.0
    try:
        while uno.process.poll() is None:  # jog the carriages back and forth until the run ends
            for i in range(description.actuator_count):
                link.command(m.Jog(actuator=i, position=sign * 0.05 * (1 + i % 2)))
            sign = -sign
            time.sleep(0.5)
    except (LinkError, OSError):  # the simulation ended under a command
        pass
    link.close()
    uno.wait(timeout_s=600)
    rig_side = uno.stats

    report = {
        "rig_file": description.name,
        "bench": bench,
        "rig": rig_side,
        "trial": result.summary(),
        "controller": settings.controller,
        "settings": dict(settings.values),
        "plant": args.plant,
    }
    frame, loops = bench["byte_handling"], rig_side["actuator_loops"]
    worst = max(bench["main_loop_pass"]["max_cycles"], rig_side["main_loop_pass"]["max_cycles"])
    n = description.actuator_count
    print(
        f"simavr, {description.board.name} at {hz / 1e6:g} MHz ({description.describe()}), "
        f"{args.seconds:g} s simulated per run"
    )
    print(
        f"object_position frame ({settings.controller} step + reply), longest of {frame['count']} bytes handled: "
        f"{us(frame['max_cycles'], hz)}"
    )
    print(
        f"{n} actuator loops ({n} I2C reads, {n} PIDs, {n} PWM writes), {loops['count']} runs: "
        f"mean {us(loops['mean_cycles'], hz)}, max {us(loops['max_cycles'], hz)} "
        f"(period {description.value('actuator_period_us'):,} us)"
    )
    rx = rx_buffer_bytes(env)
    print(f"longest main-loop pass: {us(worst, hz)} (the {rx}-byte RX buffer lasts {rx * 10 / 115_200 * 1e6:,.0f} us)")
    print(
        f"RAM the stack never reached: bench {bench['never_used_ram_bytes']} B, rig {rig_side['never_used_ram_bytes']} "
        f"B ({description.board.mcu})"
    )
    print(f"closed-loop trial on the bench side ({args.plant} plant): {result.summary()}")
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(report, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
