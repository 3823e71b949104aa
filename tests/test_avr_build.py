"""scripts/avr_build.py: the Uno image links, fits its budget, takes its flags from platformio.ini and boots."""

from __future__ import annotations

import configparser
import importlib.util
import json
import os
import re
import select
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mantaray.protocol.boards import UNO
from mantaray.protocol.framing import encode_packet
from mantaray.protocol.messages import Boot, ResetCause, Telemetry

REPO = Path(__file__).resolve().parent.parent
SCRIPT = REPO / "scripts" / "avr_build.py"
INI = REPO / "platformio.ini"
CORE = REPO / "firmware" / "lib" / "core"

spec = importlib.util.spec_from_file_location("avr_build", SCRIPT)
avr_build = importlib.util.module_from_spec(spec)
sys.modules[spec.name] = avr_build  # dataclasses look their module up while the script loads
spec.loader.exec_module(avr_build)

HAS_ARDUINO_CORE = (avr_build.ARDUINO_AVR / "cores" / "arduino").is_dir()


# One rule for the whole suite: what scripts/setup.sh installs or builds is required, and a test without it fails
# saying what is missing (never a skip: a green run means every test ran).
def _require(present: bool, what: str) -> None:
    if not present:
        pytest.fail(f"needs {what}: run scripts/setup.sh")


@pytest.fixture
def arduino_core() -> None:
    _require(HAS_ARDUINO_CORE, "the Debian package arduino-core-avr")


@pytest.fixture
def avr_toolchain() -> None:
    _require(
        shutil.which("avr-g++") is not None and HAS_ARDUINO_CORE,
        "the Debian packages gcc-avr, binutils-avr, avr-libc and arduino-core-avr",
    )


@pytest.fixture
def simavr_tool() -> None:
    _require(shutil.which("simavr") is not None, "the Debian package simavr")


needs_arduino_core = pytest.mark.usefixtures("arduino_core")
needs_toolchain = pytest.mark.usefixtures("avr_toolchain")


def run_script(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(SCRIPT), *args], capture_output=True, text=True, timeout=300)


@pytest.fixture(scope="module")
def build(tmp_path_factory) -> tuple[Path, dict]:
    """One build into a fresh directory: (its directory, the sizes it printed with --json)."""
    out = tmp_path_factory.mktemp("avr")
    result = run_script("--out", str(out), "--json")
    assert result.returncode == 0, result.stderr
    return out, json.loads(result.stdout)


def ini_with(tmp_path: Path, **env_options: str) -> Path:
    """A copy of platformio.ini with absolute directories and [env:uno] options replaced."""
    parser = configparser.ConfigParser(inline_comment_prefixes=("#", ";"), interpolation=None)
    parser.read(INI)
    for name in ("src_dir", "lib_dir", "test_dir"):
        parser["platformio"][name] = str(REPO / parser["platformio"][name])
    for name, value in env_options.items():
        parser["env:uno"][name] = value
    path = tmp_path / "platformio.ini"
    with path.open("w") as f:
        parser.write(f)
    return path


def compile_commands(dry_run_stdout: str) -> list[str]:
    return [line for line in dry_run_stdout.splitlines() if " -c " in f" {line} "]


@needs_toolchain
def test_elf_is_built_and_fits_the_budget(build):
    out, sizes = build
    assert (out / "firmware.elf").is_file() and (out / "firmware.hex").is_file()
    berkeley = (
        subprocess.run(["avr-size", str(out / "firmware.elf")], capture_output=True, text=True, check=True)
        .stdout.splitlines()[1]
        .split()
    )
    text, data, bss = (int(n) for n in berkeley[:3])
    assert sizes["flash"]["used"] == text + data
    assert sizes["ram"]["used"] == data + bss
    assert sizes["flash"]["max"] == 32256 and sizes["ram"]["max"] == 2048
    assert sizes["flash"]["used"] <= sizes["flash"]["budget"] == int(32256 * 0.75)
    assert sizes["ram"]["used"] <= sizes["ram"]["budget"] == int(2048 * 0.60)
    assert sizes["within_budget"]
    # The core is most of the image but not all of it (Arduino serial code, libgcc float routines).
    assert 0.3 * sizes["flash"]["used"] < sizes["core"]["flash"] < sizes["flash"]["used"]


@needs_toolchain
def test_the_arrays_mega_image_builds_within_its_budgets(tmp_path):
    """The 2 x 2 array's environment (platformio.ini mega_array_2x2): the same sources for the ATmega2560."""
    result = run_script("--env", "mega_array_2x2", "--out", str(tmp_path), "--json")
    assert result.returncode == 0, result.stderr
    sizes = json.loads(result.stdout)
    assert sizes["board"] == "megaatmega2560"
    assert 0 < sizes["flash"]["used"] <= sizes["flash"]["budget"] and 0 < sizes["ram"]["used"] <= sizes["ram"]["budget"]
    header = subprocess.run(["avr-readelf", "-h", str(tmp_path / "firmware.elf")], capture_output=True, text=True)
    assert "avr:6" in header.stdout  # the ATmega2560's architecture (the Uno's ATmega328P is avr:5)


@needs_toolchain
def test_the_image_leaves_room_below_its_budgets(build):
    """Room for what comes next: 1,746 B of flash (the image at most 22,446 B, what it was before the arrays' last
    additions) and 100 B of static RAM below the budgets (once 210 B and 10 B)."""
    _, sizes = build
    assert sizes["flash"]["budget"] - sizes["flash"]["used"] >= 1746, sizes["flash"]
    assert sizes["ram"]["budget"] - sizes["ram"]["used"] >= 100, sizes["ram"]


@needs_toolchain
def test_rebuild_skips_up_to_date_objects(build):
    out, _ = build
    result = run_script("--out", str(out))
    assert result.returncode == 0, result.stderr
    assert re.search(r"compiled 0 of \d+ objects", result.stdout), result.stdout


@needs_toolchain
def test_over_budget_exits_3(build, monkeypatch, capsys):
    out, _ = build
    monkeypatch.setattr(avr_build.avr_size, "RAM_BUDGET", 0.01)
    assert avr_build.main(["--out", str(out)]) == 3
    assert "OVER BUDGET" in capsys.readouterr().out


@needs_arduino_core
def test_build_flags_reach_every_compile_command(tmp_path):
    ini = ini_with(tmp_path, build_flags="\n-std=gnu++14\n-DMANTARAY_PROBE_FLAG=1  ; inline comment")
    result = run_script("--ini", str(ini), "--dry-run", "--out", str(tmp_path / "out"))
    assert result.returncode == 0, result.stderr
    commands = compile_commands(result.stdout)
    assert len(commands) > 20  # Arduino core, core library, board sources
    assert all("-DMANTARAY_PROBE_FLAG=1" in c for c in commands)
    assert not any("inline comment" in c for c in commands)


@needs_arduino_core
def test_build_unflags_are_removed(tmp_path):
    ini = ini_with(tmp_path, build_unflags="-std=gnu++11 -Wall")
    result = run_script("--ini", str(ini), "--dry-run", "--out", str(tmp_path / "out"))
    assert result.returncode == 0, result.stderr
    for command in compile_commands(result.stdout):
        assert " -Wall " not in f" {command} " and "-std=gnu++11" not in command


@needs_arduino_core
def test_repository_ini_flags_are_the_ones_used():
    parser = configparser.ConfigParser(inline_comment_prefixes=("#", ";"), interpolation=None)
    parser.read(INI)
    build_flags = [  # an include directory as the compiler gets it: resolved against the project
        f"-I{(INI.parent / flag[2:]).resolve()}" if flag.startswith("-I") else flag
        for flag in avr_build.ini_values(parser["env:uno"]["build_flags"])
    ]
    assert any(flag.endswith("firmware/rigs/module") for flag in build_flags)  # the rig's generated headers
    result = run_script("--dry-run")
    assert result.returncode == 0, result.stderr
    cxx = [c for c in compile_commands(result.stdout) if c.startswith("avr-g++")]
    linker = [flag for flag in build_flags if flag.startswith("-Wl,")]  # PlatformIO gives these to the link only
    assert cxx and all(f" {flag} " in f" {c} " for c in cxx for flag in build_flags if flag not in linker)
    assert not any("-std=gnu++11" in c for c in cxx)  # build_unflags
    link = [c for c in result.stdout.splitlines() if c.startswith("avr-g++") and " -c " not in f" {c} "]
    assert len(link) == 1 and all(f" {flag} " in f" {link[0]} " for flag in linker)


def test_platformio_ini_builds_each_board_as_the_board_table_says():
    """Every AVR environment of platformio.ini names a board of protocol/boards.py's table under its prefix, and
    leaves the MCU and clock to the board's (no board_build override), so the table's clock is the one the image
    runs at and simavr and the benchmarks time by."""
    from mantaray.protocol.boards import PIO_BOARDS

    parser = configparser.ConfigParser(inline_comment_prefixes=(";",))
    parser.read(REPO / "platformio.ini")
    avr = [name for name in parser.sections() if parser.get(name, "platform", fallback="") == "atmelavr"]
    assert avr
    for section in avr:
        board = PIO_BOARDS[parser[section]["board"]]
        env = section.removeprefix("env:")
        assert env == "uno" or env.startswith(f"{board.pio_prefix}_")
        assert not {"board_build.mcu", "board_build.f_cpu"} & set(parser[section])


def test_unknown_board_and_missing_env_are_errors(tmp_path):
    result = run_script("--ini", str(ini_with(tmp_path, board="esp32dev")), "--dry-run")
    assert result.returncode == 1 and "esp32dev" in result.stderr
    result = run_script("--env", "nosuchenv", "--dry-run")
    assert result.returncode == 1 and "env:nosuchenv" in result.stderr


def test_missing_toolchain_names_the_debian_packages(monkeypatch, capsys, tmp_path):
    monkeypatch.setattr(avr_build.shutil, "which", lambda _tool: None)
    assert avr_build.main(["--out", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert "gcc-avr" in err and "binutils-avr" in err


def test_missing_arduino_core_names_the_debian_package(monkeypatch, capsys, tmp_path):
    monkeypatch.setattr(avr_build, "ARDUINO_AVR", tmp_path / "nowhere")
    assert avr_build.main(["--out", str(tmp_path)]) == 1
    assert "arduino-core-avr" in capsys.readouterr().err


def test_core_has_no_arduino_or_avr_includes():
    board_include = re.compile(r'#\s*include\s*[<"](Arduino\.h|avr/|util/|HardwareSerial|WProgram)')
    offenders = [
        f"{path.name}:{n}"
        for path in sorted(CORE.iterdir())
        if path.suffix in (".h", ".cpp")
        for n, line in enumerate(path.read_text().splitlines(), 1)
        if board_include.search(line)
    ]
    assert not offenders


def simavr_uart(elf: Path, want: int, deadline_s: float = 20.0) -> bytes:
    """The first `want` bytes the firmware writes to UART0 under simavr, as simavr shows them.

    simavr prints UART output in green chunks of up to 256 bytes on stderr, each byte below 0x20 as '.'.
    """
    proc = subprocess.Popen(
        ["simavr", "-m", UNO.mcu, "-f", str(UNO.f_cpu_hz), str(elf)], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
    )
    raw, uart = b"", b""
    try:
        deadline = time.monotonic() + deadline_s
        while len(uart) < want and time.monotonic() < deadline:
            if select.select([proc.stderr], [], [], 0.1)[0]:
                raw += os.read(proc.stderr.fileno(), 4096)
                uart = b"".join(re.findall(rb"\x1b\[32m(.*?)\n\x1b\[0m", raw, re.S))
    finally:
        proc.kill()
        proc.wait()
    return uart


def as_simavr_shows(frame: bytes) -> bytes:
    return bytes(b if b >= 0x20 else ord(".") for b in frame)


@needs_toolchain
@pytest.mark.usefixtures("simavr_tool")
def test_firmware_sends_boot_then_telemetry_in_simavr(build):
    out, _ = build
    uart = simavr_uart(out / "firmware.elf", want=64)
    # simavr powers the MCU on without a bootloader, so MCUSR reports a power-on reset.
    boot = as_simavr_shows(encode_packet(Boot.ID, 0, bytes([ResetCause.POWER_ON])))
    assert uart.startswith(boot), uart[:16]
    assert uart[len(boot) + 1] == Telemetry.ID  # next frame: COBS code byte, then the telemetry id
