"""The rig description (protocol/rig.toml; an array's in protocol/rigs/): read, checked, and the geometry it implies.

One module is a modules_x = modules_y = 1 rig. An array is modules_x x modules_y modules of module_size_x_m x
module_size_y_m each, with one actuator on every node of the (modules_x + 1) x (modules_y + 1) grid: neighbouring
modules share the actuators on their common edge (PROTOCOL.md §5 numbers them). The host, the simulation and the code
generator all read a rig through load(); a description that contradicts itself or its board is refused with the
field named (RigDescriptionError).
"""

from __future__ import annotations

import argparse
import functools
import math
import tomllib
from dataclasses import dataclass
from pathlib import Path

if __package__ in (None, ""):
    from boards import BOARDS, Board
    from codegen import TYPES
else:
    from .boards import BOARDS, Board
    from .codegen import TYPES

RIG_TOML = Path(__file__).with_name("rig.toml")  # the default rig: one module, the paper's
RIGS = Path(__file__).with_name("rigs")  # other rigs: arrays

PER_ACTUATOR = ("pwm_pin", "dir_pin", "motor_sign", "mux_channel", "analog_pin", "encoder_sign")
ONE_OR_PER_ACTUATOR = ("mux_address",)  # one value shared by every actuator, or one each
PINS = ("pwm_pin", "dir_pin", "analog_pin", "bench_pin", "probe_controller_pin", "probe_actuator_pin", "probe_loop_pin")
SIGNS = ("motor_sign", "encoder_sign")
MUX_CHANNELS = 8  # TCA9548A
MUX_ADDRESSES = range(0x70, 0x78)  # TCA9548A: 0x70 + its A2 A1 A0 pins
INTEGER_RANGE = {"u8": (0, 0xFF), "i8": (-0x80, 0x7F), "u16": (0, 0xFFFF), "u32": (0, 0xFFFFFFFF)}
SCALARS = (  # the other entries this module and the generator read
    "modules_x",
    "modules_y",
    "actuator_count",
    "actuator_range_m",
    "module_size_x_m",
    "module_size_y_m",
    "encoder_counts",
    "pulley_circumference_m",
    "motor_speed_rpm",
    "actuator_period_us",
    "pwm_max",
    "encoder_address",
    "encoder_angle_register",
)
PHYSICAL_RANGE = {  # entry -> (least, most) a rig can have, in the entry's unit: outside is a typo, not a rig
    "module_size_x_m": (0.05, 5.0),  # [m] a hand-sized module to a room's
    "module_size_y_m": (0.05, 5.0),
    "actuator_range_m": (0.005, 2.0),  # [m]
    "pulley_circumference_m": (0.005, 1.0),  # [m/rev] a 5-tooth GT2 pulley to a drum
    "encoder_counts": (2, 0xFFFF),  # [counts/rev]
    "motor_speed_rpm": (1.0, 30000.0),  # [rev/min]
    "actuator_period_us": (100, 1_000_000),  # [us] 10 kHz to 1 Hz
}
MAX_ACTUATORS = 16  # jog.actuator and zero.actuators (a 16-bit mask) address actuators 0..15 (schema.toml)


class RigDescriptionError(ValueError):
    """A rig file contradicts itself, its board, or (for the generator) schema.toml."""


@dataclass(frozen=True)
class Grid:
    """The shape of a rig, PROTOCOL.md §5: modules_x x modules_y modules of module_x_m x module_y_m, one actuator on
    every node of their grid. Lengths [m] in the fabric frame (origin at the surface's centre); actuator i and
    module k numbered as §5. The one place this geometry is written, for the host, the simulation and the
    conformance suite."""

    modules_x: int = 1
    modules_y: int = 1
    module_x_m: float = 0.5  # [m]
    module_y_m: float = 0.5  # [m]

    @property
    def module_count(self) -> int:
        return self.modules_x * self.modules_y

    @property
    def actuator_count(self) -> int:
        return (self.modules_x + 1) * (self.modules_y + 1)

    @property
    def half_extent_m(self) -> tuple[float, float]:
        """[m] Half the whole surface's size along x and y: the surface spans ±these about its centre."""
        return self.modules_x * self.module_x_m / 2, self.modules_y * self.module_y_m / 2

    def describe(self) -> str:
        size = f"{self.module_x_m:g} x {self.module_y_m:g} m"
        if self.module_count == 1:
            return f"one {size} module on {self.actuator_count} actuators"
        return f"a {self.modules_x} x {self.modules_y} array of {size} modules on {self.actuator_count} actuators"

    def actuator_xy(self, actuator: int) -> tuple[float, float]:
        """[m] Where actuator i stands."""
        if not 0 <= actuator < self.actuator_count:
            raise ValueError(f"actuator {actuator}: {self.describe()} has actuators 0..{self.actuator_count - 1}")
        i, j = actuator % (self.modules_x + 1), actuator // (self.modules_x + 1)
        hx, hy = self.half_extent_m
        return i * self.module_x_m - hx, j * self.module_y_m - hy

    def module_corners(self, module: int) -> tuple[int, int, int, int]:
        """Module k's four actuators, in a single module's order: (−x, −y), (+x, −y), (−x, +y), (+x, +y)."""
        if not 0 <= module < self.module_count:
            raise ValueError(f"module {module}: {self.describe()} has modules 0..{self.module_count - 1}")
        p, q = module % self.modules_x, module // self.modules_x
        row = self.modules_x + 1
        first = q * row + p
        return first, first + 1, first + row, first + row + 1

    def module_centre(self, module: int) -> tuple[float, float]:
        """[m] Module k's centre: (0, 0) on one module."""
        corners = self.module_corners(module)
        (x0, y0), (x1, y1) = self.actuator_xy(corners[0]), self.actuator_xy(corners[3])
        return (x0 + x1) / 2, (y0 + y1) / 2

    def modules_of(self, actuator: int) -> tuple[int, ...]:
        """The modules actuator i is a corner of: 1, 2 or 4 of them, lowest first."""
        return tuple(k for k in range(self.module_count) if actuator in self.module_corners(k))

    def shown(self, actuator: int) -> tuple[int, int]:
        """(module, corner) where telemetry shows actuator i after a jog: the lowest-numbered module it is a corner
        of (PROTOCOL.md, telemetry.module)."""
        module = self.modules_of(actuator)[0]
        return module, self.module_corners(module).index(actuator)

    def module_at(self, x_m: float, y_m: float) -> int | None:
        """The module over (x, y) [m] (on a shared edge: the one at larger x, y), or None outside the surface."""
        hx, hy = self.half_extent_m
        if not (-hx <= x_m <= hx and -hy <= y_m <= hy):
            return None
        p = min(int((x_m + hx) / self.module_x_m), self.modules_x - 1)
        q = min(int((y_m + hy) / self.module_y_m), self.modules_y - 1)
        return q * self.modules_x + p


@dataclass(frozen=True)
class RigDescription:
    """One rig file, checked. Lengths [m]; actuator i and module k numbered as PROTOCOL.md §5."""

    path: Path
    board: Board
    core: dict  # [core] key -> entry (value, type, unit, doc, identify)
    board_entries: dict  # [board] key -> entry

    def value(self, key: str):
        section = self.core if key in self.core else self.board_entries
        return section[key]["value"]

    @property
    def name(self) -> str:
        """The name of the rig's builds (firmware/rigs/NAME/, mantaray-vmcu-NAME): "module" for the default rig
        (protocol/rig.toml), else the file's stem."""
        return "module" if self.path.resolve() == RIG_TOML.resolve() else self.path.stem

    @property
    def vmcu_program(self) -> str:
        """The virtual MCU built for this rig."""
        return build_of(self.name, "mantaray-vmcu")

    @property
    def simavr_harness(self) -> str:
        """The simavr harness that plays this rig's board and hardware."""
        return build_of(self.name, "mantaray-simavr")

    @property
    def pio_env(self) -> str:
        """The PlatformIO environment that builds this rig's board image (platformio.ini; scripts/avr_build.py
        writes it to build/avr for the Uno's, build/avr-ENV for any other)."""
        return "uno" if self.name == "module" else f"{self.board.pio_prefix}_{self.name}"

    @property
    def modules_x(self) -> int:
        return self.core["modules_x"]["value"]

    @property
    def modules_y(self) -> int:
        return self.core["modules_y"]["value"]

    @property
    def module_count(self) -> int:
        return self.modules_x * self.modules_y

    @property
    def actuator_count(self) -> int:
        return self.core["actuator_count"]["value"]

    @property
    def actuator_range_m(self) -> float:
        return self.core["actuator_range_m"]["value"]

    @property
    def module_size_x_m(self) -> float:
        return self.core["module_size_x_m"]["value"]

    @property
    def module_size_y_m(self) -> float:
        return self.core["module_size_y_m"]["value"]

    @property
    def motor_speed_rpm(self) -> float:
        return self.core["motor_speed_rpm"]["value"]

    @property
    def pulley_circumference_m(self) -> float:
        return self.core["pulley_circumference_m"]["value"]

    @property
    def grid(self) -> Grid:
        """The shape alone: the modules and where their actuators stand."""
        return Grid(self.modules_x, self.modules_y, self.module_size_x_m, self.module_size_y_m)

    @property
    def reported(self) -> dict:
        """What the firmware reports at identify: identify_reply field -> this description's value."""
        return {e["identify"]: e["value"] for e in self.core.values() if "identify" in e}

    @property
    def reported_units(self) -> dict:
        return {e["identify"]: e.get("unit", "") for e in self.core.values() if "identify" in e}

    def describe(self) -> str:
        return self.grid.describe()


def _read(path: Path) -> dict:
    try:
        with open(path, "rb") as f:
            return tomllib.load(f)
    except FileNotFoundError:
        raise RigDescriptionError(f"{path}: no such rig file") from None
    except UnicodeDecodeError:
        raise RigDescriptionError(f"{path}: not a text file, so not a rig file (a rig file is TOML)") from None
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise RigDescriptionError(f"{path}: not a readable TOML file ({exc})") from None


def _well_formed(where: str, key: str, entry: dict) -> None:
    """An entry has a value of its type (each of a list's values), a doc and a known type."""
    if not isinstance(entry, dict) or entry.get("type") not in TYPES or "doc" not in entry or "value" not in entry:
        raise RigDescriptionError(f"{where} {key}: needs value, doc and a type of {', '.join(TYPES)}")
    listed = isinstance(entry["value"], list)
    if key in PER_ACTUATOR and not listed:
        raise RigDescriptionError(f"{where} {key}: needs a list, one value per actuator")
    if listed and key not in PER_ACTUATOR + ONE_OR_PER_ACTUATOR:
        raise RigDescriptionError(f"{where} {key}: one value, not a list")
    for v in entry["value"] if listed else [entry["value"]]:
        if entry["type"] == "f32":
            ok = isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
        else:
            low, high = INTEGER_RANGE[entry["type"]]
            ok = isinstance(v, int) and not isinstance(v, bool) and low <= v <= high
        if not ok:
            raise RigDescriptionError(f"{where} {key}: {v!r} is not a {entry['type']}")


def _entries(where: str, section: dict, template: dict | None) -> dict:
    """The section's entries. The default rig's are whole; another rig has every one of them, each whole (a copy of
    the default file) or as a plain value that takes its type, unit, doc and identify from the default's."""
    if template is None:
        return section
    missing = [key for key in template if key not in section]
    unknown = [key for key in section if key not in template]
    if missing or unknown:
        parts = ([f"lacks {', '.join(missing)}"] if missing else []) + (
            [f"has unknown {', '.join(unknown)} (known: {', '.join(template)})"] if unknown else []
        )
        raise RigDescriptionError(f"{where}: {'; '.join(parts)}")
    out = {}
    for key, value in section.items():
        if isinstance(value, dict) and value.get("type", template[key]["type"]) != template[key]["type"]:
            raise RigDescriptionError(
                f"{where} {key}: a {template[key]['type']} (protocol/rig.toml), not {value['type']}"
            )
        out[key] = {**template[key], **value} if isinstance(value, dict) else {**template[key], "value": value}
    return out


def check(rig: dict, path: Path) -> Board:
    """Raises RigDescriptionError on the first disagreement found in a rig of whole entries; returns its board."""
    where = path.name
    board = BOARDS.get(rig.get("arduino")) if isinstance(rig.get("arduino"), str) else None
    if board is None:
        raise RigDescriptionError(f"{where} arduino: {rig.get('arduino')!r} is not one of {', '.join(BOARDS)}")
    missing = [k for k in (*SCALARS, *PER_ACTUATOR, *ONE_OR_PER_ACTUATOR, *PINS) if k not in rig["core"] | rig["board"]]
    if missing:
        raise RigDescriptionError(f"{where}: lacks {', '.join(dict.fromkeys(missing))}")
    for section in ("core", "board"):
        for key, entry in rig[section].items():
            _well_formed(where, key, entry)

    def v(key: str):
        return rig["core"][key]["value"] if key in rig["core"] else rig["board"][key]["value"]

    for key in ("modules_x", "modules_y"):
        if v(key) < 1:
            raise RigDescriptionError(f"{where} {key}: {v(key)} modules; a rig has at least 1 along each axis")
    for key, (least, most) in PHYSICAL_RANGE.items():
        if not least <= v(key) <= most:
            unit = f" {rig['core'][key]['unit']}" if rig["core"][key].get("unit") else ""
            raise RigDescriptionError(
                f"{where} {key}: {v(key):g}{unit} is outside {least:g}..{most:g}{unit}, what a rig can have"
            )
    count = (v("modules_x") + 1) * (v("modules_y") + 1)
    if v("actuator_count") != count:
        raise RigDescriptionError(
            f"{where} actuator_count: {v('actuator_count')}, but {v('modules_x')} x {v('modules_y')} modules stand "
            f"on {count} actuators, (modules_x + 1) x (modules_y + 1)"
        )
    if count > MAX_ACTUATORS:
        raise RigDescriptionError(
            f"{where} modules_x, modules_y: {count} actuators; the protocol addresses at most {MAX_ACTUATORS}"
        )
    for key in PER_ACTUATOR:
        if not isinstance(v(key), list) or len(v(key)) != count:
            got = len(v(key)) if isinstance(v(key), list) else "one"
            raise RigDescriptionError(f"{where} {key}: {got} values for {count} actuators")
    for key in ONE_OR_PER_ACTUATOR:
        if isinstance(v(key), list) and len(v(key)) != count:
            raise RigDescriptionError(f"{where} {key}: {len(v(key))} values for {count} actuators (or give one)")
    for key in SIGNS:
        if any(s not in (-1, 1) for s in v(key)):
            raise RigDescriptionError(f"{where} {key}: each must be 1 or -1, got {v(key)}")
    for key in PINS:
        for pin in v(key) if isinstance(v(key), list) else [v(key)]:
            if pin not in board.pins:
                raise RigDescriptionError(f"{where} {key}: the {board.name} has no pin {pin} ({board.pin_range()})")
            if pin in board.reserved:
                raise RigDescriptionError(f"{where} {key}: pin {pin} is {board.reserved[pin]} on the {board.name}")
    for pin in v("pwm_pin"):
        if pin not in board.pwm:
            raise RigDescriptionError(
                f"{where} pwm_pin: pin {pin} has no PWM on the {board.name} ({', '.join(map(str, sorted(board.pwm)))})"
            )
    used = [pin for key in PINS for pin in (v(key) if isinstance(v(key), list) else [v(key)])]
    twice = sorted({p for p in used if used.count(p) > 1})
    if twice:
        names = [key for key in PINS if set(v(key) if isinstance(v(key), list) else [v(key)]) & set(twice)]
        raise RigDescriptionError(f"{where} {', '.join(names)}: a pin is used twice ({twice})")
    channels = v("mux_channel")
    if any(not 0 <= c < MUX_CHANNELS for c in channels):
        raise RigDescriptionError(f"{where} mux_channel: a TCA9548A has channels 0..{MUX_CHANNELS - 1}, got {channels}")
    addresses = v("mux_address") if isinstance(v("mux_address"), list) else [v("mux_address")] * count
    for address in addresses:
        if address not in MUX_ADDRESSES or address == v("encoder_address"):
            raise RigDescriptionError(
                f"{where} mux_address: 0x{address:02X} is no TCA9548A's (0x70..0x77) or is the encoders' address"
            )
    seen: dict[tuple[int, int], int] = {}
    for actuator, encoder in enumerate(zip(addresses, channels, strict=True)):
        if encoder in seen:
            raise RigDescriptionError(
                f"{where} mux_channel: actuators {seen[encoder]} and {actuator} share one encoder "
                f"(multiplexer 0x{encoder[0]:02X}, channel {encoder[1]})"
            )
        seen[encoder] = actuator
    return board


def rig_file(text: str) -> RigDescription:
    """A rig file given on a command line (an argparse type), read and checked; what is wrong with it is a usage
    error."""
    try:
        return load(text)
    except RigDescriptionError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def load(path: Path | str = RIG_TOML) -> RigDescription:
    """Read and check a rig file; RigDescriptionError names what is wrong."""
    path = Path(path)
    raw = _read(path)
    template = None if path.resolve() == RIG_TOML.resolve() else _read(RIG_TOML)
    sections = {}
    for section in ("core", "board"):
        if not isinstance(raw.get(section), dict):
            raise RigDescriptionError(f"{path.name}: needs a [{section}] table")
        sections[section] = _entries(f"{path.name} [{section}]", raw[section], template and template[section])
    board = check({"arduino": raw.get("arduino"), **sections}, path)
    return RigDescription(path=path, board=board, core=sections["core"], board_entries=sections["board"])


def committed() -> list[RigDescription]:
    """Every rig this checkout describes: the default, then protocol/rigs/*.toml by name."""
    return [load(), *(load(p) for p in sorted(RIGS.glob("*.toml")))]


@functools.cache
def default() -> RigDescription:
    """The default rig, protocol/rig.toml: what the host and the simulation assume unless given another."""
    return load()


def build_of(name: str, base: str, joiner: str = "-") -> str:
    """A rig's build of base, as CMakeLists.txt names it: base for the default rig ("module"), else base, joiner and
    the rig's name (mantaray-vmcu-array_2x2, libmantaray_capi_array_2x2)."""
    return base if name == "module" else f"{base}{joiner}{name}"


def core_differences(a: RigDescription, b: RigDescription) -> list[str]:
    """Each [core] value a states otherwise than b, in words, in the file's order: what a firmware built for b would
    not know of a."""
    return [
        f"{key} is {entry['value']} in {a.path}, {b.core[key]['value']} in {b.path}"
        for key, entry in a.core.items()
        if entry["value"] != b.core[key]["value"]
    ]


def firmware_for(description: RigDescription) -> RigDescription:
    """The committed rig whose builds (the virtual MCU, the C core) run the rig description gives: the one of its
    name if their [core] values agree, else any whose do. RigDescriptionError, naming the first value that differs
    from the committed rig of that name (or the default), where none is built for it."""
    rigs = committed()
    same_name = [r for r in rigs if r.name == description.name]
    for candidate in same_name + rigs:
        if not core_differences(description, candidate):
            return candidate
    nearest = (same_name or rigs)[0]
    raise RigDescriptionError(
        f"{description.path}: no firmware is built for this rig ({core_differences(description, nearest)[0]}); "
        f"put it in {RIGS}, run python3 protocol/generate.py and rebuild (bash scripts/setup.sh)"
    )


def named(name: str) -> RigDescription:
    """The committed rig whose builds are called name (RigDescription.name): "module", or a file's stem in rigs/."""
    return default() if name == "module" else load(RIGS / f"{name}.toml")
