"""Pytest configuration of the repository's tests: that they test this checkout, the conformance suite's plugin
(--port, fixtures), headless GL, the firmware's C API for the tests that call the transform directly."""

import ctypes
from pathlib import Path

import pytest

import mantaray.sim  # noqa: F401  (before any test imports mujoco: it picks EGL where there is no display)
from mantaray.paths import REPO, native_artifact

pytest_plugins = ["mantaray.protocol.conformance.plugin"]


def pytest_configure(config):
    """Another checkout's editable install would answer the imports, and these tests would test that one."""
    here = Path(__file__).resolve().parent.parent
    if REPO != here:
        raise pytest.UsageError(
            f"the mantaray package imported is the checkout in {REPO}, not this one ({here}): "
            f"run `make setup` (scripts/setup.sh) here first"
        )


@pytest.fixture(scope="session")
def capi():
    """libmantaray_capi: the firmware core's plane transform and tilt limit, callable with float32 arguments."""
    lib = ctypes.CDLL(str(native_artifact("libmantaray_capi.so")))
    F, P = ctypes.c_float, ctypes.POINTER(ctypes.c_float)
    lib.mr_manhattan_commands.argtypes = [F, F, F, F, P]
    lib.mr_manhattan_commands.restype = None
    lib.mr_euclidean_commands.argtypes = [F, F, F, F, F, P]
    lib.mr_euclidean_commands.restype = None
    lib.mr_max_tilt_deg.argtypes = [F, F, F]
    lib.mr_max_tilt_deg.restype = F
    return lib
