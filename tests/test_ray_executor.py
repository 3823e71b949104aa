"""--executor ray as asked or refused in one line before any work: Ray Client for a ray:// address, a cluster that
does not answer, and a local Ray instance that listens on this machine's loopback only."""

from __future__ import annotations

import importlib.util
import json
import os
import socket
import subprocess
import sys
import time

import pytest

from mantaray.sim.evaluation import executors as X

RAY = importlib.util.find_spec("ray") is not None
needs_ray = pytest.mark.skipif(not RAY, reason="Ray is not installed (pip install 'mantaray[ray]')")
LOOPBACK = {"127.0.0.1", "::1", "::ffff:127.0.0.1"}


def _heatmap(tmp_path, *args: str, timeout_s: float = 120) -> subprocess.CompletedProcess:
    return subprocess.run(
        [
            sys.executable,
            "-m",
            "mantaray.cli",
            "sim",
            "heatmap",
            "--cells",
            "1",
            "--trials",
            "1",
            "--duration",
            "0.2",
            "--jobs",
            "1",
            "--out",
            str(tmp_path / "run"),
            *args,
        ],
        capture_output=True,
        text=True,
        timeout=timeout_s,
    )


def _free_port() -> int:
    """A port nothing listens on (one the kernel just handed out and took back)."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def ray_installed(monkeypatch):
    """check_ray as on a machine with Ray, whether or not this one has it, and without Ray Client (grpc)."""
    find = importlib.util.find_spec
    monkeypatch.setattr(
        X.importlib.util,
        "find_spec",
        lambda name, *a: object() if name == "ray" else None if name == "grpc" else find(name, *a),
    )


def test_a_ray_client_address_without_ray_client_says_what_to_install(ray_installed):
    with pytest.raises(X.RayUnavailable, match='Ray Client, which is not installed: pip install "ray\\[client\\]"'):
        X.check_ray("ray://head:10001")


def test_an_address_that_refuses_says_so_at_once(ray_installed):
    started = time.monotonic()
    with pytest.raises(X.RayUnavailable, match="Connection refused"):
        X.check_ray(f"127.0.0.1:{_free_port()}")
    assert time.monotonic() - started < 2


@pytest.mark.parametrize("address", ["http://head:8265", "ray://", "head:port"])
def test_an_address_that_is_not_one_is_refused(ray_installed, address):
    with pytest.raises(X.RayUnavailable, match="--ray-address"):
        X.check_ray(address)


@needs_ray
@pytest.mark.skipif(importlib.util.find_spec("grpc") is not None, reason="Ray Client is installed here")
def test_the_helps_own_example_address_without_ray_client_is_one_line_and_exit_2_before_any_work(tmp_path):
    run = _heatmap(tmp_path, "--executor", "ray", "--ray-address", "ray://head:10001")
    assert run.returncode == 2 and not (tmp_path / "run").exists()
    assert run.stderr.splitlines() == [
        "mantaray sim heatmap: --ray-address ray://head:10001 goes through Ray Client, "
        'which is not installed: pip install "ray[client]"'
    ]


@needs_ray
def test_an_unreachable_cluster_is_one_line_and_exit_2_before_any_work(tmp_path):
    run = _heatmap(tmp_path, "--executor", "ray", "--ray-address", f"127.0.0.1:{_free_port()}")
    assert run.returncode == 2 and not (tmp_path / "run").exists()
    (line,) = run.stderr.splitlines()
    assert "Connection refused" in line and "is the cluster up" in line


@needs_ray
def test_an_address_that_answers_but_not_as_ray_gives_up_within_a_minute_in_exit_2(tmp_path):
    """Ray's own connection would retry such an address (20 tries of 30 s) for more than ten minutes."""
    with socket.create_server(("0.0.0.0", 0)) as silent:  # accepts connections and never says a word
        started = time.monotonic()
        run = _heatmap(tmp_path, "--executor", "ray", "--ray-address", f"127.0.0.1:{silent.getsockname()[1]}")
    assert run.returncode == 2 and time.monotonic() - started < 60
    assert run.stderr.splitlines()[-1].endswith("is a Ray cluster's head there?") and "Traceback" not in run.stderr


_LISTENING = """
import json, os
from mantaray.sim.evaluation.executors import RayPool
pool = RayPool(1, None)
assert pool.map_calls(lambda runner, x: 2 * x, [21]) == [42]          # a worker started and answered
import psutil                                                          # Ray's own copy
ours = {os.getpid()} | {p.pid for p in psutil.Process().children(recursive=True)}
print(json.dumps(sorted({(c.laddr.ip, psutil.Process(c.pid).name()) for c in psutil.net_connections("tcp")
                         if c.status == psutil.CONN_LISTEN and c.pid in ours})))
"""


@needs_ray
def test_a_local_ray_instance_listens_on_the_loopback_only():
    run = subprocess.run(
        [sys.executable, "-c", _LISTENING],
        capture_output=True,
        text=True,
        timeout=300,
        env={k: v for k, v in os.environ.items() if not k.startswith("RAY_")},
    )
    assert run.returncode == 0, run.stderr
    listening = json.loads(run.stdout.splitlines()[-1])
    assert {name for _, name in listening} >= {"gcs_server", "raylet"}
    assert [(ip, name) for ip, name in listening if ip not in LOOPBACK] == []
