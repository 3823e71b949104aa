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


# Test files whose tests run simulations, the AVR simulator, installs or long link-fault sequences (over about 20 s
# each on 2 cores): marked slow, so that `make test-fast` (pytest -m "not slow") leaves them out.
SLOW_FILES = {
    "test_calibrate.py",
    "test_conformance_vmcu.py",
    "test_fig3.py",
    "test_fuzz.py",
    "test_heatmap.py",
    "test_install.py",
    "test_link_faults.py",
    "test_ray_executor.py",
    "test_rig_cli.py",
    "test_sim_bridge.py",
    "test_sim_model.py",
    "test_simavr.py",
    "test_view.py",
    "test_tracker_sim.py",
    "test_video.py",
}


def pytest_collection_modifyitems(config, items):
    for item in items:
        if item.path.name in SLOW_FILES:
            item.add_marker(pytest.mark.slow)


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
