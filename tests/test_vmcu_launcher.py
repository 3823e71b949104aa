"""The virtual MCU and its launcher: a pty path appears (never in place of the user's file), the firmware process
never outlives its host, and a stop is honoured even while nobody reads its output."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
import tty

from mantaray.paths import native_artifact
from mantaray.protocol import messages as m
from mantaray.protocol.framing import encode_frame

HOST = (
    "from mantaray.host.vmcu import VirtualMcu\n"
    "v = VirtualMcu(clock='sim')\n"
    "print(v.path, v.process.pid, flush=True)\n"
    "import time; time.sleep(60)\n"
)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    with open(f"/proc/{pid}/stat") as f:  # a zombie waiting for its reaper counts as gone
        return f.read().split()[2] != "Z"


def test_the_virtual_mcu_dies_with_a_killed_host():
    host = subprocess.Popen([sys.executable, "-c", HOST], stdout=subprocess.PIPE, text=True)
    path, pid = host.stdout.readline().split()
    assert os.path.exists(path) and _alive(int(pid))
    host.send_signal(signal.SIGKILL)  # no cleanup code runs in the host
    host.wait()
    deadline = time.monotonic() + 5
    while _alive(int(pid)) and time.monotonic() < deadline:
        time.sleep(0.02)
    assert not _alive(int(pid))


def test_mantaray_vmcu_stopped_by_sigterm_leaves_no_temporary_folder():
    proc = subprocess.Popen(
        [sys.executable, "-m", "mantaray.cli", "vmcu"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    first = proc.stdout.readline()  # "virtual MCU on /tmp/mantaray-vmcu-XXXX/tty: ..."
    folder = os.path.dirname(first.split(" on ", 1)[1].split(":", 1)[0])
    assert os.path.isdir(folder) and "mantaray-vmcu-" in folder, first
    proc.stdout.readline()  # "running; ..."
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 0 and "Traceback" not in err, err
    assert not os.path.exists(folder)


def _start(link: str, *args: str) -> subprocess.Popen:
    """mantaray-vmcu --pty LINK ARGS, once LINK leads to a live pty (or the process has exited)."""
    proc = subprocess.Popen(
        [str(native_artifact("mantaray-vmcu")), "--pty", link, *args],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 5
    while proc.poll() is None and time.monotonic() < deadline:
        if os.path.realpath(link).startswith("/dev/pts/") and os.path.exists(link):
            break
        time.sleep(0.01)
    return proc


def _stop(proc: subprocess.Popen, timeout_s: float) -> float:
    """SIGTERM, then the seconds [s, wall] it took to exit; killed (and the test failed) past timeout_s."""
    t0 = time.monotonic()
    proc.send_signal(signal.SIGTERM)
    try:
        proc.wait(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
        raise AssertionError(f"mantaray-vmcu ignored SIGTERM for {timeout_s} s") from None
    return time.monotonic() - t0


def test_pty_refuses_to_replace_a_file_or_a_link_that_is_not_to_a_pty(tmp_path):
    kept = tmp_path / "notes.txt"
    kept.write_text("mine")
    elsewhere = tmp_path / "link"
    elsewhere.symlink_to(kept)
    for path in (kept, elsewhere):
        proc = _start(str(path))
        if proc.poll() is None:  # it took the path and runs
            _stop(proc, 10)
            raise AssertionError(f"mantaray-vmcu replaced {path}")
        err = proc.stderr.read()
        assert proc.returncode == 2
        assert len(err.splitlines()) == 1 and err.startswith(f"error: --pty {path}:"), err
    assert kept.read_text() == "mine" and os.readlink(elsewhere) == str(kept)


def test_pty_replaces_the_stale_link_a_killed_run_left(tmp_path):
    link = tmp_path / "tty"
    link.symlink_to("/dev/pts/999999")  # a pty that is gone
    proc = _start(str(link))
    try:
        assert proc.poll() is None and os.path.exists(link)  # now to the live pty
    finally:
        _stop(proc, 10)
    assert not os.path.lexists(link)  # and removed on the way out


def test_sigterm_stops_a_virtual_mcu_whose_output_nobody_reads(tmp_path):
    """Identify frames go in, nobody reads the replies: once the pty's output is full the firmware waits to write,
    stops reading, and the input fills too. A SIGTERM then still ends it within seconds (10 s: a busy machine)."""
    link = str(tmp_path / "tty")
    proc = _start(link, "--clock", "sim")  # no periodic telemetry: only the replies fill the pty
    try:
        fd = os.open(link, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
        tty.setraw(fd)
        frames = encode_frame(m.Identify(), 1) * 64  # each answered by a 32-byte identify_reply
        refused_since = None
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            try:
                os.write(fd, frames)
                refused_since = None
            except BlockingIOError:
                refused_since = refused_since or time.monotonic()
                if time.monotonic() - refused_since > 1.0:  # [s] no room for a second: the firmware reads no more
                    break
                time.sleep(0.01)
        assert refused_since is not None, "the pty never filled"
        assert proc.poll() is None
        _stop(proc, 10)
        os.close(fd)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
