"""Runs the protocol conformance suite against the virtual MCU, simulated and wall clock, as `mantaray conformance` does."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest
from conformance_result import assert_suite_passed

from mantaray.paths import REPO, NotBuilt, native_artifact


@pytest.fixture(scope="module")
def vmcu_built() -> None:
    """The suite's rule (tests/test_avr_build.py): a missing build fails, saying how to build it."""
    try:
        native_artifact("mantaray-vmcu")
    except NotBuilt as exc:
        pytest.fail(str(exc))


def conformance(*args: str, timeout: float = 180) -> subprocess.CompletedProcess:
    """`mantaray conformance ARGS -- -rs` in a fresh interpreter (the suite needs its own pytest session); -rs names
    every skip's reason."""
    return subprocess.run(
        [sys.executable, "-m", "mantaray.cli", "conformance", *args, "--", "-rs"],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=timeout,
        env=os.environ.copy(),
    )


def test_suite_passes_on_the_simulated_clock(vmcu_built):
    """No --port: the suite starts its own virtual MCU with the simulated clock."""
    assert_suite_passed(conformance(), "simulated")


def test_suite_passes_on_the_wall_clock_through_port(vmcu_built):
    """--port: the way a real board or the AVR simulator is tested, here a wall-clock virtual MCU."""
    from mantaray.host.vmcu import VirtualMcu

    with VirtualMcu(clock="wall") as vmcu:
        result = conformance("--port", vmcu.path)
    assert_suite_passed(result, "wall")


ARRAY = "protocol/rigs/array_2x2.toml"


def test_suite_passes_against_the_arrays_virtual_mcu(vmcu_built):
    """--rig: the suite starts the 2 x 2 array's build (mantaray-vmcu-array_2x2) and reads its shape from identify."""
    result = conformance("--rig", ARRAY)
    assert_suite_passed(result, "simulated")
    assert "another rig" not in result.stdout + result.stderr


def test_suite_passes_against_the_arrays_virtual_mcu_on_the_wall_clock_through_port(vmcu_built):
    from mantaray.host.vmcu import VirtualMcu

    with VirtualMcu(clock="wall", program="mantaray-vmcu-array_2x2") as vmcu:
        result = conformance("--port", vmcu.path, "--rig", ARRAY)
    assert_suite_passed(result, "wall")


def test_a_board_of_another_rig_is_named_and_a_bad_rig_file_is_one_line(vmcu_built):
    from mantaray.host.vmcu import VirtualMcu

    with VirtualMcu(clock="sim", program="mantaray-vmcu-array_2x2") as vmcu:
        result = conformance("--port", vmcu.path, timeout=60)  # the default rig: one module
    assert result.returncode != 0
    assert "modules_x is 2 on the board, 1 in rig.toml" in result.stdout + result.stderr
    result = conformance("--rig", "nowhere.toml", timeout=60)
    assert result.returncode == 2 and "Traceback" not in result.stdout + result.stderr
    assert (
        result.stderr.strip().splitlines()[-1]
        == "mantaray conformance: error: argument --rig: nowhere.toml: no such rig file"
    )


def test_a_missing_port_is_one_clear_line():
    result = conformance("--port", "/dev/nonexistent", timeout=60)
    assert result.returncode == 2
    assert "Traceback" not in result.stdout + result.stderr
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert lines[0].startswith("usage: mantaray conformance")  # argparse's usage, then the one line of the error
    assert lines[-1].startswith("mantaray conformance: error: /dev/nonexistent: no such device")
    assert sum("error" in line for line in lines) == 1


def test_help_lists_the_port_option():
    result = conformance("--help", timeout=60)
    assert result.returncode == 0
    assert "--port" in result.stdout and "Traceback" not in result.stderr
