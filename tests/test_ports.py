"""--port checked in one place (host/ports.py): whatever is no serial device refused at once, in one line.

By every command that takes a port; the serial devices (a pty, a link to one, a relative path to one) are let through."""

from __future__ import annotations

import os
import socket
import stat
import subprocess
import sys
import time

import pytest
from hypothesis import given, seed, settings
from hypothesis import strategies as st

from mantaray.host.ports import PortError, check_port
from mantaray.paths import REPO


@pytest.fixture
def pty_path():
    """The slave side of a fresh pty: a serial device as the virtual MCU offers one."""
    master, slave = os.openpty()
    yield os.ttyname(slave)
    os.close(slave)
    os.close(master)


def _socket(folder) -> str:
    with socket.socket(socket.AF_UNIX) as listener:  # the socket's file stays after it closes
        listener.bind(str(folder / "sock"))
    return "sock"


def _refused(port: str) -> str:
    with pytest.raises(PortError) as refused:
        check_port(port)
    text = str(refused.value)
    assert "\n" not in text
    return text


def test_a_pty_a_link_to_it_and_a_relative_path_to_it_are_serial_devices(pty_path, tmp_path, monkeypatch):
    check_port(pty_path)
    (tmp_path / "ttyLINK").symlink_to(pty_path)  # as the virtual MCU's --pty LINK and /dev/serial/by-id are
    check_port(str(tmp_path / "ttyLINK"))
    monkeypatch.chdir(tmp_path)
    check_port("ttyLINK")


@pytest.mark.parametrize(
    "make, needle",
    [
        (lambda d: "/dev/null", "is a character device but no terminal"),
        (lambda d: "/dev/zero", "is a character device but no terminal"),
        (lambda d: "/dev/tty", "a terminal device of the system itself"),
        (lambda d: "/dev/ptmx", "a terminal device of the system itself"),
        (lambda d: str(d), "is a folder, not a serial device"),
        (lambda d: (d / "notes.txt").write_text("x") and "notes.txt", "is a regular file, not a serial device"),
        (lambda d: os.mkfifo(d / "fifo") or "fifo", "is a named pipe, not a serial device"),
        (_socket, "is a socket, not a serial device"),
        (lambda d: "no-such-port", "no-such-port: no such device; is the board plugged in?"),
        (lambda d: "null", "null: no such file in this folder; did you mean --port /dev/null?"),
        (lambda d: "", "'': no such device"),
        (lambda d: "/etc/hostname/ttyACM0", "no device path (Not a directory)"),
        (lambda d: "tty\0ACM0", "'tty\\x00ACM0': no device path"),
        (lambda d: "bad\nname", "'bad\\nname': no such device"),
    ],
)
def test_every_form_that_is_no_serial_device_is_refused_in_one_line(make, needle, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert needle in _refused(make(tmp_path))


def test_a_port_this_user_may_not_open_says_which_group_to_join(pty_path):
    """As root, the check runs with nobody as its real user (the one access() asks for: root may open anything);
    as anyone else, on a pty whose permissions are taken away."""
    as_root = os.geteuid() == 0
    os.chmod(pty_path, 0o600 if as_root else 0)
    code = (
        "import sys\nfrom mantaray.host.ports import PortError, check_port\n"
        "try:\n    check_port(sys.argv[1])\nexcept PortError as exc:\n    print(exc)\n"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code, pty_path],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=REPO,
        preexec_fn=(lambda: os.setreuid(65534, 0)) if as_root else None,
    )
    assert proc.returncode == 0, proc.stderr
    assert f"{pty_path}: permission denied; add yourself to its group" in proc.stdout, proc.stdout


PATHS = st.one_of(
    st.text(max_size=40),
    st.builds(
        lambda head, tail: head + tail,
        st.sampled_from(["/dev/", "/dev/pts/", "/tmp/", "./", "../", "/proc/self/fd/", ""]),
        st.text(st.characters(blacklist_categories=["Cs"]), max_size=12),
    ),
)


@seed(20261204)
@settings(max_examples=300, deadline=None)
@given(PATHS)
def test_any_text_is_either_a_serial_device_or_one_line_saying_why_not(text):
    """Whatever a user types: PortError in one line, or a character device whose driver is a serial one."""
    try:
        check_port(text)
    except PortError as exc:
        assert str(exc) and "\n" not in str(exc)
        return
    from mantaray.host.ports import SERIAL_TYPES, terminal_type

    status = os.stat(text)
    assert stat.S_ISCHR(status.st_mode) and terminal_type(status.st_rdev) in SERIAL_TYPES


COMMANDS = {
    "rig": ("--target", "0,0"),
    "monitor": (),
    "stop": (),
    "estop": (),
    "jog": ("--actuator", "0", "--position", "0.01"),
    "zero": (),
    "conformance": (),
    "sim run": (),
}


@pytest.fixture(scope="module")
def video(tmp_path_factory) -> str:
    """A camera for the rig that opens (the rig checks its camera before its port): a few grey frames."""
    import cv2
    import numpy as np

    path = tmp_path_factory.mktemp("video") / "grey.avi"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 12.0, (64, 48))
    for _ in range(3):
        writer.write(np.full((48, 64, 3), 128, np.uint8))
    writer.release()
    return str(path)


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_every_command_with_a_port_refuses_dev_null_at_once(command, video, tmp_path):
    """/dev/null opens, takes every byte and answers none: each command waited 30 s on it, then printed pyserial's
    text."""
    extra = COMMANDS[command] + (("--camera", video) if command == "rig" else ())
    t0 = time.monotonic()
    proc = subprocess.run(
        [sys.executable, "-m", "mantaray.cli", *command.split(), "--port", "/dev/null", *extra],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
    assert (
        proc.stderr.strip()
        .splitlines()[-1]
        .endswith(
            "error: /dev/null is a character device but no terminal, so no serial device (a board is /dev/ttyACM0 or "
            "/dev/ttyUSB0, the virtual MCU prints its /dev/pts/N)"
        )
    )
    assert time.monotonic() - t0 < 20 and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "port, needle",
    [
        ("ttyACM0", "ttyACM0: no such"),  # relative: was opened as ./ttyACM0, 30 s
        ("notes.txt", "notes.txt is a regular file"),  # relative: the check skipped it, 30 s
        ("null", "did you mean --port /dev/null?"),
    ],
)
def test_a_relative_port_is_checked_as_any_other(port, needle, tmp_path):
    (tmp_path / "notes.txt").write_text("not a board")
    t0 = time.monotonic()
    proc = subprocess.run(
        [sys.executable, "-m", "mantaray.cli", "monitor", "--port", port],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 2 and needle in proc.stderr and "Traceback" not in proc.stderr, proc.stderr
    assert time.monotonic() - t0 < 20
