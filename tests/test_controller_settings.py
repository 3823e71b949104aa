"""A controller's settings file: every key a schema field the controller uses, round trip through TOML, the commands
it becomes, and one clear error for each mistake."""

from __future__ import annotations

import subprocess
import sys

import pytest
from hypothesis import given
from hypothesis import strategies as st

from mantaray.host.controller_settings import ControllerSettings, SettingsError
from mantaray.host.session import Setup, controller_axes
from mantaray.paths import REPO
from mantaray.protocol import messages as m


def _keys(controller: str) -> list[tuple[str, float, float]]:
    """(key, low, high) of every setting the controller takes, from the schema's bounds."""
    kind = m.Controller[controller.upper()]
    out = [
        (f"configure.{spec.name}", spec.min, spec.max)
        for spec in m.Configure.FIELDS
        if spec.name in m.CONTROLLER_CONFIGURE[kind]
    ]
    out += [
        (f"{cls.NAME}.{spec.name}", spec.min, spec.max) for cls in m.CONTROLLER_SETTINGS[kind] for spec in cls.FIELDS
    ]
    out += [
        (f"pid.{axis.name.lower()}.{spec.name}", spec.min, spec.max)
        for axis in controller_axes(controller)
        for spec in m.ConfigurePid.FIELDS
        if spec.name != "axis"
    ]
    return out


@st.composite
def settings(draw):
    controller = draw(st.sampled_from([c.name.lower() for c in m.Controller]))
    chosen = draw(st.lists(st.sampled_from(_keys(controller)), unique_by=lambda k: k[0], max_size=8))
    values = tuple(
        (key, draw(st.floats(low, min(high, 26.5) if key == "configure.tilt_limit" else high, allow_nan=False)))
        for key, low, high in chosen
    )
    return ControllerSettings(
        controller, values, draw(st.none() | st.from_regex(r"[A-Za-z0-9_.-]{1,12}", fullmatch=True))
    )


@given(settings())
def test_a_file_reads_back_as_it_was_written(s):
    assert ControllerSettings.loads(s.dumps("written by a test")) == s


@given(settings())
def test_the_settings_become_commands_that_carry_every_value(s):
    setup = Setup(s.configure(m.Configure()), s.gains({}), (0.0, 0.0), s.commands())
    sent = setup.commands()
    assert [type(c) for c in sent[:3]] == [m.Configure, m.ConfigureSchedule, m.ConfigureCascade]
    assert sent[0].controller == m.Controller[s.controller.upper()]
    for key, value in s.values:
        section, _, name = key.rpartition(".")
        if section.startswith("pid."):
            carriers = [c for c in sent if isinstance(c, m.ConfigurePid) and c.axis.name.lower() == section[4:]]
        else:
            carriers = [c for c in sent if c.NAME == section]
        assert len(carriers) == 1 and getattr(carriers[0], name) == value, key
    for command in sent:
        command.check()


@pytest.mark.parametrize(
    "text, needle",
    [
        ('controller = "spiral"', "controller must be one of manhattan, euclidean, scheduled, cascade"),
        ("[configure]\ntilt_limit = 10", "needs controller"),
        ('controller = "manhattan"\n[configure]\ntolerance = 0.1', "'configure.tolerance' is no setting"),
        ('controller = "euclidean"\n[pid.x]\nkp = 3', "'pid.x.kp' is no setting of the euclidean controller"),
        (
            'controller = "cascade"\n[configure_cascade]\nspeed_limit = 9',
            "configure_cascade.speed_limit: 9 m/s is outside",
        ),
        ('controller = "scheduled"\n[configure_schedule]\nedge_gain = "high"', "edge_gain must be a number"),
        ('controller = "scheduled"\n[pid.x]\nkd = -1', "pid.x.kd: -1 deg s/m is outside"),
        ('controller = "scheduled" [', "not TOML"),
        (
            'controller = "manhattan"\n[configure_schedule]\nedge_tilt = 0.5',
            "'configure_schedule.edge_tilt' is no setting",
        ),
        (
            'controller = "scheduled"\n[configure_cascade]\nspeed_limit = 0.5',
            "'configure_cascade.speed_limit' is no set",
        ),
        ('controller = "euclidean"\n[configure]\nvelocity_filter = 0.1', "'configure.velocity_filter' is no setting"),
        ('controller = "manhattan"\n[configure]\ntilt_limit = 60', "steeper than the module allows (26.565051 deg"),
        ('controller = "manhattan"\nplant = 3', "plant must be a plant's name"),
        ('controller = "manhattan"\nplant = "my rig"', "plant must be a plant's name"),
    ],
)
def test_each_mistake_is_one_clear_error(text, needle):
    with pytest.raises(SettingsError, match=None) as refused:
        ControllerSettings.loads(text, "tuned.toml")
    assert str(refused.value).startswith("tuned.toml: ") and needle in str(refused.value), refused.value


def test_the_commands_take_a_settings_file_and_refuse_a_contradicting_controller(tmp_path):
    path = tmp_path / "tuned.toml"
    path.write_text(ControllerSettings("scheduled", (("configure_schedule.edge_tilt", 0.3),)).dumps())
    run = [
        sys.executable,
        "-m",
        "mantaray.cli",
        "sim",
        "run",
        "--settings",
        str(path),
        "--duration",
        "0.5",
        "--json",
        "--out",
        str(tmp_path / "out"),
    ]
    ran = subprocess.run(run, cwd=REPO, capture_output=True, text=True, timeout=300)
    assert ran.returncode == 1 and '"controller": "scheduled"' in ran.stdout, ran.stderr
    refused = subprocess.run([*run, "--controller", "cascade"], cwd=REPO, capture_output=True, text=True, timeout=300)
    assert refused.returncode == 2 and "contradicts" in refused.stderr and "Traceback" not in refused.stderr
    path.write_text(ControllerSettings("scheduled", (("pid.x.kp", 40.0),)).dumps())
    twice = subprocess.run([*run, "--gains", "30,0,0"], cwd=REPO, capture_output=True, text=True, timeout=300)
    assert twice.returncode == 2 and "both set the PIDs' gains" in twice.stderr


def test_settings_run_on_the_plant_they_were_tuned_for_and_refuse_another(tmp_path):
    path = tmp_path / "tuned.toml"
    path.write_text(ControllerSettings("scheduled", (("pid.x.kp", 1600.0),), plant="paper").dumps())
    for command in (["run", "--duration", "0.5"], ["heatmap", "--cells", "2", "--trials", "1"]):
        other = subprocess.run(
            [
                sys.executable,
                "-m",
                "mantaray.cli",
                "sim",
                *command,
                "--settings",
                str(path),
                "--plant",
                "polyester",
                "--out",
                str(tmp_path / "out"),
            ],
            cwd=REPO,
            capture_output=True,
            text=True,
            timeout=300,
        )
        assert other.returncode == 2 and "tuned for the paper plant, not polyester" in other.stderr, other.stderr
    ran = subprocess.run(
        [
            sys.executable,
            "-m",
            "mantaray.cli",
            "sim",
            "run",
            "--settings",
            str(path),
            "--duration",
            "0.5",
            "--json",
            "--out",
            str(tmp_path / "out"),
        ],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert ran.returncode == 1 and '"plant": "paper"' in ran.stdout, ran.stderr
    path.write_text(ControllerSettings("scheduled", plant="nowhere").dumps())
    unknown = subprocess.run(
        [sys.executable, "-m", "mantaray.cli", "sim", "run", "--settings", str(path)],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert unknown.returncode == 2 and "'nowhere' that sim/model/plant.toml does not declare" in unknown.stderr


def test_a_file_that_is_not_text_is_one_clear_error(tmp_path):
    path = tmp_path / "tuned.toml"
    path.write_bytes(b"\xff\xfe\x00 not text")
    with pytest.raises(SettingsError, match="not a settings file"):
        ControllerSettings.load(path)


def test_the_controller_is_named_in_any_case_and_kept_as_the_cli_spells_it():
    assert ControllerSettings.loads('controller = "Scheduled"').controller == "scheduled"
