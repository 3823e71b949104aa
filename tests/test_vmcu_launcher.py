"""The virtual MCU launcher: a pty path appears, and the firmware process never outlives its host."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

HOST = ("from mantaray.host.vmcu import VirtualMcu\n"
        "v = VirtualMcu(clock='sim')\n"
        "print(v.path, v.process.pid, flush=True)\n"
        "import time; time.sleep(60)\n")


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    with open(f"/proc/{pid}/stat") as f:          # a zombie waiting for its reaper counts as gone
        return f.read().split()[2] != "Z"


def test_the_virtual_mcu_dies_with_a_killed_host():
    host = subprocess.Popen([sys.executable, "-c", HOST], stdout=subprocess.PIPE, text=True)
    path, pid = host.stdout.readline().split()
    assert os.path.exists(path) and _alive(int(pid))
    host.send_signal(signal.SIGKILL)                # no cleanup code runs in the host
    host.wait()
    deadline = time.monotonic() + 5
    while _alive(int(pid)) and time.monotonic() < deadline:
        time.sleep(0.02)
    assert not _alive(int(pid))


def test_mantaray_vmcu_stopped_by_sigterm_leaves_no_temporary_folder():
    proc = subprocess.Popen([sys.executable, "-m", "mantaray.cli", "vmcu"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    first = proc.stdout.readline()                  # "virtual MCU on /tmp/mantaray-vmcu-XXXX/tty: ..."
    folder = os.path.dirname(first.split(" on ", 1)[1].split(":", 1)[0])
    assert os.path.isdir(folder) and "mantaray-vmcu-" in folder, first
    proc.stdout.readline()                          # "running; ..."
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 0 and "Traceback" not in err, err
    assert not os.path.exists(folder)
