"""The Uno image's flash and static RAM, the portable core's share of them, and the budgets they are judged by."""

from __future__ import annotations

import bisect
import re
import subprocess
from pathlib import Path

FLASH_BUDGET = 0.75  # fraction of the flash the bootloader leaves
RAM_BUDGET = 0.60  # fraction of the RAM for static data; the stack needs the rest
CLONE_SUFFIX = re.compile(r"(\.(lto_priv|constprop|isra|part|cold)\.\d+)+$")
CORE_NAMESPACE = "mr::"  # the portable core's data symbols ...
BOARD_NAMESPACE = "mr::board::"  # ... except the board layer's (its HAL, pins and actuator bank)


def tool_output(command: list[str]) -> str:
    return subprocess.run(command, capture_output=True, text=True, check=True).stdout


def section_sizes(elf: Path) -> dict[str, int]:
    """[bytes] by section, from avr-size -A."""
    sizes = {}
    for line in tool_output(["avr-size", "-A", "-d", str(elf)]).splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[0].startswith(".") and parts[1].isdigit():
            sizes[parts[0]] = int(parts[1])
    return sizes


def symbols(elf: Path) -> list[tuple[int, int, str, str]]:
    """(address, size [bytes], nm type letter, demangled name) of every sized symbol."""
    listing = tool_output(["avr-nm", "-S", "--defined-only", str(elf)])
    rows = [parts for parts in (line.split(maxsplit=3) for line in listing.splitlines()) if len(parts) == 4]
    # GCC's clone suffixes (.lto_priv.N, .constprop.N, ...) stop the demangler: strip them first.
    names = "\n".join(CLONE_SUFFIX.sub("", parts[3]) for parts in rows)
    demangled = subprocess.run(["avr-c++filt"], input=names, capture_output=True, text=True, check=True).stdout
    return [
        (int(parts[0], 16), int(parts[1], 16), parts[2], name)
        for parts, name in zip(rows, demangled.splitlines(), strict=True)
    ]


def code_by_file(elf: Path, functions: list[tuple[int, int]]) -> dict[Path, int]:
    """[bytes] of function code by source file, from the DWARF line table.

    A row covers the bytes up to the next row, clipped to the function it starts in; code without line
    information (avr-libc and libgcc assembly) is left out.
    """
    rows: dict[int, Path] = {}  # address -> file of the line starting there (a later row at one address wins)
    current = None
    for line in tool_output(["avr-objdump", "--dwarf=decodedline", str(elf)]).splitlines():
        if line.endswith(":") and not line[:1].isspace():  # "CU: /path/file.cpp:" or "/path/file.h:"
            current = Path(line.removeprefix("CU: ")[:-1])
            continue
        parts = line.split()
        if current and len(parts) >= 3 and parts[2].startswith("0x"):
            rows[int(parts[2], 16)] = current
    addresses = sorted(rows)
    ranges: list[list[int]] = []  # functions merged into disjoint [start, end) (aliases share their code)
    for start, size in sorted(functions):
        if ranges and start < ranges[-1][1]:
            ranges[-1][1] = max(ranges[-1][1], start + size)
        else:
            ranges.append([start, start + size])
    by_file: dict[Path, int] = {}
    for start, end in ranges:
        for i in range(bisect.bisect_left(addresses, start), len(addresses)):
            if addresses[i] >= end:
                break
            next_row = addresses[i + 1] if i + 1 < len(addresses) else end
            by_file[rows[addresses[i]]] = by_file.get(rows[addresses[i]], 0) + min(next_row, end) - addresses[i]
    return by_file


def measure(elf: Path, lib_dir: Path, board_name: str, board) -> dict:
    """Flash and static RAM of the image and the core's share of them (the code from lib_dir), as PlatformIO counts
    them; board: its mcu, flash and ram [bytes]."""
    sections = section_sizes(elf)
    flash = sum(sections.get(s, 0) for s in (".text", ".data", ".bootloader"))
    ram = sum(sections.get(s, 0) for s in (".data", ".bss", ".noinit"))
    syms = symbols(elf)
    functions = [(addr, size) for addr, size, kind, _ in syms if kind in "tTwW" and size]
    core_code = sum(n for path, n in code_by_file(elf, functions).items() if path.is_relative_to(lib_dir))
    data = [(size, kind, name) for _, size, kind, name in syms if kind in "dDbB"]
    core_data = [
        (size, kind)
        for size, kind, name in data
        if name.startswith(CORE_NAMESPACE) and not name.startswith(BOARD_NAMESPACE)
    ]
    core_ram = sum(size for size, _ in core_data)
    core_initialised = sum(size for size, kind in core_data if kind in "dD")  # initial values stored in flash
    flash_budget = int(board.flash_bytes * FLASH_BUDGET)
    ram_budget = int(board.ram_bytes * RAM_BUDGET)
    largest = sorted(data, reverse=True)[:5]
    return {
        "elf": str(elf),
        "board": board_name,
        "mcu": board.mcu,
        "flash": {
            "used": flash,
            "max": board.flash_bytes,
            "percent": round(100 * flash / board.flash_bytes, 1),
            "budget": flash_budget,
        },
        "ram": {
            "used": ram,
            "max": board.ram_bytes,
            "percent": round(100 * ram / board.ram_bytes, 1),
            "budget": ram_budget,
        },
        "core": {"flash": core_code + core_initialised, "code": core_code, "ram": core_ram},
        "largest_ram": [{"name": name, "size": size} for size, _, name in largest],
        "within_budget": flash <= flash_budget and ram <= ram_budget,
    }


def report(sizes: dict, compiled: int, total: int, seconds: float) -> str:
    flash, ram, core = sizes["flash"], sizes["ram"], sizes["core"]

    def line(label: str, part: dict, pct_of_budget: float) -> str:
        verdict = "ok" if part["used"] <= part["budget"] else "OVER BUDGET"
        return (
            f"{label:<6}{part['used']:>6} B  {part['percent']:5.1f} % of {part['max']:>5} B"
            f"   budget {pct_of_budget:.0%} = {part['budget']} B: {verdict}"
        )

    largest = ", ".join(f"{item['name']} {item['size']} B" for item in sizes["largest_ram"])
    return "\n".join(
        [
            f"{sizes['elf']} ({sizes['board']}, {sizes['mcu']})",
            line("flash", flash, FLASH_BUDGET) + "   (.text + .data)",
            line("RAM", ram, RAM_BUDGET) + "   (.data + .bss; the stack takes from the rest)",
            f"core  {core['flash']:>6} B flash ({core['code']} B code from lib_dir, as linked and inlined, "
            f"+ initial values), {core['ram']} B static RAM ({CORE_NAMESPACE} data outside {BOARD_NAMESPACE})",
            f"largest RAM: {largest}",
            f"compiled {compiled} of {total} objects in {seconds:.1f} s",
        ]
    )
