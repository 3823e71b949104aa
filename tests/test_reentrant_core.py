"""The firmware core holds no global state: two virtual MCUs stepping different trials side by side in one process
send, frame for frame, the telemetry that each sends alone in a process of its own."""

from __future__ import annotations

import json
import math
import random
import subprocess
import sys
from pathlib import Path

from mantaray.host.link import Link
from mantaray.host.transport import InProcessTransport
from mantaray.protocol import messages as m

FRAME_US = 83_333  # [us] the paper's 12 Hz camera
STEPS = 60


def trial(seed: int) -> dict:
    """A closed-loop trial drawn from the seed: controller, target, noise and a path for the object to follow."""
    rng = random.Random(seed)
    return {
        "controller": rng.choice(["manhattan", "euclidean"]),
        "target": (rng.uniform(-0.2, 0.2), rng.uniform(-0.2, 0.2)),  # [m]
        "start": (rng.uniform(-0.2, 0.2), rng.uniform(-0.2, 0.2)),  # [m]
        "alpha": rng.uniform(0.0, 0.1),  # [m] command noise
        "noise_seed": rng.randrange(1, 2**32),
        "speed": rng.uniform(0.005, 0.02),
    }  # [m per frame] the object's drift


class Stepper:
    """One trial on one virtual MCU, a camera frame per step; the object drifts toward the target."""

    def __init__(self, spec: dict) -> None:
        self.spec, self.link = spec, Link(InProcessTransport(simulated_clock=True))
        self.link.command(
            m.Configure(
                controller=m.Controller[spec["controller"].upper()],
                noise_amplitude=spec["alpha"],
                noise_seed=spec["noise_seed"],
                telemetry_period=0,
            )
        )
        self.link.command(m.SetTarget(x=spec["target"][0], y=spec["target"][1]))
        self.link.command(m.Start())
        self.xy, self.frame = list(spec["start"]), 0

    def step(self) -> list:
        self.frame += 1
        t_us = self.frame * FRAME_US
        self.link.command(m.SimClock(now=t_us))
        t = self.link.position(m.ObjectPosition(frame=self.frame, capture_time=t_us, x=self.xy[0], y=self.xy[1]))
        for i in range(2):  # toward the target, a little off it, so the controller keeps working
            error = self.spec["target"][i] - self.xy[i]
            self.xy[i] += math.copysign(min(abs(error), self.spec["speed"]), error) * 0.9
        return [t.time, int(t.state), t.tilt_zx, t.tilt_zy, list(t.command), list(t.measured), int(t.faults)]


def alone(seed: int) -> list:
    stepper = Stepper(trial(seed))
    return [stepper.step() for _ in range(STEPS)]


def test_two_virtual_mcus_in_one_process_match_each_alone_in_its_own():
    seeds = random.Random(2026).sample(range(10_000), 2)
    a, b = Stepper(trial(seeds[0])), Stepper(trial(seeds[1]))
    side_by_side = {seeds[0]: [], seeds[1]: []}
    for _ in range(STEPS):  # interleaved: each step of one between two of the other
        side_by_side[seeds[0]].append(a.step())
        side_by_side[seeds[1]].append(b.step())
    for seed in seeds:
        proc = subprocess.run(
            [sys.executable, "-c", f"import json, test_reentrant_core as T; print(json.dumps(T.alone({seed})))"],
            capture_output=True,
            text=True,
            timeout=120,
            cwd=Path(__file__).parent,
        )
        assert proc.returncode == 0, proc.stderr
        assert json.loads(json.dumps(side_by_side[seed])) == json.loads(proc.stdout)
    moving = [row[4] for row in side_by_side[seeds[0]]]
    assert any(any(abs(c) > 1e-4 for c in cmd) for cmd in moving)  # the trials did drive the actuators
    assert side_by_side[seeds[0]] != side_by_side[seeds[1]]


def test_a_power_cycle_restarts_only_its_own_virtual_mcu():
    a, b = Stepper(trial(1)), Stepper(trial(2))
    before = [b.step() for _ in range(3)]
    a.link.transport.power_cycle()  # a's board restarts: idle, clock 0
    assert isinstance(a.link.receive(0.0), m.Boot)
    after = b.step()
    assert after[1] == int(m.State.RUNNING) and after[0] > before[-1][0]
