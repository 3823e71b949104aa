"""Runs the firmware's C++ unit tests (doctest: core_tests, board_tests in the build dir) so pytest's summary includes them."""

from __future__ import annotations

import re
import subprocess

import pytest

from mantaray.paths import NotBuilt, native_artifact

# [test cases] fewer means the binary is stale or lost test files
MIN_TEST_CASES = {
    "core_tests": 110,
    "core_tests_array_2x2": 8,
    "board_tests": 12,
    "board_tests_analog": 11,  # no silent-I2C case
}


@pytest.mark.parametrize("name", MIN_TEST_CASES)
def test_cpp_unit_tests_pass(name: str) -> None:
    try:
        binary = native_artifact(name)
    except NotBuilt as exc:
        pytest.fail(f"the C++ unit tests are not built: {exc}")
    proc = subprocess.run([str(binary), "--no-colors"], capture_output=True, text=True, timeout=300)
    output = proc.stdout + proc.stderr
    assert proc.returncode == 0, f"{binary} failed (exit {proc.returncode}):\n{output[-6000:]}"
    summary = re.search(r"test cases:\s*(\d+)\s*\|\s*(\d+) passed\s*\|\s*(\d+) failed", output)
    assert summary, f"no doctest summary in the output of {binary}:\n{output[-2000:]}"
    total, passed, failed = (int(g) for g in summary.groups())
    assert failed == 0, output[-6000:]
    assert passed >= MIN_TEST_CASES[name], f"only {passed} test cases passed; rebuild: ninja -C {binary.parent}"
