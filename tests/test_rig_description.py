"""protocol/rig.toml is the one rig description: checked against itself and the schema, reported by the firmware at
identify, compared by the host, and the source of the simulation's and the references' rig constants."""

from __future__ import annotations

import copy

import paper_reference as ref
import pytest

from mantaray.host import link as L
from mantaray.host.link import IncompatibleFirmware, Link, LinkError
from mantaray.host.transport import InProcessTransport
from mantaray.protocol import generate_rig as G
from mantaray.protocol import rig
from mantaray.protocol.generate import load_schema
from mantaray.sim import parameters as P
from mantaray.sim.bridge import Bridge
from mantaray.sim.rig import Actuators, Rig


@pytest.fixture
def description():
    return G.load_rig(), load_schema()


def test_the_committed_description_passes_its_checks(description):
    G.check(*description)


@pytest.mark.parametrize(
    "edit, needle",
    [
        (lambda r, s: r["board"]["pwm_pin"].update(value=[3, 5, 6]), "3 values for 4 actuators"),
        (lambda r, s: r["board"]["pwm_pin"].update(value=[3, 5, 6, 7]), "pin 7 has no PWM"),
        (lambda r, s: r["board"]["dir_pin"].update(value=[4, 7, 8, 13]), "a pin is used twice ([13])"),
        (lambda r, s: r["board"]["bench_pin"].update(value=20), "the Uno has no pin 20"),
        (lambda r, s: r["core"]["encoder_counts"].update(identify="encoder_cpr"), "no u16 field 'encoder_cpr'"),
        (lambda r, s: r["core"]["actuator_range_m"].update(value=0.3), "configure.tilt_limit default"),
        (lambda r, s: r["core"]["module_size_x_m"].update(value=0.6), "configure.module_x default"),
        (lambda r, s: r["core"]["motor_speed_rpm"].pop("type"), "needs value, doc and a type"),
    ],
)
def test_a_description_that_contradicts_itself_the_uno_or_the_schema_is_refused(description, edit, needle):
    rig_toml, schema = copy.deepcopy(description)
    edit(rig_toml, schema)
    with pytest.raises(G.RigDescriptionError) as info:
        G.check(rig_toml, schema)
    assert needle in str(info.value)


def test_the_firmware_reports_the_rig_it_was_built_for_at_identify():
    link = Link(InProcessTransport(simulated_clock=True))
    reply = link.identify()
    assert {name: getattr(reply, name) for name in rig.REPORTED} == pytest.approx(rig.REPORTED, rel=1e-6)
    assert link.rig_differences == []


def test_a_board_built_with_another_pulley_is_named_in_a_warning(monkeypatch):
    monkeypatch.setitem(rig.REPORTED, "pulley_circumference", 0.045)  # as if this host's rig.toml said 0.045
    link = Link(InProcessTransport(simulated_clock=True))
    link.identify()
    assert link.rig_differences == [
        "pulley_circumference is 0.04 m/rev on the board, 0.045 m/rev in this host's protocol/rig.toml"
    ]


@pytest.mark.parametrize("name, value", [("actuator_range", 0.3), ("actuator_count", 6)])
def test_a_board_built_for_other_actuators_is_refused_at_identify(monkeypatch, name, value):
    monkeypatch.setitem(rig.REPORTED, name, value)
    with pytest.raises(IncompatibleFirmware, match=f"another rig \\({name} is .* on the board"):
        Link(InProcessTransport(simulated_clock=True)).identify()
    assert name in L.BINDING_CONSTANTS


def test_the_bridge_refuses_a_simulated_rig_whose_travel_is_not_the_firmwares():
    with pytest.raises(LinkError, match="simulated rig's travel"):
        Bridge(Link(InProcessTransport(simulated_clock=True)), Rig(actuators=Actuators(range_m=0.3)))


def test_the_simulation_and_the_references_take_the_rig_from_the_description():
    assert Rig().module.size_x_m == rig.MODULE_SIZE_X_M and Rig().module.size_y_m == rig.MODULE_SIZE_Y_M
    assert Actuators().range_m == rig.ACTUATOR_RANGE_M == ref.ACTUATOR_RANGE  # the paper's ±0.25 m
    assert Actuators().motor_speed_rpm == rig.MOTOR_SPEED_RPM
    pulley = P.lookup("actuators.pulley_circumference_m")
    assert pulley.low <= rig.PULLEY_CIRCUMFERENCE_M <= pulley.high  # the board's pulley is a plausible plant
