"""A rig file (protocol/rig.toml, an array's in protocol/rigs/) is the one rig description: checked against itself, its
board and the schema, reported by the firmware at identify, compared by the host, and the source of the simulation's
and the references' rig constants."""

from __future__ import annotations

import re

import paper_reference as ref
import pytest
from hypothesis import given
from hypothesis import strategies as st

from mantaray.host import link as L
from mantaray.host.link import IncompatibleFirmware, Link, LinkError
from mantaray.host.transport import InProcessTransport
from mantaray.protocol import generate_rig as G
from mantaray.protocol import rig
from mantaray.protocol.generate import load_schema
from mantaray.sim.model import parameters as P
from mantaray.sim.model.rig import Actuators, Rig
from mantaray.sim.trial.bridge import Bridge

ARRAY = rig.RIGS / "array_2x2.toml"


def test_the_committed_descriptions_pass_their_checks_and_agree_with_the_schema():
    rigs = rig.committed()
    assert [r.name for r in rigs] == ["module", "array_2x2"]
    for description in rigs:
        G.check_schema(description, load_schema())
    one, array = rigs
    assert (one.modules_x, one.modules_y, one.actuator_count, one.board.name) == (1, 1, 4, "uno")
    assert (array.modules_x, array.modules_y, array.actuator_count, array.board.name) == (2, 2, 9, "mega2560")
    assert array.grid.half_extent_m == (0.5, 0.5)  # 1 x 1 m on 9 posts


def _edited(tmp_path, source, old: str, new: str):
    """A copy of a rig file with one line's text replaced (the line must be there)."""
    text = source.read_text()
    assert re.search(old, text, flags=re.M), old
    path = tmp_path / source.name
    path.write_text(re.sub(old, new, text, count=1, flags=re.M))
    return path


@pytest.mark.parametrize(
    "old, new, needle",
    [
        (r"^actuator_count = 9", "actuator_count = 8", "actuator_count: 8, but 2 x 2 modules stand on 9 actuators"),
        (r"^modules_y = 2", "modules_y = 0", "modules_y: 0 modules"),
        (r"^modules_x = 2", "modules_x = 3", "actuator_count: 9, but 3 x 2 modules stand on 12 actuators"),
        (r"^mux_channel = .*", "mux_channel = [0, 1, 2, 3, 4, 5, 6, 1, 0]", "actuators 1 and 7 share one encoder"),
        (r"^mux_channel = .*", "mux_channel = [0, 1, 2, 3, 4, 5, 6, 7, 8]", "a TCA9548A has channels 0..7"),
        (r"^dir_pin = .*", "", "lacks dir_pin"),
        (r"^pwm_pin = .*", "pwm_pin = [2, 3, 5, 6, 7, 8, 44, 45]", "pwm_pin: 8 values for 9 actuators"),
        (r"^pwm_pin = .*", "pwm_pin = [2, 3, 5, 6, 7, 8, 44, 45, 47]", "pin 47 has no PWM on the mega2560"),
        (r"^dir_pin = .*", "dir_pin = [22, 23, 24, 25, 26, 27, 28, 29, 31]", "a pin is used twice ([31])"),
        (r"^bench_pin = .*", "bench_pin = 70", "the mega2560 has no pin 70 (0..69)"),
        (r"^bench_pin = .*", "bench_pin = 20", "pin 20 is I2C (SDA) on the mega2560"),
        (r"^arduino = .*", 'arduino = "nano"', "arduino: 'nano' is not one of uno, mega2560"),
        (r"^encoder_counts = .*", "encoder_counts = 4096\nencoder_cpr = 4096", "has unknown encoder_cpr"),
        (r"^motor_sign = .*", "motor_sign = [1, 1, 1, 1, 1, 1, 1, 1, 0]", "motor_sign: each must be 1 or -1"),
        (r"^pwm_max = .*", "pwm_max = 256", "pwm_max: 256 is not a u8"),
        (r"^module_size_x_m = .*", "module_size_x_m = -0.5", "module_size_x_m: -0.5 m is outside 0.05..5 m"),
        (r"^module_size_y_m = .*", "module_size_y_m = 1e-9", "module_size_y_m: 1e-09 m is outside 0.05..5 m"),
        (r"^motor_speed_rpm = .*", "motor_speed_rpm = 0.0", "motor_speed_rpm: 0 rev/min is outside 1..30000"),
        (r"^actuator_range_m = .*", 'actuator_range_m = "far"', "actuator_range_m: 'far' is not a f32"),
        (r"^\[board\]", "[boards]", "needs a [board] table"),
        (r"^modules_x = 2", "modules_x = [2", "not a readable TOML file"),
        (r"^modules_x = 2", "modules_x = [2]", "modules_x: one value, not a list"),
        (r"^bench_pin = .*", "bench_pin = [31, 35]", "bench_pin: one value, not a list"),
        (r"^motor_sign = .*", "motor_sign = 1", "motor_sign: needs a list, one value per actuator"),
        (r"^arduino = .*", 'arduino = ["mega2560"]', "arduino: ['mega2560'] is not one of"),
        (r"^mux_address = .*", "mux_address = [0x70, 0x70, 0x70, 0x70, 0x70, 0x70, 0x70, 0x70, 0x20]", "0x20 is no"),
        (r"^mux_address = .*", "mux_address = 0x36", "mux_address: 0x36 is no TCA9548A's (0x70..0x77) or is the"),
        (r"^encoder_counts = .*", "encoder_counts = 0", "encoder_counts: 0 is outside 2..65535,"),
        (r"^actuator_period_us = .*", "actuator_period_us = 0", "actuator_period_us: 0 us is outside 100..1e+06 us"),
    ],
)
def test_an_array_file_that_contradicts_itself_or_its_board_is_refused_naming_the_field(tmp_path, old, new, needle):
    with pytest.raises(rig.RigDescriptionError) as info:
        rig.load(_edited(tmp_path, ARRAY, old, new))
    assert needle in str(info.value)
    assert "array_2x2.toml" in str(info.value)  # which file


@pytest.mark.parametrize(
    "old, new, needle",
    [
        (r"^pwm_pin = \{ value = \[3, 5, 6, 9\]", "pwm_pin = { value = [3, 5, 6, 7]", "pin 7 has no PWM on the uno"),
        (r"^bench_pin = \{ value = 2,", "bench_pin = { value = 19,", "pin 19 is I2C (SCL) on the uno"),
        (
            r"^motor_speed_rpm = \{ value = 120.0, type = \"f32\"",
            'motor_speed_rpm = { value = 120, type = "u8"',
            "a f32 (protocol/rig.toml), not u8",
        ),
        (r"^modules_x = \{ value = 1,", "modules_x = { value = 3,", "3 x 1 modules stand on 8 actuators"),
    ],
)
def test_the_default_file_is_checked_the_same_way(tmp_path, old, new, needle):
    with pytest.raises(rig.RigDescriptionError, match=re.escape(needle)):
        rig.load(_edited(tmp_path, rig.RIG_TOML, old, new))


def test_an_entry_given_whole_keeps_what_the_default_reports_at_identify(tmp_path):
    """A rig file may give an entry whole (as a copy of protocol/rig.toml would); it cannot drop what the host checks."""
    path = _edited(tmp_path, ARRAY, r"^modules_x = 2", 'modules_x = { value = 2, type = "u8", doc = "x" }')
    assert rig.load(path).reported["modules_x"] == 2


def test_the_default_file_without_an_entry_names_it(tmp_path):
    with pytest.raises(rig.RigDescriptionError, match="lacks modules_y"):
        rig.load(_edited(tmp_path, rig.RIG_TOML, r"^modules_y = .*", ""))


def test_a_missing_rig_file_is_one_clear_error(tmp_path):
    with pytest.raises(rig.RigDescriptionError, match="no such rig file"):
        rig.load(tmp_path / "nowhere.toml")


def test_a_binary_file_says_it_is_not_a_text_file(tmp_path):
    path = tmp_path / "myrig.toml"
    path.write_bytes(bytes(range(256)) * 8)
    with pytest.raises(rig.RigDescriptionError, match="myrig.toml: not a text file"):
        rig.load(path)


def test_a_copy_of_a_committed_rig_anywhere_runs_on_that_rigs_firmware(tmp_path):
    """A rig file is what a user writes for their own rig: from any folder, under any name, it runs on the build of
    the committed rig whose [core] values it shares."""
    path = tmp_path / "myrig.toml"
    path.write_text(ARRAY.read_text())
    assert rig.firmware_for(rig.load(path)).name == "array_2x2"
    assert Rig().with_description(rig.load(path)).module.build == "array_2x2"


def test_an_edited_copy_under_a_committed_name_is_refused_naming_the_first_difference(tmp_path):
    """The firmware built for array_2x2.toml knows 0.5 m modules; a file of that name with 0.6 m ones would run a
    simulated sheet the firmware does not describe."""
    path = _edited(tmp_path, ARRAY, r"^module_size_x_m = .*", "module_size_x_m = 0.6")
    with pytest.raises(rig.RigDescriptionError, match=r"no firmware is built for this rig \(module_size_x_m is 0.6"):
        Rig().with_description(rig.load(path))


def test_more_actuators_than_the_protocol_addresses_are_refused(tmp_path):
    text = ARRAY.read_text().replace("modules_x = 2", "modules_x = 4").replace("modules_y = 2", "modules_y = 3")
    path = tmp_path / "array_4x3.toml"
    path.write_text(text.replace("actuator_count = 9", "actuator_count = 20"))
    with pytest.raises(rig.RigDescriptionError, match="20 actuators; the protocol addresses at most 16"):
        rig.load(path)


@pytest.mark.parametrize(
    "edit, needle",
    [
        (lambda s: s["messages"][1]["fields"][1].update(default=0.6), "configure.module_x default"),
        (lambda s: next(m for m in s["messages"] if m["name"] == "jog")["fields"][0].update(max=3), "jog.actuator"),
    ],
)
def test_a_schema_that_contradicts_a_rig_is_refused(edit, needle):
    schema = load_schema()
    edit(schema)
    with pytest.raises(rig.RigDescriptionError, match=re.escape(needle)):
        G.check_schema(rig.default(), schema)


@given(st.integers(1, 3), st.integers(1, 3), st.floats(0.2, 1.0), st.floats(0.2, 1.0))
def test_the_grid_numbers_actuators_and_modules_as_the_protocol_says(nx, ny, mx, my):
    """PROTOCOL.md §5: each module's corners stand ±m/2, ±n/2 about its centre in one module's order, each actuator
    is a corner of exactly the modules that list it, a module's centre lies in that module, and telemetry shows an
    actuator in the lowest-numbered of its modules."""
    d = rig.Grid(nx, ny, mx, my)
    hx, hy = d.half_extent_m
    for k in range(d.module_count):
        corners = [d.actuator_xy(a) for a in d.module_corners(k)]
        cx = sum(x for x, _ in corners) / 4
        cy = sum(y for _, y in corners) / 4
        assert d.module_centre(k) == pytest.approx((cx, cy))
        for c, (x, y) in enumerate(corners):
            assert x == pytest.approx(cx + (mx / 2 if c & 1 else -mx / 2))
            assert y == pytest.approx(cy + (my / 2 if c & 2 else -my / 2))
        assert d.module_at(cx, cy) == k
    for a in range(d.actuator_count):
        x, y = d.actuator_xy(a)
        assert -hx - 1e-9 <= x <= hx + 1e-9 and -hy - 1e-9 <= y <= hy + 1e-9
        assert d.modules_of(a) == tuple(k for k in range(d.module_count) if a in d.module_corners(k))
        assert 1 <= len(d.modules_of(a)) <= 4
        module, corner = d.shown(a)
        assert module == min(d.modules_of(a)) and d.module_corners(module)[corner] == a
    assert d.module_at(hx + 0.01, 0.0) is None


def test_a_description_has_the_shape_of_its_entries():
    for description in rig.committed():
        g = description.grid
        assert (g.modules_x, g.modules_y, g.actuator_count) == (
            description.modules_x,
            description.modules_y,
            description.actuator_count,
        )
        assert (g.module_x_m, g.module_y_m) == (description.module_size_x_m, description.module_size_y_m)


def test_one_module_is_the_paper_numbering():
    one = rig.default().grid
    assert [one.actuator_xy(i) for i in range(4)] == [(-0.25, -0.25), (0.25, -0.25), (-0.25, 0.25), (0.25, 0.25)]
    assert one.module_corners(0) == (0, 1, 2, 3)


def test_the_firmware_reports_the_rig_it_was_built_for_at_identify():
    link = Link(InProcessTransport(simulated_clock=True))
    reply = link.identify()
    reported = rig.default().reported
    assert {"modules_x", "modules_y"} <= set(reported)
    assert {name: getattr(reply, name) for name in reported} == pytest.approx(reported, rel=1e-6)
    assert link.rig_differences == []


def test_a_board_built_with_another_pulley_is_named_in_a_warning(tmp_path):
    other = rig.load(
        _edited(
            tmp_path,
            rig.RIG_TOML,
            r"pulley_circumference_m = \{ value = 0.040",
            "pulley_circumference_m = { value = 0.045",
        )
    )
    link = Link(InProcessTransport(simulated_clock=True), description=other)
    link.identify()
    assert link.rig_differences == ["pulley_circumference is 0.04 m/rev on the board, 0.045 m/rev in rig.toml"]


def test_a_board_built_for_another_travel_is_refused_at_identify(tmp_path):
    other = rig.load(
        _edited(tmp_path, rig.RIG_TOML, r"actuator_range_m = \{ value = 0.25", "actuator_range_m = { value = 0.3")
    )
    with pytest.raises(IncompatibleFirmware, match="another rig \\(actuator_range is .* on the board"):
        Link(InProcessTransport(simulated_clock=True), description=other).identify()
    assert "actuator_range" in L.BINDING_CONSTANTS


def test_a_host_given_the_array_refuses_a_board_built_for_one_module():
    with pytest.raises(IncompatibleFirmware) as info:
        Link(InProcessTransport(simulated_clock=True), description=rig.load(ARRAY)).identify()
    text = str(info.value)
    assert "actuator_count is 4 on the board, 9 in array_2x2.toml" in text
    assert "modules_x is 1 on the board, 2 in array_2x2.toml" in text
    assert "--rig" in text


def test_the_bridge_refuses_a_simulated_rig_whose_travel_is_not_the_firmwares():
    with pytest.raises(LinkError, match="simulated rig's travel"):
        Bridge(Link(InProcessTransport(simulated_clock=True)), Rig(actuators=Actuators(range_m=0.3)))


def test_the_simulation_and_the_references_take_the_rig_from_the_description():
    one = rig.default()
    assert Rig().module.size_x_m == one.module_size_x_m and Rig().module.size_y_m == one.module_size_y_m
    assert Actuators().range_m == one.actuator_range_m == ref.ACTUATOR_RANGE  # the paper's ±0.25 m
    assert Actuators().motor_speed_rpm == one.motor_speed_rpm
    pulley = P.lookup("actuators.pulley_circumference_m")
    assert pulley.low <= one.pulley_circumference_m <= pulley.high  # the board's pulley is a plausible plant


def test_every_committed_rig_has_its_builds_under_the_names_the_description_gives():
    """The board image's PlatformIO environment puts the rig's headers on the include path; the virtual MCU and the
    simavr harness of the rig are built (CMakeLists.txt builds one of each per rig file)."""
    import configparser

    from mantaray.paths import REPO, native_artifact

    ini = configparser.ConfigParser(inline_comment_prefixes=(";",))
    ini.read(REPO / "platformio.ini")
    for description in rig.committed():
        flags = ini.get(f"env:{description.pio_env}", "build_flags")
        assert f"-Ifirmware/rigs/{description.name}" in flags.split()
        assert ini.get(f"env:{description.pio_env}", "board") == description.board.pio_board
        assert native_artifact(description.vmcu_program).exists()
        assert native_artifact(description.simavr_harness).exists()
