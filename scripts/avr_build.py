#!/usr/bin/env python3
"""Offline AVR build of the firmware (Uno, Mega 2560) with Debian's toolchain, flags from platformio.ini; reports sizes.

PlatformIO cannot fetch its own toolchain here, so this script does what `pio run -e uno` does with the Debian
packages gcc-avr, binutils-avr, avr-libc and arduino-core-avr: the Arduino core and variant, each library in
lib_dir and src_dir are compiled with PlatformIO's atmelavr/arduino flags (platform-atmelavr
builder/frameworks/arduino.py) plus build_flags minus build_unflags from the ini, then linked the same way
(LTO, --gc-sections). Two differences, neither of which changes the code: the Debian Arduino core needs
DECIMAL_DIG defined (avr-libc's float.h lacks it), and -gdwarf-4 is added so that the DWARF line table can
attribute code to source files, which is how the core's share of the flash is measured after LTO has
inlined it into the board's functions (avr_size.py measures the image and judges it against the budgets).

Exit status: 0 built and within budget, 1 build or configuration error, 3 over budget (2 is a usage error).
"""

from __future__ import annotations

import argparse
import configparser
import json
import re
import shlex
import shutil
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))  # its sibling avr_size.py, also when loaded by a test
import avr_size  # noqa: E402

from mantaray.host.avr_image import build_dir  # noqa: E402
from mantaray.protocol.boards import PIO_BOARDS, Board  # noqa: E402

REPO = Path(__file__).resolve().parent.parent
ARDUINO_AVR = Path("/usr/share/arduino/hardware/arduino/avr")  # Debian package arduino-core-avr
AVR_LIBC_HEADER = Path("/usr/lib/avr/include/avr/io.h")  # Debian package avr-libc
TOOLS = {  # command -> Debian package
    "avr-gcc": "gcc-avr",
    "avr-g++": "gcc-avr",
    "avr-gcc-ar": "gcc-avr",
    "avr-objcopy": "binutils-avr",
    "avr-objdump": "binutils-avr",
    "avr-nm": "binutils-avr",
    "avr-size": "binutils-avr",
    "avr-c++filt": "binutils-avr",
}

ARDUINO_VERSION = 10808  # the ARDUINO macro PlatformIO's atmelavr platform defines
SOURCE_EXTS = (".c", ".cpp", ".S")
# Options whose effect this script does not reproduce: refuse them rather than measure a different build.
UNSUPPORTED_OPTIONS = (
    "extends",
    "build_src_filter",
    "build_src_flags",
    "lib_deps",
    "board_build.mcu",
    "board_build.f_cpu",
)
MEASURE_FLAGS = ["-gdwarf-4"]  # debug info only (no code change): lets the line table attribute code to files


class BuildError(Exception):
    """A configuration, toolchain or compiler failure: reported in one message, exit status 1."""


@dataclass
class Flags:
    """Options by scope, as PlatformIO's SCons environment holds them."""

    ccflags: list[str] = field(default_factory=list)  # C and C++
    cflags: list[str] = field(default_factory=list)  # C only
    cxxflags: list[str] = field(default_factory=list)  # C++ only
    asppflags: list[str] = field(default_factory=list)  # .S files (they get no CCFLAGS)
    linkflags: list[str] = field(default_factory=list)
    defines: list[str] = field(default_factory=list)  # NAME or NAME=VALUE
    includes: list[Path] = field(default_factory=list)
    libs: list[str] = field(default_factory=list)

    def extend(self, other: Flags) -> None:
        for name in self.__dataclass_fields__:
            getattr(self, name).extend(getattr(other, name))

    def remove(self, unflags: Flags) -> None:
        """build_unflags: drop equal items from every scope; -DNAME also drops NAME=VALUE (as PlatformIO does)."""
        for name in self.__dataclass_fields__:
            if name != "defines":
                setattr(self, name, [f for f in getattr(self, name) if f not in getattr(unflags, name)])
        self.defines = [
            d for d in self.defines if d not in unflags.defines and d.split("=", 1)[0] not in unflags.defines
        ]


def parse_flags(items: list[str], project_dir: Path) -> Flags:
    """The subset of SCons ParseFlags that PlatformIO applies to build_flags / build_unflags."""
    flags = Flags()
    tokens = [t for item in items for t in shlex.split(item)]
    pending = None  # "-D" or "-I" waiting for its argument
    for token in tokens:
        if pending:
            token, pending = pending + token, None
        if token in ("-D", "-I"):
            pending = token
        elif token.startswith("-D"):
            flags.defines.append(token[2:])
        elif token.startswith("-I"):
            flags.includes.append((project_dir / token[2:]).resolve())
        elif token.startswith("-l"):
            flags.libs.append(token[2:])
        elif token.startswith("-Wl,"):
            flags.linkflags.append(token)
        elif token.startswith("-std="):
            (flags.cxxflags if "++" in token else flags.cflags).append(token)
        elif token.startswith("-"):
            flags.ccflags.append(token)
        else:
            raise BuildError(f"build flag {token!r}: this offline build only takes options starting with '-'")
    if pending:
        raise BuildError(f"build flag {pending} lacks its argument")
    return flags


def framework_flags(board: Board) -> Flags:
    """PlatformIO's flags for framework = arduino on atmelavr (platform-atmelavr builder/frameworks/arduino.py)."""
    machine = [f"-mmcu={board.mcu}"]
    return Flags(
        ccflags=machine + ["-Os", "-Wall", "-ffunction-sections", "-fdata-sections", "-flto"],
        cflags=["-std=gnu11", "-fno-fat-lto-objects"],
        cxxflags=["-fno-exceptions", "-fno-threadsafe-statics", "-fpermissive", "-std=gnu++11"],
        asppflags=machine + ["-x", "assembler-with-cpp"],
        linkflags=machine + ["-Os", "-Wl,--gc-sections", "-flto", "-fuse-linker-plugin"],
        defines=[f"F_CPU={board.f_cpu_hz}L", "ARDUINO_ARCH_AVR", f"ARDUINO={ARDUINO_VERSION}"],
        includes=[ARDUINO_AVR / "cores" / "arduino", ARDUINO_AVR / "variants" / board.variant],
        libs=["m"],
    )


def ini_values(raw: str) -> list[str]:
    """A multi-value option the way PlatformIO splits it: by line, else by ', '; comments dropped."""
    items = raw.split("\n") if "\n" in raw else raw.split(", ")
    values = [re.sub(r"\s+;.*$", "", item).strip() for item in items]
    return [v for v in values if v and not v.startswith((";", "#"))]


@dataclass
class Project:
    """What the build takes from platformio.ini."""

    board_name: str
    board: Board
    src_dir: Path
    lib_dir: Path
    flags: Flags  # board, build_flags, framework, then build_unflags applied: PlatformIO's order


def read_project(ini: Path, env: str) -> Project:
    parser = configparser.ConfigParser(inline_comment_prefixes=("#", ";"), interpolation=None)
    if not parser.read(ini):
        raise BuildError(f"cannot read {ini}")
    section = f"env:{env}"
    if not parser.has_section(section):
        raise BuildError(f"{ini} has no [{section}]")

    def option(name: str, default: str = "") -> str:
        for sec in (section, "env"):  # [env] holds defaults for every [env:NAME]
            if parser.has_option(sec, name):
                value = parser.get(sec, name)
                if "${" in value:
                    raise BuildError(f"{ini} [{sec}] {name}: ${{...}} interpolation is not supported here")
                return value
        return default

    for name in UNSUPPORTED_OPTIONS:
        if option(name):
            raise BuildError(f"{ini} [{section}] sets {name}, which this offline build does not reproduce")
    if option("platform") != "atmelavr" or option("framework") != "arduino":
        raise BuildError(f"[{section}] must be platform = atmelavr, framework = arduino")
    board_name = option("board")
    if board_name not in PIO_BOARDS:
        raise BuildError(f"board {board_name!r} is not in protocol/boards.py's table ({', '.join(PIO_BOARDS)})")
    board = PIO_BOARDS[board_name]

    project_dir = ini.resolve().parent

    def directory(name: str, default: str) -> Path:
        value = parser.get("platformio", name, fallback=default)
        return (project_dir / value).resolve()

    flags = parse_flags([f"-D{board.arduino_define}"], project_dir)
    flags.extend(parse_flags(ini_values(option("build_flags")), project_dir))
    flags.extend(framework_flags(board))
    flags.remove(parse_flags(ini_values(option("build_unflags")), project_dir))
    return Project(board_name, board, directory("src_dir", "src"), directory("lib_dir", "lib"), flags)


@dataclass
class Unit:
    """One source file and the object it compiles to."""

    source: Path
    obj: Path
    project: bool  # our code (warnings shown) rather than the Arduino core (warnings only with --verbose)
    command: list[str] = field(default_factory=list)


def sources(root: Path) -> list[Path]:
    return sorted(p for p in root.rglob("*") if p.suffix in SOURCE_EXTS and p.is_file())


def compile_command(unit: Unit, flags: Flags, extra_defines: list[str], extra_includes: list[Path]) -> list[str]:
    defines = [f"-D{d}" for d in flags.defines + extra_defines]
    includes = [f"-I{p}" for p in flags.includes + extra_includes]
    deps = ["-MMD", "-MF", f"{unit.obj}.d"]
    if unit.source.suffix == ".S":
        return ["avr-gcc", *flags.asppflags, *defines, *includes, *deps, "-c", "-o", str(unit.obj), str(unit.source)]
    if unit.source.suffix == ".c":
        head = ["avr-gcc", "-o", str(unit.obj), "-c", *flags.cflags]
    else:
        head = ["avr-g++", "-o", str(unit.obj), "-c", *flags.cxxflags]
    return [*head, *flags.ccflags, *MEASURE_FLAGS, *defines, *includes, *deps, str(unit.source)]


@dataclass
class Plan:
    """Every command of the build."""

    framework: list[Unit]
    libs: dict[str, list[Unit]]  # library name -> units
    src: list[Unit]
    archives: dict[Path, list[Path]]  # archive -> its objects
    link: list[str]
    ihex: list[str]
    elf: Path

    @property
    def units(self) -> list[Unit]:
        return self.framework + [u for units in self.libs.values() for u in units] + self.src

    def commands(self) -> list[list[str]]:
        archiving = [archive_command(archive, objects) for archive, objects in self.archives.items()]
        return [u.command for u in self.units] + archiving + [self.link, self.ihex]


INCLUDE = re.compile(r'^\s*#\s*include\s*[<"]([^>"]+)[>"]', re.MULTILINE)


def framework_libraries(roots: list[Path]) -> list[Path]:
    """The Arduino core's bundled libraries (Wire, SPI, ...) whose headers our sources include: PlatformIO's
    library dependency finder (lib_ldf_mode = chain) picks these up the same way."""
    wanted = {
        name
        for root in roots
        for source in sources(root)
        if source.suffix != ".S"
        for name in INCLUDE.findall(source.read_text(errors="replace"))
    }
    wanted |= {
        name
        for root in roots
        for header in root.rglob("*.h")
        for name in INCLUDE.findall(header.read_text(errors="replace"))
    }
    libraries = ARDUINO_AVR / "libraries"
    return sorted(
        lib
        for lib in libraries.iterdir()
        if (lib / "src").is_dir() and any((lib / "src" / name).is_file() for name in wanted)
    )


def plan_build(project: Project, out: Path) -> Plan:
    flags = project.flags
    # Debian's core needs DECIMAL_DIG, which avr-libc's float.h does not define (gcc's value for AVR floats).
    core_defines = ["DECIMAL_DIG=__DECIMAL_DIG__"]
    variant_dir = ARDUINO_AVR / "variants" / project.board.variant
    framework = [
        Unit(s, out / "framework" / f"{s.name}.o", False)
        for root in (ARDUINO_AVR / "cores" / "arduino", variant_dir)
        for s in sources(root)
    ]
    for unit in framework:
        unit.command = compile_command(unit, flags, core_defines, [])

    lib_roots = sorted(p for p in project.lib_dir.iterdir() if p.is_dir()) if project.lib_dir.is_dir() else []
    lib_includes = [(root / "src" if (root / "src").is_dir() else root) for root in lib_roots]
    libs: dict[str, list[Unit]] = {}
    for library in framework_libraries([project.src_dir, *lib_includes]):
        include = library / "src"
        units = [
            Unit(s, out / "framework_lib" / library.name / f"{s.relative_to(include)}.o", False)
            for s in sources(include)
        ]
        for unit in units:
            unit.command = compile_command(unit, flags, core_defines, [include, include / "utility"])
        libs[library.name] = units
        lib_includes.append(include)
    for root, include in zip(lib_roots, lib_includes, strict=False):  # the first: the framework libraries follow
        units = [Unit(s, out / "lib" / root.name / f"{s.relative_to(include)}.o", True) for s in sources(include)]
        for unit in units:
            unit.command = compile_command(unit, flags, [], lib_includes)
        libs[root.name] = units

    src = [Unit(s, out / "src" / f"{s.relative_to(project.src_dir)}.o", True) for s in sources(project.src_dir)]
    if not src:
        raise BuildError(f"no sources in src_dir {project.src_dir}")
    for unit in src:
        unit.command = compile_command(unit, flags, [], lib_includes)

    archives = {out / f"lib{name}.a": [u.obj for u in units] for name, units in libs.items() if units}
    archives[out / "libFrameworkArduino.a"] = [u.obj for u in framework]
    elf = out / "firmware.elf"
    link = [
        "avr-g++",
        "-o",
        str(elf),
        *flags.linkflags,
        *MEASURE_FLAGS,
        *[str(u.obj) for u in src],
        "-Wl,--start-group",
        *[str(a) for a in archives],
        *[f"-l{lib}" for lib in flags.libs],
        "-Wl,--end-group",
    ]
    ihex = ["avr-objcopy", "-O", "ihex", "-R", ".eeprom", str(elf), str(out / "firmware.hex")]
    return Plan(framework, libs, src, archives, link, ihex, elf)


def archive_command(archive: Path, objects: list[Path]) -> list[str]:
    return ["avr-gcc-ar", "rcs", str(archive), *[str(o) for o in objects]]


def up_to_date(target: Path, inputs: list[Path], command: list[str]) -> bool:
    """target exists, was made by this very command, and is newer than every input."""
    stamp = Path(f"{target}.cmd")
    try:
        if stamp.read_text() != shlex.join(command):
            return False
        built = target.stat().st_mtime_ns
        return all(p.stat().st_mtime_ns <= built for p in inputs)
    except FileNotFoundError:
        return False


def dependencies(unit: Unit) -> list[Path]:
    """The source and the headers it read, from the compiler's -MMD file (a missing file if never compiled)."""
    try:
        text = Path(f"{unit.obj}.d").read_text()
    except FileNotFoundError:
        return [Path(f"{unit.obj}.d")]
    return [Path(t) for t in text.split(":", 1)[1].replace("\\\n", " ").split()]


def run(command: list[str], target: Path, verbose: bool) -> subprocess.CompletedProcess:
    """Runs a build step; on success records its command line next to the target for up_to_date()."""
    if verbose:
        print(shlex.join(command), file=sys.stderr)
    target.parent.mkdir(parents=True, exist_ok=True)
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode == 0:
        Path(f"{target}.cmd").write_text(shlex.join(command))
    return result


def compile_units(units: list[Unit], jobs: int, verbose: bool) -> int:
    """Compiles the stale units in parallel; returns how many were compiled."""
    stale = [u for u in units if not up_to_date(u.obj, dependencies(u), u.command)]
    with ThreadPoolExecutor(max_workers=jobs) as pool:
        results = list(pool.map(lambda u: run(u.command, u.obj, verbose), stale))
    failed = []
    for unit, result in zip(stale, results, strict=True):
        if result.stderr and (unit.project or verbose or result.returncode):
            sys.stderr.write(result.stderr)
        if result.returncode:
            failed.append(unit.source)
    if failed:
        raise BuildError("compilation failed: " + ", ".join(str(s) for s in failed))
    return len(stale)


def execute(plan: Plan, jobs: int, verbose: bool) -> tuple[int, int]:
    """Builds what is out of date; returns (objects compiled, objects in the build)."""
    compiled = compile_units(plan.units, jobs, verbose)
    for archive, objects in plan.archives.items():
        command = archive_command(archive, objects)
        if not up_to_date(archive, objects, command):
            archive.unlink(missing_ok=True)  # rcs would keep members of objects that no longer exist
            step(command, archive, verbose)
    if not up_to_date(plan.elf, [u.obj for u in plan.src] + list(plan.archives), plan.link):
        step(plan.link, plan.elf, verbose)
    hex_file = Path(plan.ihex[-1])
    if not up_to_date(hex_file, [plan.elf], plan.ihex):
        step(plan.ihex, hex_file, verbose)
    return compiled, len(plan.units)


def step(command: list[str], target: Path, verbose: bool) -> None:
    result = run(command, target, verbose)
    sys.stderr.write(result.stderr)
    if result.returncode:
        raise BuildError(f"{command[0]} failed making {target}")


def missing_packages(compiling: bool) -> list[str]:
    """Debian packages the build lacks: the Arduino core (its file list) always, the toolchain to compile."""
    missing = set()
    if not (ARDUINO_AVR / "cores" / "arduino" / "Arduino.h").is_file():
        missing.add("arduino-core-avr")
    if compiling:
        missing |= {package for tool, package in TOOLS.items() if shutil.which(tool) is None}
        if not AVR_LIBC_HEADER.is_file():
            missing.add("avr-libc")
    return sorted(missing)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.splitlines()[0],
        epilog="Exit status: 0 within budget, 1 build or configuration error, 3 over budget.",
    )
    parser.add_argument("--ini", type=Path, default=REPO / "platformio.ini", help="project file (default: %(default)s)")
    parser.add_argument("--env", default="uno", help="PlatformIO environment to build (default: %(default)s)")
    parser.add_argument(
        "--out", type=Path, help="build directory (default: build/avr for uno, build/avr-ENV for another)"
    )
    parser.add_argument("--jobs", "-j", type=int, default=2, help="parallel compilations (default: %(default)s)")
    parser.add_argument("--json", action="store_true", help="print the sizes as JSON instead of text")
    parser.add_argument("--dry-run", action="store_true", help="print every build command, run none")
    parser.add_argument("--verbose", "-v", action="store_true", help="print commands as they run, and all warnings")
    args = parser.parse_args(argv)
    try:
        project = read_project(args.ini, args.env)
        missing = missing_packages(compiling=not args.dry_run)
        if missing:
            raise BuildError(f"the AVR toolchain is incomplete: apt-get install {' '.join(missing)}")
        out = args.out or build_dir(args.env)
        plan = plan_build(project, out.resolve())
        if args.dry_run:
            print("\n".join(shlex.join(command) for command in plan.commands()))
            return 0
        started = time.monotonic()
        compiled, total = execute(plan, max(args.jobs, 1), args.verbose)
        sizes = avr_size.measure(plan.elf, project.lib_dir, project.board_name, project.board)
        sizes["build_s"] = round(time.monotonic() - started, 2)
    except BuildError as exc:
        print(f"avr_build: {exc}", file=sys.stderr)
        return 1
    print(json.dumps(sizes, indent=2) if args.json else avr_size.report(sizes, compiled, total, sizes["build_s"]))
    over = [
        f"{label} {sizes[key]['used']} B > {sizes[key]['budget']} B"
        for key, label in (("flash", "flash"), ("ram", "RAM"))
        if sizes[key]["used"] > sizes[key]["budget"]
    ]
    if over:
        print(f"avr_build: over budget: {', '.join(over)}", file=sys.stderr)
        return 3
    return 0


if __name__ == "__main__":
    sys.exit(main())
