"""What a --port may name, checked in one place before any command connects: a serial device, nothing else.

A serial device is a board's tty or the pty of the virtual MCU or simavr; anything else is refused in one line before a
command waits out its connection timeout on it."""

from __future__ import annotations

import os
import stat

TTY_DRIVERS = "/proc/tty/drivers"  # Linux's table of terminal drivers: name, node, major, minors, type
SERIAL_TYPES = ("serial", "pty:slave")  # the driver types a board or a pty is: a UART or USB serial, a pty
EXAMPLES = "a board is /dev/ttyACM0 or /dev/ttyUSB0, the virtual MCU prints its /dev/pts/N"
OTHER_TERMINALS = {
    "system": "a terminal device of the system itself (as /dev/tty, /dev/console, /dev/ptmx)",
    "console": "a virtual console of this machine",
    "pty:master": "the master side of a pty (the program on the pty opens it, not the host)",
}


class PortError(ValueError):
    """A --port that names no serial device; the message says what it names instead and what to give."""


def check_port(port: str | None) -> None:
    """Raise PortError when the port is no serial device: a missing path (a relative name whose /dev/NAME exists is
    named), a folder, a file, a pipe, a character device that is no terminal (/dev/null) or a terminal that is no
    serial device (/dev/tty), or one this user may not open. None (no --port: the command starts its own virtual
    MCU) passes.

    Every command with --port checks it with this before it connects, where waiting would only be silence; a
    reconnection (session.connect) waits for the port to come back instead."""
    if port is None or os.name == "nt":  # no port; or COM3 and the like, which only opening tells
        return
    name = port if port.isprintable() and port else repr(port)  # the message stays one line
    try:
        status = os.stat(port)
    except FileNotFoundError:
        raise PortError(_missing(port, name)) from None
    except (OSError, ValueError) as exc:  # a name too long, a NUL byte, a path through a file ...
        raise PortError(f"{name}: no device path ({getattr(exc, 'strerror', None) or exc}); {EXAMPLES}") from None
    mode = status.st_mode
    if not stat.S_ISCHR(mode):
        kind = (
            "a folder"
            if stat.S_ISDIR(mode)
            else "a regular file"
            if stat.S_ISREG(mode)
            else "a named pipe"
            if stat.S_ISFIFO(mode)
            else "a socket"
            if stat.S_ISSOCK(mode)
            else "a block device (a disk)"
            if stat.S_ISBLK(mode)
            else "not a device"
        )
        raise PortError(f"{name} is {kind}, not a serial device ({EXAMPLES})")
    driver = terminal_type(status.st_rdev)
    if driver == "":
        raise PortError(f"{name} is a character device but no terminal, so no serial device ({EXAMPLES})")
    if driver is not None and driver not in SERIAL_TYPES:
        raise PortError(
            f"{name} is {OTHER_TERMINALS.get(driver, f'a terminal of type {driver}')}, not a serial device ({EXAMPLES})"
        )
    if not os.access(port, os.R_OK | os.W_OK):
        group = _group(status.st_gid)
        raise PortError(
            f"{name}: permission denied; add yourself to its group {group} (sudo usermod -aG {group} "
            f"$USER), then log in again"
        )


def _missing(port: str, name: str) -> str:
    in_dev = os.path.join("/dev", port)
    if port and not os.path.isabs(port) and os.path.exists(in_dev):
        return f"{name}: no such file in this folder; did you mean --port {in_dev}?"
    return (
        f"{name}: no such device; is the board plugged in? Serial devices here: "
        f"{', '.join(_serial_devices()) or 'none'}"
    )


def terminal_type(rdev: int) -> str | None:
    """The driver type (/proc/tty/drivers) of the character device rdev: "serial", "pty:slave", "console", "system"; ""
    when it is no terminal; None where the system keeps no such table (not Linux)."""
    try:
        with open(TTY_DRIVERS) as table:
            lines = table.read().splitlines()
    except OSError:
        return None
    major, minor = os.major(rdev), os.minor(rdev)
    for line in lines:
        fields = line.split()
        if len(fields) < 5 or not fields[-3].isdigit() or int(fields[-3]) != major:
            continue
        low, _, high = fields[-2].partition("-")
        if low.isdigit() and int(low) <= minor <= int(high if high.isdigit() else low):
            kind = fields[-1]
            return "system" if kind.startswith("system") else kind  # system, system:console, system:/dev/tty
    return ""


def _group(gid: int) -> str:
    import grp  # POSIX only, as this check is

    try:
        return grp.getgrgid(gid).gr_name
    except KeyError:
        return str(gid)


def _serial_devices() -> list[str]:
    from serial.tools import list_ports

    return sorted(p.device for p in list_ports.comports())
