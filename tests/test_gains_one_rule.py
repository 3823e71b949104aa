"""One rule for a controller's gains: `rig`, `sim run`, `sim heatmap` and what `sim tune` writes send the firmware the
same configure_pid bytes for the same --gains or --settings, on every plant; a plant's reading moves only the boot gains.
"""

from __future__ import annotations

import numpy as np
import pytest

from mantaray.cli import build_parser
from mantaray.host import cli as host_cli
from mantaray.host.controller_settings import ControllerSettings
from mantaray.host.session import controller_axes
from mantaray.protocol import messages as m
from mantaray.sim.cli import heatmap as cli_heatmap
from mantaray.sim.cli import run as cli_run
from mantaray.sim.evaluation.experiment import Experiment, trial_spec, trials
from mantaray.sim.model.plant import Plant
from mantaray.sim.search import tune as T

PLANTS = ("polyester", "paper")  # degrees and radians: the two readings of the paper's gains
CASES = 6  # (controller, gains) drawn from the seed


def _cases(seed: int = 42) -> list[tuple[str, tuple[float, float, float, float]]]:
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(CASES):
        controller = str(rng.choice([c.name.lower() for c in m.Controller]))
        gains = (*(round(float(v), 3) for v in rng.uniform(0.0, 200.0, 3)), round(float(rng.uniform(1.0, 26.0)), 3))
        out.append((controller, gains))
    return out


def _pid_bytes(setup, controller: str) -> dict[m.Axis, bytes]:
    """The configure_pid payload each of the controller's PIDs gets."""
    return {a: m.ConfigurePid(axis=a, **setup.gains[a]).encode_payload() for a in controller_axes(controller)}


def _parsed(argv: list[str]):
    parser = build_parser(argv)
    return parser, parser.parse_args(argv)


def _rig(options: list[str]):
    parser, args = _parsed(["rig", "--port", "/dev/null", "--camera", "0", "--target", "0,0", *options])
    return host_cli.rig_setup(args, parser, (0.0, 0.0))


def _sim_run(options: list[str], plant: str, tmp_path):
    parser, args = _parsed(["sim", "run", "--plant", plant, "--out", str(tmp_path), *options])
    return cli_run._trial(args, parser).spec.setup()


def _heatmap(options: list[str], plant: str):
    parser, args = _parsed(["sim", "heatmap", "--plant", plant, "--cells", "2", "--trials", "1", *options])
    experiment = cli_heatmap._experiment(args, parser)
    return trial_spec(experiment, trials(experiment)[0]).setup()


@pytest.mark.parametrize("controller, gains", _cases())
def test_gains_reach_the_firmware_as_given_from_every_command_on_every_plant(controller, gains, tmp_path):
    options = ["--controller", controller, "--gains", ",".join(map(str, gains))]
    expected = {a: m.ConfigurePid(a, *gains).encode_payload() for a in controller_axes(controller)}
    assert _pid_bytes(_rig(options), controller) == expected
    for plant in PLANTS:
        assert _pid_bytes(_sim_run(options, plant, tmp_path), controller) == expected, plant
        assert _pid_bytes(_heatmap(options, plant), controller) == expected, plant


@pytest.mark.parametrize("controller", [c.name.lower() for c in m.Controller])
@pytest.mark.parametrize("plant", PLANTS)
def test_what_the_tuner_measured_is_what_its_file_sends_from_every_command(controller, plant, tmp_path):
    """A candidate's settings as the tuner scores them (in the paper's units, read by the plant) and as the file it
    writes sends them: the same bytes from rig, sim run and sim heatmap."""
    rng = np.random.default_rng([7, len(controller), len(plant)])
    values = {k.key: float(rng.uniform(k.low, k.high)) for k in T.knobs(controller)}
    settings = T.settings_of(controller, values, Plant(plant).gain_scale)
    path = tmp_path / "tuned.toml"
    path.write_text(ControllerSettings(controller, settings.values, plant).dumps())
    scored = Experiment(cells=2, trials_per_cell=1, controller=controller, plant=plant, settings=settings.values)
    expected = _pid_bytes(trial_spec(scored, trials(scored)[0]).setup(), controller)
    options = ["--settings", str(path)]
    assert _pid_bytes(_rig(options), controller) == expected
    assert _pid_bytes(_sim_run(options, plant, tmp_path), controller) == expected
    assert _pid_bytes(_heatmap(options, plant), controller) == expected


def test_the_tuners_paper_units_are_read_by_the_plant_and_back():
    """settings_of and start_values are inverses through the one unit rule (plant.firmware_gain / paper_gain)."""
    scale = Plant("paper").gain_scale
    values = T.boot_values("manhattan")
    settings = T.settings_of("manhattan", values, scale)
    assert settings.get("pid.x.kp") == pytest.approx(m.PID_DEFAULTS[m.Axis.X]["kp"] * scale)
    assert settings.get("pid.x.integral_limit") == m.PID_DEFAULTS[m.Axis.X]["integral_limit"]
    back, clipped = T.start_values(settings, gain_scale=scale)
    assert back == pytest.approx(values) and clipped == []


def test_gains_and_a_file_that_sets_gains_are_refused_together(tmp_path):
    path = tmp_path / "tuned.toml"
    path.write_text(ControllerSettings("manhattan", (("pid.x.kp", 10.0),)).dumps())
    with pytest.raises(SystemExit) as exit_:
        _rig(["--settings", str(path), "--gains", "1,2,3"])
    assert exit_.value.code == 2


def test_gains_outside_the_schema_are_named_as_the_options(capsys):
    with pytest.raises(SystemExit) as exit_:
        _rig(["--gains", "20000,0,0"])
    assert exit_.value.code == 2
    assert "error: --gains: pid.x.kp: 20000 deg/m is outside 0..10000" in capsys.readouterr().err
